// libFuzzer target: a mask file as `likeness photos --masks` reads it
// (read_image, then the photos' outline, photos/outline.h), and the same
// bytes as a photo with a plain background (`likeness photos --photos`, the
// page), whole and shrunk (outline_from_plain_photo). A success
// holds points inside the image (on pixel edges, so within [0, size]) with
// finite unit normals, at least min_points of them, and a foreground share
// in (0, max]. The images are capped at 256 k pixels so the fuzzer spends
// its time on the outline, not the decoder (fuzz_image covers that).
#include "fuzz_check.h"
#include "photos/outline.h"

#include <cmath>

namespace {

void check_outline(const lk::PhotoOutline& o, const lk::OutlineOptions& options) {
  lk::fuzz::require(static_cast<int>(o.points.size()) >= options.min_points);
  lk::fuzz::require(o.foreground_share > 0 && o.foreground_share <= options.max_foreground_share);
  for (const lk::OutlinePoint& p : o.points) {
    lk::fuzz::require(p.pixel.allFinite() && p.normal.allFinite());
    lk::fuzz::require(p.pixel.x() >= 0 && p.pixel.x() <= o.width && p.pixel.y() >= 0 && p.pixel.y() <= o.height);
    lk::fuzz::require(std::abs(p.normal.norm() - 1) < 1e-6);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, size_t size) {
  lk::Image image;
  if (!lk::read_image(data, size, image, 0, size_t(1) << 18)) return 0;
  const lk::OutlineOptions options;
  lk::PhotoOutline outline;
  const std::vector<std::uint8_t> mask = lk::mask_from_image(image);
  lk::fuzz::require(mask.size() == static_cast<size_t>(image.width) * image.height);
  for (std::uint8_t m : mask) lk::fuzz::require(m <= 1);
  lk::Status s = lk::extract_outline(mask, image.width, image.height, image.width, image.height, options, outline);
  if (s) check_outline(outline, options);
  else lk::fuzz::require(!s.message.empty());
  // The wrong size is refused, not read past.
  lk::fuzz::require(!lk::extract_outline(mask, image.width, image.height, image.width + 1, image.height, options, outline));

  std::vector<std::uint8_t> plain;
  s = lk::mask_from_plain_background(image, lk::PlainBackgroundOptions{}, plain);
  if (!s) {
    lk::fuzz::require(!s.message.empty());
    return 0;
  }
  lk::fuzz::require(plain.size() == static_cast<size_t>(image.width) * image.height);
  for (std::uint8_t m : plain) lk::fuzz::require(m <= 1);
  s = lk::extract_outline(plain, image.width, image.height, image.width, image.height, options, outline);
  if (s) check_outline(outline, options);
  // As the page and `likeness photos --photos` find it: the image shrunk to
  // 64 px first, read as the copy of a photo twice its size; the points in
  // that photo's pixels.
  s = lk::outline_from_plain_photo(image, 2 * image.width, 2 * image.height, 64, lk::PlainBackgroundOptions{}, options,
                                   outline);
  if (s) {
    lk::fuzz::require(outline.width == 2 * image.width && outline.height == 2 * image.height);
    check_outline(outline, options);
  } else {
    lk::fuzz::require(!s.message.empty());
  }
  return 0;
}
