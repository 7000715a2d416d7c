// The multiresolution head of jeong2002 Sec. 5 (displaced Modified Butterfly
// hierarchy, one scalar normal displacement per vertex per level) and its
// local update for animation, Sec. 6.
//
// Evaluation, for l = 0 .. L (L = number of refinement levels):
//   N_l  = unit area-weighted vertex normals of the level-l mesh at P_l
//   P'_l = P_l + d_l * N_l                 (the level-l output mesh)
//   P_{l+1} = Butterfly(P'_l)              (P_0 = control positions)
// Arrays: P_l, P'_l, N_l, d_l are #V_l long; #V_0 = #control vertices,
// #V_{l+1} = #V_l + #E_l. Level-l triangles: control triangles for l = 0,
// levels[l-1].fine_triangles otherwise.
//
// Local update (Sec. 6): moving control vertices changes P only inside their
// support. Per level we precompute who depends on whom: a vertex's normal on
// its one-ring, a fine vertex on its stencil. update_control_vertices walks
// these sets level by level and re-evaluates exactly the same per-vertex
// arithmetic as evaluate(), so its result is bit-identical to a full
// recompute (exact equality, not a tolerance).
#pragma once
#include "common/progress.h"
#include "common/status.h"
#include "mesh/tri_mesh.h"
#include "subdiv/butterfly.h"

#include <cstdint>
#include <vector>

namespace lk {

// Compressed rows: row i is items[offsets[i] .. offsets[i+1]).
struct IndexRows {
  std::vector<int> offsets;  // #rows + 1
  std::vector<int> items;
  int rows() const { return offsets.empty() ? 0 : static_cast<int>(offsets.size()) - 1; }
};

// Per-level dependency sets for evaluation and local updates.
struct MultiresLevelLinks {
  IndexRows vertex_faces;   // #V_l rows: incident triangles, ascending (normal summation order)
  IndexRows normal_reach;   // #V_l rows: vertices whose normal depends on this vertex (itself + one-ring)
  IndexRows refine_reach;   // #V_l rows (l < L): level-(l+1) vertices whose P depends on this P'
};

// Evaluated positions of every level (a cache of evaluate()).
struct MultiresState {
  std::vector<std::vector<Vec3>> base;       // L+1 arrays: P_l (before displacement)
  std::vector<std::vector<Vec3>> normals;    // L+1 arrays: N_l
  std::vector<std::vector<Vec3>> displaced;  // L+1 arrays: P'_l, the level-l output mesh
  std::vector<std::vector<Vec3>> face_normals;  // L+1 arrays, #F_l: unnormalised (2 x area) normals at P_l
};

struct MultiresMesh {
  std::vector<Vec3> control;                       // #V_0 control positions (P_0)
  std::vector<Tri> control_triangles;              // #F_0
  std::vector<ButterflyLevel> levels;              // L refinement steps
  std::vector<std::vector<double>> displacements;  // L+1 arrays: d_l, #V_l each
  std::vector<MultiresLevelLinks> links;           // L+1
  MultiresState state;
  // Scratch of update_control_vertices (visit marks per level); not
  // thread-safe: one update at a time per mesh.
  struct Scratch {
    std::vector<std::vector<std::uint32_t>> base_mark, displaced_mark;  // L+1, #V_l each
    std::vector<std::vector<std::uint32_t>> face_mark;                  // L+1, #F_l each
    std::uint32_t stamp = 0;
  } scratch;

  int num_levels() const { return static_cast<int>(levels.size()); }  // L
  int num_vertices(int level) const {
    return level == 0 ? static_cast<int>(control.size()) : levels[level - 1].num_fine_vertices;
  }
  const std::vector<Tri>& triangles(int level) const {
    return level == 0 ? control_triangles : levels[level - 1].fine_triangles;
  }
};

// Builds the hierarchy over the control mesh (topology, stencils, links), with
// zero displacements, and evaluates it. Fails like build_butterfly_levels.
Status build_multires(const TriMesh& control, int levels, MultiresMesh& out);

// Full recompute of state from control + displacements (sizes must match).
Status evaluate(MultiresMesh& mesh);

// The level-l output mesh (P'_l with its triangles and normals N_l).
TriMesh level_mesh(const MultiresMesh& mesh, int level);

struct DisplacementOptions {
  // Radius of the cylinder around a vertex's normal line that collects scan
  // points. 0: half the mean edge length of the level being measured (the
  // footprint shrinks with the triangles), but at least twice the mean point
  // spacing sqrt(level area / #points), so fine levels still find data.
  double radius = 0.0;
  // Points farther than this along the normal are ignored (another sheet of
  // the surface, outliers). 0: twice the larger of the mean edge length of
  // the level and the radius.
  double max_distance = 0.0;
  // On levels >= 1 the line is also at most this many times the larger of
  // the level's mean edge and the radius long (each side): the coarser
  // levels already put the surface near the data, and a long line only
  // reaches the other sheet of thin features and costs search time (1 vs
  // off on the synthetic heads: same mean distance, a third fewer folded
  // triangles to limit, ~20 % fewer crossing pairs). 0: off.
  double fine_line_edges = 1.0;
  // When the cloud has normals (#P, as scanners give them), a point counts
  // only if its normal and the vertex normal agree: dot of the unit normals
  // above this. Thin features put two sheets facing away from each other
  // within a normal line (upper against lower lip, the two sides of an ear
  // rim, lid against socket); their points face the other way and are not
  // taken for the vertex's own sheet. Below -1: off.
  double min_normal_agreement = 0.0;
  // Fewer points than this in the cylinder means "no data": displacement 0,
  // and the subdivision surface stays smooth there (Sec. 5).
  int min_points = 3;
  // The line may cross the scan more than once (ears, lips); only points
  // within this fraction of max_distance of the crossing nearest to the
  // vertex are used. Their crossing with the line comes from a least-squares
  // quadric height field over the cylinder (one outlier-rejection pass),
  // falling back to their median below 10 points.
  double cluster_fraction = 0.25;
  // jeong2002 stores one displacement per vertex introduced on each level;
  // vertices inherited from the coarser level already lie on the data. Set
  // to re-measure them on every level as well.
  bool remeasure_coarse_vertices = false;
};

struct DisplacementStats {
  std::vector<int> measured;       // L+1: vertices with data, per level
  std::vector<int> candidates;     // L+1: vertices measured for, per level
  std::vector<double> mean_abs;    // L+1: mean |d| over measured vertices
  std::vector<double> max_abs;     // L+1
};

// Measures d_0 .. d_L from a point cloud (jeong2002 Sec. 5): before each
// refinement, the signed distance along N_l from each vertex to the surface
// the points sample near the normal line (see DisplacementOptions). Overwrites mesh.displacements and re-evaluates. Fails with
// Empty on an empty cloud, InvalidInput on non-finite points, Cancelled when
// progress asks to stop (the mesh is then left with zero displacements).
Status measure_displacements(const PointCloud& cloud, const DisplacementOptions& options, MultiresMesh& mesh,
                             DisplacementStats* stats = nullptr, const ProgressFn& progress = {});

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
  // Then the finest level's self-intersections (raycast/self_intersection.h):
  // the corners of both triangles of a crossing pair are shrunk the same way,
  // re-checking only around what moved, for at most this many rounds (0: off).
  // Pairs that cross on the smooth surface too are left alone (the smooth
  // Butterfly surface of a control mesh with sheets ~0.3 mm apart crosses
  // itself at eye and mouth corners; no shrinking undoes that). Synthetic
  // heads, seeds 1-2: ears 39-85 -> 0 pairs, lips 223-364 -> 172-244 (the
  // smooth surface has 84-152 there), mean distance +0.001 %, +0.15 s.
  int max_intersection_rounds = 40;
  // A pair whose triangles have no displacement on the finest level was
  // crossed by coarser levels: up to this many times their parents'
  // displacements are zeroed and everything is evaluated and searched again
  // (0: never; on the heads this cost 0.008 % of mean distance for little).
  int max_intersection_restarts = 0;
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
};

// Shrinks mesh.displacements as described above and re-evaluates the mesh.
// Fails with InvalidInput on mismatched arrays or options out of range
// (shrink not in [0, 1), negative ratios or counts).
Status limit_folds(MultiresMesh& mesh, const FoldLimitOptions& options = {}, FoldLimitStats* stats = nullptr);

// Bad triangles (see FoldLimitOptions) of level l of the evaluated mesh
// against the smooth hierarchy's level-l positions `smooth` (#V_l): flipped
// (normal turned over) and collapsed (area below the ratio, incl. zero area).
void count_bad_triangles(const MultiresMesh& mesh, int level, const std::vector<Vec3>& smooth,
                         const FoldLimitOptions& options, int& flipped, int& collapsed);

// The control positions refined without displacements: levels 0..L (#V_l each).
Status smooth_positions(const MultiresMesh& mesh, std::vector<std::vector<Vec3>>& out);

// A vertex set carried down the hierarchy: out[0] = control_mask (#V_0);
// a level-(l+1) vertex that is a level-l vertex keeps its membership, a new
// vertex on edge (a, b) belongs when both a and b do. out[l] is #V_l.
std::vector<std::vector<char>> propagate_vertex_mask(const MultiresMesh& mesh, const std::vector<char>& control_mask);

// How many vertices per level an update recomputed (locality, benchmarks).
struct UpdateFootprint {
  std::vector<int> base_changed;       // L+1: P_l changed (moved vertices on level 0)
  std::vector<int> displaced_changed;  // L+1: N_l and P'_l recomputed
};

// Moves control vertices (indices into control, with their new positions) and
// recomputes state only inside their support on every level; everything else
// is left untouched. A repeated index takes its last position. Fails with
// InvalidInput on mismatched sizes, an index out of range, a non-finite
// position, or a mesh that was not evaluated (nothing is changed then).
Status update_control_vertices(MultiresMesh& mesh, const std::vector<int>& moved,
                               const std::vector<Vec3>& new_positions, UpdateFootprint* footprint = nullptr);

}  // namespace lk
