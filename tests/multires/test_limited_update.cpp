// Updates limited to a level (animation shown at a coarse level): the levels
// up to the limit must equal a full recompute bit for bit, the levels above
// are marked stale, and the next full update or ensure_current() brings the
// whole hierarchy back to exactly the full recompute.
#include "mesh/primitives.h"
#include "multires/multires.h"

#include <catch2/catch.hpp>

#include <random>

using namespace lk;

namespace {

int differing(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  if (a.size() != b.size()) return -1;
  int n = 0;
  for (size_t i = 0; i < a.size(); ++i) n += a[i] != b[i];
  return n;
}

MultiresMesh displaced_sphere(std::mt19937& rng) {
  MultiresMesh m;
  REQUIRE(build_multires(make_icosphere(2), 3, m).ok());
  std::normal_distribution<double> d(0, 0.02);
  for (auto& level : m.displacements)
    for (double& x : level) x = d(rng);
  REQUIRE(evaluate(m).ok());
  return m;
}

}  // namespace

TEST_CASE("multires: an update limited to a level matches a full recompute there, and later catches up", "[multires]") {
  std::mt19937 rng(7);
  MultiresMesh local = displaced_sphere(rng);
  const int L = local.num_levels();
  std::uniform_int_distribution<int> pick(0, static_cast<int>(local.control.size()) - 1);
  std::normal_distribution<double> step(0, 0.05);
  // Rounds at levels 1, 1, 2, 0, then 3 (full) and again limited.
  const int limits[] = {1, 1, 2, 0, -1, 1, 2};
  for (int round = 0; round < 7; ++round) {
    const int limit = limits[round];
    std::vector<int> moved;
    std::vector<Vec3> to;
    for (int i = 0; i < 5; ++i) {
      const int v = pick(rng);
      moved.push_back(v);
      to.push_back(local.control[v] + Vec3(step(rng), step(rng), step(rng)));
    }
    UpdateFootprint fp;
    REQUIRE(update_control_vertices(local, moved, to, &fp, limit).ok());
    MultiresMesh full = local;  // same control and displacements
    REQUIRE(evaluate(full).ok());
    const int top = limit < 0 ? L : limit;
    INFO("round " << round << " limit " << limit);
    for (int l = 0; l <= top; ++l) CHECK(differing(local.state.displaced[l], full.state.displaced[l]) == 0);
    if (top < L) {
      CHECK(local.stale_from >= 0);
      CHECK(local.stale_from <= top + 1);
      // Levels above the limit really are behind (the moves reach them).
      int behind = 0;
      for (int l = top + 1; l <= L; ++l) behind += differing(local.state.displaced[l], full.state.displaced[l]);
      CHECK(behind > 0);
      // The footprint says nothing was recomputed above the limit.
      for (int l = top + 1; l <= L; ++l) CHECK(fp.displaced_changed[l] == 0);
    } else {
      CHECK(local.stale_from == -1);
      for (int l = 0; l <= L; ++l) {
        INFO("level " << l);
        CHECK(differing(local.state.base[l], full.state.base[l]) == 0);
        CHECK(differing(local.state.normals[l], full.state.normals[l]) == 0);
        CHECK(differing(local.state.displaced[l], full.state.displaced[l]) == 0);
      }
    }
  }
  // ensure_current() after a limited update gives the full recompute.
  REQUIRE(local.stale_from >= 0);
  REQUIRE(ensure_current(local).ok());
  CHECK(local.stale_from == -1);
  MultiresMesh full = local;
  REQUIRE(evaluate(full).ok());
  for (int l = 0; l <= L; ++l) CHECK(differing(local.state.displaced[l], full.state.displaced[l]) == 0);
}
