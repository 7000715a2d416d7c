// Initial alignment for PARTIAL scans (a face patch from one frontal
// structured-light or photogrammetry station, a Cyberware scan cut to the
// face) and the checks that decide which alignment a scan needs.
//
// jeong2002 Sec. 4.1 aligns silhouettes of the whole head in three views and
// cuts away the neck and the back of the head with planes that "may have to
// be modified by the user ... according to the specifics of the range scan
// data". For a face patch no clip plane makes the silhouettes comparable: the
// patch's outline is wherever the scanner or the user cut it, so the front
// view compares an arbitrary outline with the head's, and the side and top
// views compare the head's full depth with a shell a few cm deep. What the
// patch does constrain is where its points lie, so here every scan point
// must lie ON the (similarity-transformed) generic head while the head may
// extend beyond the scan: iterative closest points (Besl & McKay 1992) with
// Umeyama's closed-form similarity per iteration (rotation, translation, one
// scale), trimmed (pairs farther than a multiple of the median are ignored),
// from a few start scales. The non-uniform scales of Sec. 4.1 are left to
// the local and global fits: a face patch does not determine the head's depth.
//
// Coverage: an upright (+y), +z-facing cloud is called face-only when its
// upper part (the crown of a full head, the forehead of a face) is much
// shallower than it is wide: a head's crown is 1-1.25x as deep as wide, a
// frontal capture's forehead shell 0.5-0.8x.
//
// Orientation: the same ICP, cheaper, from each up axis and eight yaws; a
// scan whose best alignment turns the head far from the given up / facing,
// and fits much better so, is in another convention (facing +x, lying on
// its back ...).
//
// Shapes: generic.positions #V by 3, generic.triangles #F by 3,
// cloud.positions #P by 3. Results map a generic point p to
// linear * p + translation (cloud coordinates).
#pragma once
#include "common/progress.h"
#include "common/status.h"
#include "head/head_model.h"
#include "mesh/tri_mesh.h"

#include <cstdint>
#include <string>
#include <vector>

namespace lk {

struct CoverageOptions {
  // The upper part measured: this fraction of the cloud's height, from the top.
  double slab_fraction = 0.35;
  // Upper-part depth / width below this: face-only. Measured: the generic
  // head 1.25, a six-station synthetic scan 1.01; a one-station frontal
  // synthetic scan 0.79, its front 40 % 0.61, menpo3d James 0.70, Fran 0.49.
  double face_only_depth_ratio = 0.85;
  double outlier_fraction = 0.005;  // extreme points ignored per side
};

struct ScanCoverage {
  Vec3 extent = Vec3::Zero();  // robust x (width), y (height), z (depth) extents, cloud units
  double slab_width = 0, slab_depth = 0;  // of the upper part
  double depth_to_width = 0;   // slab_depth / slab_width
  bool face_only = false;
};

// cloud: upright (+y) and facing +z, any unit. Fails on fewer than 10 points
// or non-finite coordinates.
Status estimate_coverage(const PointCloud& cloud, const CoverageOptions& options, ScanCoverage& out);

struct FaceAlignOptions {
  // Starts: each yaw (rotation about +y, degrees) times each scale, relative
  // to the scale that makes the generic head's part inside the cloud's box
  // (measured from the nose tip) as wide as the cloud. Every start is run
  // coarsely; the best is refined. Yaw starts matter for scans whose face
  // looks diagonally (Fran's Cyberware patch looks 45 degrees off its axes):
  // ICP from a single start turns only part of the way.
  std::vector<double> start_yaws_deg = {-45.0, 0.0, 45.0};
  std::vector<double> start_scales = {0.9, 1.0, 1.1};
  // Samples are stratified, one point per cell of a voxel grid sized for the
  // count (common/sampling.h): an even cover of the scanned surface, so
  // that which points are drawn (the seed) hardly moves the result.
  int coarse_points = 800;     // samples per coarse start
  int coarse_iterations = 20;
  // The best coarse results that differ (rotation by more than
  // distinct_deg or scale by more than distinct_scale) are each refined on
  // max_points samples, then polished on final_points (the whole cloud
  // when it has no more) until the trimmed RMS changes less than
  // polish_tolerance, and the one that fits those best is taken: the
  // choice between nearly equal basins is made on the full cloud, not on a
  // subset (picking the best coarse start on a random subset turned Fran
  // differently for different subsets, and in wasm).
  int refine_candidates = 2;
  // Then the best is polished again from its scale times 1 +- each hop;
  // a score lower by more than scale_hop_gain (relative) replaces it (see
  // align_face). Empty: no hops. It corrects a one-station synthetic
  // capture's scale; the real face scans' small gains are not taken.
  std::vector<double> scale_hops = {0.01};
  double scale_hop_gain = 0.005;
  double distinct_deg = 3.0;
  double distinct_scale = 0.03;
  int max_points = 3000;       // samples for the refinement
  int final_points = 20000;    // samples for the polish and the choice
  double polish_tolerance = 1e-5;
  int max_iterations = 60;
  double relative_tolerance = 1e-4;  // stop when the trimmed RMS changes less than this
  // Pairs farther than trim_factor * median distance do not pull (the part
  // of a scan the head does not model: shoulders, hair strands, a collar).
  double trim_factor = 2.5;
  // Score of a result: mean of min(d, score_clamp)^2 over the subset, with
  // score_clamp this fraction of the cloud's bbox diagonal.
  double score_clamp_fraction = 0.03;
  // Which point of each grid cell the samples take. Any seed gives the same
  // alignment in practice (tests/align: James and Fran for seeds 1-10).
  std::uint32_t seed = 7;
};

struct FaceAlignResult {
  Mat3 linear = Mat3::Identity();  // cloud point = linear * generic point + translation
  Vec3 translation = Vec3::Zero();
  double scale = 1;                // uniform scale inside linear
  Mat3 rotation = Mat3::Identity();  // linear = scale * rotation * (generic facing -> +z, +y)
  Vec3 facing = Vec3::UnitZ();     // where the aligned face looks, cloud frame (rotation * +z)
  Vec3 up = Vec3::UnitY();         // rotation * +y
  double rms = 0;                  // trimmed RMS distance of the last iteration, cloud units
  double score = 0;                // see FaceAlignOptions::score_clamp_fraction, cloud units^2
  double inlier_fraction = 0;      // share of the subset within the trim distance
  int iterations = 0;              // over all starts
  int starts = 0;
};

// Aligns generic (ann.look / ann.up give its facing) to a cloud that is
// roughly upright (+y) and faces +z (within the yaw starts). Errors: Empty,
// InvalidInput (non-finite or too few points, bad options), NotAHead (no
// usable correspondences), Cancelled.
Status align_face(const TriMesh& generic, const HeadAnnotations& ann, const PointCloud& cloud,
                  const FaceAlignOptions& options, FaceAlignResult& out, const ProgressFn& progress = {});

struct OrientationOptions {
  // Coarse ICP from every up axis (6) times yaws 0, 45, ..., 315 degrees,
  // on `points` stratified samples (see FaceAlignOptions).
  int points = 600;
  int iterations = 30;
  // Screening: every start runs screen_iterations first; only the
  // screen_keep best of them, and the screen_keep best consistent with the
  // given orientation, go on to `iterations` and into the choice below (the
  // others' scores are no longer compared). 0: every start runs through.
  // Face scans run all 48 starts (accept_given_fraction); screening cuts
  // about a quarter of the stage's CPU with the same guess to the bit on
  // the real and turned face patches (tests/align; docs/design/align.md).
  int screen_iterations = 10;
  int screen_keep = 8;
  // The screening on this many of the `points` samples (0: all); the starts
  // kept run again from their start on all `points`: the full search's bits
  // per kept start. The 25 real-scan copies keep every map to the bit, ~0.25 s
  // less each; continuing from the screened pose moved Fran's turn and one
  // copy's fit (docs/design/align.md, session 50).
  int screen_points = 150;
  // The best `candidates` distinct coarse results and the best one
  // consistent with the given orientation are scored on final_points
  // samples (all points when the cloud has no more), the decision is made
  // there, and the best, when it would turn the scan (not consistent with
  // the given orientation), is polished there (a decision on 600 points
  // alone depended on which 600).
  int candidates = 3;
  int final_points = 8000;
  std::uint32_t seed = 7;  // which point of each grid cell is sampled
  // The given orientation is kept unless the best start ends with its up
  // more than up_tolerance_deg, or its facing more than facing_tolerance_deg,
  // away from +y / +z, AND scores below better_ratio times the best start
  // that ends consistent with the given orientation.
  double up_tolerance_deg = 40.0;
  double facing_tolerance_deg = 70.0;
  double better_ratio = 0.8;
  // The given orientation is tried first; when its trimmed RMS distance is
  // below this fraction of the cloud's bbox diagonal (a synthetic head in
  // the right orientation scores 0.4 %, the best orientations of real face
  // scans 1.4-1.7 %), no other orientation can be clearly better and the
  // other 47 starts are skipped (about 0.6 s on every well-posed fit).
  double accept_given_fraction = 0.006;
  // After the screening, the search also stops when the given orientation
  // is clearly best: every start ending turned (not consistent with it)
  // scores at least 1 / better_ratio times the given start's, the margin a
  // turn needs the other way round. The rest (the kept starts' further
  // iterations, the candidates' dense scores) could not turn the scan.
  bool stop_when_given_clearly_best = true;
  double snap_deg = 25.0;  // directions this close to an axis are reported as that axis
};

struct OrientationGuess {
  Vec3 facing = Vec3::UnitZ();       // where the face looks, in the given cloud's frame
  Vec3 up = Vec3::UnitY();           // (snapped to an axis when close to one)
  Mat3 rotation = Mat3::Identity();  // apply to the cloud: up -> +y, facing -> +z
  double score_given = 0;            // best score consistent with the given orientation (0: none)
  double score_best = 0;
  bool differs = false;              // the scan is clearly in another orientation
  bool given_clearly_best = false;   // stopped after the screening (stop_when_given_clearly_best)
};

Status guess_orientation(const TriMesh& generic, const HeadAnnotations& ann, const PointCloud& cloud,
                         const OrientationOptions& options, OrientationGuess& out,
                         const ProgressFn& progress = {});

// How fit_scaled_rotation_icp weighs a pair at distance d from the
// surface. Trim: 1 up to min(trim_factor * median d, clamp), else 0.
// Tukey / GemanMcClure: an M-estimator's weight, re-weighted every
// iteration (IRLS), with the scale s = 1.4826 * median d over the pairs
// within the clamp (a normal residual's sigma): Tukey's biweight
// (1 - (d / 4.685 s)^2)^2 inside 4.685 s and 0 outside, Geman-McClure's
// 1 / (1 + (d / s)^2)^2. The trim's cut-off is hard: pairs just inside
// 2.5 x the median (a shoulder, a pedestal's rim, hair) pull as much as
// the face; the M-estimators fade them out smoothly, so the minimum does
// not jump as pairs cross a threshold. Pairs beyond the clamp never pull.
enum class IcpLoss { Trim, Tukey, GemanMcClure };

// Point-to-plane ICP of samples onto surface (FaceAlignOptions'
// max_iterations and trim_factor), from the identity, over a rotation, a
// scale along each of the given axes (columns, a rotation) and a
// translation: linear * surface + translation fits the samples, with
// linear = rotation * axes * diag(scales) * axes^T, the pairs weighed by
// `loss`. score: mean of min(d, clamp)^2 over all samples.
struct ScaledRotationFit {
  Mat3 linear = Mat3::Identity(), rotation = Mat3::Identity();
  Vec3 scales = Vec3::Ones();
  Vec3 translation = Vec3::Zero();
  double rms = 0, score = 0, inlier_fraction = 0;  // rms and inliers over the pairs that pull (weight > 0)
  double loss_scale = 0;  // the M-estimator's s in the last iteration (0 with Trim)
  int iterations = 0;
};
Status fit_scaled_rotation_icp(const TriMesh& surface, const std::vector<Vec3>& samples, const Mat3& axes,
                               const FaceAlignOptions& options, double clamp, ScaledRotationFit& out,
                               IcpLoss loss = IcpLoss::Trim);

// "+x", "-z", ... for an axis direction; "(0.1, 0.7, 0.7)" otherwise.
std::string axis_name(const Vec3& direction);

}  // namespace lk
