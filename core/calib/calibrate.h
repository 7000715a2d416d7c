// Camera calibration from 2-D/3-D feature correspondences (tarini2002 Sec. 3:
// "about 12-15 corresponding feature points on the mesh and in the image";
// the paper uses Tsai's method with pre-calibrated intrinsics, we also
// estimate intrinsics when they are unknown).
//
// Method: normalized DLT (Hartley & Zisserman, Alg. 7.1) for an initial 3x4
// projection P; RQ decomposition of P into K, R, t (det R = +1, positive
// focal); then Levenberg-Marquardt on the reprojection error over
// f (fx = fy unless separate_focal), cx, cy, k1, k2, axis-angle rotation and
// t. Robustness: RANSAC over minimal 6-point DLT sets followed by iterative
// outlier rejection (threshold max(outlier_px, 3 * 1.4826 * MAD)). Against
// the focal/distance ambiguity: an optional soft focal prior (EXIF) and joint
// calibration of several photos sharing one focal (calibrate_cameras_shared).
//
// Shapes: correspondences #N (N >= 6); CalibResult::errors and ::outlier #N.
#pragma once
#include "calib/camera.h"
#include "common/status.h"

#include <array>
#include <vector>

namespace lk {

struct CalibOptions {
  // Known intrinsics: when known_focal > 0, fx = fy = known_focal is fixed
  // (e.g. the Kira photos: 3813.6 px at 1800x1200) and only the pose (plus
  // the principal point / distortion if not fixed) is estimated. The
  // principal point then starts at the image centre.
  double known_focal = 0;
  bool separate_focal = false;        // estimate fx and fy separately (default fx = fy)
  // Off by default: with 12-15 points on a head that fills a third of the
  // frame, a free principal point and k1 fit 1 px click noise (measured in
  // the tests: k1 up to 0.7, rotation 18 deg off). Turn on with many points.
  bool fix_principal_point = true;    // keep (cx, cy) at the image centre; forced when N < 8
  bool estimate_k1 = false;           // radial distortion k1 (needs >= 8 inliers, else fixed at 0)
  bool estimate_k2 = false;           // radial distortion k2 (needs >= 10 inliers)
  // Soft focal prior (e.g. from the photo's EXIF, see io/exif.h), used when
  // the focal is free (known_focal == 0): LM adds the residual
  // pixel_sigma * (f - focal_prior) / (focal_prior_sigma * focal_prior), i.e.
  // a Gaussian prior of relative standard deviation focal_prior_sigma against
  // click noise of pixel_sigma px per coordinate. It fixes the focal/distance
  // ambiguity of 12-15 points on a head. 0 = no prior.
  double focal_prior = 0;
  double focal_prior_sigma = 0.05;    // EXIF 35-mm-equivalent focals are rounded to 1 mm: ~2-5 %
  double pixel_sigma = 1.0;           // expected click noise per coordinate, pixels
  // When non-zero: the camera must be on this side of the points (e.g. the
  // head's look direction: a face is photographed from the front). Shallow,
  // symmetric landmark sets also fit a camera mirrored through them; this
  // picks the right one. Zero = no constraint.
  Vec3 seen_from = Vec3::Zero();
  bool robust = true;                 // RANSAC + outlier rejection
  double outlier_px = 3.0;            // minimum rejection threshold, pixels
  int ransac_iterations = 300;        // minimal-set trials at most (deterministic seed)
  // RANSAC stops once a minimal set of inliers has been drawn with this
  // probability at the best consensus so far (Hartley & Zisserman, Alg.
  // 4.5); 0: always ransac_iterations trials.
  double ransac_confidence = 0.999;
  int max_lm_iterations = 100;        // Levenberg-Marquardt iterations per refinement
};

struct CalibResult {
  Camera camera;
  std::vector<double> errors;   // #N reprojection error of each point, pixels (inf if behind camera)
  std::vector<char> outlier;    // #N, 1 = flagged (excluded from the final fit)
  double rms = 0;               // RMS reprojection error over the inliers, pixels
  int num_inliers = 0;
};

// Calibrates one photo. Fails with InvalidInput on fewer than 6
// correspondences, NaN/inf values, non-positive image size, degenerate
// configurations (collinear points; coplanar points with free intrinsics,
// which DLT cannot resolve: give known_focal), or a solution that puts the
// points behind the camera; NotConverged when no consistent camera is found.
Status calibrate_camera(const std::vector<Correspondence>& correspondences, int image_width,
                        int image_height, const CalibOptions& options, CalibResult& result);

// Several photos taken with ONE camera (same lens and zoom): one focal length
// fx = fy shared by all photos, a pose per photo, principal points at the
// image centres, no distortion. Each photo is first calibrated alone (with the
// options above, RANSAC and outlier flags included); then the focal (starting
// from the prior, else from the median of the single-photo focals) and all
// poses are refined jointly by LM on every inlier, and the outliers are
// re-classified. With 12-15 points per photo the focal is poorly determined
// by one photo (perspective effects of a head-sized object are weak); N
// photos give N independent measurements of it.
//
// Shapes: photos #P (P >= 1) sets of correspondences (each >= 6),
// image_sizes #P (width, height); result.photos #P.
struct SharedCalibResult {
  double focal = 0;                 // the shared focal, pixels
  std::vector<CalibResult> photos;  // #P: cameras with fx = fy = focal, per-point errors and outlier flags
  double rms = 0;                   // RMS reprojection error over all inliers, pixels
};
Status calibrate_cameras_shared(const std::vector<std::vector<Correspondence>>& photos,
                                const std::vector<std::array<int, 2>>& image_sizes,
                                const CalibOptions& options, SharedCalibResult& result);

}  // namespace lk
