// 8-bit images (photos, textures, renders) and float images (for filtering).
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

namespace lk {

// Row-major, top row first, interleaved channels (1 = gray, 3 = RGB, 4 = RGBA).
struct Image {
  int width = 0, height = 0, channels = 0;
  std::vector<std::uint8_t> pixels;  // width * height * channels

  bool empty() const { return width <= 0 || height <= 0 || pixels.empty(); }
  std::uint8_t* at(int x, int y) { return &pixels[(static_cast<size_t>(y) * width + x) * channels]; }
  const std::uint8_t* at(int x, int y) const { return &pixels[(static_cast<size_t>(y) * width + x) * channels]; }
  static Image make(int w, int h, int c, std::uint8_t fill = 0) {
    Image im;
    im.width = w; im.height = h; im.channels = c;
    im.pixels.assign(static_cast<size_t>(w) * h * c, fill);
    return im;
  }
};

// Same layout with float samples (usually in [0,1]).
struct ImageF {
  int width = 0, height = 0, channels = 0;
  std::vector<float> pixels;

  bool empty() const { return width <= 0 || height <= 0 || pixels.empty(); }
  float* at(int x, int y) { return &pixels[(static_cast<size_t>(y) * width + x) * channels]; }
  const float* at(int x, int y) const { return &pixels[(static_cast<size_t>(y) * width + x) * channels]; }
  static ImageF make(int w, int h, int c, float fill = 0.f) {
    ImageF im;
    im.width = w; im.height = h; im.channels = c;
    im.pixels.assign(static_cast<size_t>(w) * h * c, fill);
    return im;
  }
};

ImageF to_float(const Image& im);          // divides by 255
Image to_bytes(const ImageF& im);          // clamps to [0,1], rounds

// The image scaled to width x height (stb_image_resize's filters, each
// channel alike); empty for an empty image or a size below 1.
Image resized(const Image& im, int width, int height);

}  // namespace lk
