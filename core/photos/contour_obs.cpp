#include "photos/contour_obs.h"

#include "photos/self_calibration.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace lk {
namespace {

double cross2(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

Vec3 triangle_normal(const TriMesh& mesh, int f) {
  const Tri& t = mesh.triangles[size_t(f)];
  const Vec3 n = (mesh.positions[size_t(t[1])] - mesh.positions[size_t(t[0])])
                     .cross(mesh.positions[size_t(t[2])] - mesh.positions[size_t(t[0])]);
  return n.norm() > 0 ? Vec3(n.normalized()) : Vec3::Zero();
}

}  // namespace

const std::vector<int>& mediapipe_face_oval() {
  static const std::vector<int> loop = {10,  338, 297, 332, 284, 251, 389, 356, 454, 323, 361, 288,
                                        397, 365, 379, 378, 400, 377, 152, 148, 176, 149, 150, 136,
                                        172, 58,  132, 93,  234, 127, 162, 21,  54,  103, 67,  109};
  return loop;
}

std::vector<std::pair<int, Vec2>> outline_normals(const std::vector<Vec2>& points, const std::vector<char>& present,
                                                  const std::vector<int>& loop) {
  std::vector<int> ids;
  for (int m : loop)
    if (m >= 0 && size_t(m) < points.size() && present[size_t(m)]) ids.push_back(m);
  std::vector<std::pair<int, Vec2>> out;
  if (ids.size() < 8) return out;
  Vec2 centre = Vec2::Zero();
  for (int m : ids) centre += points[size_t(m)];
  centre /= double(ids.size());
  const size_t n = ids.size();
  for (size_t k = 0; k < n; ++k) {
    const Vec2 d = points[size_t(ids[(k + 1) % n])] - points[size_t(ids[(k + n - 1) % n])];
    if (d.norm() < 1e-9) continue;
    Vec2 nrm = Vec2(-d.y(), d.x()) / d.norm();
    if (nrm.dot(points[size_t(ids[k])] - centre) < 0) nrm = -nrm;
    out.emplace_back(ids[k], nrm);
  }
  return out;
}

std::vector<ContourObservation> contour_observations(const TriMesh& mesh, const std::vector<SurfacePoint>& landmarks,
                                                     const std::vector<Vec2>& points,
                                                     const std::vector<char>& present, const Camera& camera,
                                                     int camera_index, const ContourOptions& options,
                                                     std::vector<char>& is_contour) {
  is_contour.assign(points.size(), 0);
  std::vector<ContourObservation> out;
  const Vec3 C = camera.center();
  const std::vector<int>& loop = mediapipe_face_oval();
  const int n = int(loop.size());
  for (const auto& [m, normal] : outline_normals(points, present, loop)) {
    if (size_t(m) >= landmarks.size() || !landmarks[size_t(m)].valid()) continue;
    const int k = int(std::find(loop.begin(), loop.end(), m) - loop.begin());
    if (std::min(k, n - k) < options.min_loop_depth) continue;
    SurfacePoint sp = landmarks[size_t(m)];
    sp.offset = Vec3::Zero();  // the place on the surface; the rim is searched near it
    const Vec3 X = surface_position(mesh, sp);
    const double view_cos = triangle_normal(mesh, sp.triangle).dot((C - X).normalized());
    if (view_cos >= options.max_view_cos) continue;
    ContourObservation o;
    o.camera = camera_index;
    o.landmark = m;
    o.point = sp;
    o.pixel = points[size_t(m)];
    o.normal = normal;
    out.push_back(o);
    is_contour[size_t(m)] = 1;
  }
  return out;
}

ContourSet::ContourSet(const TriMesh& mesh, std::vector<Camera> cameras, std::vector<ContourObservation> observations,
                       const ContourOptions& options)
    : triangles_(mesh.triangles), cameras_(std::move(cameras)), obs_(std::move(observations)), options_(options) {
  edges_ = mesh_edge_list(triangles_);
  reweight(mesh.positions);
}

std::vector<ContourSet::Match> ContourSet::find_matches(const std::vector<Vec3>& P) const {
  std::vector<Match> out;
  TriMesh at;
  at.triangles = triangles_;
  at.positions = P;
  for (size_t c = 0; c < cameras_.size(); ++c) {
    bool any = false;
    for (const ContourObservation& o : obs_) any = any || o.camera == int(c);
    if (!any) continue;
    const std::vector<RimEdge> rims = find_rim_edges(P, triangles_, edges_, cameras_[c], false);
    for (size_t k = 0; k < obs_.size(); ++k) {
      const ContourObservation& o = obs_[k];
      if (o.camera != int(c)) continue;
      const Vec3 X = surface_position(at, o.point);
      const RimEdge* best = nullptr;
      double best_t = std::numeric_limits<double>::infinity();
      for (const RimEdge& r : rims) {
        if (r.excluded || r.outward.dot(o.normal) < options_.min_normal_cos) continue;
        if (std::min((P[size_t(r.a)] - X).norm(), (P[size_t(r.b)] - X).norm()) > options_.reach_m) continue;
        const Vec2 e = r.pb - r.pa;
        const double den = cross2(o.normal, e);
        if (std::abs(den) < 1e-3 * e.norm()) continue;
        const double t = cross2(r.pa - o.pixel, e) / den, u = cross2(r.pa - o.pixel, o.normal) / den;
        if (u < -0.05 || u > 1.05 || std::abs(t) > options_.search_px || std::abs(t) >= std::abs(best_t)) continue;
        best_t = t;
        best = &r;
      }
      if (!best) continue;
      Match m;
      m.observation = int(k);
      // Orient (a, b) so that line_distance is positive outside the rim.
      const Vec2 e = best->pb - best->pa;
      const bool keep = Vec2(-e.y(), e.x()).dot(best->outward) > 0;
      m.a = keep ? best->a : best->b;
      m.b = keep ? best->b : best->a;
      out.push_back(m);
    }
  }
  return out;
}

double ContourSet::distance(const std::vector<Vec3>& P, const Match& m) const {
  const ContourObservation& o = obs_[size_t(m.observation)];
  const Camera& cam = cameras_[size_t(o.camera)];
  Vec2 pa, pb;
  if (!cam.project(P[size_t(m.a)], pa) || !cam.project(P[size_t(m.b)], pb))
    return std::numeric_limits<double>::infinity();
  return line_distance(pa, pb, o.pixel, nullptr, nullptr);
}

bool ContourSet::evaluate(const std::vector<Vec3>& P, Eigen::VectorXd& r, int row,
                          std::vector<Eigen::Triplet<double>>* jacobian) const {
  for (const Match& m : matches_) {
    const ContourObservation& o = obs_[size_t(m.observation)];
    const Camera& cam = cameras_[size_t(o.camera)];
    ProjectionJacobian ja, jb;
    if (!projection_jacobian(cam, P[size_t(m.a)], Vec2::Zero(), ja) ||
        !projection_jacobian(cam, P[size_t(m.b)], Vec2::Zero(), jb))
      return false;
    const double sw = std::sqrt(m.weight * o.prior_weight);
    Vec2 ga, gb;
    r[row] = sw * line_distance(ja.residual, jb.residual, o.pixel, &ga, &gb);
    if (jacobian)
      for (int k = 0; k < 3; ++k) {
        jacobian->emplace_back(row, 3 * m.a + k, sw * ga.dot(ja.d_point.col(k)));
        jacobian->emplace_back(row, 3 * m.b + k, sw * gb.dot(jb.d_point.col(k)));
      }
    ++row;
  }
  return true;
}

void ContourSet::reweight(const std::vector<Vec3>& positions) {
  matches_ = find_matches(positions);
  for (Match& m : matches_) m.weight = huber_weight(std::abs(distance(positions, m)), options_.huber_px);
}

std::vector<double> ContourSet::signed_distances(const std::vector<Vec3>& positions) const {
  std::vector<double> d(obs_.size(), std::numeric_limits<double>::quiet_NaN());
  for (const Match& m : find_matches(positions)) d[size_t(m.observation)] = distance(positions, m);
  return d;
}

std::vector<ContourDistance> contour_distances(const TriMesh& generic, const std::vector<SurfacePoint>& landmarks,
                                               const std::vector<LandmarkPhoto>& photos, const SelfCalibResult& calib,
                                               const std::vector<Vec3>& positions, const ContourOptions& options) {
  ContourOptions all = options;
  all.max_view_cos = 2;  // every loop landmark
  all.min_loop_depth = 0;
  TriMesh at = generic;
  at.positions = positions;
  std::vector<Camera> cameras;
  std::vector<ContourObservation> obs;
  std::vector<int> photo_of;
  for (size_t i = 0; i < photos.size() && i < calib.photos.size(); ++i) {
    if (!calib.photos[i].used) continue;
    std::vector<char> is_contour;
    for (const ContourObservation& o : contour_observations(at, landmarks, photos[i].points, photos[i].present,
                                                            calib.photos[i].camera, int(cameras.size()), all,
                                                            is_contour)) {
      obs.push_back(o);
      photo_of.push_back(int(i));
    }
    cameras.push_back(calib.photos[i].camera);
  }
  std::vector<ContourDistance> out;
  if (obs.empty()) return out;
  const ContourSet set(at, cameras, obs, all);
  const std::vector<double> d = set.signed_distances(positions);
  const std::vector<int>& loop = mediapipe_face_oval();
  for (size_t k = 0; k < obs.size(); ++k) {
    ContourDistance c;
    c.photo = photo_of[k];
    c.landmark = obs[k].landmark;
    c.loop_index = int(std::find(loop.begin(), loop.end(), c.landmark) - loop.begin());
    c.pixel = obs[k].pixel;
    c.px = d[k];
    const Camera& cam = cameras[size_t(obs[k].camera)];
    const double depth = cam.to_camera(surface_position(at, obs[k].point)).z();
    c.mm = 1000 * c.px * depth / (0.5 * (cam.fx + cam.fy));
    out.push_back(c);
  }
  return out;
}

}  // namespace lk
