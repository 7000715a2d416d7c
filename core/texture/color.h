// sRGB <-> linear conversions for texturing. Photos are sRGB-encoded; colours
// from several photos are averaged, filtered and blended in linear light
// (an average of encoded values darkens edges and mixes hues wrongly), and
// the final texture is encoded back to sRGB (IEC 61966-2-1 curves).
#pragma once
#include "image/image.h"

#include <cstdint>

namespace lk {

// Exact sRGB decoding of an 8-bit value (table lookup).
float srgb8_to_linear(std::uint8_t v);
// Encoding of a linear value in [0,1] (clamped) to 8 bits, rounded.
std::uint8_t linear_to_srgb8(float linear);

// Whole images. The 8-bit image's channels are kept (alpha, if any, is
// treated as linear: divided by 255 / multiplied by 255).
ImageF srgb_to_linear(const Image& image);
Image linear_to_srgb(const ImageF& image);

}  // namespace lk
