// Burt & Adelson pyramids and the multiresolution spline (tarini2002 Sec.
// 3.2 [2]): exact reconstruction, seam removal with detail kept.
#include "texture/pyramid.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <random>

using namespace lk;

namespace {

ImageF noise_image(int w, int h, int c, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  ImageF im = ImageF::make(w, h, c);
  for (float& p : im.pixels) p = u(rng);
  return im;
}

// A textured image: smooth ramp plus fine noise (the detail a spline must keep).
ImageF detailed_image(int w, int h) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-0.15f, 0.15f);
  ImageF im = ImageF::make(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int k = 0; k < 3; ++k)
        im.at(x, y)[k] = 0.5f + 0.1f * std::sin(0.02f * (x + 2 * y) + k) + u(rng);
  return im;
}

// Energy of the finest Laplacian level over columns [x0, x1).
double detail_energy(const ImageF& im, int x0, int x1) {
  std::vector<ImageF> lap;
  laplacian_pyramid(im, 2, lap);
  double e = 0;
  for (int y = 0; y < im.height; ++y)
    for (int x = x0; x < x1; ++x)
      for (int k = 0; k < 3; ++k) e += double(lap[0].at(x, y)[k]) * lap[0].at(x, y)[k];
  return e;
}

// Mean over rows and channels of columns [x0, x1).
double column_mean(const ImageF& im, int x0, int x1) {
  double s = 0;
  for (int y = 0; y < im.height; ++y)
    for (int x = x0; x < x1; ++x)
      for (int k = 0; k < 3; ++k) s += im.at(x, y)[k];
  return s / (double(im.height) * (x1 - x0) * 3);
}

}  // namespace

TEST_CASE("Laplacian pyramid collapses back to its image exactly") {
  for (auto [w, h, c] : {std::array<int, 3>{101, 67, 3}, {64, 64, 1}, {1, 9, 2}, {33, 2, 4}}) {
    const ImageF im = noise_image(w, h, c, 11u + w);
    const int levels = max_pyramid_levels(w, h) + 2;  // even past 1x1-ish sizes
    std::vector<ImageF> lap;
    laplacian_pyramid(im, levels, lap);
    REQUIRE(lap.size() == size_t(levels));
    ImageF back;
    collapse_laplacian(lap, back);
    REQUIRE(back.width == w);
    REQUIRE(back.height == h);
    float worst = 0;
    for (size_t i = 0; i < im.pixels.size(); ++i) worst = std::max(worst, std::abs(back.pixels[i] - im.pixels[i]));
    CHECK(worst < 4e-6f);  // float rounding only
  }
}

TEST_CASE("REDUCE keeps constants and halves sizes rounding up, and EXPAND keeps constants") {
  ImageF c = ImageF::make(37, 20, 3, 0.25f);
  ImageF r, e;
  pyramid_reduce(c, r);
  CHECK(r.width == 19);
  CHECK(r.height == 10);
  for (float p : r.pixels) CHECK(p == Approx(0.25f).epsilon(1e-6));
  pyramid_expand(r, 37, 20, e);
  CHECK(e.width == 37);
  for (float p : e.pixels) CHECK(p == Approx(0.25f).epsilon(1e-6));
  // A ramp is kept by EXPAND inside (the kernel interpolates linear functions).
  ImageF ramp = ImageF::make(16, 1, 1);
  for (int x = 0; x < 16; ++x) ramp.at(x, 0)[0] = float(x);
  ImageF up;
  pyramid_expand(ramp, 32, 1, up);
  for (int x = 4; x < 26; ++x) CHECK(up.at(x, 0)[0] == Approx(x / 2.0).margin(1e-5));
}

TEST_CASE("multiresolution spline removes a gain seam and keeps the detail") {
  const int w = 256, h = 128, border = 128;
  const ImageF base = detailed_image(w, h);
  ImageF darker = base;
  for (float& p : darker.pixels) p *= 0.6f;  // the same skin under dimmer light
  ImageF left = ImageF::make(w, h, 1, 0.f), right = ImageF::make(w, h, 1, 0.f);
  ImageF hard = base;  // the unblended composite: a cut at the border
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      (x < border ? left : right).at(x, y)[0] = 1.f;
      if (x >= border)
        for (int k = 0; k < 3; ++k) hard.at(x, y)[k] = darker.at(x, y)[k];
    }
  ImageF blended;
  REQUIRE(multiresolution_spline({base, darker}, {left, right}, 0, blended).ok());
  REQUIRE(blended.width == w);

  // The jump across the border: means of the 3 columns either side.
  const double jump_hard = std::abs(column_mean(hard, border, border + 3) - column_mean(hard, border - 3, border));
  const double jump_blend =
      std::abs(column_mean(blended, border, border + 3) - column_mean(blended, border - 3, border));
  WARN("seam jump: cut " << jump_hard << ", spline " << jump_blend << " (" << jump_hard / jump_blend << "x less)");
  CHECK(jump_hard > 0.15);
  CHECK(jump_blend * 5 < jump_hard);

  // Fine detail away from the border (32+ columns off) within a few percent.
  const double e_hard_l = detail_energy(hard, 8, border - 32), e_blend_l = detail_energy(blended, 8, border - 32);
  const double e_hard_r = detail_energy(hard, border + 32, w - 8), e_blend_r = detail_energy(blended, border + 32, w - 8);
  WARN("detail energy kept: left " << e_blend_l / e_hard_l << ", right " << e_blend_r / e_hard_r);
  CHECK(e_blend_l / e_hard_l == Approx(1.0).margin(0.03));
  CHECK(e_blend_r / e_hard_r == Approx(1.0).margin(0.03));

  // With one mask covering everything the spline is the identity.
  ImageF all = ImageF::make(w, h, 1, 1.f), none = ImageF::make(w, h, 1, 0.f), same;
  REQUIRE(multiresolution_spline({base, darker}, {all, none}, 0, same).ok());
  float worst = 0;
  for (size_t i = 0; i < base.pixels.size(); ++i) worst = std::max(worst, std::abs(same.pixels[i] - base.pixels[i]));
  CHECK(worst < 1e-5f);
}

TEST_CASE("spline rejects mismatched inputs") {
  ImageF a = ImageF::make(16, 16, 3), m = ImageF::make(16, 16, 1), wrong = ImageF::make(8, 16, 1);
  ImageF out;
  CHECK(multiresolution_spline({a}, {}, 0, out).code == ErrorCode::InvalidInput);
  CHECK(multiresolution_spline({a}, {wrong}, 0, out).code == ErrorCode::InvalidInput);
  CHECK(multiresolution_spline({a}, {a}, 0, out).code == ErrorCode::InvalidInput);  // mask must be 1 channel
  SplineBlender b;
  CHECK(b.add(a, m).code == ErrorCode::InvalidInput);  // before begin
  CHECK(b.begin(0, 16, 3, 0).code == ErrorCode::InvalidInput);
}
