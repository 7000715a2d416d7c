// Kira's landmark files (tests/photos/data/kira): the page's detector run on
// nine real photos of one person (the photos stay in ../shared/data).
#pragma once
#include "photos/landmarks.h"

#include <vector>

namespace lk::test {

// 0001-0010 without 0005 (no face found in it), in that order; each file
// must read (REQUIRE).
std::vector<LandmarkPhoto> kira_landmark_photos();

}  // namespace lk::test
