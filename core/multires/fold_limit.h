// Keeping the displaced hierarchy a clean surface: no turned-over or
// collapsed triangles, and sheets that do not cross on the finest level.
// Not in jeong2002 (its Sec. 5 displacements are trusted as measured).
#pragma once
#include "common/status.h"
#include "multires/multires.h"
#include "raycast/bvh.h"

#include <array>
#include <cstdint>
#include <vector>

namespace lk {

// Fold-safe limiting (not in jeong2002, whose Sec. 5 displacements are
// trusted as measured). Where the normal line of a vertex reaches the other
// side of a thin or concave feature (lip and eye corners, nostrils, the
// groove behind an ear) the measured displacement turns triangles over. A
// triangle of level l is bad when, compared with the same triangle of the
// smooth hierarchy (the Butterfly levels of the control mesh with every
// displacement 0), its normal turned by more than acos(min_normal_cos) or its
// area fell below min_area_ratio of the smooth one. Level by level, coarse to
// fine, the displacements of a bad triangle's corners on its own level are
// scaled by `shrink` (not dropped: the rest of the detail stays), and the
// level is re-evaluated, until it has no bad triangle. A corner shrunk
// max_shrinks times is set to 0. A bad triangle whose corners carry no
// displacement on its level was bent by the coarser levels: then its corners
// get the displacement that puts them on the smooth surface along their
// normal (pockets and holes have no data anyway), and if that is not enough
// the displacements of the parent triangle's corners (then of its
// neighbourhood, the Butterfly stencil of its edges) on the level above are
// set to 0 (at once: every step up re-evaluates the levels below), and
// evaluation resumes there.
// All displacements 0 is the smooth surface itself, so the loop ends with no
// bad triangle unless max_rounds runs out (remaining_bad says). The same
// shrinking then separates sheets that cross on the finest level (lips, ear
// rims, eyelids against the eye pockets).
struct FoldLimitOptions {
  double min_normal_cos = 0.0;  // 0: only triangles turned over by more than 90 degrees
  double min_area_ratio = 0.02; // displaced / smooth area below this: collapsed
  double shrink = 0.5;          // factor per round
  int max_shrinks = 8;          // 0.5^8 = 1/256 of the measured value, then 0
  int max_rounds = 200;         // over all levels, against endless loops
  bool shrink_coarser_levels = true;  // false: a bad triangle without displacement of its own stays bad
  // Before the folds: the crossings of every level but the finest, coarse to
  // fine, are separated the same way (see max_intersection_rounds), each
  // level before it is refined into the next (false: only the finest):
  // fewer level-3 pairs on the real scans, Table 1 within their noise.
  bool separate_coarser_levels = true;
  // Each level's displacements were measured from the coarser levels as
  // they were: where the fold pass shrinks a level-l displacement (its
  // crossings' separation, or a restart for a finer fold), every finer level
  // over that vertex's footprint (tens of mm on level 0) used to move with
  // it, crossing or not. With this, the finer vertices refined from what
  // moved keep the positions they had (their displacement re-taken along
  // their normal over the new base, where they carry one), and are let go
  // (back to the displacement as measured, over the new base) the first
  // time a fold or a crossing of their own level needs them to move;
  // shrinking follows from there. Without it the separation cost the
  // scans accuracy (figures: docs/design/subdiv_multires.md).
  bool keep_finer_heights = true;
  // Then the finest level's self-intersections (raycast/self_intersection.h):
  // the corners of both triangles of a crossing pair are shrunk the same way,
  // re-checking only around what moved, for at most this many rounds (0: off).
  // Pairs that cross on the smooth surface too are left alone (the smooth
  // Butterfly surface of a control mesh with sheets ~0.3 mm apart crosses
  // itself at eye and mouth corners; no shrinking undoes that).
  int max_intersection_rounds = 40;
  // A pair whose triangles have no displacement on the finest level was
  // crossed by coarser levels: up to this many times their parents'
  // displacements are zeroed and everything is evaluated and searched again
  // (0: never; on the heads this cost 0.008 % of mean distance for little).
  int max_intersection_restarts = 0;
  // A crossing pair whose corners carry no displacement on the finest level
  // (crossed by coarser levels) but does not cross on the smooth surface:
  // its corners get the displacement that puts them on the smooth surface
  // along their normals, and are not shrunk back (false: left crossing,
  // unless restarts are allowed). On the synthetic heads this took the ears'
  // last crossings away without a full re-evaluation.
  bool crossing_corners_to_smooth = true;
  // And when that is not enough (the level above moved the vertices
  // sideways), the corners of the pair's parent triangle on the level above
  // go onto the smooth surface, and the two finest levels are re-evaluated.
  bool crossing_parents_to_smooth = true;
  // The closing fold pass (below) may shrink corners back into a crossing:
  // this many times, the crossings around what it moved are separated again
  // and the fold pass repeated (searches are local, not full).
  int separation_repeats = 2;
  // Vertices on crease curves (MultiresMesh::creases, e.g. the eye rims and
  // lip lines) keep no displacement on any level: their normal averages the
  // two sheets meeting at the crease (skin and pocket), so it is no surface
  // normal, and measuring along it reaches the other lip. The rims then
  // follow the fitted control mesh's crease curves.
  bool undisplaced_creases = true;
  // Each visit of a level recomputes only what changed since the last one
  // (normals, bad triangles, the next level's base, the BVH's boxes); false
  // evaluates, scans and refits everything on every visit. Same result bit
  // for bit (tests/multires/test_fold_incremental.cpp compares the two),
  // for less CPU per fit.
  bool incremental = true;
  // The separation gives a finest-level pair up when no corner of it can
  // move (its corners and its parents' are on the smooth surface); later
  // restarts and fold passes move the base under those heights, so such a
  // pair can cross again unseen. When one does, the whole limiter runs once
  // more on its result (nothing held, every pair seen from the start) and
  // that is kept if it leaves fewer crossing pairs in all (the demo
  // sample's last ear crossings).
  bool second_pass = true;
  // Last resort, after all the above: finest-level pairs still crossing
  // that the smooth surface does not cross (coarser levels bent them, and
  // no corner or parent could be moved off) get the smooth surface over
  // their control faces: every displacement of levels k..L there is set to
  // 0. Tries go from the least change to the most: k = L-1 down to 0, each
  // for the pairs' own faces and then up to this many rings of control
  // faces around them (< 0: off). The first try that leaves none of those
  // pairs and turns or collapses none of the triangles it moved is kept;
  // otherwise the one with the fewest pairs in all, if fewer than before
  // (the smooth surface's own crossings count: zeroing can bring them
  // back). Two rings: a face capture's hair-covered ear kept pairs with
  // one; the synthetic seeds never reach the second (figures:
  // docs/design/subdiv_multires.md).
  int smooth_region_rings = 2;
};

struct FoldLimitStats {
  std::vector<int> bad_found;  // L+1: bad triangles found on the first check of each level
  std::vector<int> shrunk;     // L+1: distinct vertices whose displacement was shrunk
  std::vector<int> zeroed;     // L+1: of those, set to 0
  int rounds = 0;              // shrink rounds over all levels
  int remaining_bad = 0;       // bad triangles left on the finest level (0 unless max_rounds ran out)
  int corrected = 0;           // zero displacements set to reach the smooth surface
  int restarts = 0;            // evaluations resumed on a coarser level
  int intersections_found = 0; // crossing triangle pairs on the finest level before separating
  int intersections_left = 0;  // after (0 unless rounds ran out or the smooth surface itself crosses)
  int crease_zeroed = 0;       // displacements of crease vertices set to 0 (all levels)
  int crossing_corrected = 0;  // finest-level corners of crossing pairs put on the smooth surface
  std::vector<int> coarse_intersections_found;  // L: crossing pairs of levels 0..L-1 before separating them
  std::vector<int> coarse_intersections_left;   // L: after (incl. pairs that cross on the smooth level too)
  // second_pass: finest-level crossing pairs before and after it (0 / 0:
  // it did not run), and whether it was kept (then the counts above are the
  // second pass's, rounds the sum of both).
  int second_pass_before = 0, second_pass_after = 0;
  bool second_pass_kept = false;
  // smooth_region_rings: crossing pairs (not crossing on the smooth
  // surface) it found, the control faces it smoothed (0: did not run or was
  // not kept) and the pairs left in all after it.
  // smoothed_from_level: the coarsest level whose displacements it set to 0
  // (-1: none).
  int smoothed_pairs_before = 0, smoothed_control_faces = 0, smoothed_pairs_after = 0, smoothed_from_level = -1;
  // The finest level's crossing pairs as limit_folds left it (#pairs by 2,
  // a < b, sorted: find_self_intersections of mesh.state.displaced[L]),
  // when it searched them whole anyway (the second pass or the last resort
  // ran, i.e. whenever max_intersection_rounds > 0 and smooth_region_rings
  // >= 0, the defaults); the quality
  // report (pipeline/fit_quality.h) takes them instead of searching again.
  // finest_pairs_of says whether they still describe the given positions
  // (an edit after the fit moves the level).
  bool finest_pairs_known = false;
  // How the finest level's pairs were found for the above and for the
  // separation's start: whole searches, and the pairs already known at the
  // same positions (incremental runs: those of the last whole search, kept
  // up to date by the separation's searches around what it moved).
  int finest_whole_searches = 0, finest_known_reused = 0;
  std::vector<std::array<int, 2>> finest_pairs;
  std::uint64_t finest_pairs_fingerprint = 0;  // positions_fingerprint of the level searched
};

// FNV-1a over the bytes of the positions: tells whether a level moved since
// its crossing pairs were searched.
std::uint64_t positions_fingerprint(const std::vector<Vec3>& positions);

// The limiter's finest-level pairs (FoldLimitStats::finest_pairs) when they
// were searched on exactly these positions; null otherwise.
const std::vector<std::array<int, 2>>* finest_pairs_of(const FoldLimitStats& stats,
                                                       const std::vector<Vec3>& finest_positions);

// The crossing pairs of finest (the finest level as the limiter left it or
// moved since): the limiter's own (finest_pairs_of) when they still describe
// its positions, else a whole search (find_self_intersections).
Status finest_crossing_pairs(const FoldLimitStats& stats, const TriMesh& finest,
                             std::vector<std::array<int, 2>>& pairs);

// Shrinks mesh.displacements as described above and re-evaluates the mesh.
// Fails with InvalidInput on mismatched arrays or options out of range
// (shrink not in [0, 1), negative ratios or counts).
// finest_tree (optional): a tree over the finest level's triangles, its
// boxes at any positions (e.g. fit_global's relief_tree): taken over and
// refitted instead of building one. A tree over other triangles is left
// alone. The crossing searches find the same pairs on any tree, so the
// result is the same either way. Unless it was such a tree, on return it
// holds the limiter's tree over the finest level, its boxes refitted to the
// level's final positions (when there is one: max_intersection_rounds > 0),
// for closest points on the result (fit_head's Table 1 figures of the
// subdivision).
Status limit_folds(MultiresMesh& mesh, const FoldLimitOptions& options = {}, FoldLimitStats* stats = nullptr,
                   MeshBvh* finest_tree = nullptr);

// Bad triangles (see FoldLimitOptions) of level l of the evaluated mesh
// against the smooth hierarchy's level-l positions `smooth` (#V_l): flipped
// (normal turned over) and collapsed (area below the ratio, incl. zero area).
void count_bad_triangles(const MultiresMesh& mesh, int level, const std::vector<Vec3>& smooth,
                         const FoldLimitOptions& options, int& flipped, int& collapsed);

// Vertices on the crease curves of each level: L+1 masks, #V_l each (1 on a
// tagged control edge's endpoints and every vertex refined from one).
std::vector<std::vector<char>> crease_vertex_masks(const MultiresMesh& mesh);

// The control positions refined without displacements: levels 0..L (#V_l each).
Status smooth_positions(const MultiresMesh& mesh, std::vector<std::vector<Vec3>>& out);

}  // namespace lk
