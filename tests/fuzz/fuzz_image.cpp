// libFuzzer target: read_image (io.h) on arbitrary bytes. A success is an
// image whose pixel array matches its declared size, within the pixel limit.
// The decoded image may legitimately be far larger than the input (a PNG
// compresses), so the heap is bounded by the pixel limit, not the input.
#include "fuzz_check.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, size_t size) {
  lk::Image image;
  // 1 Mpixel instead of the default 64: the same checks, and the fuzzer
  // spends its time on the decoders rather than on filling big images.
  const size_t max_pixels = size_t(1) << 20;
  const lk::Status s = lk::read_image(data, size, image, 0, max_pixels);
  if (!s) {
    lk::fuzz::require(!s.message.empty());
    return 0;
  }
  lk::fuzz::require(image.width > 0 && image.height > 0);
  lk::fuzz::require(image.channels >= 1 && image.channels <= 4);
  lk::fuzz::require(static_cast<std::uint64_t>(image.width) * image.height <= max_pixels);
  lk::fuzz::require(image.pixels.size() ==
                    static_cast<size_t>(image.width) * image.height * static_cast<size_t>(image.channels));
  return 0;
}
