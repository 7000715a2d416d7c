#include "photos/landmark_slide.h"

#include <algorithm>
#include <cmath>

namespace lk {

SlideView slide_view(const LandmarkSlide& slide, const Vec3& C) {
  SlideView v;
  if (!(slide.yaw_range > 0) || !(slide.pitch_range > 0)) return v;
  const double h2 = C.x() * C.x() + C.z() * C.z(), h = std::sqrt(h2), r2 = h2 + C.y() * C.y();
  if (!(h > 0)) return v;
  const double yaw = std::atan2(C.x(), C.z()), pitch = std::atan2(C.y(), h);
  v.a = yaw / slide.yaw_range;
  v.b = pitch / slide.pitch_range;
  if (std::abs(v.a) < 1) v.d_center.row(0) << C.z() / h2 / slide.yaw_range, 0, -C.x() / h2 / slide.yaw_range;
  else v.a = v.a > 0 ? 1 : -1;
  if (std::abs(v.b) < 1)
    v.d_center.row(1) << -C.y() * C.x() / (h * r2) / slide.pitch_range, h / r2 / slide.pitch_range,
        -C.y() * C.z() / (h * r2) / slide.pitch_range;
  else v.b = v.b > 0 ? 1 : -1;
  return v;
}

namespace {
double ipow(double x, int n) {
  double r = 1;
  for (int k = 0; k < n; ++k) r *= x;
  return r;
}
}  // namespace

Vec3 landmark_shift(const LandmarkSlide& slide, int m, const SlideView& view, Mat3* d_center) {
  if (d_center) d_center->setZero();
  if (m < 0 || size_t(m) >= slide.shifts.size() || slide.shifts[size_t(m)].size() != slide.terms.size())
    return Vec3::Zero();
  Vec3 s = Vec3::Zero(), da = Vec3::Zero(), db = Vec3::Zero();
  for (size_t k = 0; k < slide.terms.size(); ++k) {
    const int i = slide.terms[k][0], j = slide.terms[k][1];
    const Vec3& D = slide.shifts[size_t(m)][k];
    s += ipow(view.a, i) * ipow(view.b, j) * D;
    if (i > 0) da += i * ipow(view.a, i - 1) * ipow(view.b, j) * D;
    if (j > 0) db += j * ipow(view.a, i) * ipow(view.b, j - 1) * D;
  }
  if (d_center) *d_center = da * view.d_center.row(0) + db * view.d_center.row(1);
  return s;
}

double landmark_sigma(const LandmarkSlide& slide, int m, const Vec3& C) {
  if (!slide.has_sigma() || m < 0 || size_t(m) >= slide.sigma.size()) return 0;
  const std::vector<double>& s = slide.sigma[size_t(m)];
  const std::vector<double>& y = slide.sigma_yaw;
  if (s.size() != y.size() || s.empty()) return 0;
  const double yaw = std::atan2(C.x(), C.z());
  if (yaw <= y.front()) return s.front();
  if (yaw >= y.back()) return s.back();
  const size_t k = size_t(std::upper_bound(y.begin(), y.end(), yaw) - y.begin());
  const double t = (yaw - y[k - 1]) / (y[k] - y[k - 1]);
  return (1 - t) * s[k - 1] + t * s[k];
}

}  // namespace lk
