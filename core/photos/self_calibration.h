// Self-calibration from landmarks (issue 37, stage 2): uncalibrated photos
// of one head -> one shared focal length and a pose per photo, plus the 3-D
// positions of the landmarks on this person's head.
//
// 1. Each photo alone: its landmarks against the generic head's mapped
//    points (core/calib: DLT, RANSAC, LM); a photo that cannot be calibrated
//    is refused with the reason.
// 2. All photos with one focal (calibrate_cameras_shared, EXIF prior optional).
// 3. Bundle adjustment of the focal, every pose and every landmark's 3-D
//    position (the person's shape is unknown), each landmark pulled toward
//    its generic-head position with a Gaussian prior (sigma shape_sigma_m;
//    this also fixes the gauge: absolute scale is not observable from
//    uncalibrated photos, so the result has the generic head's size).
//    Robust: Huber weights by iterative reweighting, so a wrong landmark
//    loses its pull.
// 4. A photo whose robust RMS reprojection error stays far above the others'
//    (another person, a mislabelled file) is refused and step 3 re-run.
// 5. With >= 3 photos: the adjustment's focal weighed by the photos'
//    disagreement and combined with a prior (SelfCalibOptions, below).
//
// Coordinates: the generic head's (metres). Principal points at the image
// centres, no distortion (phone photos are undistorted by the phone).
// Shapes: photos #P, landmarks #M (the map's points; invalid = unmapped),
// each photo's points #N (indices >= M are ignored).
#pragma once
#include "calib/camera.h"
#include "common/status.h"
#include "photos/landmarks.h"

#include <string>
#include <vector>

namespace lk {

struct SelfCalibOptions {
  double focal_prior_px = 0;        // EXIF focal in pixels (0 = none)
  double focal_prior_sigma = 0.05;  // its relative standard deviation
  double pixel_sigma = 2.0;         // expected landmark noise per coordinate, pixels
  double shape_sigma_m = 0.01;      // how far a person's landmark may sit from the generic's
  double huber_k = 2.0;             // Huber threshold, in pixel_sigma units
  int reweighting_rounds = 4;       // IRLS rounds, each a full LM run
  int min_landmarks = 12;           // fewer in a photo: refused
  // A landmark is used in a photo only where the generic head's normal at
  // its mapped point faces the photo's camera: cos(angle) >= min_view_cos
  // (the detector puts hidden points on the silhouette). -1 keeps all.
  double min_view_cos = 0.3;
  // Refusal of a photo after bundle adjustment: the median error of its
  // landmarks above max(refuse_factor * the photos' median of medians,
  // refuse_min_sigma * pixel_sigma). The factor sits above what a real
  // detector reaches on real photos of one person (its bias changes with
  // the view: 2.0x on the Kira photos from below), so only a face that
  // differs clearly is caught (docs/design/photos.md).
  double refuse_factor = 3.0;
  double refuse_min_sigma = 2.0;
  // Refuse a photo whose landmarks fit only a camera that sees the head
  // upside down (head's +y pointing down the image).
  bool refuse_upside_down = true;
  // With a slide model (landmark_slide.h) that has a scatter: each
  // observation's noise is the landmark's scatter at that view, in pixels
  // (at least min_sigma_px), instead of pixel_sigma for all.
  bool use_slide_sigma = true;
  double min_sigma_px = 1.0;
  // A per-photo depth scale k in the bundle adjustment (0 = off): each
  // photo sees the landmarks with their depth about the head's origin, along
  // its optical axis, times k (prior: k ~ N(mean, depth_scale_sigma)). It
  // takes up an error shared by all of a photo's points that looks like a
  // nearer or farther camera (the detector's "zoom"), which otherwise moves
  // the shared focal. The mean: depth_scale_0 + depth_scale_yaw2 *
  // (yaw / 60 deg)^2 at the photo's view from the shared calibration.
  double depth_scale_sigma = 0;
  double depth_scale_0 = 1;
  double depth_scale_yaw2 = 0;
  // The focal from the landmarks with its honest uncertainty, then a prior.
  // A detector's error is shared by a photo's points (its "zoom"), so the
  // bundle adjustment, weighing every point as independent, is far too sure
  // of its focal. With >= 3 photos and a prior (EXIF's focal_prior_px, else
  // the typical phone's below): the bundle adjustment runs without the
  // prior, its focal's variance is taken from the photos' disagreement
  // (jackknife: each photo left out in turn), the two are combined as
  // Gaussians, and the adjustment runs again at that focal. Exact points
  // agree across photos and override any prior; a detector's do not.
  // Off by default (`likeness photos --focal-jackknife`): on the detected
  // sessions it brings the focal within 10 % but the heads 0.03-0.1 mm
  // farther from the people, and Kira's focal farther from her lens
  // (docs/design/photos.md, "The focal from the landmarks, honestly weighed").
  bool focal_from_jackknife = false;
  // No EXIF: a phone main camera's 35-mm-equivalent focal (on the image
  // diagonal, 43.27 mm) as the prior, and its relative sigma (0 = none).
  double typical_focal_35mm = 26;
  double typical_focal_sigma = 0.08;
  // With a slide model (a learned detector): that detector's landmarks'
  // focal over the true one, measured on its training sessions; the
  // landmarks' focal (and its jackknife sigma) is divided by it. 1 = none.
  // The photos job sets MediaPipe's (PhotosJobOptions::mediapipe_focal_ratio).
  double slide_focal_ratio = 1;
};

// In its own inline namespace: project/texture_job.h and the texture
// self-test also define an lk::PhotoCalibration, and two classes of one
// mangled name in one program break the one-definition rule (the linker
// kept one destructor for both). Code that names lk::PhotoCalibration
// still finds this one where only this header is included.
inline namespace self_calib {
struct PhotoCalibration {
  bool used = false;
  std::string refusal;              // why the photo was dropped (empty when used)
  Camera camera;                    // valid when used
  double rms_px = 0;                // RMS reprojection error after BA over the inliers, pixels
  double median_px = 0;             // median reprojection error of its landmarks after BA (the refusal's measure)
  int num_landmarks = 0;
  int num_hidden = 0;               // landmarks left out as turned away from this camera
  int num_outliers = 0;             // landmarks with error beyond 2 huber_k pixel_sigma
  std::vector<double> weights;      // #N, final IRLS weight of each landmark (0 where absent)
  double depth_scale = 1;           // the bundle adjustment's per-photo depth scale (1 when off)
};
}  // namespace self_calib

struct SelfCalibResult {
  double focal = 0;                      // the shared focal, pixels
  double focal_before_ba = 0;            // the shared calibration's focal, before the bundle adjustment
  double focal_landmarks_raw = 0;        // the bundle adjustment's focal without a prior (0: not measured)
  double focal_landmarks = 0;            // the same over slide_focal_ratio (the detector's bias out)
  double focal_landmarks_sigma = 0;      // its jackknife standard deviation over the photos, pixels
  double focal_prior = 0, focal_prior_sigma = 0;  // the prior combined with it (EXIF or typical), pixels
  std::vector<PhotoCalibration> photos;  // #P
  std::vector<Vec3> landmarks;           // #M, bundle-adjusted 3-D positions (generic where unmapped/unseen)
  std::vector<char> landmark_seen;       // #M, 1 = observed in >= 2 used photos
  double initial_rms_px = 0, final_rms_px = 0;  // all used photos, before/after BA
  int lm_iterations = 0;
  int num_used() const;
};

// The typical phone's focal in pixels for an image (35-mm-equivalent focal
// on the diagonal: f_px = f_35 * hypot(width, height) / 43.27 mm).
double typical_focal_px(double focal_35mm, int width, int height);

// Fails with InvalidInput on inconsistent sizes or a bad option, NotConverged
// when fewer than 2 of several photos are usable (the refusals say why per
// photo). A single photo is calibrated alone (its landmarks' depths then
// rest on the generic head's prior). slide: the detector's view-dependent
// slide (landmark_slide.h, indexed as landmarks), or null: landmark m is
// then seen at its point plus its shift for the camera's view, in the
// initial cameras and in the bundle adjustment (the shift's dependence on
// the camera's pose included in the Jacobian).
Status self_calibrate(const std::vector<LandmarkPhoto>& photos, const TriMesh& generic,
                      const std::vector<SurfacePoint>& landmarks, const SelfCalibOptions& options,
                      SelfCalibResult& result, const LandmarkSlide* slide = nullptr);

// An observation's noise in pixels under the slide's scatter: the
// landmark's scatter at the camera's view times focal / depth, at least
// min_px; fallback_px where the slide has no scatter for it.
double slide_sigma_px(const LandmarkSlide& slide, int landmark, const Camera& camera, const Vec3& X, double min_px,
                      double fallback_px);

// Where a camera sees the head from, in degrees: yaw = atan2(C.x, C.z)
// (positive: from the head's left, +x), pitch = the camera centre's
// elevation above the x-z plane (positive: from above), C = the camera centre
// in the generic head's frame (origin inside the head, +y up, +z forward).
void view_angles(const Camera& camera, double& yaw_deg, double& pitch_deg);

// The bundle-adjustment residuals, exposed for the Jacobian tests: for
// photo i's observation of landmark m, the pixel residual
// (project(camera, X) - observed) and its derivatives with respect to the
// focal (fx = fy), the rotation increment w (R <- exp([w]x) R), t and X.
// depth_scale k: the point seen at camera coordinates (R X)_xy + t_xy,
// k (R X)_z + t_z (SelfCalibOptions::depth_scale_sigma); d_depth_scale its
// derivative.
struct ProjectionJacobian {
  Vec2 residual = Vec2::Zero();
  Eigen::Matrix<double, 2, 1> d_focal, d_depth_scale;
  Eigen::Matrix<double, 2, 3> d_rotation, d_translation, d_point;
};
bool projection_jacobian(const Camera& camera, const Vec3& X, const Vec2& observed, ProjectionJacobian& out,
                         double depth_scale = 1);

// The same for landmark m that slides with the view: the residual of
// X + landmark_shift(camera centre), and the shift's dependence on the
// camera's rotation and translation added to those derivatives.
bool slid_projection_jacobian(const Camera& camera, const Vec3& X, const LandmarkSlide& slide, int landmark,
                              const Vec2& observed, ProjectionJacobian& out, double depth_scale = 1);

}  // namespace lk
