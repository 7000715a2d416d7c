// The detector's face-outline landmarks as contour observations for the
// shape fit (issue 37): MediaPipe puts its face-oval points on the face's
// visible outline, which slides over the cheek and jaw as the view turns;
// matched to fixed surface points (plus a learned slide) they pull the
// wrong surface point where the true contour lies elsewhere. Here each such
// landmark must instead lie on the line its nearby occluding contour (rim)
// projects to, as a mask's outline point does (silhouette_obs.h, fua1998
// eq. 11): residual = signed pixel distance from the detected point to the
// rim edge met along the outline's normal, the edge searched near the
// landmark's surface place (within reach_m in 3-D) among every occluding
// contour of the current mesh (the jaw seen over the neck counts: the
// detector marks it). Rims are re-found at every reweighting round.
//
// Which landmarks: the outline loop's points whose surface place is seen
// at a grazing angle (normal . view direction < max_view_cos at the start
// shape): those the detector puts on the contour; the others (the
// forehead's top of the loop in a frontal view) stay fixed features.
//
// Shapes: outline loop #K (landmark indices, in order round the face).
#pragma once
#include "calib/camera.h"
#include "photos/landmarks.h"
#include "photos/self_calibration.h"
#include "photos/shape_fit.h"
#include "photos/silhouette_obs.h"

#include <array>
#include <vector>

namespace lk {

// MediaPipe Face Mesh's FACEMESH_FACE_OVAL, in order round the face (36).
const std::vector<int>& mediapipe_face_oval();

struct ContourOptions {
  double max_view_cos = 0.5;  // landmarks seen more frontally than this stay fixed features
  // Only the loop's points at least this many places from its top (the
  // forehead) on either side, i.e. the jaw and chin below the ears: higher
  // up the detector follows the face's edge in front of the ears and
  // hair, not the head's occluding contour (measured: docs/design/photos.md).
  int min_loop_depth = 13;
  double reach_m = 0.03;      // rim edges whose nearer vertex is this close to the landmark's place
  double search_px = 80;      // how far along the outline's normal (either way)
  double huber_px = 4;
  double min_normal_cos = 0.3;  // the outline's normal vs the rim's outward direction
};

struct ContourObservation {
  int camera = 0;
  int landmark = -1;
  SurfacePoint point;             // the landmark's surface place (the rim is searched near it)
  Vec2 pixel = Vec2::Zero(), normal = Vec2::Zero();  // detected point; outward normal of the detected outline
  double weight = 1, prior_weight = 1;
};

// Per photo, the outline loop's present landmarks with their outward image
// normals (perpendicular to the chord of their loop neighbours, pointing
// away from the loop's centroid). Empty when fewer than 8 are present.
std::vector<std::pair<int, Vec2>> outline_normals(const std::vector<Vec2>& points, const std::vector<char>& present,
                                                  const std::vector<int>& loop);

class ContourSet : public ObservationSet {
 public:
  // Rims are first matched at mesh.positions.
  ContourSet(const TriMesh& mesh, std::vector<Camera> cameras, std::vector<ContourObservation> observations,
             const ContourOptions& options);
  const char* type_name() const override { return "contours"; }
  int num_residuals() const override { return int(matches_.size()); }
  bool evaluate(const std::vector<Vec3>& positions, Eigen::VectorXd& r, int row,
                std::vector<Eigen::Triplet<double>>* jacobian) const override;
  void reweight(const std::vector<Vec3>& positions) override;
  // (No inlier_pixel_errors: the fit's rms stays the fixed features'.)

  struct Match {
    int observation = -1;
    int a = -1, b = -1;   // rim edge
    double weight = 1;
  };
  // Rims found at these positions; signed distance (px, + = the detected
  // point outside the rim: the head narrower there than the photo) of each
  // matched observation (NaN: no rim within reach).
  std::vector<double> signed_distances(const std::vector<Vec3>& positions) const;
  const std::vector<ContourObservation>& observations() const { return obs_; }
  const std::vector<Match>& matches() const { return matches_; }

 private:
  std::vector<Match> find_matches(const std::vector<Vec3>& positions) const;
  double distance(const std::vector<Vec3>& positions, const Match& m) const;

  std::vector<Tri> triangles_;
  std::vector<std::array<int, 4>> edges_;
  std::vector<Camera> cameras_;
  std::vector<ContourObservation> obs_;
  ContourOptions options_;
  std::vector<Match> matches_;
};

// Splits a photo's landmark observations: the outline loop's landmarks
// whose surface place (on `mesh`) this camera sees at a grazing angle
// (< options.max_view_cos) are contour observations. is_contour[m] = 1 for
// those; returns them.
std::vector<ContourObservation> contour_observations(const TriMesh& mesh, const std::vector<SurfacePoint>& landmarks,
                                                     const std::vector<Vec2>& points,
                                                     const std::vector<char>& present, const Camera& camera,
                                                     int camera_index, const ContourOptions& options,
                                                     std::vector<char>& is_contour);

// For reports: every used photo's outline-loop landmarks against the rim
// of the head at `positions` (the generic head's triangles), found as the
// contour observations do but for every loop landmark, whatever its view.
struct ContourDistance {
  int photo = 0, landmark = -1;
  int loop_index = 0;       // 0: the loop's top (forehead), 18: the chin; 1..17 one side, 19..35 the other
  Vec2 pixel = Vec2::Zero();
  double px = 0, mm = 0;    // + = the detected point outside the rim (the head narrower there); NaN: no rim within reach
};
std::vector<ContourDistance> contour_distances(const TriMesh& generic, const std::vector<SurfacePoint>& landmarks,
                                               const std::vector<LandmarkPhoto>& photos, const SelfCalibResult& calib,
                                               const std::vector<Vec3>& positions, const ContourOptions& options);

}  // namespace lk
