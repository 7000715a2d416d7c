// Crossing triangle pairs of a control mesh's SMOOTH (undisplaced) Butterfly
// level, with the head's crease curves, counted in one named region of the
// generic head (annotations carried down the levels): how many pairs touch
// it. Shared by the pipeline tests that check where sheets cross.
#pragma once
#include "head/head_model.h"
#include "multires/multires.h"
#include "pipeline/fit_quality.h"
#include "head/head_creases.h"
#include "raycast/self_intersection.h"

#include <catch2/catch.hpp>
#include <string>

namespace lk::test {

// With the given creases (a fit's MultiresMesh::creases, which may hold
// more than the head's curves: GlobalFitResult::fold_crease_edges).
inline int smooth_region_pairs(const TriMesh& control, const ButterflyCreases& creases, const HeadAnnotations& ann,
                               int level, const std::string& region) {
  MultiresMesh mr;
  REQUIRE(build_multires(control, creases, level, mr).ok());
  const TriMesh mesh = level_mesh(mr, level);
  std::vector<std::array<int, 2>> pairs;
  REQUIRE(find_self_intersections(mesh, pairs).ok());
  const auto it = ann.regions.find(region);
  REQUIRE(it != ann.regions.end());
  return count_pairs_touching(mr, level, pairs, it->second);
}

// With the generic head's crease curves, as the fit refines its levels
// (head_creases of the generic head: its rims, its canthi, its socket
// rings; corners picked on the fitted control could be other vertices).
inline int smooth_region_pairs(const TriMesh& control, const GenericHead& generic, int level,
                               const std::string& region) {
  return smooth_region_pairs(control, head_creases(generic.mesh, generic.annotations), generic.annotations, level,
                             region);
}

}  // namespace lk::test
