#include "texture/pyramid.h"

#include <algorithm>
#include <string>

namespace lk {
namespace {

// Burt & Adelson's generating kernel with a = 0.4.
constexpr float kW0 = 0.4f, kW1 = 0.25f, kW2 = 0.05f;

// Reflection without repeating the edge sample: -1 -> 1, n -> n - 2.
inline int reflect(int i, int n) {
  if (n == 1) return 0;
  while (i < 0 || i >= n) {
    if (i < 0) i = -i;
    if (i >= n) i = 2 * (n - 1) - i;
  }
  return i;
}

// Resizes without giving memory back, so scratch images are reused.
void reshape(ImageF& im, int w, int h, int c) {
  im.width = w;
  im.height = h;
  im.channels = c;
  im.pixels.resize(static_cast<size_t>(w) * h * c);
}

// Horizontal pass of REDUCE: (w, h) -> ((w+1)/2, h). Interior samples
// index directly; only the two outermost on each side reflect.
void reduce_rows(const ImageF& in, ImageF& out) {
  const int w = in.width, h = in.height, c = in.channels, w2 = (w + 1) / 2;
  reshape(out, w2, h, c);
  for (int y = 0; y < h; ++y) {
    const float* row = in.at(0, y);
    float* dst = out.at(0, y);
    for (int x2 = 0; x2 < w2; ++x2) {
      const int x = 2 * x2;
      float* o = dst + static_cast<size_t>(x2) * c;
      if (x >= 2 && x + 2 < w) {
        const float* m = row + static_cast<size_t>(x) * c;
        for (int k = 0; k < c; ++k)
          o[k] = kW2 * (m[k - 2 * c] + m[k + 2 * c]) + kW1 * (m[k - c] + m[k + c]) + kW0 * m[k];
        continue;
      }
      const float* a = row + static_cast<size_t>(reflect(x - 2, w)) * c;
      const float* b = row + static_cast<size_t>(reflect(x - 1, w)) * c;
      const float* m = row + static_cast<size_t>(x) * c;
      const float* d = row + static_cast<size_t>(reflect(x + 1, w)) * c;
      const float* e = row + static_cast<size_t>(reflect(x + 2, w)) * c;
      for (int k = 0; k < c; ++k) o[k] = kW2 * (a[k] + e[k]) + kW1 * (b[k] + d[k]) + kW0 * m[k];
    }
  }
}

// Vertical pass of REDUCE: (w, h) -> (w, (h+1)/2), whole rows at a time.
void reduce_cols(const ImageF& in, ImageF& out) {
  const int w = in.width, h = in.height, c = in.channels, h2 = (h + 1) / 2;
  const size_t n = static_cast<size_t>(w) * c;
  reshape(out, w, h2, c);
  for (int y2 = 0; y2 < h2; ++y2) {
    const int y = 2 * y2;
    const float* a = in.at(0, reflect(y - 2, h));
    const float* b = in.at(0, reflect(y - 1, h));
    const float* m = in.at(0, y);
    const float* d = in.at(0, reflect(y + 1, h));
    const float* e = in.at(0, reflect(y + 2, h));
    float* dst = out.at(0, y2);
    for (size_t i = 0; i < n; ++i) dst[i] = kW2 * (a[i] + e[i]) + kW1 * (b[i] + d[i]) + kW0 * m[i];
  }
}

// EXPAND in 1-D, from the kernel with the factor 2 folded in:
// even fine samples 2j: 0.1 c[j-1] + 0.8 c[j] + 0.1 c[j+1];
// odd fine samples 2j+1: 0.5 c[j] + 0.5 c[j+1]. Coarse borders reflect.
constexpr float kEvenSide = 2 * kW2, kEvenMid = 2 * kW0, kOdd = 2 * kW1;

void expand_rows(const ImageF& in, int w, ImageF& out) {
  const int wc = in.width, h = in.height, c = in.channels;
  reshape(out, w, h, c);
  for (int y = 0; y < h; ++y) {
    const float* row = in.at(0, y);
    float* dst = out.at(0, y);
    for (int j = 0; 2 * j < w; ++j) {
      // Fine samples 2j and 2j+1 from coarse j-1, j, j+1.
      const float* m = row + static_cast<size_t>(reflect(j, wc)) * c;
      const float* l = (j >= 1 && j < wc) ? m - c : row + static_cast<size_t>(reflect(j - 1, wc)) * c;
      const float* r = (j + 1 < wc) ? m + c : row + static_cast<size_t>(reflect(j + 1, wc)) * c;
      float* even = dst + static_cast<size_t>(2 * j) * c;
      for (int k = 0; k < c; ++k) even[k] = kEvenSide * (l[k] + r[k]) + kEvenMid * m[k];
      if (2 * j + 1 < w) {
        float* odd = even + c;
        for (int k = 0; k < c; ++k) odd[k] = kOdd * (m[k] + r[k]);
      }
    }
  }
}

void expand_cols(const ImageF& in, int h, ImageF& out) {
  const int w = in.width, hc = in.height, c = in.channels;
  const size_t n = static_cast<size_t>(w) * c;
  reshape(out, w, h, c);
  for (int y = 0; y < h; ++y) {
    const int j = y / 2;
    float* dst = out.at(0, y);
    if ((y & 1) == 0) {
      const float* l = in.at(0, reflect(j - 1, hc));
      const float* m = in.at(0, reflect(j, hc));
      const float* r = in.at(0, reflect(j + 1, hc));
      for (size_t i = 0; i < n; ++i) dst[i] = kEvenSide * (l[i] + r[i]) + kEvenMid * m[i];
    } else {
      const float* m = in.at(0, reflect(j, hc));
      const float* r = in.at(0, reflect(j + 1, hc));
      for (size_t i = 0; i < n; ++i) dst[i] = kOdd * (m[i] + r[i]);
    }
  }
}

// Scratch for the separable passes; one per thread of use (static storage
// would make concurrent calls race, and the core has no globals).
struct Scratch {
  ImageF half;
};

void reduce_with(const ImageF& in, ImageF& out, Scratch& s) {
  reduce_rows(in, s.half);
  reduce_cols(s.half, out);
}

void expand_with(const ImageF& coarse, int w, int h, ImageF& out, Scratch& s) {
  expand_rows(coarse, w, s.half);
  expand_cols(s.half, h, out);
}

// Laplacian pyramid into `pyr`, reusing its images' memory; `next` is scratch.
void build_laplacian(const ImageF& image, int levels, std::vector<ImageF>& pyr, ImageF& expanded,
                     Scratch& s) {
  pyr.resize(static_cast<size_t>(levels));
  reshape(pyr[0], image.width, image.height, image.channels);
  std::copy(image.pixels.begin(), image.pixels.end(), pyr[0].pixels.begin());
  // Gaussian levels first (each from the previous), then subtract expansions
  // from the finest down, so each G_{k+1} is still intact when L_k needs it.
  for (int k = 0; k + 1 < levels; ++k) reduce_with(pyr[k], pyr[k + 1], s);
  for (int k = 0; k + 1 < levels; ++k) {
    expand_with(pyr[k + 1], pyr[k].width, pyr[k].height, expanded, s);
    float* g = pyr[k].pixels.data();
    const float* e = expanded.pixels.data();
    const size_t n = pyr[k].pixels.size();
    for (size_t i = 0; i < n; ++i) g[i] -= e[i];
  }
}

}  // namespace

void pyramid_reduce(const ImageF& in, ImageF& out) {
  Scratch s;
  reduce_with(in, out, s);
}

void pyramid_expand(const ImageF& coarse, int width, int height, ImageF& out) {
  Scratch s;
  expand_with(coarse, width, height, out, s);
}

int max_pyramid_levels(int width, int height) {
  int levels = 1;
  int w = width, h = height;
  while (std::min(w, h) > 8) {
    w = (w + 1) / 2;
    h = (h + 1) / 2;
    ++levels;
  }
  return levels;
}

void gaussian_pyramid(const ImageF& image, int levels, std::vector<ImageF>& pyramid) {
  levels = std::max(1, levels);
  Scratch s;
  pyramid.resize(static_cast<size_t>(levels));
  pyramid[0] = image;
  for (int k = 0; k + 1 < levels; ++k) reduce_with(pyramid[k], pyramid[k + 1], s);
}

void laplacian_pyramid(const ImageF& image, int levels, std::vector<ImageF>& pyramid) {
  Scratch s;
  ImageF expanded;
  build_laplacian(image, std::max(1, levels), pyramid, expanded, s);
}

void collapse_laplacian(const std::vector<ImageF>& pyramid, ImageF& image) {
  if (pyramid.empty()) {
    image = ImageF();
    return;
  }
  Scratch s;
  ImageF current = pyramid.back(), expanded;
  for (int k = static_cast<int>(pyramid.size()) - 2; k >= 0; --k) {
    expand_with(current, pyramid[k].width, pyramid[k].height, expanded, s);
    const float* l = pyramid[k].pixels.data();
    float* e = expanded.pixels.data();
    const size_t n = pyramid[k].pixels.size();
    for (size_t i = 0; i < n; ++i) e[i] += l[i];
    std::swap(current, expanded);
  }
  image = std::move(current);
}

Status SplineBlender::begin(int width, int height, int channels, int levels) {
  if (width < 1 || height < 1 || channels < 1)
    return Status::error(ErrorCode::InvalidInput, "spline: empty image size");
  width_ = width;
  height_ = height;
  channels_ = channels;
  const int most = max_pyramid_levels(width, height);
  levels_ = (levels <= 0 || levels > most) ? most : levels;
  sum_.resize(static_cast<size_t>(levels_));
  int w = width, h = height;
  for (int k = 0; k < levels_; ++k) {
    reshape(sum_[k], w, h, channels);
    std::fill(sum_[k].pixels.begin(), sum_[k].pixels.end(), 0.f);
    w = (w + 1) / 2;
    h = (h + 1) / 2;
  }
  return Status::success();
}

Status SplineBlender::add(const ImageF& image, const ImageF& mask) {
  if (levels_ == 0) return Status::error(ErrorCode::InvalidInput, "spline: add() before begin()");
  if (image.width != width_ || image.height != height_ || image.channels != channels_ ||
      image.pixels.size() != static_cast<size_t>(width_) * height_ * channels_)
    return Status::error(ErrorCode::InvalidInput, "spline: image size differs from begin()");
  if (mask.width != width_ || mask.height != height_ || mask.channels != 1 ||
      mask.pixels.size() != static_cast<size_t>(width_) * height_)
    return Status::error(ErrorCode::InvalidInput, "spline: mask must be one channel of the image's size");
  Scratch s{std::move(half_)};
  build_laplacian(image, levels_, image_pyr_, expanded_, s);
  mask_pyr_.resize(static_cast<size_t>(levels_));
  reshape(mask_pyr_[0], width_, height_, 1);
  std::copy(mask.pixels.begin(), mask.pixels.end(), mask_pyr_[0].pixels.begin());
  for (int k = 0; k + 1 < levels_; ++k) reduce_with(mask_pyr_[k], mask_pyr_[k + 1], s);
  half_ = std::move(s.half);
  const int c = channels_;
  for (int k = 0; k < levels_; ++k) {
    const float* m = mask_pyr_[k].pixels.data();
    const float* l = image_pyr_[k].pixels.data();
    float* out = sum_[k].pixels.data();
    const size_t n = static_cast<size_t>(sum_[k].width) * sum_[k].height;
    for (size_t i = 0; i < n; ++i) {
      const float w = m[i];
      if (w == 0.f) continue;
      for (int ch = 0; ch < c; ++ch) out[i * c + ch] += w * l[i * c + ch];
    }
  }
  return Status::success();
}

Status SplineBlender::finish(ImageF& out) {
  if (levels_ == 0) return Status::error(ErrorCode::InvalidInput, "spline: finish() before begin()");
  collapse_laplacian(sum_, out);
  return Status::success();
}

Status multiresolution_spline(const std::vector<ImageF>& images, const std::vector<ImageF>& masks,
                              int levels, ImageF& out) {
  if (images.empty() || images.size() != masks.size())
    return Status::error(ErrorCode::InvalidInput,
                         "spline: need as many masks as images (" + std::to_string(images.size()) + " images, " +
                             std::to_string(masks.size()) + " masks)");
  SplineBlender blender;
  Status s = blender.begin(images[0].width, images[0].height, images[0].channels, levels);
  for (size_t i = 0; s && i < images.size(); ++i) s = blender.add(images[i], masks[i]);
  if (s) s = blender.finish(out);
  return s;
}

}  // namespace lk
