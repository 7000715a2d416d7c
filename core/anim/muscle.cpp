#include "anim/muscle.h"

#include <algorithm>
#include <cmath>

namespace lk {

namespace {
constexpr double kHalfPi = 1.57079632679489661923;
}

double smoothstep01(double t) {
  t = std::clamp(t, 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}

SparseField linear_muscle_field(const LinearMuscle& m, const std::vector<Vec3>& positions,
                                const std::function<double(int)>& mask) {
  SparseField out;
  const Vec3 axis = m.insertion - m.attachment;
  const double length = axis.norm();
  if (!(length > 1e-9)) return out;
  const Vec3 dir = axis / length;
  const double cos_cone = std::cos(m.cone);
  for (std::size_t v = 0; v < positions.size(); ++v) {
    const Vec3 d = positions[v] - m.attachment;
    const double dist = d.norm();
    if (!(dist > 1e-9) || dist >= length + m.reach) continue;
    const double c = d.dot(dir) / dist;
    if (c <= cos_cone) continue;
    // Waters' angular falloff: 1 on the axis, 0 at the cone's edge.
    const double angular = (c - cos_cone) / (1.0 - cos_cone);
    // Radial: rises from the attachment to the insertion, falls beyond it.
    const double radial = dist <= length ? std::sin(kHalfPi * dist / length)
                                         : std::cos(kHalfPi * (dist - length) / m.reach);
    const double w = mask(static_cast<int>(v)) * angular * radial;
    if (w <= 0) continue;
    out.index.push_back(static_cast<int>(v));
    out.delta.push_back(-w * m.pull * length * (d / dist));
  }
  return out;
}

SparseField sphincter_field(const Sphincter& s, const std::vector<Vec3>& positions,
                            const std::function<double(int)>& mask) {
  SparseField out;
  for (std::size_t v = 0; v < positions.size(); ++v) {
    const Vec3 d = positions[v] - s.center;
    if (d.z() < -s.depth) continue;
    const double rho = std::sqrt((d.x() / s.a) * (d.x() / s.a) + (d.y() / s.b) * (d.y() / s.b));
    if (rho >= 1.0) continue;
    const double w = mask(static_cast<int>(v)) * std::cos(kHalfPi * rho);
    if (w <= 0) continue;
    out.index.push_back(static_cast<int>(v));
    out.delta.push_back(w * Vec3(-s.squeeze * d.x(), 0.0, s.protrude));
  }
  return out;
}

}  // namespace lk
