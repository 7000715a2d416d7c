// Image metrics (core/image/metrics.h) against analytic answers: PSNR of a
// noise image with known MSE, SSIM of constant images (closed form) and its
// monotone drop with blur and noise, the seam measure on ramps with and
// without a step, and the bad inputs that must give clear errors.
#include "image/metrics.h"
#include "common/prng.h"

#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <numeric>

using namespace lk;

namespace {

// Structured content at several scales so SSIM has structure to lose.
Image pattern(int w, int h) {
  Image im = Image::make(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c)
        im.at(x, y)[c] = static_cast<std::uint8_t>(
            128 + 50 * std::sin(0.21 * x + 0.7 * c) * std::cos(0.17 * y) + 25 * std::sin(0.05 * (x + 2 * y)) +
            30 * std::sin(0.9 * x + c) * std::sin(1.3 * y));
  return im;
}

// Gaussian blur (separable, clamped borders): its frequency response falls
// monotonically with sigma, so SSIM must too (a box blur's sidelobes would not).
Image gaussian_blur(const Image& in, double sigma) {
  const int r = static_cast<int>(std::ceil(3 * sigma));
  std::vector<double> k(2 * r + 1);
  double sum = 0;
  for (int i = -r; i <= r; ++i) sum += k[i + r] = std::exp(-i * i / (2 * sigma * sigma));
  for (double& v : k) v /= sum;
  std::vector<double> tmp(in.pixels.size());
  Image out = in;
  for (int pass = 0; pass < 2; ++pass)
    for (int y = 0; y < in.height; ++y)
      for (int x = 0; x < in.width; ++x)
        for (int c = 0; c < in.channels; ++c) {
          double acc = 0;
          for (int i = -r; i <= r; ++i) {
            const int xx = pass == 0 ? std::clamp(x + i, 0, in.width - 1) : x;
            const int yy = pass == 1 ? std::clamp(y + i, 0, in.height - 1) : y;
            const size_t idx = (static_cast<size_t>(yy) * in.width + xx) * in.channels + c;
            acc += k[i + r] * (pass == 0 ? in.pixels[idx] : tmp[idx]);
          }
          const size_t o = (static_cast<size_t>(y) * in.width + x) * in.channels + c;
          if (pass == 0) tmp[o] = acc;
          else out.pixels[o] = static_cast<std::uint8_t>(std::lround(acc));
        }
  return out;
}

Image add_noise(const Image& in, int amplitude, std::uint64_t seed) {
  SplitMix64 rng(seed);
  Image out = in;
  for (auto& v : out.pixels) {
    const int d = static_cast<int>(rng.next() % (2 * amplitude + 1)) - amplitude;
    v = static_cast<std::uint8_t>(std::clamp(int(v) + d, 0, 255));
  }
  return out;
}

}  // namespace

TEST_CASE("psnr of uniform +-k noise matches its analytic MSE", "[metrics]") {
  // Every offset in [-k, k] occurs equally often (a shuffled cycle), so the
  // MSE is exactly the variance of the discrete uniform: k (k + 1) / 3.
  for (int k : {1, 4, 10}) {
    const int w = 63, h = 42;  // 2646 samples per channel... times 3 = 7938
    Image a = Image::make(w, h, 3, 128), b = a;
    const int n = static_cast<int>(b.pixels.size());
    const int period = 2 * k + 1;
    REQUIRE(n % period == 0);
    std::vector<int> offsets(n);
    for (int i = 0; i < n; ++i) offsets[i] = i % period - k;
    SplitMix64 rng(7);
    for (int i = n - 1; i > 0; --i) std::swap(offsets[i], offsets[rng.next() % (i + 1)]);
    for (int i = 0; i < n; ++i) b.pixels[i] = static_cast<std::uint8_t>(128 + offsets[i]);
    PsnrResult r;
    REQUIRE(compute_psnr(a, b, {}, r).ok());
    const double mse = k * (k + 1) / 3.0;
    CHECK(r.mse == Approx(mse).epsilon(1e-12));
    CHECK(r.psnr_db == Approx(10 * std::log10(255.0 * 255.0 / mse)).epsilon(1e-12));
    CHECK(r.pixels == w * h);
  }
}

TEST_CASE("psnr scores only masked pixels and ignores alpha", "[metrics]") {
  Image a = Image::make(20, 10, 3, 100), b = a;
  PixelMask mask(200, 0);
  for (int y = 0; y < 10; ++y)
    for (int x = 0; x < 20; ++x) {
      if (x < 10) mask[y * 20 + x] = 1;
      else b.at(x, y)[1] = 200;  // differs only outside the mask
    }
  PsnrResult r;
  REQUIRE(compute_psnr(a, b, mask, r).ok());
  CHECK(std::isinf(r.psnr_db));
  CHECK(r.mse == 0);
  CHECK(r.pixels == 100);
  // Outside differences count without the mask: 100 pixels off by 100 in one
  // of 3 channels of 200 pixels -> MSE = 100 * 100^2 / 600.
  REQUIRE(compute_psnr(a, b, {}, r).ok());
  CHECK(r.mse == Approx(100.0 * 10000 / 600));
  // An RGBA render compares with an RGB truth; alpha is not a colour.
  Image rgba = Image::make(20, 10, 4, 100);
  for (int i = 0; i < 200; ++i) rgba.pixels[i * 4 + 3] = 7;
  REQUIRE(compute_psnr(a, rgba, {}, r).ok());
  CHECK(std::isinf(r.psnr_db));
}

TEST_CASE("ssim of constant images has the closed form of its luminance term", "[metrics]") {
  // sigma = 0 in both: the contrast-structure term is C2 / C2 = 1.
  for (int va : {50, 128}) {
    for (int vb : {50, 90, 200}) {
      Image a = Image::make(24, 24, 1, static_cast<std::uint8_t>(va));
      Image b = Image::make(24, 24, 1, static_cast<std::uint8_t>(vb));
      SsimResult r;
      REQUIRE(compute_ssim(a, b, {}, {}, r).ok());
      const double c1 = (0.01 * 255) * (0.01 * 255);
      CHECK(r.ssim == Approx((2.0 * va * vb + c1) / (double(va) * va + double(vb) * vb + c1)).epsilon(1e-9));
      CHECK(r.pixels == 14 * 14);  // window centres 5 pixels from each border
    }
  }
}

TEST_CASE("ssim is 1 for identical images and drops monotonically with blur and noise", "[metrics]") {
  const Image a = pattern(96, 80);
  for (SsimMode mode : {SsimMode::Luminance, SsimMode::PerChannel}) {
    SsimOptions opt;
    opt.mode = mode;
    SsimResult r;
    REQUIRE(compute_ssim(a, a, {}, opt, r).ok());
    CHECK(r.ssim == Approx(1.0).epsilon(1e-12));
    double last = 1.0;
    for (double sigma : {0.5, 1.0, 1.5, 2.5}) {
      REQUIRE(compute_ssim(a, gaussian_blur(a, sigma), {}, opt, r).ok());
      INFO("blur sigma " << sigma << ": ssim " << r.ssim);
      CHECK(r.ssim < last - 0.002);
      last = r.ssim;
    }
    last = 1.0;
    for (int amplitude : {3, 10, 25, 60}) {
      REQUIRE(compute_ssim(a, add_noise(a, amplitude, 11), {}, opt, r).ok());
      INFO("noise +-" << amplitude << ": ssim " << r.ssim);
      CHECK(r.ssim < last - 0.002);
      last = r.ssim;
    }
    CHECK(last < 0.6);  // heavy noise leaves little structure
  }
}

TEST_CASE("ssim with a mask scores only the selected window centres", "[metrics]") {
  const Image a = pattern(64, 64);
  Image b = a;
  for (int y = 0; y < 64; ++y)
    for (int x = 40; x < 64; ++x)
      for (int c = 0; c < 3; ++c) b.at(x, y)[c] = static_cast<std::uint8_t>(255 - a.at(x, y)[c]);
  PixelMask left(64 * 64, 0);
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 30; ++x) left[y * 64 + x] = 1;  // windows reach x < 35: untouched
  SsimResult masked, whole;
  REQUIRE(compute_ssim(a, b, left, {}, masked).ok());
  REQUIRE(compute_ssim(a, b, {}, {}, whole).ok());
  CHECK(masked.ssim == Approx(1.0).epsilon(1e-12));
  CHECK(whole.ssim < 0.7);
  CHECK(masked.pixels == (30 - 5) * (64 - 10));
}

TEST_CASE("seam measure is ~0 on a ramp without a step and the step size with one", "[metrics]") {
  const int w = 128, h = 64;
  std::vector<int> labels(w * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) labels[y * w + x] = x < w / 2 ? 0 : 1;
  for (int step : {0, 6, 20}) {
    Image tex = Image::make(w, h, 3);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        for (int c = 0; c < 3; ++c)
          // An anisotropic ramp (1 per texel along x, none along y) plus
          // the step on the right half.
          tex.at(x, y)[c] = static_cast<std::uint8_t>(40 + x + (x >= w / 2 ? step : 0));
    SeamResult r;
    REQUIRE(texture_seam(tex, labels, {}, {}, r).ok());
    INFO("step " << step << ": seam " << r.seam);
    CHECK(r.seam == Approx(step).margin(1e-9));
    CHECK(r.abs_excess == Approx(step).margin(1e-9));
    CHECK(r.cross_pairs == h);
  }
}

TEST_CASE("seam measure tracks the step under texture noise and ignores unlabelled texels", "[metrics]") {
  const int w = 160, h = 160;
  // Four quadrant regions, a hole of unlabelled texels, a chart mask border.
  std::vector<int> labels(w * h);
  PixelMask chart(w * h, 0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      labels[y * w + x] = (x < w / 2 ? 0 : 1) + (y < h / 2 ? 0 : 2);
      if (std::abs(x - 40) < 8 && std::abs(y - 100) < 8) labels[y * w + x] = -1;
      chart[y * w + x] = (x > 2 && y > 2 && x < w - 3 && y < h - 3) ? 1 : 0;
    }
  double last = -1;
  for (int step : {0, 4, 12, 30}) {
    Image tex = Image::make(w, h, 3);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const int region = labels[y * w + x] < 0 ? 0 : labels[y * w + x];
        for (int c = 0; c < 3; ++c) {
          int v = 100 + step * region / 3;
          if (labels[y * w + x] < 0 || !chart[y * w + x]) v = 255;  // garbage outside: must not count
          tex.at(x, y)[c] = static_cast<std::uint8_t>(v);
        }
      }
    const Image noisy = add_noise(tex, 8, 3);
    SeamResult r;
    REQUIRE(texture_seam(noisy, labels, chart, {}, r).ok());
    INFO("step " << step << ": seam " << r.seam);
    // Steps between quadrants: |0-1| = step/3, |0-2| = 2 step/3, |1-3| = 2 step/3,
    // |2-3| = step/3, equally many pairs each: RMS sqrt(5/18) step. The
    // noise (+-8, sd 6.9 for a difference) over ~150 pairs per label pair
    // is removed from the squared means on average; what is left is its
    // fluctuation (~0.6 on the squared scale).
    CHECK(r.seam == Approx(std::sqrt(5.0 / 18.0) * step).margin(1.0));
    CHECK(r.seam > last);
    // The plain absolute measure under-reads small steps hidden in noise.
    if (step == 4) CHECK(r.abs_excess < 0.5 * r.seam);
    last = r.seam;
  }
}

TEST_CASE("seam measure drops by the ramp width when a blend spreads the step", "[metrics]") {
  const int w = 200, h = 40, step = 40;
  std::vector<int> labels(w * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) labels[y * w + x] = x < w / 2 ? 0 : 1;
  for (int ramp : {1, 4, 10, 20}) {
    Image tex = Image::make(w, h, 3);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        // Linear ramp from 80 to 80 + step over `ramp` texels centred on the boundary.
        const double t = std::clamp((x - (w / 2 - ramp / 2.0) + 0.5) / ramp, 0.0, 1.0);
        for (int c = 0; c < 3; ++c) tex.at(x, y)[c] = static_cast<std::uint8_t>(std::lround(80 + step * t));
      }
    SeamResult r;
    REQUIRE(texture_seam(tex, labels, {}, {}, r).ok());
    INFO("ramp " << ramp << ": seam " << r.seam);
    CHECK(r.seam == Approx(double(step) / ramp).margin(0.6));
  }
}

TEST_CASE("metrics reject bad input with clear errors", "[metrics]") {
  const Image a = Image::make(16, 16, 3, 10), small = Image::make(8, 16, 3, 10);
  PsnrResult p;
  SsimResult s;
  SeamResult seam;
  Status st = compute_psnr(a, small, {}, p);
  CHECK(st.code == ErrorCode::InvalidInput);
  CHECK(st.message.find("16x16x3 vs 8x16x3") != std::string::npos);
  CHECK(compute_psnr(a, Image{}, {}, p).code == ErrorCode::InvalidInput);
  CHECK(compute_psnr(a, a, PixelMask(5, 1), p).code == ErrorCode::InvalidInput);
  CHECK(compute_psnr(a, a, PixelMask(256, 0), p).code == ErrorCode::Empty);
  CHECK(compute_psnr(a, Image::make(16, 16, 1, 10), {}, p).code == ErrorCode::InvalidInput);
  Image broken = a;
  broken.pixels.resize(10);
  CHECK(compute_psnr(a, broken, {}, p).code == ErrorCode::InvalidInput);
  CHECK(compute_ssim(small, small, {}, {}, s).code == ErrorCode::InvalidInput);  // 8 < 11
  SsimOptions even;
  even.window = 10;
  CHECK(compute_ssim(a, a, {}, even, s).code == ErrorCode::InvalidInput);
  PixelMask border_only(256, 0);
  border_only[0] = 1;
  CHECK(compute_ssim(a, a, border_only, {}, s).code == ErrorCode::Empty);
  CHECK(texture_seam(a, std::vector<int>(10, 0), {}, {}, seam).code == ErrorCode::InvalidInput);
  CHECK(texture_seam(a, std::vector<int>(256, 0), {}, {}, seam).code == ErrorCode::Empty);  // one region
  SeamOptions zero;
  zero.pair_distance = 0;
  CHECK(texture_seam(a, std::vector<int>(256, 0), {}, zero, seam).code == ErrorCode::InvalidInput);
}
