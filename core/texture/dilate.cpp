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
  // power-of-two block grid (lines along the texture's middle). Level 0 is
  // the image itself, its weights the known flags.
  struct Level {
    int w, h;
    std::vector<float> color;   // w * h * c, weighted mean
    std::vector<float> weight;  // w * h, coverage in [0, 1]
  };
  std::vector<Level> levels;  // levels[k] is pyramid level k + 1
  auto fine_color = [&](int k) -> const float* { return k == 0 ? image.pixels.data() : levels[k - 1].color.data(); };
  auto fine_weight = [&](int k, size_t i) -> float {
    return k == 0 ? (known[i] ? 1.f : 0.f) : levels[k - 1].weight[i];
  };
  int fw = w0, fh = h0;
  for (int k = 0; fw > 1 || fh > 1; ++k) {
    Level g{(fw + 1) / 2, (fh + 1) / 2, {}, {}};
    g.color.assign(static_cast<size_t>(g.w) * g.h * c, 0.f);
    g.weight.assign(static_cast<size_t>(g.w) * g.h, 0.f);
    const float* fc = fine_color(k);
    for (int y = 0; y < g.h; ++y) {
      for (int x = 0; x < g.w; ++x) {
        float sum[8] = {0, 0, 0, 0, 0, 0, 0, 0};
        float wsum = 0;
        int children = 0;
        for (int dy = 0; dy < 2; ++dy) {
          for (int dx = 0; dx < 2; ++dx) {
            const int xx = 2 * x + dx, yy = 2 * y + dy;
            if (xx >= fw || yy >= fh) continue;
            ++children;
            const size_t i = static_cast<size_t>(yy) * fw + xx;
            const float wi = fine_weight(k, i);
            if (wi <= 0.f) continue;
            for (int ch = 0; ch < c; ++ch) sum[ch] += wi * fc[i * c + ch];
            wsum += wi;
          }
        }
        if (wsum <= 0.f) continue;
        const size_t o = static_cast<size_t>(y) * g.w + x;
        g.weight[o] = wsum / children;
        for (int ch = 0; ch < c; ++ch) g.color[o * c + ch] = sum[ch] / wsum;
      }
    }
    fw = g.w;
    fh = g.h;
    levels.push_back(std::move(g));
  }
  // Pull: from the coarsest level (1x1, coverage > 0) down, every texel
  // becomes w * own + (1 - w) * (bilinear interpolation of the completed
  // coarser level at its centre); known texels of level 0 (w = 1) stay.
  long filled = 0;
  for (int k = static_cast<int>(levels.size()) - 1; k >= 0; --k) {
    const Level& g = levels[k];
    const int w = k == 0 ? w0 : levels[k - 1].w, h = k == 0 ? h0 : levels[k - 1].h;
    float* fc = k == 0 ? image.pixels.data() : levels[k - 1].color.data();
    for (int y = 0; y < h; ++y) {
      const double gy = std::clamp((y + 0.5) / 2.0 - 0.5, 0.0, static_cast<double>(g.h - 1));
      const int y0 = static_cast<int>(gy), y1 = std::min(y0 + 1, g.h - 1);
      const float ty = static_cast<float>(gy - y0);
      for (int x = 0; x < w; ++x) {
        const size_t i = static_cast<size_t>(y) * w + x;
        const float wi = fine_weight(k, i);
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
          fc[i * c + ch] = wi * fc[i * c + ch] + (1 - wi) * up;
        }
        if (k == 0) ++filled;
      }
    }
  }
  return filled;
}

}  // namespace lk
