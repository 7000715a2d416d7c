// The detector's view-dependent slide (issue 37): a real face-landmark
// detector (MediaPipe) does not see a landmark at one fixed place on the
// head; its point moves with the view (the face's outline follows the
// silhouette over the cheek, the lids and lips shift by a few mm), which no
// fixed map holds. Per landmark, a 3-D shift in the head's frame as a
// smooth function of where the camera sees the head from, and the
// landmark's remaining scatter there (the detector's reliability), both
// learned from the real detector's points on synthetic sessions with their
// truth (landmark_learning.h) and stored in the landmark map (version 2).
//
// The view: the camera centre C in the head's frame (origin inside the
// head, +y up, +z forward), yaw = atan2(C.x, C.z), pitch = atan2(C.y,
// hypot(C.x, C.z)) (self_calibration.h's view_angles), each divided by the
// range the model was learned on and clamped to [-1, 1] (a view beyond it
// gets the edge's shift: a polynomial is not extrapolated). The shift is
// sum_k a^i_k b^j_k D_k over the terms (i_k, j_k) (a, b: normalized yaw,
// pitch), D_k a 3-vector per landmark and term.
//
// Shapes: landmarks #M; terms #K; scatter bins #B.
#pragma once
#include "common/types.h"

#include <array>
#include <vector>

namespace lk {

struct LandmarkSlide {
  double yaw_range = 0, pitch_range = 0;         // radians; views are normalized by these (0: no model)
  std::vector<std::array<int, 2>> terms;         // #K, exponents (i, j) of a, b; no (0, 0) (the map point is the constant)
  std::vector<std::vector<Vec3>> shifts;         // #M, each #K (empty: this landmark does not slide), metres
  // The scatter left after the slide, per landmark at yaw bin centres (linear
  // between them, constant beyond): metres at the landmark, per image
  // coordinate. Empty: no scatter model (all landmarks alike).
  std::vector<double> sigma_yaw;                 // #B, radians, increasing
  std::vector<std::vector<double>> sigma;        // #M, each #B (empty: none for this landmark)
  bool has_slide() const { return yaw_range > 0 && pitch_range > 0 && !terms.empty() && !shifts.empty(); }
  bool has_sigma() const { return !sigma_yaw.empty() && !sigma.empty(); }
};

// Normalized view (a, b) of a camera centre, and its derivatives with
// respect to C (zero where clamped).
struct SlideView {
  double a = 0, b = 0;
  Eigen::Matrix<double, 2, 3> d_center = Eigen::Matrix<double, 2, 3>::Zero();
};
SlideView slide_view(const LandmarkSlide& slide, const Vec3& camera_center);

// Landmark m's shift at a view, and (optional) its derivative with respect
// to the camera centre (3x3). Zero where the landmark has no slide.
Vec3 landmark_shift(const LandmarkSlide& slide, int m, const SlideView& view, Mat3* d_center = nullptr);

// Landmark m's scatter at a camera centre, metres (0: no model for it).
double landmark_sigma(const LandmarkSlide& slide, int m, const Vec3& camera_center);

}  // namespace lk
