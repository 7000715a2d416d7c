#include "photos/eye_lids.h"

#include "anim/face_pose.h"
#include "numeric/powell.h"
#include "head/head_creases.h"
#include "subdiv/butterfly.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <utility>

namespace lk {

const LidContour& mediapipe_lid_contour(int eye) {
  // FACEMESH_LEFT_EYE / FACEMESH_RIGHT_EYE of the detector (the person's left
  // is the head's +x).
  static constexpr std::array<double, 7> upper_at{0.055, 0.127, 0.247, 0.43, 0.6, 0.82, 0.942};
  static constexpr std::array<double, 7> lower_at{0.097, 0.209, 0.34, 0.533, 0.712, 0.864, 0.954};
  static const LidContour left{263, 362, {466, 388, 387, 386, 385, 384, 398}, {249, 390, 373, 374, 380, 381, 382},
                               upper_at, lower_at};
  static const LidContour right{33, 133, {246, 161, 160, 159, 158, 157, 173}, {7, 163, 144, 145, 153, 154, 155},
                                upper_at, lower_at};
  return eye == 0 ? left : right;
}

int lid_contour_eye(int landmark) {
  for (int eye = 0; eye < 2; ++eye) {
    const LidContour& c = mediapipe_lid_contour(eye);
    if (landmark == c.outer || landmark == c.inner || std::find(c.upper.begin(), c.upper.end(), landmark) != c.upper.end() ||
        std::find(c.lower.begin(), c.lower.end(), landmark) != c.lower.end())
      return eye;
  }
  return -1;
}

bool camera_sees_lids(const GenericHead& generic, int eye, const Camera& camera) {
  const Vec3 centre = (eye == 0 ? generic.annotations.eye_left : generic.annotations.eye_right).center;
  return (camera.center() - centre).normalized().dot(generic.annotations.look.normalized()) >= 0.866;
}

double opening_gap(const std::vector<Vec2>& outline, const Vec2& a, const Vec2& b, const Vec2& centre) {
  const Vec2 axis = b - a;
  if (axis.norm() <= 0 || outline.size() < 3) return 0;
  const Vec2 d = Vec2(-axis.y(), axis.x()).normalized();  // across the opening
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  int hits = 0;
  for (size_t i = 0; i < outline.size(); ++i) {
    const Vec2 p = outline[i], q = outline[(i + 1) % outline.size()];
    // centre + s d = p + t (q - p), t in [0, 1)
    const Vec2 e = q - p;
    const double den = d.x() * (-e.y()) - d.y() * (-e.x());
    if (std::abs(den) < 1e-12) continue;
    const Vec2 r = p - centre;
    const double s = (r.x() * (-e.y()) - r.y() * (-e.x())) / den;
    const double t = (d.x() * r.y() - d.y() * r.x()) / den;
    if (t < 0 || t >= 1) continue;
    lo = std::min(lo, s);
    hi = std::max(hi, s);
    ++hits;
  }
  return hits >= 2 ? hi - lo : 0;
}

Status landmark_lid_opening(const LandmarkPhoto& photo, int eye, const Vec2& centre, LidOpening& out) {
  if (eye < 0 || eye > 1) return Status::error(ErrorCode::InvalidInput, "lid opening: eye must be 0 or 1");
  const LidContour& c = mediapipe_lid_contour(eye);
  auto at = [&](int i, Vec2& p) {
    if (i >= static_cast<int>(photo.points.size()) || !photo.present[static_cast<size_t>(i)]) return false;
    p = photo.points[static_cast<size_t>(i)];
    return true;
  };
  std::vector<Vec2> outline;
  Vec2 p, outer, inner;
  bool ok = at(c.outer, outer) && at(c.inner, inner);
  outline.push_back(outer);
  for (int i : c.upper) ok = ok && at(i, p), outline.push_back(p);
  outline.push_back(inner);
  for (auto it = c.lower.rbegin(); it != c.lower.rend(); ++it) ok = ok && at(*it, p), outline.push_back(p);
  if (!ok) return Status::error(ErrorCode::InvalidInput, "lid opening: the photo lacks a lid point of that eye");
  out.width_px = (outer - inner).norm();
  out.gap_px = opening_gap(outline, outer, inner, centre);
  return Status::success();
}

namespace {

// A point on the mesh edge (a, b) at t from a: a triangle holding the edge,
// barycentric weights on a and b.
bool point_on_edge(const TriMesh& mesh, int a, int b, double t, SurfacePoint& out) {
  for (size_t f = 0; f < mesh.triangles.size(); ++f) {
    const Tri& tri = mesh.triangles[f];
    int ia = -1, ib = -1;
    for (int k = 0; k < 3; ++k) {
      if (tri[k] == a) ia = k;
      if (tri[k] == b) ib = k;
    }
    if (ia < 0 || ib < 0) continue;
    out.triangle = static_cast<int>(f);
    out.barycentric = Vec3::Zero();
    out.barycentric[ia] = 1 - t;
    out.barycentric[ib] = t;
    out.offset = Vec3::Zero();
    return true;
  }
  return false;
}

}  // namespace

Status lid_margin_points(const GenericHead& generic, const std::vector<SurfacePoint>& landmarks,
                         std::vector<SurfacePoint>& out) {
  out.assign(landmarks.size(), SurfacePoint{});
  const TriMesh& mesh = generic.mesh;
  for (int eye = 0; eye < 2; ++eye) {
    const std::vector<int>& loop = (eye == 0 ? generic.annotations.eye_left : generic.annotations.eye_right).rim;
    const int n = static_cast<int>(loop.size());
    if (n < 4) return Status::error(ErrorCode::InvalidInput, "lid margin: the head has no eye rim loop");
    auto P = [&](int i) { return mesh.positions[static_cast<size_t>(loop[static_cast<size_t>(((i % n) + n) % n)])]; };
    int lo = 0, hi = 0;
    for (int i = 0; i < n; ++i) {
      if (P(i).x() < P(lo).x()) lo = i;
      if (P(i).x() > P(hi).x()) hi = i;
    }
    // The two halves from the -x corner to the +x corner, as loop index paths.
    std::vector<int> half[2];
    for (int dir = 0; dir < 2; ++dir)
      for (int i = lo;; i += dir == 0 ? 1 : -1) {
        half[dir].push_back(((i % n) + n) % n);
        if (((i % n) + n) % n == hi) break;
      }
    auto mean_y = [&](const std::vector<int>& h) {
      double y = 0;
      for (int i : h) y += P(i).y();
      return y / double(h.size());
    };
    const std::vector<int>& upper = mean_y(half[0]) > mean_y(half[1]) ? half[0] : half[1];
    const std::vector<int>& lower = &upper == &half[0] ? half[1] : half[0];
    // A corner: the extreme vertex, or the middle of its edge to a loop
    // neighbour at nearly the same x (a rim may end in a short upright edge).
    // The rim as the level mesh draws it: the crease curve refined three
    // times (8 samples per control edge). A point on a control edge keeps
    // its offset to that curve, as a map point keeps its offset to the
    // smooth surface (the chord lies inside the curved lid).
    std::vector<Vec3> curve;
    if (Status s = refined_eye_rim(mesh, generic, eye, 3, curve); !s) return s;
    const int per_edge = static_cast<int>(curve.size()) / n;
    auto on_rim = [&](int ia, int ib, double t, SurfacePoint& sp) {
      ia = ((ia % n) + n) % n;
      ib = ((ib % n) + n) % n;
      if (!point_on_edge(mesh, loop[static_cast<size_t>(ia)], loop[static_cast<size_t>(ib)], t, sp)) return false;
      const int nc = static_cast<int>(curve.size());
      const double at = per_edge * (ia + (ib == (ia + 1) % n ? t : -t));
      const int k0 = static_cast<int>(std::floor(at));
      const double f = at - k0;
      const Vec3 c = (1 - f) * curve[static_cast<size_t>(((k0 % nc) + nc) % nc)] +
                     f * curve[static_cast<size_t>((((k0 + 1) % nc) + nc) % nc)];
      sp.offset = c - surface_position(mesh, sp);
      return true;
    };
    auto corner = [&](int i, SurfacePoint& sp) {
      for (int d : {1, -1})
        if (std::abs(P(i + d).x() - P(i).x()) < 0.5e-3) return on_rim(i, i + d, 0.5, sp);
      return on_rim(i, i + 1, 0, sp);
    };
    // On a half, where it reaches x (clamped to its ends).
    auto along = [&](const std::vector<int>& h, double x, SurfacePoint& sp) {
      for (size_t k = 0; k + 1 < h.size(); ++k) {
        const double xa = P(h[k]).x(), xb = P(h[k + 1]).x();
        const bool last = k + 2 == h.size();
        if ((x >= xa && x <= xb) || (k == 0 && x < xa) || last) {
          const double t = xb > xa ? std::clamp((x - xa) / (xb - xa), 0.0, 1.0) : 0.5;
          return on_rim(h[k], h[k + 1], t, sp);
        }
      }
      return false;
    };
    const LidContour& c = mediapipe_lid_contour(eye);
    // Eye 0 (+x): the outer corner is the +x end; eye 1: the -x end.
    const int outer_i = eye == 0 ? hi : lo, inner_i = eye == 0 ? lo : hi;
    auto have = [&](int m) { return m < static_cast<int>(landmarks.size()) && landmarks[static_cast<size_t>(m)].valid(); };
    bool ok = true;
    if (have(c.outer)) ok = ok && corner(outer_i, out[static_cast<size_t>(c.outer)]);
    if (have(c.inner)) ok = ok && corner(inner_i, out[static_cast<size_t>(c.inner)]);
    const double x_outer = P(outer_i).x(), x_inner = P(inner_i).x();
    for (size_t k = 0; k < 7; ++k) {
      if (have(c.upper[k]))
        ok = ok && along(upper, x_outer + c.upper_at[k] * (x_inner - x_outer), out[static_cast<size_t>(c.upper[k])]);
      if (have(c.lower[k]))
        ok = ok && along(lower, x_outer + c.lower_at[k] * (x_inner - x_outer), out[static_cast<size_t>(c.lower[k])]);
    }
    if (!ok) return Status::error(ErrorCode::InvalidInput, "lid margin: an eye rim edge is not a mesh edge");
  }
  return Status::success();
}

Status refined_eye_rim(const TriMesh& head, const GenericHead& generic, int eye, int level, std::vector<Vec3>& rim) {
  if (eye < 0 || eye > 1 || level < 0 || level > 4)
    return Status::error(ErrorCode::InvalidInput, "eye rim: eye 0 or 1, level 0..4");
  if (head.positions.size() != generic.mesh.positions.size())
    return Status::error(ErrorCode::InvalidInput, "eye rim: the head does not have the generic head's topology");
  std::vector<int> loop = (eye == 0 ? generic.annotations.eye_left : generic.annotations.eye_right).rim;
  if (loop.size() < 3) return Status::error(ErrorCode::InvalidInput, "eye rim: the generic head has no rim loop");
  std::vector<Vec3> positions = head.positions;
  if (level > 0) {
    TriMesh topo;
    topo.positions = head.positions;
    topo.triangles = generic.mesh.triangles;
    std::vector<ButterflyLevel> levels;
    if (Status s = build_butterfly_levels(topo, head_creases(generic.mesh, generic.annotations), level, levels); !s) return s;
    for (const ButterflyLevel& lv : levels) {
      std::map<std::pair<int, int>, int> wanted;
      for (size_t i = 0; i < loop.size(); ++i) {
        const int a = loop[i], b = loop[(i + 1) % loop.size()];
        wanted[{std::min(a, b), std::max(a, b)}] = -1;
      }
      for (size_t k = 0; k < lv.edge_endpoints.size(); ++k) {
        const auto& e = lv.edge_endpoints[k];
        auto it = wanted.find({std::min(e[0], e[1]), std::max(e[0], e[1])});
        if (it != wanted.end()) it->second = lv.num_coarse_vertices + static_cast<int>(k);
      }
      std::vector<int> fine;
      for (size_t i = 0; i < loop.size(); ++i) {
        const int a = loop[i], b = loop[(i + 1) % loop.size()];
        const int mid = wanted[{std::min(a, b), std::max(a, b)}];
        if (mid < 0) return Status::error(ErrorCode::InvalidInput, "eye rim: consecutive rim vertices share no edge");
        fine.push_back(a);
        fine.push_back(mid);
      }
      loop.swap(fine);
      std::vector<Vec3> next;
      if (Status s = apply(lv, positions, next); !s) return s;
      positions.swap(next);
    }
  }
  rim.clear();
  for (int v : loop) rim.push_back(positions[static_cast<size_t>(v)]);
  return Status::success();
}

Status head_lid_opening(const TriMesh& head, const GenericHead& generic, int eye, int level, const Camera& camera,
                        const Vec2& centre, LidOpening& out) {
  std::vector<Vec3> rim;
  if (Status s = refined_eye_rim(head, generic, eye, level, rim); !s) return s;
  // The corners: the rim's ends along x on the generic head (the canthi
  // head_creases makes crease corners), on the control mesh, whose rim
  // vertices the refined loop keeps.
  const std::vector<int>& loop = (eye == 0 ? generic.annotations.eye_left : generic.annotations.eye_right).rim;
  const std::vector<Vec3>& at = generic.mesh.positions;
  int lo = loop[0], hi = loop[0];
  for (int v : loop) {
    if (at[static_cast<size_t>(v)].x() < at[static_cast<size_t>(lo)].x()) lo = v;
    if (at[static_cast<size_t>(v)].x() > at[static_cast<size_t>(hi)].x()) hi = v;
  }
  std::vector<Vec2> outline(rim.size());
  for (size_t i = 0; i < rim.size(); ++i)
    if (!camera.project(rim[i], outline[i]))
      return Status::error(ErrorCode::InvalidInput, "lid opening: the eye rim is behind the camera");
  Vec2 a, b;
  camera.project(head.positions[static_cast<size_t>(lo)], a);
  camera.project(head.positions[static_cast<size_t>(hi)], b);
  out.width_px = (b - a).norm();
  out.gap_px = opening_gap(outline, a, b, centre);
  return Status::success();
}

Status fit_lid_pose(const GenericHead& generic, const std::vector<SurfacePoint>& lid_points,
                    const std::vector<LandmarkPhoto>& photos, const SelfCalibResult& calib, TriMesh& head,
                    LidPoseResult& out, double huber_px) {
  out = LidPoseResult{};
  if (calib.photos.size() != photos.size())
    return Status::error(ErrorCode::InvalidInput, "lid pose: the calibration is for other photos");
  if (!(huber_px > 0)) return Status::error(ErrorCode::InvalidInput, "lid pose: huber_px must be positive");
  // The opening across each lid column: the upper and the lower contour
  // point k of one eye in one photo, their distance (not their place: where
  // the eye sits is the shape fit's, and a shift of the whole opening must
  // not be fitted by opening one lid and closing the other).
  struct Column {
    const Camera* camera;
    int upper, lower;
    double gap_px;
  };
  std::vector<Column> cols;
  for (size_t i = 0; i < photos.size(); ++i) {
    const PhotoCalibration& pc = calib.photos[i];
    if (!pc.used) continue;
    for (int eye = 0; eye < 2; ++eye) {
      if (!camera_sees_lids(generic, eye, pc.camera)) continue;
      const LidContour& c = mediapipe_lid_contour(eye);
      for (size_t k = 0; k < 7; ++k) {
        const size_t u = static_cast<size_t>(c.upper[k]), l = static_cast<size_t>(c.lower[k]);
        if (u >= lid_points.size() || l >= lid_points.size() || !lid_points[u].valid() || !lid_points[l].valid() ||
            u >= photos[i].points.size() || l >= photos[i].points.size() || !photos[i].present[u] || !photos[i].present[l])
          continue;
        cols.push_back({&pc.camera, int(u), int(l), (photos[i].points[u] - photos[i].points[l]).norm()});
      }
    }
  }
  out.observations = static_cast<int>(cols.size());
  if (cols.empty()) return Status::success();  // no photo marks the lids: the shape fit's stand
  FaceRig rig;
  if (Status s = make_face_rig(head, generic, rig); !s) return with_context(s, "lid pose");
  // One value per eye: g > 0 closes both lids by g (the rig's upper and
  // lower lid channels), g < 0 opens the upper lid (the rig lowers no lower
  // lid).
  auto controls_of = [](const Eigen::VectorXd& g) {
    FaceControls c;
    c[kLidL] = g[0];
    c[kLidR] = g[1];
    c[kLowerLidL] = std::max(0.0, g[0]);
    c[kLowerLidR] = std::max(0.0, g[1]);
    return c;
  };
  TriMesh at = head;
  auto cost = [&](const Eigen::VectorXd& g, double* rms) {
    if (std::abs(g[0]) > 1 || std::abs(g[1]) > 1) return std::numeric_limits<double>::infinity();
    at.positions = pose_face(rig, controls_of(g));
    double sum = 0, sq = 0;
    for (const Column& c : cols) {
      Vec2 a, b;
      if (!c.camera->project(surface_position(at, lid_points[static_cast<size_t>(c.upper)]), a) ||
          !c.camera->project(surface_position(at, lid_points[static_cast<size_t>(c.lower)]), b))
        return std::numeric_limits<double>::infinity();
      const double e = std::abs((a - b).norm() - c.gap_px);
      sq += e * e;
      sum += e <= huber_px ? e * e : huber_px * (2 * e - huber_px);  // Huber
    }
    if (rms) *rms = std::sqrt(sq / double(cols.size()));
    return sum;
  };
  const Eigen::VectorXd g0 = Eigen::VectorXd::Zero(2);
  cost(g0, &out.rms_before_px);
  PowellOptions po;
  po.initial_step = Eigen::VectorXd::Constant(2, 0.2);
  po.line_absolute_tolerance = 1e-3;
  po.tolerance = 1e-6;
  PowellResult pr;
  if (Status s = powell_minimize([&](const Eigen::VectorXd& g) { return cost(g, nullptr); }, g0, po, pr); !s)
    return with_context(s, "lid pose");
  cost(pr.x, &out.rms_after_px);
  const FaceControls best = controls_of(pr.x);
  out.upper = {best[kLidL], best[kLidR]};
  out.lower = {best[kLowerLidL], best[kLowerLidR]};
  head.positions = pose_face(rig, best);
  return Status::success();
}

}  // namespace lk
