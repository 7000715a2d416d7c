// libFuzzer target: the points files the texture calibration reads
// ("u v X Y Z" per line, parse_correspondences): a success holds at least one
// point and only finite numbers.
#include "fuzz_check.h"
#include "texture/correspondences.h"

#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  std::vector<lk::Correspondence> points;
  const lk::Status s = lk::fuzz::watched(size, [&] { return lk::parse_correspondences(text, points); });
  if (!s) {
    lk::fuzz::require(!s.message.empty());
    return 0;
  }
  lk::fuzz::require(!points.empty());
  for (const lk::Correspondence& c : points) lk::fuzz::require(c.pixel.allFinite() && c.point.allFinite());
  return 0;
}
