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
  // head up / down from the initialization): each is taken through the
  // coarse levels and the one with the least D there goes on to the final
  // resolution (with no coarse level: the least D at the final one). {0}:
  // one start, as the paper. Three starts (0, 15, -15) put Demosthenes'
  // nudged copies in one basin but not Plato's, for twice the alignment's
  // CPU and a worse fit of Demosthenes (docs/design/fit_real_scans.md).
  std::vector<double> pitch_starts_deg = {0.0};
  // Fraction of the clipped head height (from the top) over which the head
  // width and front are measured for the initialization.
  double init_slab_fraction = 0.5;
  // Fraction of extreme cloud points ignored per side when measuring
  // extents, so a few stray scanner points do not move the initial box.
  double init_outlier_fraction = 0.001;
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
