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
