// Synthetic cameras looking at head-sized point sets, shared by the
// calibration tests: ground truth for every calibrated parameter.
#pragma once
#include "calib/camera.h"
#include "common/prng.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <vector>

namespace lk {
namespace calib_test {

inline const double kPi = 3.14159265358979323846;

// Feature-like points on the front of a head-sized ellipsoid (metres).
inline std::vector<Vec3> head_points(SplitMix64& rng, int n) {
  std::vector<Vec3> pts;
  while (int(pts.size()) < n) {
    const Vec3 d(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
    if (d.norm() < 0.2 || d.norm() > 1) continue;
    Vec3 p = d.normalized();
    if (p.z() < -0.1) continue;  // features are on the visible front
    pts.push_back(Vec3(0.075 * p.x(), 0.11 * p.y(), 0.095 * p.z()));
  }
  return pts;
}

// A camera looking at the head from yaw/pitch (degrees) at a distance.
inline Camera look_at_head(double yaw, double pitch, double roll, double distance, double f, double cx,
                    double cy, double k1 = 0, double k2 = 0) {
  Camera c;
  c.width = 1800;
  c.height = 1200;
  c.fx = c.fy = f;
  c.cx = cx;
  c.cy = cy;
  c.k1 = k1;
  c.k2 = k2;
  const double a = yaw * kPi / 180, b = pitch * kPi / 180;
  const Vec3 centre = distance * Vec3(std::sin(a) * std::cos(b), std::sin(b), std::cos(a) * std::cos(b));
  const Vec3 z = (-centre).normalized();
  Vec3 y = -(Vec3::UnitY() - Vec3::UnitY().dot(z) * z).normalized();  // image y runs down
  Vec3 x = y.cross(z);
  Mat3 R;
  R.row(0) = x;
  R.row(1) = y;
  R.row(2) = z;
  R = Eigen::AngleAxisd(roll * kPi / 180, Vec3::UnitZ()).toRotationMatrix() * R;
  c.R = R;
  c.t = -R * centre;
  return c;
}

inline std::vector<Correspondence> observe(const Camera& cam, const std::vector<Vec3>& pts,
                                    SplitMix64* noise = nullptr, double sigma = 0) {
  std::vector<Correspondence> cs;
  for (const auto& p : pts) {
    Correspondence c;
    c.point = p;
    REQUIRE(cam.project(p, c.pixel));
    if (noise) c.pixel += sigma * Vec2(noise->gaussian(), noise->gaussian());
    cs.push_back(c);
  }
  return cs;
}

inline double rotation_error_deg(const Mat3& a, const Mat3& b) {
  return Eigen::AngleAxisd(a.transpose() * b).angle() * 180 / kPi;
}

inline Camera random_camera(SplitMix64& rng, bool distortion) {
  return look_at_head(rng.uniform(-60, 60), rng.uniform(-20, 20), rng.uniform(-5, 5),
                      rng.uniform(0.6, 1.0), rng.uniform(2500, 4000), 900 + rng.uniform(-40, 40),
                      600 + rng.uniform(-40, 40), distortion ? rng.uniform(-0.15, 0.05) : 0,
                      distortion ? rng.uniform(-0.2, 0.2) : 0);
}


}  // namespace calib_test
}  // namespace lk
