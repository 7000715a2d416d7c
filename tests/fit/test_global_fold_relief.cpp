// The smooth-surface guard's fold relief (global_fit.h): folds of the
// Modified Butterfly level 3 inside control faces that share a corner,
// which the guarded level 2 does not show (James's cheek, brow and eye-rim
// pairs; docs/fit_real.md "Folds that first appear on level 3").
#include "fit/closest_point.h"
#include "fit/global_fit.h"
#include "mesh/geometry.h"
#include "mesh/primitives.h"
#include "raycast/self_intersection.h"
#include "subdiv/butterfly.h"
#include "step_sheets.h"

#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <random>

using namespace lk;

namespace {

// New crossing pairs of the mesh refined `levels` times (no creases) that
// the start's refinement does not have; `folds`: those whose two control
// faces share a corner.
struct LevelPairs {
  int all = 0, folds = 0;
};

LevelPairs smooth_pairs(const TriMesh& m, const TriMesh& start, int levels) {
  const auto now = test::smooth_level_pairs(m, levels), before = test::smooth_level_pairs(start, levels);
  const int per = 1 << (2 * levels);
  LevelPairs out;
  for (const auto& p : now) {
    if (std::binary_search(before.begin(), before.end(), p)) continue;
    ++out.all;
    bool shared = false;
    for (int a : m.triangles[p[0] / per])
      for (int b : m.triangles[p[1] / per]) shared |= a == b;
    out.folds += shared;
  }
  return out;
}

// The step sheets (step_sheets.h) with B's data stepping down to low_z.
// With the guard at level 2 the fitted control mesh's level 2 does not
// cross, but its level 3 folds in 15 pairs around B's step, all inside
// control faces that share a corner.
using test::make_step_sheets;
using test::StepSheets;

GlobalFitOptions guarded_options() {
  GlobalFitOptions o;
  o.smooth_guard_level = 2;
  o.smooth_guard_stiffness = 1.0;  // as test_global_smooth_guard.cpp
  return o;
}

}  // namespace

// Written against the defaults only, so it also builds on the code before
// the relief (897959c), where it fails: 15 folds on level 3.
TEST_CASE("global fit: the guarded fit's smooth level 3 folds less than level 2 alone allows") {
  const StepSheets c = make_step_sheets(0.005);
  TriMesh out;
  GlobalFitResult r;
  REQUIRE(fit_global(c.points, c.start, c.topo, {}, guarded_options(), out, r).ok());
  const LevelPairs level2 = smooth_pairs(out, c.start, 2), level3 = smooth_pairs(out, c.start, 3);
  INFO("level 2: " << level2.all << " new pairs; level 3: " << level3.all << " (" << level3.folds << " folds)");
  CHECK(level2.all == 0);
  CHECK(level3.folds <= 10);  // 15 without the relief
}

TEST_CASE("global fit: the fold relief takes out level-3 folds the level-2 guard does not see") {
  const StepSheets c = make_step_sheets(0.005);
  const double diag = bounding_box(c.points).diagonal();

  GlobalFitOptions off = guarded_options();
  off.smooth_guard_relief_steps = 0;
  TriMesh out_off;
  GlobalFitResult r_off;
  REQUIRE(fit_global(c.points, c.start, c.topo, {}, off, out_off, r_off).ok());
  const LevelPairs off2 = smooth_pairs(out_off, c.start, 2), off3 = smooth_pairs(out_off, c.start, 3);
  INFO("relief off: level 2 " << off2.all << ", level 3 " << off3.all << " (" << off3.folds << " folds)");
  CHECK(off2.all == 0);           // the guarded level is clean ...
  CHECK(off3.folds >= 10);        // ... its level 3 folds (16 measured; 15 before the filtered orientations)
  CHECK(off3.folds == off3.all);  // inside faces that share a corner
  CHECK(r_off.relief_steps == 0);
  CHECK(r_off.relief_vertices == 0);

  TriMesh out;
  GlobalFitResult r;
  REQUIRE(fit_global(c.points, c.start, c.topo, {}, guarded_options(), out, r).ok());
  const LevelPairs on2 = smooth_pairs(out, c.start, 2), on3 = smooth_pairs(out, c.start, 3);
  INFO("relief on: level 2 " << on2.all << ", level 3 " << on3.all << " (" << on3.folds << " folds); relief "
                             << r.relief_folds_before << " -> " << r.relief_folds_after << " in " << r.relief_steps
                             << " steps, " << r.relief_vertices << " vertices");
  CHECK(r.relief_folds_before == off3.folds);
  CHECK(r.relief_folds_after == on3.folds);  // counted on the whole level, not estimated
  CHECK(on3.folds <= off3.folds - 5);        // 16 -> 9 measured
  CHECK(on2.all == 0);
  CHECK(r.relief_steps > 0);
  CHECK(r.relief_vertices > 0);
  CHECK(r.relief_vertices <= 40);  // local: 31 of the 882 control vertices measured
  std::vector<std::array<int, 2>> control_pairs;
  REQUIRE(find_self_intersections(out, control_pairs).ok());
  CHECK(control_pairs.empty());
  CHECK(r.turned_after == 0);
  // Only the relieved vertices moved, and B still follows its data.
  int moved = 0;
  for (int v = 0; v < out.num_vertices(); ++v) moved += (out.positions[v] - out_off.positions[v]).norm() > 0;
  CHECK(moved == r.relief_vertices);
  const double b_on = point_to_surface_stats(c.b_points, out, diag).mean_pct;
  const double b_off = point_to_surface_stats(c.b_points, out_off, diag).mean_pct;
  INFO("B's points: mean % " << b_on << " with the relief, " << b_off << " without");
  CHECK(b_on < 1.1 * b_off);
}

TEST_CASE("global fit: the fold relief leaves a fit without folds alone") {
  // B's data far above A: nothing folds, the relief must not move anything.
  const StepSheets c = make_step_sheets(0.1);
  GlobalFitOptions off = guarded_options();
  off.smooth_guard_relief_steps = 0;
  TriMesh out_off, out_on;
  GlobalFitResult r_off, r_on;
  REQUIRE(fit_global(c.points, c.start, c.topo, {}, off, out_off, r_off).ok());
  REQUIRE(fit_global(c.points, c.start, c.topo, {}, guarded_options(), out_on, r_on).ok());
  const LevelPairs level3 = smooth_pairs(out_off, c.start, 3);
  INFO("level 3 without the relief: " << level3.folds << " folds");
  if (level3.folds == 0) {
    CHECK(r_on.relief_folds_before == 0);
    CHECK(r_on.relief_steps == 0);
    CHECK(out_on.positions == out_off.positions);
  } else {
    // Folds there too: the relief may only lower their count.
    CHECK(smooth_pairs(out_on, c.start, 3).folds < level3.folds);
  }
  // The relief is part of the smooth-surface guard: off with it.
  GlobalFitOptions unguarded;
  unguarded.smooth_guard_level = 0;
  TriMesh out_unguarded;
  GlobalFitResult r_unguarded;
  REQUIRE(fit_global(c.points, c.start, c.topo, {}, unguarded, out_unguarded, r_unguarded).ok());
  CHECK(r_unguarded.relief_folds_before == 0);
  CHECK(r_unguarded.relief_steps == 0);
}

TEST_CASE("global fit: the fold relief refuses bad options") {
  const StepSheets c = make_step_sheets(0.1);
  TriMesh out;
  GlobalFitResult r;
  GlobalFitOptions o = guarded_options();
  o.smooth_guard_relief_shares = {0.25, std::nan("")};
  CHECK(fit_global(c.points, c.start, c.topo, {}, o, out, r).code == ErrorCode::InvalidInput);
  o.smooth_guard_relief_shares = {-0.5};
  CHECK(fit_global(c.points, c.start, c.topo, {}, o, out, r).code == ErrorCode::InvalidInput);
  o = guarded_options();
  o.smooth_guard_relief_level = 9;
  CHECK(fit_global(c.points, c.start, c.topo, {}, o, out, r).code == ErrorCode::InvalidInput);
}
