// Crossing triangle pairs of a control mesh's SMOOTH (undisplaced) Butterfly
// level, with the head's crease curves, counted in one named region of the
// generic head (annotations carried down the levels): how many pairs touch
// it. Shared by the pipeline tests that check where sheets cross.
#pragma once
#include "head/head_model.h"
#include "multires/multires.h"
#include "pipeline/fit_quality.h"
#include "raycast/self_intersection.h"

#include <catch2/catch.hpp>
#include <string>

namespace lk::test {

inline int smooth_region_pairs(const TriMesh& control, const HeadAnnotations& ann, int level,
                               const std::string& region) {
  ButterflyCreases creases;
  for (const CreaseCurve& c : ann.creases) add_crease_polyline(c.vertices, c.closed, creases);
  MultiresMesh mr;
  REQUIRE(build_multires(control, creases, level, mr).ok());
  const TriMesh mesh = level_mesh(mr, level);
  std::vector<std::array<int, 2>> pairs;
  REQUIRE(find_self_intersections(mesh, pairs).ok());
  const auto it = ann.regions.find(region);
  REQUIRE(it != ann.regions.end());
  return count_pairs_touching(mr, level, pairs, it->second);
}

}  // namespace lk::test
