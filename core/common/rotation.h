// Rotations parameterized by a rotation vector, shared by the solvers that
// step a rotation that way (calibration, alignment, self-calibration,
// texture registration).
#pragma once

#include <Eigen/Geometry>
#include <Eigen/SVD>

#include "common/types.h"

namespace lk {

// [v]x: the cross-product matrix, [v]x a = v x a.
inline Mat3 skew(const Vec3& v) {
  Mat3 m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

// exp([w]x): the rotation by |w| radians about w; the identity for w = 0.
inline Mat3 rotation_from_vector(const Vec3& w) {
  const double angle = w.norm();
  return angle > 0 ? Mat3(Eigen::AngleAxisd(angle, w / angle).toRotationMatrix()) : Mat3::Identity();
}

// The rotation nearest to m (its polar factor U V^T, m = U S V^T): the
// turn of a linear map that also stretches. May be a reflection (det -1)
// when m mirrors; the callers check.
inline Mat3 nearest_rotation(const Mat3& m) {
  const Eigen::JacobiSVD<Mat3> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
  return svd.matrixU() * svd.matrixV().transpose();
}

}  // namespace lk
