#include "texture/color.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace lk {
namespace {

double decode(double e) { return e <= 0.04045 ? e / 12.92 : std::pow((e + 0.055) / 1.055, 2.4); }

const std::array<float, 256>& decode_table() {
  static const std::array<float, 256> table = [] {
    std::array<float, 256> t{};
    for (int i = 0; i < 256; ++i) t[i] = static_cast<float>(decode(i / 255.0));
    return t;
  }();
  return table;
}

// Encoding by table (a pow() per texel channel costs ~0.3 s at 2048^2):
// 2^16 linear steps. One step is 1.5e-5 linear, 0.05 of an 8-bit level
// after the 12.92 slope of the dark end, so the table agrees with the exact
// rounded encoding except within a twentieth of a level of a rounding tie.
constexpr int kEncodeSteps = 1 << 16;

const std::vector<std::uint8_t>& encode_table() {
  static const std::vector<std::uint8_t> table = [] {
    std::vector<std::uint8_t> t(kEncodeSteps + 1);
    for (int i = 0; i <= kEncodeSteps; ++i) {
      const double l = static_cast<double>(i) / kEncodeSteps;
      const double e = l <= 0.0031308 ? 12.92 * l : 1.055 * std::pow(l, 1.0 / 2.4) - 0.055;
      t[i] = static_cast<std::uint8_t>(std::lround(std::clamp(e, 0.0, 1.0) * 255.0));
    }
    return t;
  }();
  return table;
}

}  // namespace

float srgb8_to_linear(std::uint8_t v) { return decode_table()[v]; }

std::uint8_t linear_to_srgb8(float linear) {
  // NaN fails both comparisons and maps to 0.
  const float c = linear > 0.f ? (linear < 1.f ? linear : 1.f) : 0.f;
  return encode_table()[static_cast<size_t>(c * kEncodeSteps + 0.5f)];
}

ImageF srgb_to_linear(const Image& image) {
  ImageF out = ImageF::make(image.width, image.height, image.channels);
  const auto& table = decode_table();
  const bool alpha = image.channels == 4 || image.channels == 2;
  for (size_t i = 0; i < image.pixels.size(); ++i) {
    const bool is_alpha = alpha && (i % image.channels) == static_cast<size_t>(image.channels - 1);
    out.pixels[i] = is_alpha ? image.pixels[i] / 255.f : table[image.pixels[i]];
  }
  return out;
}

Image linear_to_srgb(const ImageF& image) {
  Image out = Image::make(image.width, image.height, image.channels);
  const bool alpha = image.channels == 4 || image.channels == 2;
  for (size_t i = 0; i < image.pixels.size(); ++i) {
    const bool is_alpha = alpha && (i % image.channels) == static_cast<size_t>(image.channels - 1);
    if (is_alpha) {
      const float a = std::clamp(image.pixels[i], 0.f, 1.f);
      out.pixels[i] = static_cast<std::uint8_t>(std::lround(a * 255.f));
    } else {
      out.pixels[i] = linear_to_srgb8(image.pixels[i]);
    }
  }
  return out;
}

}  // namespace lk
