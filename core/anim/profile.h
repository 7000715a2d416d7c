// A piecewise-linear function of x through points (the lip line's height,
// an eye's gap per column), clamped at its ends. Internal to core/anim.
#pragma once
#include <algorithm>
#include <utility>
#include <vector>

namespace lk {

struct Profile {
  std::vector<double> x, y;  // x ascending
  static Profile through(std::vector<std::pair<double, double>> points) {
    std::sort(points.begin(), points.end());
    Profile p;
    for (const auto& [px, py] : points) {
      p.x.push_back(px);
      p.y.push_back(py);
    }
    return p;
  }
  double operator()(double at) const {
    if (x.empty()) return 0;
    if (at <= x.front()) return y.front();
    if (at >= x.back()) return y.back();
    const std::size_t i = static_cast<std::size_t>(std::upper_bound(x.begin(), x.end(), at) - x.begin());
    const double t = (at - x[i - 1]) / std::max(1e-12, x[i] - x[i - 1]);
    return y[i - 1] + t * (y[i] - y[i - 1]);
  }
};

}  // namespace lk
