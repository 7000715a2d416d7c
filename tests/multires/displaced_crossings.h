// Crossing pairs of a displaced level that do not cross on the smooth
// (undisplaced) level too: what the fold limiter's separation is for (the
// Butterfly corner rules fold a flat grid's corners over in its plane, and
// the limiter leaves pairs of the smooth surface alone). Shared by the fold
// limiter's tests.
#pragma once
#include "multires/fold_limit.h"
#include "multires/multires.h"
#include "raycast/self_intersection.h"

#include <catch2/catch.hpp>

namespace lk::test {

inline size_t displaced_crossing_pairs(const MultiresMesh& mr, int level) {
  std::vector<std::vector<Vec3>> smooth;
  REQUIRE(smooth_positions(mr, smooth).ok());
  std::vector<std::array<int, 2>> pairs;
  REQUIRE(find_self_intersections(level_mesh(mr, level), pairs).ok());
  size_t n = 0;
  for (const auto& p : pairs)
    n += !mesh_triangles_cross(smooth[level], mr.triangles(level)[p[0]], mr.triangles(level)[p[1]]);
  return n;
}

}  // namespace lk::test
