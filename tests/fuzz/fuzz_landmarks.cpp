// libFuzzer target: the landmark files of `likeness photos` and the page
// (parse_landmarks_json) and the landmark map (parse_landmark_map_json), on
// the same bytes. A success holds finite points inside the widened image
// (landmarks) or within 10 m (map), and one presence flag per point.
#include "fuzz_check.h"
#include "photos/landmarks.h"

#include <cmath>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  lk::LandmarkPhoto photo;
  lk::Status s = lk::fuzz::watched(size, [&] { return lk::parse_landmarks_json(text, photo); });
  if (!s) {
    lk::fuzz::require(!s.message.empty());
  } else {
    lk::fuzz::require(photo.width >= 1 && photo.height >= 1 && photo.width <= lk::kMaxLandmarkImageSide &&
                      photo.height <= lk::kMaxLandmarkImageSide);
    lk::fuzz::require(photo.points.size() == photo.present.size() && int(photo.points.size()) <= lk::kMaxLandmarks);
    for (size_t i = 0; i < photo.points.size(); ++i)
      if (photo.present[i])
        lk::fuzz::require(photo.points[i].allFinite() && std::abs(photo.points[i].x()) <= 2.0 * photo.width &&
                          std::abs(photo.points[i].y()) <= 2.0 * photo.height);
  }
  lk::LandmarkMap map;
  s = lk::fuzz::watched(size, [&] { return lk::parse_landmark_map_json(text, map); });
  if (!s) {
    lk::fuzz::require(!s.message.empty());
    return 0;
  }
  lk::fuzz::require(map.points.size() == map.present.size() && int(map.points.size()) <= lk::kMaxLandmarks);
  for (size_t i = 0; i < map.points.size(); ++i)
    if (map.present[i]) lk::fuzz::require(map.points[i].allFinite() && map.points[i].cwiseAbs().maxCoeff() <= 10);
  return 0;
}
