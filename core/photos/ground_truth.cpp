#include "photos/ground_truth.h"

#include "raycast/bvh.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace lk {

Similarity fit_similarity(const std::vector<Vec3>& from, const std::vector<Vec3>& to, const std::vector<int>& vertices) {
  Similarity s;
  if (vertices.empty()) return s;
  Eigen::Matrix3Xd A(3, long(vertices.size())), B(3, long(vertices.size()));
  for (size_t i = 0; i < vertices.size(); ++i) {
    A.col(long(i)) = from[size_t(vertices[i])];
    B.col(long(i)) = to[size_t(vertices[i])];
  }
  const Eigen::Matrix4d T = Eigen::umeyama(A, B, true);
  const Mat3 sR = T.topLeftCorner<3, 3>();
  s.scale = std::cbrt(sR.determinant());
  s.R = sR / s.scale;
  s.t = T.topRightCorner<3, 1>();
  return s;
}

Camera transform_camera(const Camera& c, const Similarity& s) {
  // x_c = R X + t with X = (R_s^T (Y - t_s)) / scale; scaling the camera
  // coordinates by `scale` leaves the image unchanged.
  Camera out = c;
  out.R = c.R * s.R.transpose();
  out.t = s.scale * c.t - out.R * s.t;
  return out;
}

double rotation_angle_deg(const Mat3& Ra, const Mat3& Rb) {
  const Eigen::AngleAxisd aa(Mat3(Ra.transpose() * Rb));
  return std::abs(aa.angle()) * 180.0 / 3.14159265358979323846;
}

DistanceStats surface_distances(const TriMesh& from, const std::vector<int>& vertices, const TriMesh& to) {
  MeshBvh bvh;
  if (!build_bvh(to, bvh) || bvh.empty()) return DistanceStats{};
  std::vector<double> d;
  int guess = -1;
  for (int v : vertices) {
    if (v < 0 || v >= from.num_vertices()) continue;
    const ClosestPoint c = closest_point_near(bvh, from.positions[size_t(v)], guess);
    guess = c.triangle;
    d.push_back(c.distance);
  }
  return summarize_distances(d, 0);
}

}  // namespace lk
