// The whole scan -> head job of jeong2002 (Sec. 4.1-5, Table 1), for the CLI
// and the web app: a raw point cloud in, a fitted control mesh and its
// displaced Modified Butterfly levels out, with the paper's per-stage
// accuracy figures.
//
//   1. initial alignment   align/initial_alignment.h  (Sec. 4.1); a face-only
//      scan (face_alignment.h: shallow upper part) is aligned by trimmed ICP
//      instead, and the unobserved rest of the head keeps the generic shape.
//      Before that, the orientation is checked by coarse ICP from every up
//      axis and eight yaws (guess_orientation), so a scan in another
//      convention is turned round with a note, or refused with a hint.
//      A turn is kept only when, aligned, more of the scan lies near the
//      head than with the scan aligned as given (the search's score alone
//      turned a bust to a wrong pose).
//      A whole head whose points mostly lie off the silhouette-aligned head
//      (a hat, a beard, a pedestal) is aligned again on its upper face
//      (face_refine.h) before it is refused.
//   2. local fitting       fit/local_fit.h             (Sec. 4.2), after
//      moving the eye region (ours, same header) to the scan's eyes
//   3. global fitting      fit/global_fit.h            (Sec. 4.3)
//   4. subdivision         multires/multires.h         (Sec. 5)
//      then displacements that turn a triangle over or collapse it are
//      shrunk until none does (limit_folds), level by level.
//
// Frames. The scan may be in any unit (m, cm, mm: picked from its size) and
// any position; `up` and `facing` say how it is oriented. Everything is
// computed and returned in the HEAD frame: metres, +y up, +z facing, the
// scan's position rotated and scaled but not moved (scan_to_head maps scan
// coordinates there; its inverse brings results back onto the scan).
//
// Timing is not done here (core has no clocks): stage boundaries are
// reported through FitStageObserver, and the caller times them. Stage names:
// "initial_alignment", "local_fitting", "global_fitting", "subdivision".
//
// Stats per stage: distances from the scan points that are fitted (the neck
// below the generic head's neck plane is cut away) to the current surface,
// in percent of the scan's bbox diagonal, as the paper's Table 1.
//
// Shapes: scan #P by 3; control #V by 3 / #F by 3 (the generic head's
// connectivity); level l mesh #V_l by 3 / 4^l #F by 3.
#pragma once
#include "align/face_alignment.h"
#include "align/face_refine.h"
#include "align/initial_alignment.h"
#include "common/progress.h"
#include "common/status.h"
#include "fit/closest_point.h"
#include "fit/global_fit.h"
#include "fit/local_fit.h"
#include "head/head_model.h"
#include "multires/displacement.h"
#include "multires/fold_limit.h"
#include "multires/multires.h"
#include "multires/surface_samples.h"
#include "pipeline/scan_thinning.h"
#include "pipeline/untangle.h"

#include <functional>
#include <string>
#include <vector>

namespace lk {

struct FitHeadOptions {
  Vec3 up = Vec3::UnitY();      // the scan's up direction
  Vec3 facing = Vec3::UnitZ();  // the direction the scanned face looks
  int levels = 3;               // Butterfly refinement levels (paper: 2 shown)
  // Dense point clouds fitted on cell averages (pipeline/scan_thinning.h)
  // over cells of side e / thin_cells_per_edge, e the generic head's mean
  // edge at the finest level (in the scan's unit as guessed): with 4, the
  // displacements' footprints (radius at least e / 2) still hold about as
  // many averages as their footprint_points, and each average carries its
  // points' noise averaged. Only when that keeps at most thin_max_share of
  // the points; meshes (faces) are not thinned. Table 1 and the stages'
  // stats are then over the averages, in percent of the full scan's size.
  // 0 (the default): off. With 4 a 2M-point synthetic head fitted on 0.87M
  // averages came 0.607 -> 0.660 mm from its truth where scanned: not
  // lossless (docs/design/page.md). `likeness fit --thin-cells X`.
  double thin_cells_per_edge = 0.0;
  double thin_max_share = 0.75;
  // Non-head rejection (ErrorCode::NotAHead):
  int min_points = 1000;             // fewer points cannot describe a head
  double min_thickness_ratio = 0.05; // smallest / largest PCA extent (std); a plane has ~0
  // After alignment, at least this share of the points must lie within
  // near_distance_pct of the aligned generic head (noise or a chair does not).
  double min_near_fraction = 0.6;
  double near_distance_pct = 2.0;    // percent of the bbox diagonal
  // A whole head that fails the check above after the silhouette alignment
  // is aligned again on its upper face (align/face_refine.h: a hat, a
  // beard or a pedestal misled the silhouettes) and checked again. With
  // face_refine.symmetry_yaw_start (a head turned on its bust; off by
  // default) the match that leaves the scan refused runs again without it.
  bool refine_on_face = true;
  FaceRefineOptions face_refine;
  // The result turned about the head frame's up to the aligned generic
  // head's look: once the alignment is final, the head frame turns by the
  // yaw of the alignment's rotation (the polar factor of its map), so the
  // fitted face looks along +z, as the generic head's does, whatever way
  // the scan faced or the head turned on its bust. Up stays the scan's (as
  // given or as the orientation check turned it): a bust's pitch under the
  // silhouettes is less sure than its up, and the face rig was measured on
  // fits upright that way. The face rig (lids and jaw turn about x), the
  // glTF export and the page's views read that frame; scan_to_head carries
  // the turn. The fit runs unturned and its figures do not change. Off by
  // default: the rig on the page's real fits gains lid pairs on Gutenberg's
  // blink (turned 17 deg: 0 -> 3 on the control mesh) and a mouth-bag pair
  // on James (6 deg); docs/design/fit_real_scans.md. Off: the frame of up
  // and facing (and of the orientation check's turn).
  bool face_frame = false;
  // When that alignment on the face does not pass the check either, the
  // face is matched again from the pitch candidates (FaceRefineOptions::
  // candidate_pitches_deg), the one with the largest share of the points
  // near the head (measured as the check above, on at most
  // choose_pitch_points of them) chosen, and kept when that share is larger.
  bool choose_face_pitch = true;
  int choose_pitch_points = 4000;
  bool cut_neck = true;              // drop points below the generic head's neck plane
  bool measure_stages = true;        // compute the per-stage distance stats
  int stats_max_points = 0;          // measure on at most this many points (0: all)
  AlignOptions align;
  // Partial scans: Auto measures the coverage (face_alignment.h); the
  // others force one alignment.
  enum class ScanKind { Auto, WholeHead, FaceOnly };
  ScanKind scan_kind = ScanKind::Auto;
  CoverageOptions coverage;
  FaceAlignOptions face_align;
  // Orientation check: Off trusts up/facing; Hint fails with NotAHead and a
  // message naming the likely --up/--facing when the scan clearly fits
  // better in another orientation; Auto rotates the scan to it and adds a
  // note instead.
  enum class OrientationCheck { Off, Hint, Auto };
  OrientationCheck orientation_check = OrientationCheck::Auto;
  OrientationOptions orientation;
  // When > 0, a scan given as a mesh is searched on its surface's cell
  // averages over cells of this fraction of its diagonal
  // (surface_cell_averages), not on its vertices. With 0.005 Fran's face
  // split 1:4, refused on its vertices, is turned as the original; but on
  // the busts turned by right angles it makes wrong heads of refusals
  // (Demosthenes 7 -> 12 of 24, Fran 0 -> 1): an option, off
  // (docs/design/fit_real_scans.md, "The same surface, sampled more
  // densely"). A raw cloud is searched on its points either way.
  double orientation_surface_cell = 0.0;
  // With Auto, a mesh refused in the orientation its vertices' search chose
  // is searched again on its surface's cell averages (cells of this
  // fraction of its diagonal) and aligned where that search turns it; kept
  // only when it passes as a face patch (align_face), whose match does not
  // pass in a wrong pose as a bust's silhouettes do. Fran's face split 1:4,
  // refused on her vertices, is turned as the original (docs/design/
  // fit_real_scans.md, "A second search on the surface"). 0: off.
  double orientation_surface_retry_cell = 0.005;
  // With Auto: when the alignment is refused (too few points near the head)
  // in the orientation the screened search chose, the search runs again
  // with every start run through (no screening) and, where it finds another
  // orientation, the scan is aligned there; kept only if that passes. Off:
  // on busts turned by right angles it turns refusals into wrong heads
  // (docs/design/align.md, "A second search when the alignment is refused").
  bool orientation_retry_unscreened = false;
  // A mesh with more vertices than averages over cells of this fraction of
  // its diagonal (surface_cell_averages), refused after the searches above,
  // is aligned once more with its silhouettes and coverage taken from those
  // averages, and kept when that passes: a bust's pose otherwise rests on
  // how densely it was tessellated (Gutenberg at 64x his density refused).
  // 0: off.
  double dense_mesh_retry_cell = 0.005;
  // A mesh whose mean edge is shorter than this fraction of its diagonal
  // has its face matched (refine_alignment_on_face and its near share) to
  // its vertices, not its triangles: they lie closer than the match errs
  // anyway, and a closest triangle costs in proportion to the distance over
  // the triangles' size (a 555-thousand-vertex bust spent 80 % of its 28 s
  // alignment there). 0: always the triangles.
  double face_match_vertices_edge = 0.002;
  // With Auto and the default axes (+y up, face along +z): a scan refused
  // there is aligned once more with +z up and the face along -y (Blender's
  // and CAD tools' convention, taken as given), and where that passes the
  // refusal names those axes. Only named, not fitted: on the busts' 24
  // right-angle turns it is right for 2 and wrong for 10 (docs/design/
  // align.md, "Busts written with +z up").
  bool suggest_z_up = true;
  LocalFitOptions local;
  // Before the feature boxes, the eyes and brows move as one soft region
  // (fit/local_fit.h: translation and scale, fitted to the scan) when the
  // head has eye rims; false keeps them where the alignment put them. On
  // by default: the rims land on the scan's eyes and the synthetic heads
  // come closer to their truth, for a slightly higher Table 1 on the real
  // scans (figures: docs/design/fit.md). `likeness fit --no-eye-region`.
  bool fit_eye_region = true;
  EyeRegionOptions eye_region;
  GlobalFitOptions global;
  // Displacement measurement; min_points raised from 3 to 12 so the sparse
  // junk a scanner returns from hair (a few points per normal line) counts
  // as "no data" and the scalp stays smooth (same mean distance).
  DisplacementOptions displacement = [] {
    DisplacementOptions d;
    d.min_points = 12;
    return d;
  }();
  // Cap on |displacement| (percent of the bbox diagonal) when
  // displacement.max_distance is 0. The control mesh already fits the scan
  // in the least-squares sense (residuals ~0.1 %), so longer normal lines
  // only reach the other side of thin features (lips, nostrils, ears) or
  // hair junk; 1 % is about 4.5 mm on a head.
  double displacement_max_pct = 1.0;
  // The generic head's neck goes on below the neck cut. Measured from the
  // points above the cut only, its displacements dropped to the smooth
  // surface right at the cut, one column of the neck's long triangles at a
  // time: streaks under the jaw. The scan down to this far below the cut
  // (metres), where its nearest surface is the neck's, is measured too; it
  // is not fitted and not in Table 1's distances. 0: the cut is the data's
  // edge. Longer reaches push a face capture's neck into the ear lobes.
  double displacement_below_neck_cut = 0.010;
  // Whole-head scans (busts): the scanned neck is fitted where it is
  // scanned. The scan's points below the neck cut, down to the lower end of
  // the aligned generic neck, whose nearest point of the locally fitted
  // head is inside a neck triangle and lies along its normal within
  // scanned_neck_max_angle_deg (not beyond the neck's lower rim: shoulders,
  // a chest or a pillar flaring out below it), are fitted after the head's
  // global fit, by the neck's control vertices alone (the rest held where
  // the head's fit left them), and join the displacements; everything below
  // the generic neck's end is cut. Table 1's distances stay over the points
  // above the cut. Face-only captures keep the band above (their cut passes
  // under the ear lobes). false: the band above on every scan (the figures
  // before it was on; docs/design/fit_real_scans.md).
  bool fit_scanned_neck = true;
  double scanned_neck_max_angle_deg = 45.0;
  // The scanned neck's fit runs the global fit's smooth-surface guard
  // (GlobalFitOptions::smooth_guard_*: its passes on all points, the fold
  // and pleat relief) as the head's fit does. Off: its round and its pass
  // on all points only; crossings the neck leaves on the finest level are
  // the crossing guard's (guard_other_crossings), as anywhere else.
  // Figures (CPU and the fits, 25 copies): docs/design/fit_real_scans.md,
  // session 51.
  bool scanned_neck_smooth_guard = false;
  // The scanned neck's held fit reaches a neck centimetres off: when the
  // median distance of the neck's points to the head's fit exceeds the
  // trimming distance of the head fit's last pass (its held round counts
  // every point beyond that as an outlier, and such a neck was not pulled:
  // Gutenberg's, 45 mm median), the neck's control vertices are first
  // fitted to the neck's points alone over the head's rounds of smoothing
  // (the trimming then taken from the neck's own residuals), the rest
  // held, and the held round starts there. Necks within the trimming
  // distance are fitted as without it. Off by default: it reaches
  // Gutenberg's neck (11.4 -> 0.1 mm median) and Demosthenes' Table 1 is
  // lower, but not every head figure is the same or better (Gutenberg's
  // and Plato's Table 1 up by 0.0002 %, a shifted Plato's smooth level 3
  // from 0 to 20 pairs; docs/design/fit_real_scans.md, "The scanned neck
  // reached where it lies centimetres off").
  bool scanned_neck_reach = false;
  // Scans that come as meshes (PointCloud::faces): their triangles are
  // sampled every surface_sample_edges x the finest level's mean edge and
  // the samples are measured with the scan's points (multires/
  // surface_samples.h): the finest levels no longer guess the surface
  // between samples several of their edges apart. Triangles with an edge
  // above surface_sample_max_edge_ratio x the median (holes bridged) are
  // left out. 0: off (the vertices only, as for a raw cloud).
  double surface_sample_edges = 1.0;
  double surface_sample_max_edge_ratio = 4.0;
  int surface_sample_max = 2000000;
  // After measuring: displacements that turn a triangle over or collapse it
  // (against the smooth Butterfly levels) are shrunk until none does.
  FoldLimitOptions fold_limit;
  // Refine the generic head's crease curves (eye rims, lip lines:
  // HeadAnnotations::creases) as creases, so the skin's Butterfly stencils
  // do not reach over the rims into the pockets (false: the plain scheme).
  bool rim_creases = true;
  // Before subdividing: where the fitted control mesh's smooth Butterfly
  // level untangle_level crosses itself and the aligned generic head's does
  // not (two sheets pulled onto the same points: an ear's back against the
  // scalp), the corners of the control faces under those pairs move
  // untangle_erode_pct of the diagonal into the head along their normals,
  // up to untangle_iterations times (and not after two steps without
  // fewer pairs); the state with the fewest such pairs is kept (fit_head.cpp).
  // untangle_level 0: off. Face captures (face_untangle_level) are searched
  // on level 3, where their sparse data still crossed after level 2 was
  // clean; whole heads stay on level 2 (no new level-3 pairs, and the
  // search costs time). With untangle_hinges_last, a first erosion pass
  // leaves out the corners the two sheets share or neighbour (an ear's root
  // where its back lies on the scalp): moving those too made more pairs.
  // Then the folds left within one sheet are taken untangle_restore_share
  // of the way back to the template's shape over the corners of their
  // control faces and up to untangle_restore_rings rings around them
  // (pipeline/untangle.h; -1: off). Figures: docs/design/fit.md.
  int untangle_level = 2;
  int face_untangle_level = 3;
  int untangle_iterations = 6;
  double untangle_erode_pct = 0.03;
  bool untangle_hinges_last = true;
  int untangle_restore_rings = 4;
  double untangle_restore_share = 0.25;
  // The global fit's pleat relief (GlobalFitOptions::smooth_guard_pleat_steps)
  // judged on the surface the fit returns: when the untangled level still
  // crosses itself, the pleat steps whose vertices reach (within two rings:
  // Butterfly's support) a control face under those pairs are undone, with
  // every step sharing a vertex with them, then all steps, and the
  // untangling runs again from there; kept when it leaves fewer pairs. A
  // pleat step near a crossing can hold it there (Fran as given: 4 pairs the
  // erosion takes out without the steps and not with them).
  bool pleat_undo_where_crossing = true;
  // After global fitting, the mouth bag (held where local fitting put it)
  // follows its lips (carry_mouth_bag below). Held in place, it poked out
  // through the skin where the lips moved back: Fran's mouth corner went
  // 3.5 mm back and her smooth level 3 crossed itself in 35 pairs there.
  bool carry_mouth_bag = true;
  // Every edge of the ears (region "ears") becomes a binding edge of global
  // fitting (E_binding keeps its edge VECTOR), as the eye sockets' are: the
  // ear keeps its shape and follows the scan as a whole. On face-only
  // captures (FaceOnlyScans), whose ears are seen from the side under hair:
  // free, an ear's thin flap is pulled onto the scalp's points and its own
  // bowl's at once and folds. Whole-head scans see the ears and lost
  // accuracy when always bound (figures: docs/design/fit.md), so with
  // WhereTheyCross they are fitted free first; when the fitted control
  // mesh's smooth finest level crosses itself at an ear (a real bust's ear
  // folded by the data around it, whichever small change the generic head
  // had: docs/design/fit_real_scans.md), the global fit is run again with
  // the ear edges bound and kept when its ears do not cross; face captures
  // are bound from the start. Costs one self-intersection search of the
  // smooth finest level, and a second global fit when an ear folds.
  enum class EarBinding { Off, FaceOnlyScans, WhereTheyCross, Always };
  EarBinding bind_ear_edges = EarBinding::WhereTheyCross;
  // WhereTheyCross's second fit, warm: > 0 starts it from the free fit's
  // control mesh and runs only the last ear_refit_warm_rounds of
  // GlobalFitOptions::smooth_weights (then the final pass and the guards).
  // Cheaper (Demosthenes 8.0 -> 6.8 s), its ears hold, but it lands in
  // another minimum than the whole fit again: Table 1 0.0531 -> 0.0538 %,
  // a synthetic head 14 % farther from its truth (figures: docs/design/
  // fit_real_scans.md). 0 (the default): the whole fit from the local fit.
  int ear_refit_warm_rounds = 0;
  // WhereTheyCross, decided after the free global fit's rounds, before its
  // smooth-surface guard (GlobalFitTerms::after_rounds): the free fit's
  // smooth finest level is searched at the ears there; when they cross, the
  // bound fit runs at once, and when it is kept the free fit's guard (whose
  // result would be thrown away) is skipped. The same decision as after
  // the guard wherever the guard never takes the free fit's ears from
  // crossing to clean or back, which held on every real scan, copy and
  // synthetic seed measured at smooth level 3 (docs/design/fit_real_scans.md);
  // the note's and ear_binding's free count is then the count after the
  // rounds. Used with levels == 3 only: at level 1 the guard's fold creases
  // do take ears to clean (Demosthenes: no refit after the guard, one kept
  // after the rounds). false: decided after the free fit's guard. The warm refit
  // (ear_refit_warm_rounds) starts from the guarded free fit: decided after.
  bool ear_refit_after_rounds = true;
  // WhereTheyCross's bound fit given up after its rounds, before its guard,
  // when its ears' pairs at smooth level 3 there are more than this: not
  // kept, and its guard (whose result would be thrown away) is not paid.
  // The same head wherever the decision is the same (the bound count
  // reported is then the one after the rounds). 0 (the default): judged at
  // its end. Off because no count separates them: at 100, Plato's five
  // copies (193-368 pairs there, none kept) save 1-2 s of CPU, but
  // Gutenberg turned by 0.05 deg (106 there, 0 at its end, kept) is given
  // up and fits worse (docs/design/fit_real_scans.md, session 48). Cold
  // refits at levels == 3 only.
  int ear_refit_give_up_pairs = 0;
  // When an ear (a connected part of region "ears") still crosses itself or
  // the head at the finest level, its control vertices take the aligned
  // generic ear's shape, carried by the harmonic interpolation of the
  // movement of the head around it (carry_mouth_bag), and the levels and
  // displacements are measured again; kept only when the ears' pairs drop
  // and no others appear. Where the data is no ear (carved hair over it)
  // the ear keeps the generic shape; where nothing crosses nothing changes.
  // Costs one self-intersection search of the finest level per fit, and a
  // second subdivision stage when an ear crosses.
  bool hold_crossing_ears = true;
  // Last, where the finest level still crosses itself at the lips or the
  // ears (a pair touching either region), the fit gives way there, from the
  // least change to the most, per cluster of crossings (pairs sharing a
  // control corner): the displacements over the control faces under the
  // pairs (grown by 0-2 rings, faded on the finer levels) go to 0; then
  // those control vertices (1-5 rings) are smoothed (umbrella sweeps) or
  // moved half or all of the way to the aligned generic head's shape
  // carried by the movement of the head around them (carry_mouth_bag's
  // solve), with the displacements over their support faded too. A step is
  // kept when it leaves fewer pairs at the lips and ears and fewer pairs in
  // all; up to feature_guard_rounds passes over the clusters. Where nothing
  // crosses nothing changes: the ears and lips follow the scan wherever it
  // fits them cleanly. The note says what was relaxed.
  bool guard_feature_crossings = true;
  int feature_guard_rounds = 6;
  // Then the same steps for every other crossing pair (the scalp, the neck's
  // seam, the eye rims), per cluster, kept when they leave fewer such pairs
  // and no more at the lips and ears: a head that crosses itself anywhere
  // is a defect a user sees and exports. Needs guard_feature_crossings.
  bool guard_other_crossings = true;
  // When the guard moved control vertices, the displacements are measured
  // again over the moved control mesh (its dropped detail back), the guard
  // runs again on that, and the result is kept when it leaves no more pairs.
  bool guard_remeasure = true;
  // The guard's choice by cost: per cluster, the first step of the ladder
  // that leaves fewer pairs and up to guard_cost_extra_tries steps after it
  // are tried, and of those leaving no more pairs than the first, the one
  // whose level lies least farther from the scan's measured points (summed
  // over the points near what it moved) is kept (false: the first).
  bool guard_choose_by_cost = true;
  int guard_cost_extra_tries = 3;
  // The global fit's scan-to-mesh term E_back (GlobalFitOptions::back_*:
  // control vertices over scanned skin held to the scan's surface under
  // them; ears and pockets left out) with this weight. On face captures,
  // whose few points per control vertex let a template feature stick out
  // where no point is nearest to it (a generic nose tip standing off a
  // real nose). Not on whole-head scans: dense ones gain nothing. Its
  // normal rays (GlobalFitOptions::back_ray_*) meet a mesh scan's
  // triangles over fitted skin, or a point cloud's points. Figures:
  // docs/design/fit.md.
  enum class BackTerm { Off, FaceOnlyScans, Always };
  BackTerm back_term = BackTerm::FaceOnlyScans;
  double back_weight = 1.0;
  // The global fit's smooth-surface guard (GlobalFitOptions::smooth_guard_*:
  // rest-shape weights where the control mesh's smooth level 2 crosses
  // itself, then the fold relief of level 3) runs on every scan. Face-only
  // captures need it most: their sparse data bend the control mesh sharply
  // around the eyes, brow and nose. On whole heads it takes the brow folds
  // of clean scans, cheaply where it has no work (figures:
  // docs/design/fit.md). FaceOnlyScans: only there; Off: never
  // (GlobalFitOptions as given).
  enum class SmoothGuard { Off, FaceOnlyScans, Always };
  SmoothGuard smooth_guard = SmoothGuard::Always;
  // The global fit's data surface (GlobalFitOptions::data_level) on
  // whole-head scans: their last passes measure the points against the
  // control mesh's Butterfly level 1, the surface the user gets, instead of
  // its flat triangles (fit/data_surface.h): closer to the truth where
  // scanned and in the holes, for a little time (figures:
  // docs/design/fit.md). Face-only captures keep global.data_level (0 by
  // default): on hair-covered ears level 1 raised the crossing pairs.
  // -1: global.data_level on every scan.
  int whole_head_data_level = 1;
};

struct FitStageReport {
  std::string name;
  DistanceStats distance;  // scan points to the surface after the stage
  // The same on the stage's own surface, as the stage left it: differs from
  // distance only for "global_fitting" when later steps (untangling, the ear
  // hold, the crossing guard) moved the control mesh the fit returns.
  DistanceStats as_fitted;
};

// Called by fit_head at stage boundaries. finished() comes right after the
// stage's work and BEFORE its stats are measured, so a timer stopped there
// times the work only; measured() follows with the stats. measured() comes
// once more for "global_fitting" when the untangling, the ear hold or the
// crossing guard moved control vertices after it: the later figures are the
// returned control mesh's, and replace the earlier.
struct FitStageObserver {
  std::function<void(const std::string& stage)> started;
  std::function<void(const std::string& stage, const TriMesh& surface)> finished;
  std::function<void(const FitStageReport& report)> measured;
};

struct FitHeadResult {
  int points = 0;               // scan points given
  ScanThinning thinning;        // thin_cells_per_edge: the cloud fitted (kept of points)
  int fitted_points = 0;        // after the neck cut
  double bbox_diagonal = 0;     // the scan's, in scan units
  double unit_to_metres = 1;    // the unit picked: 1 (m), 0.01 (cm), 0.001 (mm)
  AffineMap scan_to_head;       // rotation * unit scale (no translation)
  AffineMap generic_to_head;    // the initial alignment
  // FitHeadOptions::face_frame: the turn about +y from the frame of up and
  // facing (and the orientation check) to the head frame, and the aligned
  // face's yaw it undid (degrees, + towards +x).
  Mat3 face_frame_turn = Mat3::Identity();
  double face_frame_deg = 0;
  TriMesh aligned, local, control;  // control mesh after each fitting stage
  MultiresMesh multires;        // levels over `control` with displacements
  std::vector<TriMesh> level_meshes;  // levels 1..L (displaced)
  std::vector<FitStageReport> stages;
  AlignResult alignment;        // silhouette alignment (whole heads)
  ScanCoverage coverage;
  bool face_only = false;       // aligned by align_face
  FaceAlignResult face_alignment;
  OrientationGuess orientation; // when the check ran
  bool orientation_checked = false;
  bool turned = false;          // the scan was turned from its given orientation (a note says how)
  std::vector<std::string> notes;  // what the user should know (auto-orientation, partial scan)
  LocalFitResult local_fit;
  BoxFit eye_fit;               // the eye region (skipped when off or the head has no eye rims)
  GlobalFitResult global_fit;
  double near_fraction = 0;     // share of points near the aligned head (sanity check)
  bool refined_on_face = false; // aligned again on the face (FitHeadOptions::refine_on_face)
  FaceRefineResult face_refine;
  int pocket_points = 0;        // fitted points nearest to an eye socket / the mouth bag: not fitted
  int neck_points = 0;          // scan points below the neck cut fitted as the neck (fit_scanned_neck)
  // FitHeadOptions::scanned_neck_reach: the neck points' median distance to
  // the head's fit and the head fit's last trimming distance (0 when the
  // option is off or no neck was fitted), and whether the neck was fitted
  // to its own points first.
  struct NeckReach {
    double median_before = 0, trim_distance = 0;
    bool reached = false;
  } neck_reach;
  int isolated_points = 0;  // skin points left out of fitting as isolated (DisplacementOptions::isolated_density_ratio)
  SurfaceSampleStats surface_samples;  // samples of the scan's triangles measured (0: a raw cloud)
  int zeroed_displacements = 0; // displacements dropped in pockets or because they folded triangles
  FoldLimitStats fold_limit;    // what the fold limiter shrank
  // Crossing pairs of the control mesh's smooth level untangle_level that the
  // aligned generic head's does not have, before, between and after the
  // untangling's steps (the control mesh above is the untangled one).
  UntangleResult untangle;
  // bind_ear_edges WhereTheyCross: the smooth finest level's pairs at the
  // ears after the free fit (after its rounds with ear_refit_after_rounds)
  // and after the fit with the ears bound (the same when it was not run),
  // and whether the bound fit was kept.
  struct EarBinding {
    int free_pairs = 0, bound_pairs = 0;
    bool bound = false;
  } ear_binding;
  int ears_held = 0;            // ears held in their generic shape (hold_crossing_ears)
  // guard_feature_crossings: the finest level's pairs touching the lips or
  // ears before and after it, the steps kept, and the control vertices
  // whose displacements it dropped / that it moved toward the generic shape.
  struct FeatureGuard {
    int pairs_before = 0, pairs_after = 0, steps = 0, relaxed_vertices = 0, moved_vertices = 0;
    int other_pairs_before = 0, other_pairs_after = 0;  // the pairs touching neither (guard_other_crossings)
    bool remeasured = false;  // guard_remeasure was kept (pairs_after, other_pairs_after: after it)
  } feature_guard;
  // FitHeadOptions::pleat_undo_where_crossing: the pleat steps undone (0: none).
  int pleat_steps_undone = 0;
};

// Fits generic (the generic head with annotations, in metres) to scan.
// Errors: Empty (no points), InvalidInput (NaN/inf, bad options),
// NotAHead (too few points, a flat cloud, points that do not lie on a
// head-shaped surface after alignment), NotConverged, Cancelled.
Status fit_head(const PointCloud& scan, const GenericHead& generic, const FitHeadOptions& options,
                FitHeadResult& out, const FitStageObserver& observer = {},
                const ProgressFn& progress = {});

// The cloud fit_head fits instead of scan (FitHeadOptions::thin_cells_per_edge):
// true and thinned (with thinning's figures) when scan is thinned, false
// (thinned untouched, thinning.points == thinning.kept) otherwise.
// fit_project calls it first to let the full scan's normals go.
Status thin_scan_for_fit(const PointCloud& scan, const GenericHead& generic, const FitHeadOptions& options,
                         PointCloud& thinned, ScanThinning& thinning);

// fit_head on a cloud thin_scan_for_fit made (options with thinning off),
// then out says so: out.points the full scan's count, a note to the user.
Status fit_head_thinned(const PointCloud& thinned, const ScanThinning& thinning, const GenericHead& generic,
                        const FitHeadOptions& options, FitHeadResult& out, const FitStageObserver& observer = {},
                        const ProgressFn& progress = {});

// One step of the crossing guard's ladder as tried on a cluster: whether
// it leaves fewer pairs (FitHeadOptions::guard_feature_crossings' rule),
// the pairs it leaves and what it loses (guard_choose_by_cost).
struct GuardTry {
  bool helps = false;
  int pairs_left = 0;
  double cost = 0;
};
// The step the guard keeps among `tries` (ladder order, least change
// first): -1 when none helps; else the first that helps, or (by_cost) of
// it and the extra_tries steps after it, the one losing least among those
// that help and leave no more pairs than it (the first of equals).
int choose_guard_step(const std::vector<GuardTry>& tries, bool by_cost, int extra_tries);

// The mouth bag follows its lips (FitHeadOptions::carry_mouth_bag). The bag
// is held where local fitting put it during global fitting (E_constraint:
// its points are not skin) while the lips around its opening follow the
// scan; where they move back by more than the bag's depth behind them (5 mm
// at the inner lip), the bag's wall comes out through the skin. So the
// movement of the bag's vertices becomes the harmonic interpolation (uniform
// weights over the bag's edges) of the movement of the vertices around it,
// which are the boundary condition: a translation of the lips carries the
// bag unchanged, and the bag bends smoothly where the lips moved apart.
// mouth_bag: #V flags; before: the mesh global fitting started from;
// control: its result (#V by 3, same triangles), whose bag vertices are
// replaced. A bag with no vertex outside it as a neighbour is left as it is.
Status carry_mouth_bag(const std::vector<char>& mouth_bag, const MeshTopology& topology, const TriMesh& before,
                       TriMesh& control);

// The rotation taking a scan with the given up and facing directions to the
// head frame (+y up, +z facing). Fails when they are (nearly) parallel.
Status orientation_from_conventions(const Vec3& up, const Vec3& facing, Mat3& rotation);

// 1, 0.01 or 0.001: the unit whose head-sized reading of the diagonal is most
// plausible (a head's bbox diagonal is about 0.35 m).
double guess_unit_to_metres(double bbox_diagonal);

}  // namespace lk
