// Filling the unused texture space: push-pull (whole background) and ring
// dilation keep the chart's texels and extend its colours outwards.
#include "texture/dilate.h"

#include <catch2/catch.hpp>
#include <cmath>

using namespace lk;

TEST_CASE("push-pull fills everything from the known texels, leaving them unchanged") {
  const int w = 97, h = 64;
  ImageF im = ImageF::make(w, h, 3, 0.f);
  std::vector<char> known(size_t(w) * h, 0);
  // A disk of known texels with a ramp: the fill must stay within its range.
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      if (std::hypot(x - 40.0, y - 30.0) < 20) {
        known[size_t(y) * w + x] = 1;
        for (int k = 0; k < 3; ++k) im.at(x, y)[k] = 0.2f + 0.01f * x + 0.1f * k;
      }
  const ImageF before = im;
  long unknown = 0;
  for (char k : known) unknown += !k;
  CHECK(push_pull_fill(im, known) == unknown);
  float lo = 1e9f, hi = -1e9f;
  for (size_t i = 0; i < known.size(); ++i)
    if (known[i]) {
      for (int k = 0; k < 3; ++k) CHECK(im.pixels[i * 3 + k] == before.pixels[i * 3 + k]);
      lo = std::min(lo, before.pixels[i * 3]);
      hi = std::max(hi, before.pixels[i * 3]);
    }
  for (size_t i = 0; i < known.size(); ++i) {
    CHECK(im.pixels[i * 3] >= lo - 1e-5f);
    CHECK(im.pixels[i * 3] <= hi + 1e-5f);
  }
  // Smooth: neighbouring filled texels differ by no more than a few texels'
  // worth of the known ramp (0.01 per texel; measured 0.033). A fill that
  // showed its block grid would jump by a good part of the range (0.38).
  float worst = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x + 1 < w; ++x)
      if (!known[size_t(y) * w + x] && !known[size_t(y) * w + x + 1])
        worst = std::max(worst, std::abs(im.at(x, y)[0] - im.at(x + 1, y)[0]));
  CHECK(worst < 0.04f);
  // A constant is continued exactly.
  ImageF flat = ImageF::make(w, h, 1, 0.f);
  for (size_t i = 0; i < known.size(); ++i) flat.pixels[i] = known[i] ? 0.7f : -5.f;
  push_pull_fill(flat, known);
  for (float p : flat.pixels) CHECK(p == Approx(0.7f).epsilon(1e-5));
  // Nothing known: unchanged, 0 filled.
  ImageF none = ImageF::make(8, 8, 3, 0.25f);
  CHECK(push_pull_fill(none, std::vector<char>(64, 0)) == 0);
  CHECK(none.pixels[5] == 0.25f);
}

TEST_CASE("ring dilation grows the known area by exactly N rings") {
  const int w = 21, h = 21;
  ImageF im = ImageF::make(w, h, 1, 0.f);
  std::vector<char> known(size_t(w) * h, 0);
  known[10 * w + 10] = 1;
  im.at(10, 10)[0] = 0.5f;
  CHECK(dilate_rings(im, known, 3) == 7 * 7 - 1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const bool inside = std::abs(x - 10) <= 3 && std::abs(y - 10) <= 3;
      CHECK(bool(known[size_t(y) * w + x]) == inside);
      if (inside) CHECK(im.at(x, y)[0] == Approx(0.5f));
    }
}
