// A synthetic photo session for the photos tests: the generic head, a
// synthetic person (core/synth, seed), the placeholder landmark map (468
// generic-head face vertices: a stand-in until the real MediaPipe map lands;
// the code under test reads any map), and cameras with noisy landmarks.
#pragma once
#include "head/generic_head.h"
#include "photos/landmarks.h"
#include "photos/synthetic_views.h"
#include "synth/synth_head.h"

#include <catch2/catch.hpp>

namespace lk::test {

struct PhotoScenario {
  GenericHead generic, person;
  LandmarkMap map;
  std::vector<SurfacePoint> landmarks;  // on the generic head (and, same topology, the person)
  SyntheticSession session;
};

inline PhotoScenario make_photo_scenario(std::uint32_t seed, const SyntheticViewsOptions& views = {}) {
  PhotoScenario s;
  REQUIRE(load_generic_head(s.generic));
  REQUIRE(synthesize_head(s.generic, seed, SynthHeadOptions{}, s.person));
  REQUIRE(placeholder_landmark_map(s.generic, 468, s.map));
  REQUIRE(attach_landmark_map(s.map, s.generic.mesh, 1e-3, s.landmarks));
  REQUIRE(make_synthetic_views(s.person, s.landmarks, seed, views, s.session));
  return s;
}

}  // namespace lk::test
