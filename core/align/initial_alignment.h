// Initial alignment of the generic head to a scan: jeong2002 Sec. 4.1.
// Finds the affine transform T (rotation, translation, non-uniform scale) of
// the generic mesh G minimizing D = sum over the front, side and top views of
// the pixels covered by exactly one of the silhouettes of T(G) and of the
// point cloud P (the paper's XOR + glGetHistogram), with Powell's method
// (numeric/powell.h). Both G and P are cut by a neck plane and a back-of-head
// plane that are fixed in the world once the initial T is known ("a generic
// position and orientation for each of these planes based on the initial T").
//
// Shapes: generic.positions #V by 3, generic.triangles #F by 3,
// cloud.positions #P by 3. The result maps a generic point p to
// linear * p + translation (world = scan coordinates).
//
// Differences from the paper, on purpose:
//  - CPU bit masks instead of an OpenGL frame buffer: an evaluation costs
//    about 0.5 ms of CPU at 256^2 (1 ms at 512^2) instead of the paper's
//    0.1-0.3 s (6-10 min over 8-14 x 250-300 evaluations); with two
//    threads, each draws half the triangles (common/helper_thread.h).
//  - Coarse-to-fine (64^2, 128^2, then the final resolution) for a wider
//    basin of convergence; on our test scans it does not save evaluations.
//  - Initialization: the paper matches bounding boxes. A scan's neck can be
//    longer or shorter than G's, and its back may be missing, so we match the
//    top of the head, the head's width over its upper half and the front
//    (nose) instead, with one uniform scale. Powell then fits the three scales.
//  - Sparse clouds: holes are closed morphologically (silhouette.h) instead of
//    raising the point size, so the outline does not grow.
#pragma once
#include "align/face_alignment.h"
#include "align/silhouette.h"
#include "common/progress.h"
#include "common/status.h"
#include "head/head_model.h"
#include "image/image.h"
#include "mesh/tri_mesh.h"

#include <array>
#include <vector>

namespace lk {

struct AlignOptions {
  // Final mask resolution N (N x N per view). The paper used 256 and 512.
  int resolution = 256;
  // Coarser resolutions solved first, in order; those >= resolution are skipped.
  std::vector<int> coarse_resolutions = {64, 128};
  // The view window is the cube around the clipped cloud and the initially
  // placed clipped generic head, grown by this fraction of its side per side.
  double window_margin = 0.12;
  // Cut the neck below the generic head's neck plane, and the back of the
  // head behind its back plane (both from HeadAnnotations).
  bool use_neck_clip = true;
  bool use_back_clip = true;
  // Draw only the generic's triangles that face each view (half the work;
  // needs the outward, counter-clockwise orientation of head_model.h).
  bool cull_back_faces = true;
  // Hole filling of the cloud's silhouettes.
  PointSplatOptions splat;
  // Powell, per resolution level. The objective is an integer pixel count,
  // so tolerance is a relative decrease per sweep of the directions.
  double tolerance = 1e-4;
  int max_iterations = 30;
  int max_evaluations = 6000;
  // Initial search steps (how far each parameter may plausibly be off):
  // translation as a fraction of the head height, rotation in degrees,
  // scale as a relative change (log scale).
  double step_translation = 0.05;
  double step_rotation_deg = 4.0;
  double step_scale = 0.05;
  // Starts of the search, as turns about the horizontal axis (degrees,
  // head up / down from the initialization). With several starts and
  // choose_at_final each is taken through every level (and polished, when
  // polish is on) and the least polished score, else the least final D,
  // chooses; without choose_at_final the least D on the coarse levels
  // chooses and only that start goes on to the final resolution. {0}: one
  // start, as the paper. {0, 10, -10} with the polish puts every turned
  // copy of Demosthenes within 0.7 deg of his pose as given (13 deg apart
  // with one start) but fits Plato and Gutenberg worse, so it is not the
  // default (docs/design/align.md, "Basins").
  std::vector<double> pitch_starts_deg = {0.0};
  bool choose_at_final = true;
  // Fraction of the clipped head height (from the top) over which the head
  // width and front are measured for the initialization.
  double init_slab_fraction = 0.5;
  // Fraction of extreme cloud points ignored per side when measuring
  // extents, so a few stray scanner points do not move the initial box.
  double init_outlier_fraction = 0.001;
  // Polish (not in the paper): the silhouettes' pixel count is flat in the
  // head's pitch on real busts, and where Powell stops on it changes with a
  // 0.05 deg turn of the scan (Demosthenes: 1-20 deg apart). Each start's
  // pose is then refined by a smooth measure: point-to-plane ICP of every
  // k-th clipped scan point (by index: the same points however the scan is
  // turned) onto the placed head, over a rotation, a scale along each of
  // the head's axes and a translation (face_alignment.h,
  // fit_scaled_rotation_icp), and the least clamped score after it chooses
  // between the starts. Off by default: it fits Plato and Gutenberg worse
  // (docs/design/align.md, "Basins").
  bool polish = false;
  int polish_points = 4000;
  int polish_iterations = 60;
  // How the polish weighs its pairs (face_alignment.h): Trim is session
  // 46's hard cut at 2.5 x the median; Tukey and GemanMcClure are robust
  // weights whose scale comes from the median distance, so shoulders, a
  // pedestal and hair fade out instead of pulling up to a threshold.
  IcpLoss polish_loss = IcpLoss::Trim;
  // With several polished starts: keep the one whose upper face
  // (face_refine.h, upper_face_samples, face_samples of them) lies closest
  // to the kept scan points (mean of min(d, face_clamp_fraction * the kept
  // scan's diagonal)), instead of the least whole-scan polished score: the
  // face must lie on the scan whatever else the scan holds. Off: with
  // Tukey's polish it holds Demosthenes' turned copies within 0.5 deg but
  // not Gutenberg's (up to 16 deg), and fits all three busts worse as
  // given (docs/design/align.md, "A robust polish").
  bool choose_by_face = false;
  int face_samples = 800;
  double face_clamp_fraction = 0.02;
  // Smooth score (not in the paper): Powell minimizes the symmetric chamfer
  // distance between the outlines of the mesh's and the scan's silhouettes
  // (silhouette.h, outline_chamfer) instead of the integer D, so it sees a
  // slope under sub-pixel moves; reverse distances are capped at
  // max(4 px, resolution / smooth_cap_divisor). D is still reported and
  // still chooses between pitch starts. Off by default: measured less
  // unstable than D on Demosthenes and Plato but still 1-9 deg apart, and it
  // refuses Gutenberg as given (docs/design/align.md, "A smooth silhouette score").
  bool smooth_score = false;
  int smooth_cap_divisor = 16;
};

// Per resolution level of the coarse-to-fine optimization.
struct AlignLevel {
  int resolution = 0;
  std::array<int, kSilhouetteViews> xor_before{};  // per view, at this level's start
  std::array<int, kSilhouetteViews> xor_after{};
  int evaluations = 0;
  int iterations = 0;
  std::vector<double> xor_per_iteration;  // D after each Powell sweep
  PointSilhouetteInfo cloud;              // closing radius and coverage per view
};

// Where the silhouettes are taken: the world-fixed window and clip planes.
struct AlignFrame {
  ViewWindow window;               // resolution = AlignOptions::resolution
  std::vector<ClipPlane> clips;    // world coordinates; neck first, then back (when used)
};

struct AlignResult {
  Mat3 linear = Mat3::Identity();  // world point = linear * generic point + translation
  Vec3 translation = Vec3::Zero();
  TriMesh aligned;                 // the generic mesh under that transform
  Mat3 initial_linear = Mat3::Identity();  // the initialization, before Powell
  Vec3 initial_translation = Vec3::Zero();
  // D per view at the final resolution, for the initial and the final T.
  std::array<int, kSilhouetteViews> xor_before{};
  std::array<int, kSilhouetteViews> xor_after{};
  int evaluations = 0;             // objective evaluations over all levels
  int iterations = 0;              // Powell sweeps over all levels
  std::vector<AlignLevel> levels;
  AlignFrame frame;
  // The optimized parameters: translation (in head heights), rotation vector
  // (radians, axis * angle), log scale per generic axis.
  std::array<double, 9> parameters{};
  // The polish (AlignOptions::polish): applied when `polished`; D per view
  // after it, its turn (deg) and scale on top of the silhouettes' pose.
  bool polished = false;
  std::array<int, kSilhouetteViews> xor_polished{};
  double polish_turn_deg = 0, polish_scale = 1, polish_rms = 0;
  int polish_iterations = 0;
  // Every pitch start as it ended (with several starts and choose_at_final):
  // its final D, polished score and face distance (AlignOptions::
  // choose_by_face; -1 when not measured); `chosen` indexes the one kept.
  struct Start {
    double pitch_deg = 0;
    int xor_final = 0;
    double polish_score = -1, face_distance = -1;
  };
  std::vector<Start> starts;
  int chosen = 0;
};

// Aligns generic (with its annotations, for the clip planes and the facing
// ann.look / ann.up) to cloud. The cloud must be roughly upright (+y) and
// face +z, as the paper assumes; its units and position are free.
// Errors: Empty (no points / no triangles), InvalidInput (NaN/inf, index out
// of range, a cloud without 3D extent, bad options), NotAHead (clipping
// leaves nothing to compare), Cancelled (progress returned false).
Status align_initial(const TriMesh& generic, const HeadAnnotations& ann, const PointCloud& cloud,
                     const AlignOptions& options, AlignResult& out, const ProgressFn& progress = {});

// Sum over views of xor_count.
int total_xor(const std::array<int, kSilhouetteViews>& per_view);

// Debug images like the paper's Fig. 2, one per view (front, side, top), each
// frame.window.resolution square, RGB: white where exactly one silhouette
// covers (the XOR the optimizer counts), dark grey where both cover, black
// elsewhere. Draws generic under (linear, translation) against the cloud,
// with the frame's clip planes and the options' hole filling. Pass
// result.initial_* for "before" and result.linear/translation for "after".
Status align_difference_images(const TriMesh& generic, const Mat3& linear, const Vec3& translation,
                               const PointCloud& cloud, const AlignFrame& frame,
                               const AlignOptions& options, std::array<Image, kSilhouetteViews>& out);

// The three views side by side with 2-pixel gaps, for a single PNG.
Image concat_views(const std::array<Image, kSilhouetteViews>& views);

}  // namespace lk
