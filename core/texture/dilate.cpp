#include "texture/dilate.h"

#include <algorithm>
#include <cmath>

namespace lk {

long dilate_rings(ImageF& image, std::vector<char>& known, int texels) {
  const int w = image.width, h = image.height, c = image.channels;
  if (w <= 0 || h <= 0 || known.size() != static_cast<size_t>(w) * h) return 0;
  long filled = 0;
  std::vector<int> ring;  // texels filled in this ring, applied after the ring
  std::vector<float> colors;
  for (int pass = 0; pass < texels; ++pass) {
    ring.clear();
    colors.clear();
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        const size_t i = static_cast<size_t>(y) * w + x;
        if (known[i]) continue;
        float sum[8] = {0, 0, 0, 0, 0, 0, 0, 0};
        int n = 0;
        for (int dy = -1; dy <= 1; ++dy) {
          const int yy = y + dy;
          if (yy < 0 || yy >= h) continue;
          for (int dx = -1; dx <= 1; ++dx) {
            const int xx = x + dx;
            if (xx < 0 || xx >= w || !known[static_cast<size_t>(yy) * w + xx]) continue;
            const float* p = image.at(xx, yy);
            for (int k = 0; k < c && k < 8; ++k) sum[k] += p[k];
            ++n;
          }
        }
        if (n == 0) continue;
        ring.push_back(static_cast<int>(i));
        for (int k = 0; k < c; ++k) colors.push_back(k < 8 ? sum[k] / n : 0.f);
      }
    }
    if (ring.empty()) break;
    for (size_t r = 0; r < ring.size(); ++r) {
      known[ring[r]] = 1;
      std::copy(colors.begin() + r * c, colors.begin() + (r + 1) * c,
                image.pixels.begin() + static_cast<size_t>(ring[r]) * c);
    }
    filled += static_cast<long>(ring.size());
  }
  return filled;
}

long push_pull_fill(ImageF& image, const std::vector<char>& known) {
  const int w0 = image.width, h0 = image.height, c = image.channels;
  if (w0 <= 0 || h0 <= 0 || c <= 0 || known.size() != static_cast<size_t>(w0) * h0) return 0;
  // Push: level k+1 averages the known texels of each 2x2 block of level k.
  // Colours are stored normalized, weight 1 where anything was known.
  struct Level {
    int w, h;
    std::vector<float> color;   // w * h * c
    std::vector<char> has;      // w * h
  };
  std::vector<Level> levels;
  levels.push_back({w0, h0, {}, known});
  levels[0].color = image.pixels;
  bool any = std::any_of(known.begin(), known.end(), [](char k) { return k != 0; });
  if (!any) return 0;
  while (levels.back().w > 1 || levels.back().h > 1) {
    const Level& f = levels.back();
    Level g{(f.w + 1) / 2, (f.h + 1) / 2, {}, {}};
    g.color.assign(static_cast<size_t>(g.w) * g.h * c, 0.f);
    g.has.assign(static_cast<size_t>(g.w) * g.h, 0);
    for (int y = 0; y < g.h; ++y) {
      for (int x = 0; x < g.w; ++x) {
        float sum[8] = {0, 0, 0, 0, 0, 0, 0, 0};
        int n = 0;
        for (int dy = 0; dy < 2; ++dy) {
          for (int dx = 0; dx < 2; ++dx) {
            const int xx = 2 * x + dx, yy = 2 * y + dy;
            if (xx >= f.w || yy >= f.h) continue;
            const size_t i = static_cast<size_t>(yy) * f.w + xx;
            if (!f.has[i]) continue;
            for (int k = 0; k < c && k < 8; ++k) sum[k] += f.color[i * c + k];
            ++n;
          }
        }
        if (n == 0) continue;
        const size_t o = static_cast<size_t>(y) * g.w + x;
        g.has[o] = 1;
        for (int k = 0; k < c && k < 8; ++k) g.color[o * c + k] = sum[k] / n;
      }
    }
    levels.push_back(std::move(g));
  }
  // Pull: from the coarsest level (1x1, known since something is known)
  // down, each unknown texel takes the bilinear interpolation of the (now
  // complete) coarser level at its centre, so the fill is smooth.
  long filled = 0;
  for (int k = static_cast<int>(levels.size()) - 2; k >= 0; --k) {
    Level& f = levels[k];
    const Level& g = levels[k + 1];
    for (int y = 0; y < f.h; ++y) {
      const double gy = std::clamp((y + 0.5) / 2.0 - 0.5, 0.0, static_cast<double>(g.h - 1));
      const int y0 = static_cast<int>(gy), y1 = std::min(y0 + 1, g.h - 1);
      const float ty = static_cast<float>(gy - y0);
      for (int x = 0; x < f.w; ++x) {
        const size_t i = static_cast<size_t>(y) * f.w + x;
        if (f.has[i]) continue;
        const double gx = std::clamp((x + 0.5) / 2.0 - 0.5, 0.0, static_cast<double>(g.w - 1));
        const int x0 = static_cast<int>(gx), x1 = std::min(x0 + 1, g.w - 1);
        const float tx = static_cast<float>(gx - x0);
        const float* a = &g.color[(static_cast<size_t>(y0) * g.w + x0) * c];
        const float* b = &g.color[(static_cast<size_t>(y0) * g.w + x1) * c];
        const float* d = &g.color[(static_cast<size_t>(y1) * g.w + x0) * c];
        const float* e = &g.color[(static_cast<size_t>(y1) * g.w + x1) * c];
        for (int ch = 0; ch < c; ++ch)
          f.color[i * c + ch] = (1 - ty) * ((1 - tx) * a[ch] + tx * b[ch]) + ty * ((1 - tx) * d[ch] + tx * e[ch]);
        if (k == 0) ++filled;
      }
    }
  }
  image.pixels = std::move(levels[0].color);
  return filled;
}

}  // namespace lk
