// Basic math types of the core. Positions are double precision: the fitting
// stages solve least-squares systems on them; the renderer converts to float.
#pragma once
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <vector>

namespace lk {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;
using Vec4 = Eigen::Vector4d;
using Mat3 = Eigen::Matrix3d;
using Mat4 = Eigen::Matrix4d;
using Tri = std::array<int, 3>;  // vertex indices, counter-clockwise seen from outside

struct BBox {
  Vec3 min = Vec3::Constant(1e300);
  Vec3 max = Vec3::Constant(-1e300);
  void extend(const Vec3& p) { min = min.cwiseMin(p); max = max.cwiseMax(p); }
  bool valid() const { return (max.array() >= min.array()).all(); }
  Vec3 center() const { return 0.5 * (min + max); }
  Vec3 size() const { return max - min; }
  double diagonal() const { return valid() ? (max - min).norm() : 0.0; }
};

}  // namespace lk
