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
  if (w0 <= 0 || h0 <= 0 || c <= 0 || c > 8 || known.size() != static_cast<size_t>(w0) * h0) return 0;
  if (std::none_of(known.begin(), known.end(), [](char k) { return k != 0; })) return 0;
  // Push: level k+1 holds, per 2x2 block of level k, the weighted mean
  // colour and the mean weight (the block's coverage). Coverage fractions,
  // not "any child known" flags: a coarse texel that is only partly covered
  // must not overrule the smooth fill around it, or the fill shows the
  // power-of-two block grid (lines along the texture's middle).
  struct Level {
    int w, h;
    std::vector<float> color;   // w * h * c, weighted mean
    std::vector<float> weight;  // w * h, coverage in [0, 1]
  };
  std::vector<Level> levels;
  {
    Level l0{w0, h0, image.pixels, std::vector<float>(known.size())};
    for (size_t i = 0; i < known.size(); ++i) l0.weight[i] = known[i] ? 1.f : 0.f;
    levels.push_back(std::move(l0));
  }
  while (levels.back().w > 1 || levels.back().h > 1) {
    const Level& f = levels.back();
    Level g{(f.w + 1) / 2, (f.h + 1) / 2, {}, {}};
    g.color.assign(static_cast<size_t>(g.w) * g.h * c, 0.f);
    g.weight.assign(static_cast<size_t>(g.w) * g.h, 0.f);
    for (int y = 0; y < g.h; ++y) {
      for (int x = 0; x < g.w; ++x) {
        float sum[8] = {0, 0, 0, 0, 0, 0, 0, 0};
        float wsum = 0;
        int children = 0;
        for (int dy = 0; dy < 2; ++dy) {
          for (int dx = 0; dx < 2; ++dx) {
            const int xx = 2 * x + dx, yy = 2 * y + dy;
            if (xx >= f.w || yy >= f.h) continue;
            ++children;
            const size_t i = static_cast<size_t>(yy) * f.w + xx;
            const float wi = f.weight[i];
            if (wi <= 0.f) continue;
            for (int k = 0; k < c; ++k) sum[k] += wi * f.color[i * c + k];
            wsum += wi;
          }
        }
        const size_t o = static_cast<size_t>(y) * g.w + x;
        if (wsum <= 0.f) continue;
        g.weight[o] = wsum / children;
        for (int k = 0; k < c; ++k) g.color[o * c + k] = sum[k] / wsum;
      }
    }
    levels.push_back(std::move(g));
  }
  // Pull: from the coarsest level (1x1, coverage > 0) down, every texel
  // becomes w * own + (1 - w) * (bilinear interpolation of the completed
  // coarser level at its centre); known texels of level 0 (w = 1) stay.
  for (int k = static_cast<int>(levels.size()) - 2; k >= 0; --k) {
    Level& f = levels[k];
    const Level& g = levels[k + 1];
    for (int y = 0; y < f.h; ++y) {
      const double gy = std::clamp((y + 0.5) / 2.0 - 0.5, 0.0, static_cast<double>(g.h - 1));
      const int y0 = static_cast<int>(gy), y1 = std::min(y0 + 1, g.h - 1);
      const float ty = static_cast<float>(gy - y0);
      for (int x = 0; x < f.w; ++x) {
        const size_t i = static_cast<size_t>(y) * f.w + x;
        const float wi = f.weight[i];
        if (wi >= 1.f) continue;
        const double gx = std::clamp((x + 0.5) / 2.0 - 0.5, 0.0, static_cast<double>(g.w - 1));
        const int x0 = static_cast<int>(gx), x1 = std::min(x0 + 1, g.w - 1);
        const float tx = static_cast<float>(gx - x0);
        const float* a = &g.color[(static_cast<size_t>(y0) * g.w + x0) * c];
        const float* b = &g.color[(static_cast<size_t>(y0) * g.w + x1) * c];
        const float* d = &g.color[(static_cast<size_t>(y1) * g.w + x0) * c];
        const float* e = &g.color[(static_cast<size_t>(y1) * g.w + x1) * c];
        for (int ch = 0; ch < c; ++ch) {
          const float up = (1 - ty) * ((1 - tx) * a[ch] + tx * b[ch]) + ty * ((1 - tx) * d[ch] + tx * e[ch]);
          f.color[i * c + ch] = wi * f.color[i * c + ch] + (1 - wi) * up;
        }
      }
    }
  }
  long filled = 0;
  for (char k : known) filled += k == 0;
  image.pixels = std::move(levels[0].color);
  return filled;
}

}  // namespace lk
