#include "head/head_shape.h"

#include <algorithm>
#include <cmath>

namespace lk {
namespace {

// The head's shape as a signed distance function (negative inside). Built
// from smoothly blended ellipsoids; mirror-symmetric because it only sees |x|.

double sd_ellipsoid(const Vec3& p, const Vec3& c, const Vec3& r) {
  const Vec3 q = p - c;
  const double k0 = (q.array() / r.array()).matrix().norm();
  const double k1 = (q.array() / (r.array() * r.array())).matrix().norm();
  if (k1 < 1e-12) return -r.minCoeff();
  return k0 * (k0 - 1.0) / k1;
}

double sd_sphere(const Vec3& p, const Vec3& c, double r) { return (p - c).norm() - r; }

// A capsule whose radius goes linearly from ra at a to rb at b.
double sd_tapered_capsule(const Vec3& p, const Vec3& a, const Vec3& b, double ra, double rb) {
  const Vec3 ab = b - a;
  const double t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  return (p - (a + t * ab)).norm() - (ra + t * (rb - ra));
}

// Polynomial smooth minimum: blends two shapes with a fillet of size k.
double smooth_min(double a, double b, double k) {
  const double h = std::max(k - std::abs(a - b), 0.0) / k;
  return std::min(a, b) - h * h * k * 0.25;
}
double smooth_max(double a, double b, double k) { return -smooth_min(-a, -b, k); }

}  // namespace

double HeadShape::distance(const Vec3& p0) const {
  const Vec3 p(std::abs(p0.x()), p0.y(), p0.z());
  double d = sd_ellipsoid(p, {0, 0.030, -0.014}, {0.074, 0.100, 0.097});        // cranium
  d = smooth_min(d, sd_ellipsoid(p, {0, 0.062, -0.030}, {0.071, 0.065, 0.080}), 0.03);   // parietal
  d = smooth_min(d, sd_ellipsoid(p, {0, 0.060, 0.030}, {0.055, 0.050, 0.058}), 0.02);    // forehead
  d = smooth_min(d, sd_ellipsoid(p, {0, -0.005, 0.035}, {0.058, 0.055, 0.063}), 0.02);   // midface
  d = smooth_min(d, sd_ellipsoid(p, {0, -0.058, 0.016}, {0.058, 0.047, 0.075}), 0.025);  // jaw
  d = smooth_min(d, sd_ellipsoid(p, {0.048, -0.068, -0.010}, {0.016, 0.022, 0.030}), 0.02);  // jaw angle
  d = smooth_min(d, sd_ellipsoid(p, {0, -0.088, 0.076}, {0.024, 0.016, 0.018}), 0.016);  // chin
  d = smooth_min(d, sd_ellipsoid(p, {0.048, 0.004, 0.052}, {0.024, 0.020, 0.030}), 0.03);  // cheekbone
  d = smooth_min(d, sd_ellipsoid(p, {0.040, -0.030, 0.045}, {0.024, 0.030, 0.032}), 0.03);  // cheek
  d = smooth_min(d, sd_ellipsoid(p, {0, 0.045, 0.077}, {0.050, 0.013, 0.018}), 0.028);  // brow ridge
  // Eye socket: hollow under the brow, then the lids over the eyeball.
  d = smooth_max(d, -sd_ellipsoid(p, {0.033, 0.023, 0.090}, {0.020, 0.013, 0.018}), 0.016);
  d = smooth_min(d, sd_sphere(p, eye_center, lid_radius), 0.004);
  // Nose: bridge, tip, wings (alae).
  double nose = sd_tapered_capsule(p, {0, 0.032, 0.090}, {0, -0.010, 0.114}, 0.0055, 0.0075);
  nose = smooth_min(nose, sd_sphere(p, {0, -0.012, 0.112}, 0.0090), 0.008);
  nose = smooth_min(nose, sd_ellipsoid(p, {0.0135, -0.019, 0.100}, {0.0085, 0.0075, 0.0095}), 0.006);
  d = smooth_min(d, nose, 0.007);
  // Lips: two volumes meeting in a crease (the lip line).
  const double upper = sd_ellipsoid(p, {0, slit_y + 0.0060, 0.091}, {0.024, 0.0070, 0.0100});
  const double lower = sd_ellipsoid(p, {0, slit_y - 0.0070, 0.088}, {0.021, 0.0080, 0.0100});
  d = smooth_min(d, std::min(upper, lower), 0.006);
  // Neck: an elliptic cylinder below the head.
  // Its axis leans forward going down, as a neck does.
  const double axis_z = -0.020 - 0.1 * (p.y() + 0.08);
  const double nx = p.x() / 0.058, nz = (p.z() - axis_z) / 0.060;
  const double neck = smooth_max((std::sqrt(nx * nx + nz * nz) - 1.0) * 0.058, p.y() + 0.035, 0.03);
  d = smooth_min(d, neck, 0.03);
  return d;
}

Vec3 HeadShape::gradient(const Vec3& p) const {
  const double h = 1e-5;
  Vec3 g;
  for (int k = 0; k < 3; ++k) {
    Vec3 a = p, b = p;
    a[k] += h;
    b[k] -= h;
    g[k] = (distance(a) - distance(b)) / (2 * h);
  }
  return g;
}

Vec3 HeadShape::cast(const Vec3& origin, const Vec3& dir) const {
  const Vec3 d = dir.normalized();
  const double step = 0.0004, far = 0.3;
  for (double t = far; t > 0; t -= step) {
    if (distance(origin + t * d) < 0) {
      double lo = t, hi = t + step;  // lo inside, hi outside
      for (int k = 0; k < 40; ++k) {
        const double mid = 0.5 * (lo + hi);
        (distance(origin + mid * d) > 0 ? hi : lo) = mid;
      }
      return origin + 0.5 * (lo + hi) * d;
    }
  }
  return origin;
}

Vec3 HeadShape::project(Vec3 p) const {
  for (int k = 0; k < 30; ++k) {
    const Vec3 g = gradient(p);
    const double g2 = g.squaredNorm();
    if (g2 < 1e-12) break;
    p -= distance(p) * g / g2;
  }
  return p;
}

}  // namespace lk
