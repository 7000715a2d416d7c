// Global control-mesh fitting: jeong2002 Sec. 4.3.
//
//   E_global = E_dist + lambda E_smooth + mu E_binding + nu E_constraint
//
// minimized over all control vertex positions X (#V by 3). Each iteration
// projects the scan points onto the current mesh (exact closest points, see
// closest_point.h), linearizes E_dist as point-to-plane distance of the
// barycentric combination of the projecting triangle's corners (Hoppe et al.
// 1994; Marschner et al. 2000) plus a small point-to-point share for
// conditioning, and solves the resulting sparse 3#V by 3#V normal equations
// with a sparse LDL^T by 3x3 vertex blocks (block_ldlt.h), whose factor
// later iterations reuse as the preconditioner of conjugate gradients while
// the matrix changes little. A backtracking step on the TRUE energy (true
// closest-point distances) makes every iteration decrease E_global, which
// the returned per-iteration energies show.
//
// Normalization (so the weights do not depend on scan density or mesh size):
//   E_dist       = 1/#S  sum_p min(d_p, tau)^2          over the point set S
//   E_smooth     = 1/#V  sum_v |L(v) - L0(v)|^2          umbrella operator L
//   E_binding    = 1/#V  sum_e |(x_a - x_b) - r_e|^2     binding edges
//   E_constraint = 1/#V  sum_c |x_c - x~_c|^2            constrained vertices
// so lambda = 1 weighs a vertex's smoothness like the data of an average
// vertex. tau trims outliers (points farther than a few times the median
// residual count as tau, and do not pull).
//
// Deviations from the paper, chosen on purpose:
// - L0(v) is the umbrella vector of the generic head as aligned (the
//   reference mesh, below; without one, of the input) when
//   preserve_rest_shape is set (default): in holes the surface keeps the
//   generic head's shape instead of shrinking towards its one-ring
//   centroids (the paper's pure umbrella, L0 = 0, is available).
// - r_e is the edge vector before global fitting. For the virtual lip edges,
//   whose ends coincide in the generic head, that is the paper's sum of l_e^2;
//   for mesh edges (behind the ears) binding the edge VECTOR keeps the ear's
//   shape without pulling it onto the skull as a pure length penalty would.
// - The smoothing weight decreases over rounds (as Hoppe's spring constant):
//   rounds on a random subsample of the scan, from strong to weak smoothing,
//   then final_iterations on all points.
// - Fold guard (not in the paper). Where the data is poor or misleading
//   (hair over the ears, features the alignment put a centimetre off,
//   slivers at the eye corners), point-to-plane distances let vertices slide
//   past their neighbours and turn triangles over (on a real face capture,
//   a crease band from the eye corners to the ears). E_smooth cannot
//   prevent it: turning a thin triangle moves its
//   corners by a millimetre, which the umbrella term barely notices, and a
//   lambda strong enough would flatten the face everywhere. So every step is
//   checked instead: no triangle may come to face against its normal in the
//   REFERENCE mesh (the aligned generic head). When the full step would turn
//   some, their corners get an anchor term
//     E_guard = 1/#V sum_v g_v |x_v - a_v|^2     (a_v: x_v when first guarded)
//   and the iteration is solved again from the same start; g_v grows by
//   fold_stiffen_factor while the step still turns them (at most
//   fold_guard_attempts solves), then the backtracking takes the longest
//   step that lowers E_global and turns nothing. Anchors are cleared at each
//   round. So vertices are held only where and when the fit would fold, and
//   no step turns a triangle: the result has at most the triangles the input
//   already had turned (and E_smooth pulls those back, next points).
//   g_v enters E_global, so the energy changes definition at
//   iterations with stiffened > 0; their energy_before is measured with the
//   new weights.
// - No-crossing guard (not in the paper; GlobalFitOptions::crossing_guard).
//   The fold guard keeps each triangle facing its way, but two triangles
//   that share no edge can still pass through each other: lid skin through
//   the eye-socket pocket behind it at the outer eye corners, sheets of an
//   ear, the lips. The same mechanism answers it: after each solve the
//   triangle pairs that cross at the full step and did not cross at x
//   (self_intersection.h rules) have all six corners anchored and
//   stiffened, and the backtracking accepts no step with a new crossing
//   pair. Pairs already crossing in the input may stay. The check looks
//   only at pairs whose boxes, swept over the step (a corner moves on a
//   segment, so each trial of the backtracking lies inside), overlap: found
//   once per solve by a sweep along the longest axis, then each trial step
//   tests those few thousand pairs instead of a full BVH search.
// - Smooth-surface guard (not in the paper; GlobalFitOptions::smooth_guard_*).
//   The control triangles may not cross, but their Modified Butterfly
//   surface still can: its stencils overshoot where the fit bends the
//   control mesh more sharply than the template (eye rims, brow, nose and
//   ears of the real scans: most of their level-3 self-intersections were
//   already on this smooth surface, which the displacements' fold limiter
//   leaves alone by design). Butterfly is linear in the control positions,
//   so a crossing pair of the smooth level L (subdiv/butterfly.h, with
//   GlobalFitTerms::smooth_creases) belongs to the control faces it refines
//   (level-L face f lies in control face f / 4^L). After the rounds, the
//   pairs of level L that the reference's level L does not have are found
//   (one self-intersection search; level 2 of the generic head is ~43k
//   triangles); the corners of their control faces and those corners'
//   rings get a rest-shape weight r_v,
//     E_rest = 1/#V sum_v r_v |L(v) - L0(v)|^2    (the rows of E_smooth),
//   which pulls the local shape back towards the template's (whose smooth
//   surface does not cross there), and one more pass on all points is
//   solved; r_v grows (smooth_guard_factor) while the count falls: stiffer
//   patches only moved the crossings to their rims. The state
//   with the fewest pairs is returned, so a pass that does not help changes
//   nothing. Later searches start only from the level's triangles under
//   weighted vertices and their rings (the BVH refit, not rebuilt). Like
//   g_v, r_v enters E_global (counted in e_guard) from the pass it is
//   raised in. fit_head runs it on every scan (FitHeadOptions::
//   smooth_guard).
// - Fold relief (part of the smooth-surface guard; GlobalFitOptions::
//   smooth_guard_relief_*). Level 2 can be clean while level 3 folds inside
//   one control face or two that share a corner: the fit made a sliver
//   with a sharp kink (on a real face capture, most smooth level-3 pairs
//   sat in a few such faces, none crossing on level 2). After
//   the guard, the new pairs of level 3 whose control faces share a corner
//   are found (one search of the whole level, ~173k triangles on the
//   generic head, made only when a level-3 triangle turns against the
//   reference's: smooth_guard_relief_when_turned); the corners of those
//   faces, cluster by cluster, step
//   their umbrella vectors towards the template's (x_v -= s (L(v) - L0(v)),
//   s from smooth_guard_relief_shares: a line search counted on a tree of
//   the control faces within four rings), keeping the share with the
//   fewest folds, as long as no control triangle turns or crosses. A last
//   search of the whole level keeps the result only when it has fewer new
//   pairs than before. Only those few vertices move (the displacements
//   carry the detail they leave); vertices under E_constraint or ignored by
//   the guard never do. Not a term of E_global: the step after the
//   minimization, like the untangling in fit_head.
// - Pleat relief (GlobalFitOptions::smooth_guard_pleat_steps), after the
//   fold relief's steps, where the relief runs. A fold can be too tight to
//   cross itself: a pleat on a cheek of the smooth level 3 (edges bent by
//   over 100 deg where the generic head's bend by a few), a dark slit in
//   every render, and no crossing pair for the fold relief to see. A pleat edge of the relief level bends by more than 90 deg where
//   the reference's bends by less than 45 (outside ignored faces; turned
//   triangles alone are no sign: James's columella turns smoothly past the
//   generic's, and unturning it put his subnasale back inside his nose).
//   The same umbrella steps, cluster by cluster over the corners of the
//   control faces holding pleat edges, scored by the pleat edges of the
//   whole level; a share is taken only when it turns and crosses no more
//   control triangles and adds no new pair anywhere on the level (the
//   triangles it moved searched again on the relief's tree, refit).
// - Fold creases (GlobalFitOptions::smooth_guard_crease_*), after the
//   relief. Some folds do not answer the umbrella step: where a plate ear
//   meets the head a control edge can bend by over 100 deg, and Butterfly's
//   8-point stencil reaching across it overshoots into a pleat that the
//   relief leaves at every share. Such
//   an edge refined as a crease (the 4-point rule along it, the two sides
//   no longer mixed) does not pleat, and a crease at a sharp bend is where
//   the surface turns anyway. So the sharpest uncreased edge of a face that
//   still folds is tried as a crease, counted on the window's tree, and
//   kept when the new pairs there drop (folds or not: a crease can trade
//   folds for two sheets crossing); the set is kept only when a search of
//   the whole level has fewer new pairs. The edges go to the subdivision
//   stage (GlobalFitResult::fold_crease_edges), which refines them as
//   creases like the eye rims and lip lines. Positions are not changed.
// - Data surface (GlobalFitOptions::data_level, off by default). The
//   points may be measured against the control mesh's Butterfly level L
//   instead of its flat triangles (fit/data_surface.h): E_dist's rows go
//   to the control vertices through the stencils, the closest points and
//   the backtracking's energies are taken on level L. The guards still
//   work on the control triangles.
// - Scan-to-mesh term (not in the paper; GlobalFitOptions::back_*, off
//   unless back_weight > 0):
//     E_back = back_weight/#V sum_{v in B} (n_v . x_v - o_v)^2
//   E_dist runs from the points to the mesh, so a vertex that sticks out
//   where no point is nearest to it costs only its smoothness, and the
//   rest shape (the template's umbrella vectors) keeps a template feature
//   standing: on a face capture with a few points per control vertex,
//   James's generic nose tip stood 6 mm off his nose. B are the vertices
//   (not in GlobalFitTerms::back_ignored) over one sheet of scan: their
//   back_neighbours nearest points lie within back_patch_edges mean control
//   edges, are flat, the vertex lies over their patch (not beyond a hole's
//   rim) within back_max_edges edges, and the mesh faces the patch's way.
//   (n_v, o_v) is the tangent plane, at the vertex's foot, of a quadric
//   height field fitted to the patch: the centroid's plane lies inside a
//   curved patch by its sag and pulled whole convex regions in. Taken at
//   the start of each round and fixed for it, so every round minimizes one
//   quadratic energy; an interpolating subdivision passes through every
//   control vertex, so the term puts the limit surface on the scan there.
//   Where the points give no such patch, a vertex farther than
//   back_ray_min_edges from the scan takes the scan's plane where its
//   normal line meets the scan (either way, within back_ray_edges, facing
//   the vertex's way within 60 degrees), from the second round on: the
//   first triangle the line hits when the scan came as a mesh
//   (GlobalFitTerms::back_surface), else the plane of the
//   back_ray_neighbours points nearest the first of the line's steps
//   (back_ray_step_edges) that has a point within one step. The case: James's columella drops 13 mm over 17 mm
//   where the template's nose underside is level; the generic columella
//   base (control vertex 440) sat 8.5 mm up inside his nose, where its 16
//   nearest points hold columella, nostril floor and lip (a fold, no
//   plane) and no point is nearest to it. Its normal points down the
//   columella to his subnasale, 10 mm away.
// - Why the aligned template and not the local fit as rest shape: local
//   fitting moves each feature box by an affine map and blends the rest, so
//   its shape has steps at the box walls (a ridge across James's nose bridge
//   at the nose box's top) and may hand over turned triangles (its blend
//   squashed the box of James's hair-covered ears: 12 turned). A rest shape
//   taken from it holds both; the template's has fewer turned triangles,
//   the same mean distance and no ridge (docs/design/fit.md).
#pragma once
#include "common/progress.h"
#include "common/status.h"
#include "mesh/topology.h"
#include "mesh/tri_mesh.h"
#include "raycast/bvh.h"
#include "subdiv/butterfly.h"

#include <array>
#include <cstdint>
#include <functional>
#include <vector>

namespace lk {

struct GlobalFitOptions {
  // lambda per round; the number of rounds is the size of this list. Early
  // rounds keep the mesh stiff while correspondences are still poor.
  std::vector<double> smooth_weights = {1.0, 0.2, 0.05};
  double binding_weight = 1.0;      // mu: binding edges keep ears and lips in shape
  double constraint_weight = 10.0;  // nu: inner-lip vertices stay put
  // Share of point-to-point distance added to point-to-plane: regularizes
  // sliding along the surface, keeps the normal equations well conditioned.
  double point_to_point_weight = 0.1;
  bool preserve_rest_shape = true;  // see header comment
  // The surface E_dist measures the points against (fit/data_surface.h):
  // 0 the control mesh's triangles (the paper), L > 0 its Modified
  // Butterfly level L (with GlobalFitTerms::smooth_creases), linear in the
  // control positions. Level L serves the passes on all points (the final
  // iterations and the smooth-surface guard's passes), or every round with
  // data_level_on_subsamples. Off by default: on a face capture it doubled
  // the crossing pairs at the ears and eye rims (fit_head turns it on for
  // whole heads: FitHeadOptions::whole_head_data_level).
  int data_level = 0;
  bool data_level_on_subsamples = false;
  int max_iterations_per_round = 4;
  double relative_tolerance = 5e-3;  // stop a round when E changes less than this
  int subsample_points = 10000;      // points per round (0: all); a random subset
  // After the rounds, this many iterations on ALL points with the last
  // lambda (the paper fits a 50k subsample; the last pass sees everything).
  int final_iterations = 1;
  // Trimming: residuals beyond max(trim_factor * median, trim_floor) count
  // as that distance. trim_floor is in units of the mesh's mean edge length.
  double trim_factor = 4.0;
  double trim_floor_edges = 0.25;
  std::uint32_t seed = 1;
  // Fold guard (see header comment): at most fold_guard_attempts re-solves
  // per iteration (0 disables the guard and the fold check); fold_stiffness
  // is g_v of a newly anchored vertex (1: like one average vertex's
  // smoothness at lambda 1), multiplied by fold_stiffen_factor per further
  // detection up to fold_max_stiffness (by then the vertex barely moves).
  // A gentle start matters: anchoring hard at once held the eye corners of
  // the synthetic heads off their data.
  int fold_guard_attempts = 8;
  double fold_stiffness = 1.0;
  double fold_stiffen_factor = 4.0;
  double fold_max_stiffness = 1e4;
  // No-crossing guard (see header comment; needs fold_guard_attempts > 0):
  // no step may make two control triangles cross that did not cross before.
  bool crossing_guard = true;
  // Smooth-surface guard (see header comment): after the rounds, the
  // control mesh refined smooth_guard_level times by Modified Butterfly
  // (with GlobalFitTerms::smooth_creases) may cross itself where the
  // reference's refinement does not; then the rest-shape weights r_v of
  // the control vertices under those pairs rise (smooth_guard_stiffness at
  // first, times smooth_guard_factor per further pass, at most
  // smooth_guard_max_stiffness) and one more pass on all points is solved,
  // up to smooth_guard_passes times. The state with the fewest such pairs
  // is kept (a pass that does not help changes nothing). 0 levels or 0
  // passes: off.
  int smooth_guard_level = 2;
  int smooth_guard_passes = 2;
  double smooth_guard_stiffness = 0.25;
  double smooth_guard_factor = 4.0;
  double smooth_guard_max_stiffness = 16.0;
  // Fold relief (see header comment), part of the smooth-surface guard:
  // crossing pairs of the smooth level smooth_guard_relief_level whose two
  // control faces share a corner (folds, not two sheets) and which the
  // reference's level does not have. Per cluster of their faces' corners,
  // the corners' umbrella vectors step towards the template's by the share
  // of smooth_guard_relief_shares that leaves the fewest folds (none kept
  // when none lowers the count or one would turn or cross control
  // triangles); at most smooth_guard_relief_steps sweeps. 0 level or
  // steps: off.
  int smooth_guard_relief_level = 3;
  int smooth_guard_relief_steps = 3;
  std::vector<double> smooth_guard_relief_shares = {0.25, 0.5};
  // Search the relief level for folds only when one of its triangles turns
  // against the reference's level (a fold turns one; the search is ~100 ms
  // on the generic head's level 3, the check ~5 ms).
  bool smooth_guard_relief_when_turned = true;
  // Pleat relief (header comment), after the fold relief's steps: at most
  // this many sweeps of the same steps, scored by the relief level's pleat
  // edges (0: off).
  int smooth_guard_pleat_steps = 3;
  // No vertex of a pleat step moves farther than this many mean control
  // edges (the pleats are kinks of a few tenths of a millimetre; a longer
  // step reshapes what the data put there: James's columella base).
  double smooth_guard_pleat_max_move_edges = 0.1;
  // Fold creases (see header comment), after the relief's steps: up to
  // smooth_guard_crease_trials times, the sharpest control edge (dihedral
  // above smooth_guard_crease_min_angle_deg) of a face that still folds is
  // tried as a crease of the levels; it is kept when the new pairs around
  // it (folds or not) drop. At most smooth_guard_crease_max_edges edges (0: off), kept only
  // when the whole level has fewer new pairs with them
  // (GlobalFitResult::fold_crease_edges; the subdivision stage refines
  // them as creases).
  int smooth_guard_crease_max_edges = 4;
  int smooth_guard_crease_trials = 6;
  double smooth_guard_crease_min_angle_deg = 40.0;
  // Scan-to-mesh term E_back (see header comment; 0: off, the paper's
  // energy): weight per vertex, like lambda (fit_head sets it from
  // FitHeadOptions::back_term). A control vertex has a plane when its
  // back_neighbours nearest scan points lie within back_patch_edges mean
  // control edges, are flat (smallest covariance eigenvalue at most
  // back_flatness times the middle one), the vertex lies over them (not
  // beyond the patch's rim: a hole's edge) within back_max_edges edges, and
  // the mesh's normal there is within acos(back_min_cos) of the plane's.
  double back_weight = 0.0;
  int back_neighbours = 16;
  double back_patch_edges = 1.0;
  double back_max_edges = 1.0;
  double back_flatness = 0.2;
  double back_min_cos = 0.7;
  // Normal rays onto the scan's triangles (header comment), from round
  // back_ray_first_round on (the first starts from the local fit, whose
  // misfit leaves many vertices off the scan by a quarter edge: rays there
  // pulled the jaw and ears and crossed them). 0: off. Figures:
  // docs/design/fit.md.
  double back_ray_edges = 1.0;
  double back_ray_min_edges = 0.25;
  int back_ray_first_round = 1;
  double back_ray_step_edges = 0.1;  // point clouds: the line's steps
  int back_ray_neighbours = 8;       // point clouds: the plane where the line meets them
};

// Terms of E_binding and E_constraint, from the head's annotations.
struct GlobalFitTerms {
  std::vector<std::array<int, 2>> binding_edges;  // vertex pairs (mesh or virtual edges)
  std::vector<int> constrained_vertices;
  // #V by 3: the template as aligned (before local fitting): the rest shape
  // of E_smooth and the orientation the fold guard keeps for every
  // triangle. Empty: the input mesh serves as both.
  std::vector<Vec3> fold_reference;
  // Crease curves of the Butterfly refinement the smooth-surface guard
  // checks (the same the multiresolution levels will use).
  ButterflyCreases smooth_creases;
  // #V flags (or empty): pairs of the smooth level with a control face
  // whose corners are all flagged do not count (parts the rest-shape
  // weights cannot move: the mouth bag, held by E_constraint and carried
  // after the fit by fit_head).
  std::vector<char> smooth_guard_ignored;
  // #V flags (or empty): vertices E_back leaves alone (the pockets: eye
  // sockets and the mouth bag, whose scan points are not fitted).
  std::vector<char> back_ignored;
  // The scan's own triangles (head frame) when it came as a mesh, else
  // empty: E_back's normal rays (GlobalFitOptions::back_ray_edges).
  TriMesh back_surface;
  // #V by 3 (or empty): where the iterations start (a warm start from an
  // earlier fit of the same points: fit_head's ear refit). E_binding's edge
  // vectors and E_constraint's positions are still the input mesh's, and
  // pairs crossing or triangles turned at the start may stay, as the
  // input's do. Empty: the iterations start at the input mesh.
  std::vector<Vec3> start;
  // Optional: called once with the positions (#V by 3) after the rounds and
  // the final pass on all points, before the smooth-surface guard's passes,
  // the fold and pleat relief and the fold creases. Returning false ends
  // the fit there (GlobalFitResult::stopped_after_rounds: the result is that
  // state, unguarded), for a caller that has already decided the guarded
  // result will not be used (fit_head's ear refit). Returning true goes on
  // exactly as without it.
  std::function<bool(const std::vector<Vec3>& positions)> after_rounds;
  // Optional: a tree over the fold relief's level (smooth level
  // smooth_guard_relief_level of the input's triangles) at any positions,
  // e.g. one a caller built to count that level's pairs. The relief's
  // first search refits it instead of building one (the same pairs) and
  // moves it out; left alone when the relief does not search or its
  // triangles differ.
  MeshBvh* relief_start_tree = nullptr;
};

struct GlobalFitIteration {
  int round = 0;
  int points = 0;              // #S in this round
  double smooth_weight = 0;    // lambda in this round
  double trim_distance = 0;    // tau in this round
  double energy_before = 0;    // E_global at the start of the iteration
  double energy_after = 0;     // E_global after the accepted step (<= energy_before)
  // The fit's last iteration may accept its step on an upper bound of
  // E_dist (distances to the triangles the points projected to before the
  // step) without projecting again; then energy_after and e_dist are that
  // bound, still <= energy_before, and the true energy is lower.
  bool energy_after_is_bound = false;
  double e_dist = 0, e_smooth = 0, e_binding = 0, e_constraint = 0;  // after, unweighted
  double e_guard = 0;          // after, weighted by g_v (the anchors)
  double e_back = 0;           // after, weighted (back_weight / #V)
  double step = 1;             // accepted fraction of the linear solve's step (0: none)
  int stiffened = 0;           // guard weights g_v raised in this iteration (E_global redefined)
  int turned = 0;              // triangles turned against the reference after the step
};

struct GlobalFitResult {
  std::vector<GlobalFitIteration> iterations;
  // Control vertices E_back held to a scan plane in the first and the last round.
  int back_vertices_first = 0;
  int back_vertices = 0;
  // Of those, held by a normal ray onto the scan's triangles, summed over the rounds.
  int back_ray_planes = 0;
  int data_level = 0;          // the data surface's level (0 also when Butterfly could not refine the mesh)
  int rounds = 0;
  int turned_before = 0;       // triangles of the input turned against the reference
  int turned_after = 0;        // ... of the result
  int guard_raises = 0;        // sum of stiffened over all iterations
  int crossing_before = 0;     // control triangle pairs crossing in the input (self_intersection.h)
  int crossing_after = 0;      // ... in the result (counted with the guard on or off)
  // Smooth-surface guard: crossing pairs of the smooth level
  // smooth_guard_level that the reference's level does not have, after the
  // rounds and in the result; passes solved; control vertices whose
  // rest-shape weight it raised. All 0 when the guard is off (or the mesh
  // cannot be refined: smooth_guard_skipped).
  int smooth_crossing_before = 0;
  int smooth_crossing_after = 0;
  int smooth_guard_passes = 0;
  int smooth_guard_vertices = 0;
  bool smooth_guard_skipped = false;
  // Fold relief: whether the relief level was searched (no turned triangle
  // skips it: smooth_guard_relief_when_turned), new fold pairs of the
  // relief level before and after it, steps taken, control vertices moved.
  bool relief_searched = false;
  int relief_folds_before = 0;
  int relief_folds_after = 0;
  // Pleat relief: the relief level's pleat edges (header comment) before
  // and after it, and its steps.
  int pleats_before = 0, pleats_after = 0, pleat_steps = 0;
  // Each kept pleat step's control vertices, and how far the steps moved
  // every vertex (#V, zero where none moved; empty without a step): what
  // fit_head needs to undo steps where the surface it returns still
  // crosses (FitHeadOptions::pleat_undo_where_crossing).
  std::vector<std::vector<int>> pleat_step_vertices;
  std::vector<Vec3> pleat_shift;
  int relief_steps = 0;
  int relief_vertices = 0;
  // Fold creases: control edges to refine as creases (pairs of vertices),
  // empty when none was kept.
  std::vector<std::array<int, 2>> fold_crease_edges;
  // GlobalFitTerms::after_rounds returned false: the guard did not run.
  bool stopped_after_rounds = false;
};

// points: the scan points to fit (already stripped of clipped regions), #P.
// mesh: the control mesh after local fitting; topology: its connectivity.
// out: the fitted mesh (same triangles, new positions). Fails on empty or
// non-finite input, index errors in terms, or a singular system.
// relief_tree (optional): receives the fold relief's tree over the smooth
// level smooth_guard_relief_level (its boxes at some positions of that
// level; empty when the relief did not search), so that a caller refining
// the fit to that level can refit it instead of building one
// (limit_folds's finest_tree).
Status fit_global(const std::vector<Vec3>& points, const TriMesh& mesh, const MeshTopology& topology,
                  const GlobalFitTerms& terms, const GlobalFitOptions& options, TriMesh& out,
                  GlobalFitResult& result, const ProgressFn& progress = {}, MeshBvh* relief_tree = nullptr);

// Triangles of mesh whose normal points against (or is degenerate relative
// to) the same triangle's normal in reference (same triangles, positions
// #V by 3): dot(n_f(mesh), n_f(reference)) <= 0. Ascending face indices.
std::vector<int> turned_triangles(const std::vector<Vec3>& reference, const TriMesh& mesh);

}  // namespace lk
