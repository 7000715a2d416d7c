// The fold limiter can separate crossings on every level, not only the
// finest (FoldLimitOptions::separate_coarser_levels). A level-0 displacement that
// pushes one sheet through another is refined into every finer level; the
// finest level's separation alone leaves the coarser output levels crossed
// (on the menpo3d James scan levels 0-2 crossed in 25 / 235 / 627 pairs at
// the ears, docs/journal.md).
#include "multires/fold_limit.h"
#include "multires/multires.h"
#include "displaced_crossings.h"
#include "raycast/self_intersection.h"

#include <catch2/catch.hpp>

#include <cmath>

using namespace lk;

namespace {

// Two square grids n x n with spacing h, facing each other like two lips:
// sheet A in z = 0 facing +z, sheet B in z = gap facing -z. Returns the
// index of A's first vertex (0) and B's (n * n).
TriMesh facing_sheets(int n, double h, double gap) {
  TriMesh m;
  for (int sheet = 0; sheet < 2; ++sheet) {
    const int base = static_cast<int>(m.positions.size());
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        // Jittered (fixed pattern): exact grids make coplanar ties.
        const double jx = 0.1 * h * std::sin(12.9898 * i + 78.233 * j + sheet);
        const double jy = 0.1 * h * std::sin(39.3468 * i + 11.135 * j + 2 * sheet);
        const double jz = 0.02 * gap * std::sin(73.156 * i + 52.235 * j + 3 * sheet);
        m.positions.emplace_back(i * h + jx, j * h + jy, sheet * gap + jz);
      }
    for (int j = 0; j + 1 < n; ++j)
      for (int i = 0; i + 1 < n; ++i) {
        const int a = base + j * n + i, b = a + 1, c = a + n, d = c + 1;
        if (sheet == 0) {
          m.triangles.push_back({a, b, d});
          m.triangles.push_back({a, d, c});
        } else {  // reversed: normal -z
          m.triangles.push_back({a, d, b});
          m.triangles.push_back({a, c, d});
        }
      }
  }
  return m;
}

// Sheet A's interior pushed 4 mm up on level 0, through sheet B 2 mm above.
MultiresMesh pushed_through(int levels) {
  const int n = 8;
  const double h = 0.01;
  MultiresMesh mr;
  REQUIRE(build_multires(facing_sheets(n, h, 0.002), levels, mr).ok());
  for (int j = 2; j < n - 2; ++j)
    for (int i = 2; i < n - 2; ++i) mr.displacements[0][j * n + i] = 0.004;
  // Some detail of its own on the finer levels, so they have something to shrink.
  for (int l = 1; l <= levels; ++l)
    for (int v = 0; v < mr.num_vertices(l); ++v) mr.displacements[l][v] = 0.0001;
  REQUIRE(evaluate(mr).ok());
  return mr;
}

}  // namespace

TEST_CASE("fold limit: a sheet pushed through another on level 0 crosses on no level afterwards") {
  const int L = 3;
  MultiresMesh before = pushed_through(L);
  // The setup does what it says: every level crosses where the smooth one does not.
  for (int l = 0; l <= L; ++l) CHECK(test::displaced_crossing_pairs(before, l) > 0);

  SECTION("with the coarser levels separated") {
    MultiresMesh mr = before;
    FoldLimitOptions o;
    o.separate_coarser_levels = true;
    FoldLimitStats stats;
    REQUIRE(limit_folds(mr, o, &stats).ok());
    for (int l = 0; l <= L; ++l) {
      INFO("level " << l);
      CHECK(test::displaced_crossing_pairs(mr, l) == 0);
    }
    REQUIRE(stats.coarse_intersections_found.size() == static_cast<size_t>(L));
    CHECK(stats.coarse_intersections_found[0] > 0);
    for (int l = 0; l < L; ++l) CHECK(stats.coarse_intersections_left[l] == 0);
    CHECK(stats.remaining_bad == 0);
    INFO("level-0 displacement at the bump " << mr.displacements[0][3 * 8 + 3]);
    // Separated, not flattened: sheet A's interior still bulges towards B
    // (the level-0 displacement is shrunk to below the gap, not dropped).
    CHECK(mr.displacements[0][3 * 8 + 3] > 0);
    CHECK(mr.displacements[0][3 * 8 + 3] < 0.002);
  }
  SECTION("only the finest level separated (the old behaviour): the coarser output levels stay crossed") {
    MultiresMesh mr = before;
    FoldLimitOptions o;
    o.separate_coarser_levels = false;
    REQUIRE(limit_folds(mr, o).ok());
    CHECK(test::displaced_crossing_pairs(mr, 1) > 0);
  }
}

TEST_CASE("fold limit: coarser-level separation gives the same result incrementally and in full") {
  MultiresMesh fast = pushed_through(2), full = pushed_through(2);
  FoldLimitOptions o;
  o.separate_coarser_levels = true;
  FoldLimitStats fs, ss;
  REQUIRE(limit_folds(fast, o, &fs).ok());
  o.incremental = false;
  REQUIRE(limit_folds(full, o, &ss).ok());
  CHECK(fs.coarse_intersections_found == ss.coarse_intersections_found);
  CHECK(fs.coarse_intersections_left == ss.coarse_intersections_left);
  for (int l = 0; l <= 2; ++l) CHECK(fast.displacements[l] == full.displacements[l]);
}

TEST_CASE("fold limit: the last resort puts the smooth surface over crossings nothing else separated") {
  const int L = 3;
  const MultiresMesh before = pushed_through(L);
  // Everything that would separate the pushed sheet on the way is off: the
  // finest level's pairs are all crossed by level 0, and shrinking their
  // own corners cannot undo that.
  FoldLimitOptions o;
  o.separate_coarser_levels = false;
  o.crossing_corners_to_smooth = false;
  o.crossing_parents_to_smooth = false;
  o.second_pass = false;

  MultiresMesh off = before;
  o.smooth_region_rings = -1;
  REQUIRE(limit_folds(off, o).ok());
  const size_t left_without = test::displaced_crossing_pairs(off, L);
  REQUIRE(left_without > 0);

  MultiresMesh mr = before;
  o.smooth_region_rings = 1;
  FoldLimitStats stats;
  REQUIRE(limit_folds(mr, o, &stats).ok());
  CHECK(test::displaced_crossing_pairs(mr, L) == 0);
  CHECK(stats.smoothed_pairs_before == static_cast<int>(left_without));
  CHECK(stats.smoothed_pairs_after == 0);
  CHECK(stats.remaining_bad == 0);
  // Level 0 pushed the sheet through: only the smooth surface from level 0
  // on separates it.
  CHECK(stats.smoothed_from_level == 0);
  CHECK(mr.displacements[0][3 * 8 + 3] == 0);
  // Local: the faces around the pairs, not the whole mesh; the finer
  // levels' detail elsewhere is kept as it was.
  CHECK(stats.smoothed_control_faces > 0);
  CHECK(stats.smoothed_control_faces < static_cast<int>(mr.control_triangles.size()));
  int kept = 0;
  for (size_t v = 0; v < mr.displacements[L].size(); ++v) kept += mr.displacements[L][v] == off.displacements[L][v] && mr.displacements[L][v] != 0;
  CHECK(kept > 0);
  // The state is the evaluation of what was kept, and the pairs handed on
  // describe it.
  MultiresMesh again = mr;
  REQUIRE(evaluate(again).ok());
  CHECK(again.state.displaced[L] == mr.state.displaced[L]);
  const auto* known = finest_pairs_of(stats, mr.state.displaced[L]);
  REQUIRE(known != nullptr);
  CHECK(known->empty());
}
