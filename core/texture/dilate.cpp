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

namespace {

// One push step: per 2x2 block of the finer level, the weighted mean colour
// and the mean weight (the block's coverage). WeightAt(i) gives the finer
// level's weights (flags on level 0, floats above), so level 0 needs no
// float copy of its known flags.
template <class WeightAt>
void push_level(const float* fc, WeightAt weight_at, int fw, int fh, int c, std::vector<float>& gc,
                std::vector<float>& gw, int gw_w, int gw_h) {
  gc.assign(static_cast<size_t>(gw_w) * gw_h * c, 0.f);
  gw.assign(static_cast<size_t>(gw_w) * gw_h, 0.f);
  for (int y = 0; y < gw_h; ++y) {
    const int y0 = 2 * y, ny = (y0 + 1 < fh) ? 2 : 1;
    for (int x = 0; x < gw_w; ++x) {
      const int x0 = 2 * x, nx = (x0 + 1 < fw) ? 2 : 1;
      float sum[8] = {0, 0, 0, 0, 0, 0, 0, 0};
      float wsum = 0;
      for (int dy = 0; dy < ny; ++dy) {
        const size_t row = static_cast<size_t>(y0 + dy) * fw;
        for (int dx = 0; dx < nx; ++dx) {
          const size_t i = row + x0 + dx;
          const float wi = weight_at(i);
          if (wi <= 0.f) continue;
          const float* p = fc + i * c;
          for (int ch = 0; ch < c; ++ch) sum[ch] += wi * p[ch];
          wsum += wi;
        }
      }
      if (wsum <= 0.f) continue;
      const size_t o = static_cast<size_t>(y) * gw_w + x;
      gw[o] = wsum / static_cast<float>(nx * ny);
      const float inv = 1.f / wsum;
      for (int ch = 0; ch < c; ++ch) gc[o * c + ch] = sum[ch] * inv;
    }
  }
}

// Bilinear lookup positions of fine samples 0..n-1 in a coarse axis of m
// samples: centre (i + 0.5) / 2 - 0.5, clamped.
void pull_axis(int n, int m, std::vector<int>& lo, std::vector<int>& hi, std::vector<float>& t) {
  lo.resize(n);
  hi.resize(n);
  t.resize(n);
  for (int i = 0; i < n; ++i) {
    const double g = std::clamp((i + 0.5) / 2.0 - 0.5, 0.0, static_cast<double>(m - 1));
    lo[i] = static_cast<int>(g);
    hi[i] = std::min(lo[i] + 1, m - 1);
    t[i] = static_cast<float>(g - lo[i]);
  }
}

// One pull step: every finer texel with weight w < 1 becomes
// w * own + (1 - w) * bilinear(coarser).
template <class WeightAt>
long pull_level(float* fc, WeightAt weight_at, int fw, int fh, int c, const std::vector<float>& gc, int gw_w,
                int gw_h) {
  std::vector<int> xl, xh, yl, yh;
  std::vector<float> tx, ty;
  pull_axis(fw, gw_w, xl, xh, tx);
  pull_axis(fh, gw_h, yl, yh, ty);
  long changed = 0;
  for (int y = 0; y < fh; ++y) {
    const float* r0 = &gc[static_cast<size_t>(yl[y]) * gw_w * c];
    const float* r1 = &gc[static_cast<size_t>(yh[y]) * gw_w * c];
    const float vy = ty[y];
    for (int x = 0; x < fw; ++x) {
      const size_t i = static_cast<size_t>(y) * fw + x;
      const float wi = weight_at(i);
      if (wi >= 1.f) continue;
      const float* a = r0 + static_cast<size_t>(xl[x]) * c;
      const float* b = r0 + static_cast<size_t>(xh[x]) * c;
      const float* d = r1 + static_cast<size_t>(xl[x]) * c;
      const float* e = r1 + static_cast<size_t>(xh[x]) * c;
      const float vx = tx[x];
      float* o = fc + i * c;
      for (int ch = 0; ch < c; ++ch) {
        const float up = (1 - vy) * ((1 - vx) * a[ch] + vx * b[ch]) + vy * ((1 - vx) * d[ch] + vx * e[ch]);
        o[ch] = wi * o[ch] + (1 - wi) * up;
      }
      ++changed;
    }
  }
  return changed;
}

}  // namespace

long push_pull_fill(ImageF& image, const std::vector<char>& known) {
  const int w0 = image.width, h0 = image.height, c = image.channels;
  if (w0 <= 0 || h0 <= 0 || c <= 0 || c > 8 || known.size() != static_cast<size_t>(w0) * h0) return 0;
  if (std::none_of(known.begin(), known.end(), [](char k) { return k != 0; })) return 0;
  // Coverage fractions, not "any child known" flags: a coarse texel that is
  // only partly covered must not overrule the smooth fill around it, or the
  // fill shows the power-of-two block grid (lines along the texture's
  // middle). Level 0 is the image itself, its weights the known flags.
  struct Level {
    int w, h;
    std::vector<float> color;   // w * h * c, weighted mean
    std::vector<float> weight;  // w * h, coverage in [0, 1]
  };
  std::vector<Level> levels;  // levels[k] is pyramid level k + 1
  const auto known_weight = [&known](size_t i) { return known[i] ? 1.f : 0.f; };
  int fw = w0, fh = h0;
  while (fw > 1 || fh > 1) {
    Level g{(fw + 1) / 2, (fh + 1) / 2, {}, {}};
    if (levels.empty()) {
      push_level(image.pixels.data(), known_weight, fw, fh, c, g.color, g.weight, g.w, g.h);
    } else {
      const Level& f = levels.back();
      push_level(f.color.data(), [&f](size_t i) { return f.weight[i]; }, fw, fh, c, g.color, g.weight, g.w, g.h);
    }
    fw = g.w;
    fh = g.h;
    levels.push_back(std::move(g));
  }
  // Pull: from the coarsest level (1x1, coverage > 0) down.
  for (int k = static_cast<int>(levels.size()) - 1; k >= 1; --k) {
    Level& f = levels[k - 1];
    pull_level(f.color.data(), [&f](size_t i) { return f.weight[i]; }, f.w, f.h, c, levels[k].color, levels[k].w,
               levels[k].h);
  }
  return pull_level(image.pixels.data(), known_weight, w0, h0, c, levels[0].color, levels[0].w, levels[0].h);
}

}  // namespace lk
