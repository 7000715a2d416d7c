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
  ButterflyCreases creases;                        // the control mesh's crease curves the levels were built with
  std::vector<std::vector<double>> displacements;  // L+1 arrays: d_l, #V_l each
  std::vector<MultiresLevelLinks> links;           // L+1
  // #V_L after measure_displacements (empty before): each vertex's data
  // support on the level that introduced it, 1 = measured with data all
  // round, between 0 and 1 = at the data's edge (support taper), 0 = no
  // data. Where it is below 1 the displacement is (partly) carried across
  // the data's edge rather than measured (DisplacementOptions::
  // edge_fade_control_edges). Not used by evaluation.
  std::vector<double> data_support;
  MultiresState state;
  // After an update limited to level l < L (see update_control_vertices), the
  // levels above l are out of date from this level on; -1: every level is
  // current. evaluate() and ensure_current() bring them back.
  int stale_from = -1;
  // Scratch of update_control_vertices (visit marks per level, and its work
  // lists, kept so that an update allocates nothing); sized by evaluate(), so
  // the first update after a build costs what the others do. Not
  // thread-safe: one update at a time per mesh.
  struct Scratch {
    std::vector<std::vector<std::uint32_t>> base_mark, displaced_mark;  // L+1, #V_l each
    std::vector<std::vector<std::uint32_t>> face_mark;                  // L+1, #F_l each
    std::uint32_t stamp = 0;
    std::vector<int> changed, reached, spread, targets;
    // An animation moves the same control vertices frame after frame: once
    // a moved list repeats, its work lists per level (faces, normals and
    // refinement targets, its support on every level without pruning) are
    // kept and replayed, without marks, gathering or sorting. The last few
    // lists are remembered (a pose and its way back, two expressions in
    // turn), the least recently used first to go.
    struct Plan {
      std::vector<int> moved;  // the moved list it is for, as given
      int top = -1;            // the highest level it reaches
      bool built = false;
      std::vector<std::vector<int>> faces, reached, targets;  // per level
    };
    std::vector<Plan> plans;  // most recently used first
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
// The same with crease curves (subdiv/butterfly.h): the two sides of a crease
// refine independently (eye and lip rims against their pockets).
Status build_multires(const TriMesh& control, const ButterflyCreases& creases, int levels, MultiresMesh& out);

// Full recompute of state from control + displacements (sizes must match).
Status evaluate(MultiresMesh& mesh);

// The level-l output mesh (P'_l with its triangles and normals N_l).
TriMesh level_mesh(const MultiresMesh& mesh, int level);

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
// recomputes state only inside their support on every level up to
// max_level (< 0 or >= L: all levels); everything else is left untouched. A
// repeated index takes its last position. Levels above max_level are then
// out of date (stale_from): an animation shown at level 1 need not pay for
// level 3. An update that reaches a stale level first re-evaluates the whole
// hierarchy, so its result is again bit-identical to a full recompute. Fails
// with InvalidInput on mismatched sizes, an index out of range, a
// non-finite position, or a mesh that was not evaluated (nothing is changed
// then).
Status update_control_vertices(MultiresMesh& mesh, const std::vector<int>& moved,
                               const std::vector<Vec3>& new_positions, UpdateFootprint* footprint = nullptr,
                               int max_level = -1);

// Re-evaluates the hierarchy if a limited update left levels out of date;
// call before reading state of a level above the last update's max_level.
Status ensure_current(MultiresMesh& mesh);

}  // namespace lk
