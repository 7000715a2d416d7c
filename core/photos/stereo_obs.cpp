#include "photos/stereo_obs.h"

#include "raycast/bvh.h"

#include <algorithm>
#include <cmath>

namespace lk {

bool point_facet_distance(const Vec3& a, const Vec3& x1, const Vec3& x2, const Vec3& x3, double& d,
                          Eigen::Matrix<double, 1, 9>* gradient) {
  const Vec3 N = (x2 - x1).cross(x3 - x1);  // (C_x, C_y, C_z) of eq. 9
  const double m = N.norm();
  d = 0;
  if (gradient) gradient->setZero();
  if (!(m > 1e-300)) return false;
  const Vec3 n = N / m, e = a - x1;
  d = n.dot(e);  // D / |C|
  if (gradient) {
    // dd/dN = (e - d n) / m; dN/dx1 = [x3 - x2]x, dN/dx2 = [x1 - x3]x, dN/dx3 = [x2 - x1]x.
    const Vec3 g = (e - d * n) / m;
    gradient->segment<3>(0) = (g.cross(x3 - x2) - n).transpose();
    gradient->segment<3>(3) = g.cross(x1 - x3).transpose();
    gradient->segment<3>(6) = g.cross(x2 - x1).transpose();
  }
  return true;
}

StereoAttractorSet::StereoAttractorSet(const TriMesh& mesh, const std::vector<StereoPatch>& patches,
                                       const std::vector<Vec3>& positions)
    : triangles_(mesh.triangles) {
  att_.reserve(patches.size());
  for (const StereoPatch& p : patches) {
    StereoAttractor a;
    a.point = p.centre;
    a.normal = p.normal;
    att_.push_back(a);
  }
  reweight(positions);
}

bool StereoAttractorSet::evaluate(const std::vector<Vec3>& positions, Eigen::VectorXd& r, int row,
                                  std::vector<Eigen::Triplet<double>>* jacobian) const {
  Eigen::Matrix<double, 1, 9> g;
  for (const StereoAttractor& a : att_) {
    r[row] = 0;
    if (a.triangle >= 0 && a.weight > 0) {
      const Tri& t = triangles_[size_t(a.triangle)];
      double d;
      point_facet_distance(a.point, positions[size_t(t[0])], positions[size_t(t[1])], positions[size_t(t[2])], d,
                           jacobian ? &g : nullptr);
      const double s = std::sqrt(a.weight);
      r[row] = s * d;
      if (jacobian)
        for (int c = 0; c < 3; ++c)
          for (int j = 0; j < 3; ++j) jacobian->emplace_back(row, 3 * t[size_t(c)] + j, s * g[3 * c + j]);
    }
    ++row;
  }
  return true;
}

void StereoAttractorSet::reweight(const std::vector<Vec3>& positions) {
  TriMesh m;
  m.positions = positions;
  m.triangles = triangles_;
  MeshBvh bvh;
  if (att_.empty() || !build_bvh(m, bvh)) {
    for (StereoAttractor& a : att_) a.triangle = -1, a.weight = 0;
    return;
  }
  std::vector<double> dist(att_.size(), 0.0), found;
  found.reserve(att_.size());
  for (size_t i = 0; i < att_.size(); ++i) {
    StereoAttractor& a = att_[i];
    const ClosestPoint cp = closest_point_near(bvh, a.point, a.triangle);
    a.triangle = cp.found() ? cp.triangle : -1;
    a.weight = 0;
    dist[i] = cp.distance;
    if (cp.found()) found.push_back(cp.distance);
  }
  if (found.empty()) return;
  std::nth_element(found.begin(), found.begin() + long(found.size() / 2), found.end());
  const double median = std::max(found[found.size() / 2], 1e-9);
  for (size_t i = 0; i < att_.size(); ++i) {
    StereoAttractor& a = att_[i];
    if (a.triangle < 0) continue;
    const Tri& t = triangles_[size_t(a.triangle)];
    const Vec3 &x1 = positions[size_t(t[0])], &x2 = positions[size_t(t[1])], &x3 = positions[size_t(t[2])];
    const Vec3 N = (x2 - x1).cross(x3 - x1);
    if (!(N.norm() > 1e-300)) continue;
    const double agree = a.normal.squaredNorm() > 0 ? std::max(0.0, N.normalized().dot(a.normal)) : 1.0;
    a.weight = std::exp(-dist[i] / median) * agree;  // eq. 10, the distance to the surface
  }
}

std::vector<double> StereoAttractorSet::surface_distances(const std::vector<Vec3>& positions) const {
  TriMesh m;
  m.positions = positions;
  m.triangles = triangles_;
  MeshBvh bvh;
  std::vector<double> out;
  if (att_.empty() || !build_bvh(m, bvh)) return out;
  out.reserve(att_.size());
  for (const StereoAttractor& a : att_) out.push_back(closest_point(bvh, a.point).distance);
  return out;
}

}  // namespace lk
