#include "photos/landmark_learning.h"

#include "mesh/geometry.h"
#include "raycast/bvh.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>

namespace lk {
namespace {

double median_of(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

Vec3 surface_normal(const TriMesh& mesh, const std::vector<Vec3>& vn, const SurfacePoint& p) {
  const Tri& t = mesh.triangles[size_t(p.triangle)];
  Vec3 n = Vec3::Zero();
  for (int k = 0; k < 3; ++k) n += p.barycentric[k] * vn[size_t(t[k])];
  return n.normalized();
}

}  // namespace

Status learn_landmark_map(const TriMesh& generic, const LandmarkMap& start,
                          const std::vector<DetectedSessionView>& sessions, const LearnMapOptions& options,
                          LandmarkMap& out, LearnMapReport* report) {
  if (!(options.min_view_cos >= -1 && options.min_view_cos < 1) || options.min_views < 2 ||
      options.min_sessions < 1 || !(options.max_offset_m > 0))
    return Status::error(ErrorCode::InvalidInput, "learn_landmark_map: bad options");
  std::vector<SurfacePoint> attached;
  Status s = attach_landmark_map(start, generic, options.max_offset_m, attached);
  if (!s) return with_context(s, "learn_landmark_map");
  const size_t M = start.points.size();
  std::vector<std::vector<Vec3>> found(M);  // per landmark, one generic-frame point per session
  for (size_t si = 0; si < sessions.size(); ++si) {
    const DetectedSessionView& ses = sessions[si];
    if (!ses.person || ses.person->triangles.size() != generic.triangles.size() ||
        ses.person->positions.size() != generic.positions.size() || ses.cameras.size() != ses.photos.size())
      return Status::error(ErrorCode::InvalidInput,
                           "learn_landmark_map: session " + std::to_string(si) + " has another topology or sizes");
    const TriMesh& person = *ses.person;
    const std::vector<Vec3> vn = vertex_normals(person);
    MeshBvh bvh;
    s = build_bvh(person, bvh);
    if (!s) return with_context(s, "learn_landmark_map");
    for (size_t m = 0; m < M; ++m) {
      if (!attached[m].valid()) continue;
      const Vec3 P = surface_position(person, attached[m]);
      const Vec3 n = surface_normal(person, vn, attached[m]);
      // Linear triangulation: for each view, rows (R_a - x_a R_2) X = -(t_a - x_a t_2), a = 0, 1.
      Mat3 A = Mat3::Zero();
      Vec3 b = Vec3::Zero();
      int views = 0;
      for (size_t c = 0; c < ses.cameras.size(); ++c) {
        const LandmarkPhoto& ph = ses.photos[c];
        if (m >= ph.points.size() || !ph.present[m]) continue;
        const Camera& cam = ses.cameras[c];
        if (n.dot((cam.center() - P).normalized()) < options.min_view_cos) continue;
        const Vec2 x((ph.points[m].x() - cam.cx) / cam.fx, (ph.points[m].y() - cam.cy) / cam.fy);
        for (int a = 0; a < 2; ++a) {
          const Vec3 row = cam.R.row(a).transpose() - x[a] * cam.R.row(2).transpose();
          const double rhs = -(cam.t[a] - x[a] * cam.t[2]);
          A += row * row.transpose();
          b += row * rhs;
        }
        ++views;
      }
      if (views < options.min_views) continue;
      // Views too close in direction give no depth: refuse an ill-conditioned system.
      Eigen::SelfAdjointEigenSolver<Mat3> eig(A);
      if (!(eig.eigenvalues()[0] > 1e-6 * eig.eigenvalues()[2])) continue;
      const Vec3 X = A.ldlt().solve(b);
      if (!X.allFinite()) continue;
      // Onto the generic head: the person's closest surface place, the same place on the generic, the offset kept.
      const ClosestPoint cp = closest_point(bvh, X);
      if (!cp.found()) continue;
      SurfacePoint sp;
      sp.triangle = cp.triangle;
      sp.barycentric = cp.barycentric;
      sp.offset = X - cp.point;
      if (sp.offset.norm() > options.max_offset_m) sp.offset *= options.max_offset_m / sp.offset.norm();
      found[m].push_back(surface_position(generic, sp));
    }
  }
  out = start;
  std::vector<double> moves;
  for (size_t m = 0; m < M; ++m) {
    if (int(found[m].size()) < options.min_sessions) continue;
    Vec3 med;
    for (int k = 0; k < 3; ++k) {
      std::vector<double> v;
      for (const Vec3& p : found[m]) v.push_back(p[k]);
      med[k] = median_of(v);
    }
    moves.push_back((med - start.points[m]).norm());
    out.points[m] = med;
  }
  if (moves.empty()) return Status::error(ErrorCode::Empty, "learn_landmark_map: no landmark seen in enough views");
  if (report) {
    report->learned = int(moves.size());
    report->median_move_m = median_of(moves);
  }
  return Status::success();
}

}  // namespace lk
