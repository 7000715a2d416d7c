// Crossing pairs of a displaced level that do not cross on the smooth
// (undisplaced) level too: what the fold limiter's separation is for (the
// Butterfly corner rules fold a flat grid's corners over in its plane, and
// the limiter leaves pairs of the smooth surface alone). Shared by the fold
// limiter's tests.
#pragma once
#include "mesh/primitives.h"
#include "multires/fold_limit.h"
#include "multires/multires.h"
#include "raycast/self_intersection.h"

#include <catch2/catch.hpp>

namespace lk::test {

// Two unit icospheres (subdivided once) side by side, 0.2 apart: displaced
// outwards by more than 0.1 they cross each other.
inline TriMesh two_spheres_apart() {
  const TriMesh a = make_icosphere(1);
  TriMesh two = a;
  const int na = static_cast<int>(a.positions.size());
  for (const Vec3& p : a.positions) two.positions.push_back(p + Vec3(2.2, 0, 0));
  for (const Tri& t : a.triangles) two.triangles.push_back({t[0] + na, t[1] + na, t[2] + na});
  return two;
}

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
