// libFuzzer target: read_jpeg_exif (io/exif.h) on arbitrary bytes, then the
// focal in pixels every rule gives for an image size taken from the input.
// A success holds finite, non-negative focal tags; a focal in pixels is
// finite and non-negative for any size; the heap stays bounded by the input
// (the reader copies strings, never what a count merely declares).
#include "fuzz_check.h"
#include "io/exif.h"

#include <cmath>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, size_t size) {
  lk::ExifInfo exif;
  const lk::Status s = lk::fuzz::watched(size, [&] { return lk::read_jpeg_exif(data, size, exif); });
  if (!s) {
    lk::fuzz::require(!s.message.empty());
    return 0;
  }
  lk::fuzz::require(std::isfinite(exif.focal_length_mm) && exif.focal_length_mm >= 0);
  lk::fuzz::require(std::isfinite(exif.focal_plane_x_resolution) && std::isfinite(exif.focal_plane_y_resolution));
  // The photo's size: from the first bytes when there are some (any int,
  // zero and negative included), else a phone's 4032 x 3024.
  int width = 4032, height = 3024;
  if (size >= 4) {
    width = static_cast<std::int16_t>(data[0] | data[1] << 8);
    height = static_cast<std::int16_t>(data[2] | data[3] << 8);
  }
  for (const double sensor_mm : {0.0, 6.17, -1.0, 1e-300}) {
    std::string source;
    const double f = lk::exif_focal_pixels(exif, width, height, sensor_mm, &source);
    lk::fuzz::require(std::isfinite(f) && f >= 0);
    lk::fuzz::require(f == 0 || !source.empty());
  }
  return 0;
}
