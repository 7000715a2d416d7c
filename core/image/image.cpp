#include "image/image.h"

#include <algorithm>
#include <cmath>

namespace lk {

ImageF to_float(const Image& im) {
  ImageF out = ImageF::make(im.width, im.height, im.channels);
  for (size_t i = 0; i < im.pixels.size(); ++i) out.pixels[i] = im.pixels[i] / 255.f;
  return out;
}

Image to_bytes(const ImageF& im) {
  Image out = Image::make(im.width, im.height, im.channels);
  for (size_t i = 0; i < im.pixels.size(); ++i)
    out.pixels[i] = static_cast<std::uint8_t>(std::lround(std::clamp(im.pixels[i], 0.f, 1.f) * 255.f));
  return out;
}

}  // namespace lk
