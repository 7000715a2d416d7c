#include "test_kira.h"

#include "test_data.h"

#include <catch2/catch.hpp>

namespace lk::test {

std::vector<LandmarkPhoto> kira_landmark_photos() {
  std::vector<LandmarkPhoto> photos;
  for (const char* n : {"0001", "0002", "0003", "0004", "0006", "0007", "0008", "0009", "0010"}) {
    const std::string text = read_file_text(source_dir() + "/tests/photos/data/kira/" + n + ".json");
    INFO(n << ".json");
    REQUIRE_FALSE(text.empty());
    LandmarkPhoto ph;
    REQUIRE(parse_landmarks_json(text, ph));
    photos.push_back(ph);
  }
  return photos;
}

}  // namespace lk::test
