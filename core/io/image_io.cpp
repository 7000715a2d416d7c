// Image decoding (stb_image) and PNG encoding (stb_image_write). This is the
// one translation unit of the project that compiles the stb implementations.
//
// Truncated JPEGs: stb_image decodes a JPEG cut in half without complaint,
// filling the missing rows with grey. A half-grey photo would silently ruin a
// texture, so before decoding we walk the JPEG's marker structure and refuse
// data that ends before the end-of-image marker. Truncated PNGs already fail
// inside stb (the compressed stream or IEND chunk is missing).
#include "io/io.h"

#include <climits>
#include <cstring>
#include <string>

#define STBI_NO_STDIO
#define STBI_FAILURE_USERMSG
#define STB_IMAGE_IMPLEMENTATION
#define STB_IMAGE_WRITE_IMPLEMENTATION
#define STBI_WRITE_NO_STDIO
#if defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#pragma GCC diagnostic ignored "-Wsign-compare"
#pragma GCC diagnostic ignored "-Wshadow"
#pragma GCC diagnostic ignored "-Wimplicit-fallthrough"
#pragma GCC diagnostic ignored "-Wunused-parameter"
#pragma GCC diagnostic ignored "-Wunused-but-set-variable"
#endif
#include <stb/stb_image.h>
#include <stb/stb_image_write.h>
#if defined(__GNUC__)
#pragma GCC diagnostic pop
#endif

namespace lk {

namespace {

bool is_jpeg(const std::uint8_t* d, size_t n) { return n >= 3 && d[0] == 0xFF && d[1] == 0xD8 && d[2] == 0xFF; }

// Walks JPEG segments (SOI, length-prefixed segments, entropy-coded scan
// data up to the next marker) and reports whether an EOI marker is reached
// before the data ends. Bytes after EOI (camera trailers) are allowed.
bool jpeg_reaches_end_marker(const std::uint8_t* d, size_t n) {
  size_t i = 2;  // after SOI
  while (i + 1 < n) {
    if (d[i] != 0xFF) return false;  // lost sync: corrupt
    std::uint8_t marker = d[i + 1];
    if (marker == 0xFF) {  // fill byte
      ++i;
      continue;
    }
    i += 2;
    if (marker == 0xD9) return true;                        // EOI
    if (marker == 0x01 || (marker >= 0xD0 && marker <= 0xD7)) continue;  // no length
    if (i + 1 >= n) return false;
    const size_t length = (size_t(d[i]) << 8) | d[i + 1];
    if (length < 2 || i + length > n) return false;
    i += length;
    if (marker == 0xDA) {
      // Scan data: runs until a marker other than a stuffed 0xFF00 or RSTn.
      while (i + 1 < n) {
        if (d[i] == 0xFF && d[i + 1] != 0x00 && !(d[i + 1] >= 0xD0 && d[i + 1] <= 0xD7)) break;
        ++i;
      }
      if (i + 1 >= n) return false;
    }
  }
  return false;
}

void append_to_bytes(void* context, void* data, int size) {
  Bytes* out = static_cast<Bytes*>(context);
  const std::uint8_t* p = static_cast<const std::uint8_t*>(data);
  out->insert(out->end(), p, p + size);
}

}  // namespace

Status read_image(const std::uint8_t* data, size_t size, Image& image, int want_channels, size_t max_pixels) {
  image = Image();
  if (size == 0) return Status::error(ErrorCode::Empty, "empty input: no bytes");
  if (want_channels < 0 || want_channels > 4)
    return Status::error(ErrorCode::InvalidInput, "want_channels must be 0..4, got " + std::to_string(want_channels));
  if (size > static_cast<size_t>(INT_MAX)) return Status::error(ErrorCode::TooLarge, "image data over 2 GiB");
  const int n = static_cast<int>(size);
  int w = 0, h = 0, c = 0;
  if (!stbi_info_from_memory(data, n, &w, &h, &c))
    return Status::error(ErrorCode::InvalidInput,
                         std::string("not an image (PNG, JPEG, BMP, TGA, GIF, PSD, HDR, PIC, PNM): ") +
                             stbi_failure_reason());
  if (w <= 0 || h <= 0) return Status::error(ErrorCode::InvalidInput, "image has no pixels");
  if (static_cast<std::uint64_t>(w) * static_cast<std::uint64_t>(h) > max_pixels)
    return Status::error(ErrorCode::TooLarge, "image is " + std::to_string(w) + "x" + std::to_string(h) +
                                                  ", over the limit of " + std::to_string(max_pixels) + " pixels");
  if (is_jpeg(data, size) && !jpeg_reaches_end_marker(data, size))
    return Status::error(ErrorCode::Truncated, "truncated JPEG: the data ends before the end-of-image marker");
  // Gray+alpha has no Image layout of its own: expand to RGBA.
  const int channels = want_channels != 0 ? want_channels : (c == 2 ? 4 : c);
  int dw = 0, dh = 0, dc = 0;
  stbi_uc* pixels = stbi_load_from_memory(data, n, &dw, &dh, &dc, channels);
  if (!pixels)
    return Status::error(ErrorCode::InvalidInput, std::string("cannot decode image: ") + stbi_failure_reason());
  image.width = dw;
  image.height = dh;
  image.channels = channels;
  image.pixels.assign(pixels, pixels + static_cast<size_t>(dw) * dh * channels);
  stbi_image_free(pixels);
  return Status::success();
}

Bytes write_png(const Image& image) {
  Bytes out;
  if (image.width <= 0 || image.height <= 0 || image.channels < 1 || image.channels > 4 ||
      image.pixels.size() != static_cast<size_t>(image.width) * image.height * image.channels)
    return out;
  stbi_write_png_to_func(append_to_bytes, &out, image.width, image.height, image.channels, image.pixels.data(),
                         image.width * image.channels);
  return out;
}

}  // namespace lk
