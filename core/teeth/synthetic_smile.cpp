// Synthetic smile with known hidden tooth parts (see synthetic_smile.h).
#include "teeth/synthetic_smile.h"

#include <algorithm>
#include <cmath>

namespace lk {

SyntheticSmile make_synthetic_smile(const SyntheticSmileOptions& o) {
  constexpr double kPi = 3.14159265358979323846;
  const int w = std::max(32, o.width), h = std::max(16, o.height);
  // Layout units: a 320 x 160 smile, scaled to w x h.
  const double sx = w / 320.0, sy = h / 160.0;
  const int bite = static_cast<int>(std::lround(80 * sy));
  SyntheticSmile s;
  s.bite_row = bite;
  s.image = Image::make(w, h, 3);
  s.tooth.assign(static_cast<size_t>(w) * h, 0);
  s.lip.assign(static_cast<size_t>(w) * h, 0);
  std::vector<std::uint8_t> painted(static_cast<size_t>(w) * h, 0);
  // Premolar, canine, lateral, central, central, lateral, canine, premolar;
  // heights follow real crowns (upper central 10.5 mm, lateral 9, canine 10,
  // premolar 8; lower central 9, lateral 9.5, canine 11, premolar 8).
  const double widths[8] = {30, 34, 32, 40, 40, 32, 34, 30};
  const double upper_h[8] = {40, 50, 44, 52, 52, 44, 50, 40};
  const double lower_h[8] = {36, 42, 38, 36, 36, 38, 42, 36};
  double left = 24;
  for (int t = 0; t < 8; ++t) {
    const int xa = static_cast<int>(std::lround(left * sx)), xb = static_cast<int>(std::lround((left + widths[t]) * sx));
    for (int x = xa; x < xb && x < w; ++x) {
      const double u = (x - xa + 0.5) / (xb - xa) * 2 - 1;  // -1..1 across the tooth
      const bool gap = x - xa < std::max(1, static_cast<int>(std::lround(3 * sx)));
      for (int arch = 0; arch < 2; ++arch) {
        const double height = (arch == 0 ? upper_h[t] : lower_h[t]) * sy;
        const double top = height - 0.12 * (xb - xa) * sy / sx * u * u;  // arched crown
        const int gap_rows = static_cast<int>(std::lround(2 * sy));
        for (int i = 0; i < top; ++i) {
          const int y = arch == 0 ? bite - gap_rows - i : bite + gap_rows + i;
          if (y < 0 || y >= h) continue;
          std::uint8_t* p = s.image.at(x, y);
          painted[static_cast<size_t>(y) * w + x] = 1;
          if (gap) { p[0] = p[1] = p[2] = 12; continue; }
          const double g = i / top;  // 0 at the bite, 1 at the gum
          const double shade = 0.88 + 0.12 * std::cos(0.5 * kPi * u);
          const double base[3] = {0.93, 0.90, 0.82}, cervical[3] = {0.86, 0.76, 0.58};
          const double mix = std::max(0.0, g - 0.6) / 0.4;  // yellower in the last 40 %
          for (int k = 0; k < 3; ++k)
            p[k] = static_cast<std::uint8_t>(std::lround(255 * shade * ((1 - mix) * base[k] + mix * cervical[k])));
          s.tooth[static_cast<size_t>(y) * w + x] = 1;
        }
      }
    }
    left += widths[t];
  }
  const int arch_left = static_cast<int>(std::lround(24 * sx)), arch_right = static_cast<int>(std::lround(left * sx));
  // Gums everywhere else; the bite line dark between the arches.
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      if (painted[static_cast<size_t>(y) * w + x]) continue;
      std::uint8_t* p = s.image.at(x, y);
      const bool bite_line = std::abs(y - bite + 0.5) < 2 * sy && x >= arch_left && x < arch_right;
      const double c[3] = {0.80 + 0.03 * std::sin(0.4 * x / sx + 0.2 * y / sy), 0.30, 0.32};
      for (int k = 0; k < 3; ++k) p[k] = bite_line ? 10 : static_cast<std::uint8_t>(std::lround(255 * c[k]));
    }
  // Lips: the upper edge 8 rows above the tallest crown, dipping over
  // x = 70..170; the lower edge 8 rows below the longest lower crown, rising
  // over x = 170..260 (layout units).
  for (int x = 0; x < w; ++x) {
    const double lx = x / sx;
    const double bu = lx > 70 && lx < 170 ? 0.5 - 0.5 * std::cos(2 * kPi * (lx - 70) / 100.0) : 0;
    const double bl = lx > 170 && lx < 260 ? 0.5 - 0.5 * std::cos(2 * kPi * (lx - 170) / 90.0) : 0;
    const double upper_edge = bite + (-2 - 52 - 8 + o.upper_dip * bu) * sy;
    const double lower_edge = bite + (2 + 42 + 8 - o.lower_rise * bl) * sy;
    for (int y = 0; y < h; ++y)
      if (y < upper_edge || y > lower_edge) {
        std::uint8_t* p = s.image.at(x, y);
        p[0] = 176; p[1] = 66; p[2] = 72;  // lip red
        s.lip[static_cast<size_t>(y) * w + x] = 1;
      }
  }
  return s;
}

}  // namespace lk
