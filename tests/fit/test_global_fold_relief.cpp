// The smooth-surface guard's fold relief (global_fit.h): folds of the
// Modified Butterfly level 3 inside control faces that share a corner,
// which the guarded level 2 does not show (James's cheek, brow and eye-rim
// pairs; docs/journal.md "Folds that first appear on level 3"). What it
// does on folds is tested on James (tests/pipeline/test_face_scan.cpp):
// the step sheets' level-3 "folds" these tests counted until 22 Nov were
// rounding noise of flat sheets (raycast/self_intersection.h), and no
// synthetic sheet found since folds on level 3 alone.
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
#include <limits>
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

// The step sheets (step_sheets.h) with B stepping down to low_z.
using test::make_step_sheets;
using test::StepSheets;

GlobalFitOptions guarded_options() {
  GlobalFitOptions o;
  o.smooth_guard_level = 2;
  o.smooth_guard_stiffness = 4.0;  // as test_global_smooth_guard.cpp
  return o;
}

// The sheets fitted with two sets of options.
void fit_both(const StepSheets& c, const GlobalFitOptions& a, const GlobalFitOptions& b, TriMesh& out_a,
              GlobalFitResult& r_a, TriMesh& out_b, GlobalFitResult& r_b) {
  REQUIRE(fit_global(c.points, c.start, c.topo, c.terms(), a, out_a, r_a).ok());
  REQUIRE(fit_global(c.points, c.start, c.topo, c.terms(), b, out_b, r_b).ok());
}

}  // namespace

TEST_CASE("global fit: the fold relief leaves a fit without folds alone") {
  // B's data far above A: nothing folds, the relief must not move anything.
  const StepSheets c = make_step_sheets(0.1);
  GlobalFitOptions off = guarded_options();
  off.smooth_guard_relief_steps = 0;
  TriMesh out_off, out_on;
  GlobalFitResult r_off, r_on;
  fit_both(c, off, guarded_options(), out_off, r_off, out_on, r_on);
  const LevelPairs level3 = smooth_pairs(out_off, c.flat_mesh(), 3);
  INFO("level 3 without the relief: " << level3.all << " new pairs, " << level3.folds << " folds");
  CHECK(level3.all == 0);
  CHECK(r_on.relief_folds_before == 0);
  CHECK(r_on.relief_steps == 0);
  CHECK(r_on.fold_crease_edges.empty());
  CHECK(out_on.positions == out_off.positions);
  // The relief searches level 3 only where a triangle there turns against
  // the reference's (smooth_guard_relief_when_turned). B's step turns some
  // at its foot without folding; B without a step turns none, and then the
  // level is not searched. Searched or not, the fit is the same.
  GlobalFitOptions always_search = guarded_options();
  always_search.smooth_guard_relief_when_turned = false;
  for (const double low_z : {0.1, 0.2}) {
    const StepSheets sheets = make_step_sheets(low_z);
    TriMesh out_gated, out_searched;
    GlobalFitResult r_gated, r_searched;
    REQUIRE(fit_global(sheets.points, sheets.start, sheets.topo, sheets.terms(), guarded_options(), out_gated, r_gated)
                .ok());
    REQUIRE(fit_global(sheets.points, sheets.start, sheets.topo, sheets.terms(), always_search, out_searched,
                       r_searched)
                .ok());
    INFO("B's foot at z = " << low_z);
    CHECK(r_gated.relief_searched == (low_z < 0.2));
    CHECK(r_searched.relief_searched);
    CHECK(r_searched.relief_folds_before == 0);
    CHECK(out_searched.positions == out_gated.positions);
  }
  // The relief is part of the smooth-surface guard: off with it.
  GlobalFitOptions unguarded;
  unguarded.smooth_guard_level = 0;
  TriMesh out_unguarded;
  GlobalFitResult r_unguarded;
  REQUIRE(fit_global(c.points, c.start, c.topo, c.terms(), unguarded, out_unguarded, r_unguarded).ok());
  CHECK(r_unguarded.relief_folds_before == 0);
  CHECK(r_unguarded.relief_steps == 0);
}

TEST_CASE("global fit: a relief start tree is refitted and gives the fit its own tree would") {
  // GlobalFitTerms::relief_start_tree: a tree over the relief level's
  // triangles at other positions (here the start's level 3) is taken over
  // and refitted for the relief's first whole search; the fit, its counts
  // and the relief tree it hands out must be those of a fit that builds its
  // own. A tree over other triangles (level 2) is left alone.
  GlobalFitOptions o = guarded_options();
  o.smooth_guard_relief_when_turned = false;  // the relief searches level 3 whatever turns
  for (const double low_z : {0.1, 0.2}) {
    INFO("B's foot at z = " << low_z);
    const StepSheets c = make_step_sheets(low_z);
    TriMesh out_own, out_given;
    GlobalFitResult r_own, r_given;
    MeshBvh own_tree, handed_tree;
    REQUIRE(fit_global(c.points, c.start, c.topo, c.terms(), o, out_own, r_own, {}, &own_tree).ok());
    REQUIRE(r_own.relief_searched);
    MeshBvh start_tree, level2_tree;
    REQUIRE(build_bvh(test::butterfly_level(c.start, 3), start_tree).ok());
    REQUIRE(build_bvh(test::butterfly_level(c.start, 2), level2_tree).ok());
    GlobalFitTerms terms = c.terms();
    terms.relief_start_tree = &start_tree;
    REQUIRE(fit_global(c.points, c.start, c.topo, terms, o, out_given, r_given, {}, &handed_tree).ok());
    CHECK(start_tree.empty());  // taken over
    CHECK(out_given.positions == out_own.positions);
    CHECK(r_given.relief_folds_before == r_own.relief_folds_before);
    CHECK(r_given.relief_folds_after == r_own.relief_folds_after);
    CHECK(r_given.relief_steps == r_own.relief_steps);
    CHECK(r_given.smooth_crossing_after == r_own.smooth_crossing_after);
    // The handed-out tree: over the same triangles, fitted to the same
    // positions, and it finds the same pairs as the built one.
    REQUIRE(!handed_tree.empty());
    CHECK(handed_tree.triangles == own_tree.triangles);
    CHECK(handed_tree.positions == own_tree.positions);
    std::vector<std::array<int, 2>> pairs_own, pairs_handed;
    find_self_intersections(own_tree, pairs_own);
    find_self_intersections(handed_tree, pairs_handed);
    CHECK(pairs_handed == pairs_own);
    // Other triangles: not taken, the same fit.
    terms.relief_start_tree = &level2_tree;
    TriMesh out_level2;
    GlobalFitResult r_level2;
    REQUIRE(fit_global(c.points, c.start, c.topo, terms, o, out_level2, r_level2).ok());
    CHECK(!level2_tree.empty());
    CHECK(out_level2.positions == out_own.positions);
  }
}

TEST_CASE("global fit: the fold relief refuses bad options") {
  const StepSheets c = make_step_sheets(0.1);
  TriMesh out;
  GlobalFitResult r;
  GlobalFitOptions o = guarded_options();
  o.smooth_guard_relief_shares = {0.25, std::nan("")};
  CHECK(fit_global(c.points, c.start, c.topo, c.terms(), o, out, r).code == ErrorCode::InvalidInput);
  o.smooth_guard_relief_shares = {-0.5};
  CHECK(fit_global(c.points, c.start, c.topo, c.terms(), o, out, r).code == ErrorCode::InvalidInput);
  o = guarded_options();
  o.smooth_guard_relief_level = 9;
  CHECK(fit_global(c.points, c.start, c.topo, c.terms(), o, out, r).code == ErrorCode::InvalidInput);
  o = guarded_options();
  o.smooth_guard_crease_min_angle_deg = std::nan("");
  CHECK(fit_global(c.points, c.start, c.topo, c.terms(), o, out, r).code == ErrorCode::InvalidInput);
  o.smooth_guard_crease_min_angle_deg = 180;
  CHECK(fit_global(c.points, c.start, c.topo, c.terms(), o, out, r).code == ErrorCode::InvalidInput);
  o = guarded_options();
  o.smooth_guard_crease_trials = -1;
  CHECK(fit_global(c.points, c.start, c.topo, c.terms(), o, out, r).code == ErrorCode::InvalidInput);
  o = guarded_options();
  o.smooth_guard_crease_max_edges = -2;
  CHECK(fit_global(c.points, c.start, c.topo, c.terms(), o, out, r).code == ErrorCode::InvalidInput);
  // A NaN cap would let every pleat step through.
  for (const double cap : {std::nan(""), -0.1, std::numeric_limits<double>::infinity()}) {
    o = guarded_options();
    o.smooth_guard_pleat_max_move_edges = cap;
    CHECK(fit_global(c.points, c.start, c.topo, c.terms(), o, out, r).code == ErrorCode::InvalidInput);
  }
  o = guarded_options();
  o.smooth_guard_pleat_steps = -1;
  CHECK(fit_global(c.points, c.start, c.topo, c.terms(), o, out, r).code == ErrorCode::InvalidInput);
}

TEST_CASE("global fit: the pleat relief leaves a fit without pleats alone") {
  // B's step turns level-3 triangles at its foot (the relief searches the
  // level) but bends no edge of it by more than 90 deg: no pleat, nothing
  // to move. (Pleats themselves: the real Fran's cheek,
  // tests/pipeline/test_face_scan.cpp.)
  const StepSheets c = make_step_sheets(0.1);
  GlobalFitOptions off = guarded_options();
  off.smooth_guard_pleat_steps = 0;
  TriMesh out_off, out_on;
  GlobalFitResult r_off, r_on;
  fit_both(c, off, guarded_options(), out_off, r_off, out_on, r_on);
  CHECK(r_on.relief_searched);
  CHECK(r_on.pleats_before == 0);
  CHECK(r_on.pleat_steps == 0);
  CHECK(out_on.positions == out_off.positions);
}
