// Pinhole camera with radial distortion, as calibrated from 2-D/3-D feature
// correspondences (tarini2002 Sec. 3 uses Tsai's method; we estimate the same
// parameters: focal length, principal point, radial distortion k1 k2, pose).
// Data only; calibration lives in calibrate.h.
#pragma once
#include "common/types.h"

namespace lk {

// World -> camera: x_c = R * X + t. The camera looks along +z_c, image x to
// the right, image y DOWN (pixel rows), origin at the top-left pixel corner.
// Projection: (x, y) = (x_c/z_c, y_c/z_c); r2 = x^2 + y^2;
// d = 1 + k1 r2 + k2 r2^2; u = fx * d * x + cx; v = fy * d * y + cy.
struct Camera {
  double fx = 1000, fy = 1000;  // pixels
  double cx = 0, cy = 0;        // principal point, pixels
  double k1 = 0, k2 = 0;        // radial distortion
  Mat3 R = Mat3::Identity();
  Vec3 t = Vec3::Zero();
  int width = 0, height = 0;    // image size, pixels

  Vec3 to_camera(const Vec3& X) const { return R * X + t; }
  Vec3 center() const { return -R.transpose() * t; }  // camera centre in world
  // Pixel position of X; returns false when X is behind the camera.
  bool project(const Vec3& X, Vec2& uv) const {
    const Vec3 c = to_camera(X);
    if (c.z() <= 1e-12) return false;
    const double x = c.x() / c.z(), y = c.y() / c.z();
    const double r2 = x * x + y * y;
    const double d = 1 + k1 * r2 + k2 * r2 * r2;
    uv = Vec2(fx * d * x + cx, fy * d * y + cy);
    return true;
  }
};

// One 2-D/3-D correspondence: pixel (u, v) in the photo, point X on the head.
struct Correspondence {
  Vec2 pixel = Vec2::Zero();
  Vec3 point = Vec3::Zero();
};

}  // namespace lk
