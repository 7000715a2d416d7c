// Debian's stb_image_resize 0.97, compiled once here (its default filters:
// Mitchell when shrinking, Catmull-Rom when enlarging), behind resized().
#include "image/image.h"

#define STB_IMAGE_RESIZE_IMPLEMENTATION
#define STB_IMAGE_RESIZE_STATIC
#include <stb/stb_image_resize.h>  // (a system header: its warnings are not ours)

namespace lk {

Image resized(const Image& im, int width, int height) {
  if (im.empty() || width <= 0 || height <= 0 || im.channels < 1 ||
      im.pixels.size() < static_cast<size_t>(im.width) * size_t(im.height) * size_t(im.channels))
    return {};
  Image out = Image::make(width, height, im.channels);
  if (!stbir_resize_uint8(im.pixels.data(), im.width, im.height, 0, out.pixels.data(), width, height, 0, im.channels))
    return {};
  return out;
}

}  // namespace lk
