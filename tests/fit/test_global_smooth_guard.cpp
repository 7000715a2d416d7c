// The global fit's smooth-surface guard (global_fit.h): the control mesh's
// Modified Butterfly surface must not cross itself where the control
// triangles do not.
#include "fit/closest_point.h"
#include "fit/global_fit.h"
#include "mesh/geometry.h"
#include "mesh/primitives.h"
#include "raycast/self_intersection.h"
#include "subdiv/butterfly.h"
#include "step_sheets.h"

#include <catch2/catch.hpp>
#include <algorithm>
#include <random>

using namespace lk;

namespace {

// Crossing pairs of the mesh refined `levels` times (no creases) that the
// reference's refinement does not have.
int smooth_pairs(const TriMesh& m, const TriMesh& reference, int levels) {
  const auto now = test::smooth_level_pairs(m, levels), before = test::smooth_level_pairs(reference, levels);
  int fresh = 0;
  for (const auto& p : now) fresh += !std::binary_search(before.begin(), before.end(), p);
  return fresh;
}

// The step sheets (step_sheets.h): B steps down at x = 0.5 from z = 0.3 to
// 0.005, just above A. The fitted control mesh does not cross itself, but
// B's Butterfly surface dips through A at the foot of the step: 118 pairs
// of smooth level 2, each between A and B.
using test::make_step_sheets;
using test::StepSheets;

}  // namespace

TEST_CASE("global fit: the smooth-surface guard keeps the Butterfly surface from crossing itself") {
  const StepSheets c = make_step_sheets(0.005, 0.3);
    const double diag = bounding_box(c.points).diagonal();

  GlobalFitOptions unguarded;
  unguarded.smooth_guard_level = 0;
  TriMesh out_unguarded;
  GlobalFitResult r_unguarded;
  REQUIRE(fit_global(c.points, c.start, c.topo, c.terms(), unguarded, out_unguarded, r_unguarded).ok());
  std::vector<std::array<int, 2>> control_pairs;
  REQUIRE(find_self_intersections(out_unguarded, control_pairs).ok());
  CHECK(control_pairs.empty());  // the control sheets do not cross ...
  const int unguarded_pairs = smooth_pairs(out_unguarded, c.flat_mesh(), 2);
  INFO("smooth level 2 without the guard: " << unguarded_pairs << " pairs");
  CHECK(unguarded_pairs >= 10);  // ... their Butterfly surface does (118 measured)
  CHECK(r_unguarded.smooth_guard_passes == 0);
  CHECK(r_unguarded.smooth_crossing_before == 0);

  GlobalFitOptions guarded;
  guarded.smooth_guard_level = 2;
  guarded.smooth_guard_stiffness = 4.0;  // 1.0 leaves 42 pairs after 2 passes: the data hold the step
  TriMesh out;
  GlobalFitResult r;
  REQUIRE(fit_global(c.points, c.start, c.topo, c.terms(), guarded, out, r).ok());
  REQUIRE(find_self_intersections(out, control_pairs).ok());
  CHECK(control_pairs.empty());
  CHECK(smooth_pairs(out, c.flat_mesh(), 2) == 0);
  CHECK(r.smooth_crossing_before == unguarded_pairs);
  CHECK(r.smooth_crossing_after == 0);
  CHECK(r.smooth_guard_passes >= 1);
  CHECK(r.smooth_guard_vertices > 0);
  for (const auto& it : r.iterations) CHECK(it.energy_after <= it.energy_before);
  // B still follows its data: the guard holds its step's shape, not the sheet.
  const double b_guarded = point_to_surface_stats(c.b_points, out, diag).mean_pct;
  const double b_unguarded = point_to_surface_stats(c.b_points, out_unguarded, diag).mean_pct;
  const double b_start = point_to_surface_stats(c.b_points, c.flat_mesh(), diag).mean_pct;  // flat: no step
  INFO("B's points: mean % " << b_guarded << " guarded, " << b_unguarded << " unguarded, " << b_start << " for the flat reference");
  CHECK(b_guarded < 0.6 * b_start);
  CHECK(b_guarded < 1.2 * b_unguarded);

  // Pairs with a control face of ignored vertices only (here sheet B's,
  // one face of every pair) are left alone.
  GlobalFitTerms ignoring = c.terms();
  ignoring.smooth_guard_ignored.assign(c.start.num_vertices(), 0);
  std::fill(ignoring.smooth_guard_ignored.begin() + c.b_first_vertex, ignoring.smooth_guard_ignored.end(), 1);
  TriMesh out_ignoring;
  GlobalFitResult r_ignoring;
  REQUIRE(fit_global(c.points, c.start, c.topo, ignoring, guarded, out_ignoring, r_ignoring).ok());
  CHECK(r_ignoring.smooth_crossing_before == 0);
  CHECK(r_ignoring.smooth_guard_passes == 0);
  CHECK(smooth_pairs(out_ignoring, c.flat_mesh(), 2) == unguarded_pairs);
}

TEST_CASE("global fit: the smooth-surface guard refuses ignore flags of the wrong size") {
  const StepSheets c = make_step_sheets();
  GlobalFitTerms terms = c.terms();
  terms.smooth_guard_ignored.assign(c.start.num_vertices() - 1, 0);
  TriMesh out;
  GlobalFitResult r;
  CHECK(fit_global(c.points, c.start, c.topo, terms, {}, out, r).code == ErrorCode::InvalidInput);
}

TEST_CASE("global fit: after_rounds sees the state the guard starts from, and ends the fit there when told") {
  // GlobalFitTerms::after_rounds (fit_head's ear refit decides there).
  // Going on must give the fit without the hook to the bit; stopping must
  // hand back the positions the hook saw, unguarded.
  const StepSheets c = make_step_sheets(0.005, 0.3);
  GlobalFitOptions guarded;
  guarded.smooth_guard_level = 2;
  guarded.smooth_guard_stiffness = 4.0;
  TriMesh plain_out;
  GlobalFitResult plain;
  REQUIRE(fit_global(c.points, c.start, c.topo, c.terms(), guarded, plain_out, plain).ok());
  REQUIRE(plain.smooth_guard_passes >= 1);  // else the guard has nothing to skip

  GlobalFitTerms on = c.terms();
  int calls = 0;
  std::vector<Vec3> seen;
  on.after_rounds = [&](const std::vector<Vec3>& positions) {
    ++calls;
    seen = positions;
    return true;
  };
  TriMesh on_out;
  GlobalFitResult on_r;
  REQUIRE(fit_global(c.points, c.start, c.topo, on, guarded, on_out, on_r).ok());
  CHECK(calls == 1);
  CHECK(on_out.positions == plain_out.positions);
  CHECK(on_r.iterations.size() == plain.iterations.size());
  CHECK(on_r.smooth_crossing_after == plain.smooth_crossing_after);
  CHECK_FALSE(on_r.stopped_after_rounds);
  // The hook saw the state the guard counted its pairs on.
  TriMesh at_hook = c.start;
  at_hook.positions = seen;
  CHECK(smooth_pairs(at_hook, c.flat_mesh(), 2) == plain.smooth_crossing_before);
  CHECK(plain.smooth_crossing_before > 0);

  GlobalFitTerms stop = c.terms();
  stop.after_rounds = [](const std::vector<Vec3>&) { return false; };
  TriMesh stop_out;
  GlobalFitResult stop_r;
  REQUIRE(fit_global(c.points, c.start, c.topo, stop, guarded, stop_out, stop_r).ok());
  CHECK(stop_r.stopped_after_rounds);
  CHECK(stop_out.positions == seen);
  CHECK(stop_r.smooth_guard_passes == 0);
  CHECK(stop_r.iterations.size() < plain.iterations.size());
}
