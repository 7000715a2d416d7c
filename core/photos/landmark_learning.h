// A landmark map re-made from the detector's own points on photos whose
// truth is known (synthetic people and cameras, tests/browser/
// detect_synth_photos.mjs): each landmark triangulated from the detector's
// pixels with the true cameras, carried onto the generic head through the
// person's surface (same triangle and barycentrics, plus the offset from
// the surface), and the median over the people taken. The result is where
// the detector sees each landmark, which for MediaPipe is not on the skin:
// its eye and lip points sit mm in front of it (docs/design/photos.md).
//
// Shapes: sessions #S; in each, cameras and photos #C (photo c seen by
// camera c); the start map #M; the person meshes have the generic's triangles.
#pragma once
#include "calib/camera.h"
#include "common/status.h"
#include "photos/landmarks.h"

#include <array>
#include <vector>

namespace lk {

struct DetectedSessionView {
  const TriMesh* person = nullptr;     // the truth, same triangles as the generic head
  std::vector<Camera> cameras;         // #C, the truth
  std::vector<LandmarkPhoto> photos;   // #C, the detector's points
};

struct LearnMapOptions {
  double min_view_cos = 0.3;     // a view counts where the landmark's surface faces its camera by this much
  int min_views = 2;             // per session, to triangulate
  int min_sessions = 2;          // sessions agreeing, else the start map's point is kept
  double max_offset_m = 0.012;   // off-surface offsets clamped (PhotosJobOptions::map_max_distance_m is above it)
};

struct LearnMapReport {
  int learned = 0;                // landmarks re-made
  double median_move_m = 0;       // from the start map
};

// start: the map being corrected (its points give the surface place whose
// normal decides visibility); out: same detector and indices. Fails with
// InvalidInput on a session whose sizes disagree or a person of another
// topology, Empty when no landmark could be learned.
Status learn_landmark_map(const TriMesh& generic, const LandmarkMap& start,
                          const std::vector<DetectedSessionView>& sessions, const LearnMapOptions& options,
                          LandmarkMap& out, LearnMapReport* report = nullptr);

// The map and the detector's view-dependent slide learned together
// (landmark_slide.h): per landmark, its offset o from its surface place and
// its shifts D_k, so that the true camera c sees it at the person's surface
// place + o + sum_k phi_k(view_c) D_k where the detector put it. Gauss-Newton
// on the reprojection errors (each view's rows scaled by depth / focal,
// i.e. metres at the landmark), Huber weights, a Gaussian prior on the
// shifts (ridge: (noise_m / shift_prior_m)^2). Then the scatter left, per
// landmark, kernel-smoothed over the views' yaw at sigma_yaw_deg. Done
// twice: the second pass from the first's points re-attached (their
// surface place under them). A landmark with fewer views than
// 2 (terms + 1) keeps a fixed point (no slide) when it has min_views.
struct LearnSlideOptions {
  double min_view_cos = 0.3;        // as LearnMapOptions (and the self-calibration's visibility)
  int min_views = 4;                // over all sessions, for a point
  int min_sessions = 2;
  std::vector<std::array<int, 2>> terms = {{1, 0}, {0, 1}, {2, 0}, {1, 1}, {0, 2}, {3, 0}};
  double shift_prior_m = 0.005;     // expected size of a shift coefficient
  double noise_m = 0.0015;          // expected scatter (sets the ridge and the Huber threshold, 3 x)
  double max_offset_m = 0.012;      // as LearnMapOptions
  std::vector<double> sigma_yaw_deg = {-60, -45, -30, -15, 0, 15, 30, 45, 60};
  double sigma_kernel_deg = 12;     // Gaussian kernel over the views' yaw for the scatter
  int passes = 2;
};

struct LearnSlideReport {
  int learned = 0, sliding = 0;     // landmarks with a point, and of those with a slide
  double yaw_range_deg = 0, pitch_range_deg = 0;  // of the training views
  double rms_fixed_m = 0, rms_slide_m = 0;        // training residual (metres at the landmark, per coordinate): point only, with the slide
};

Status learn_landmark_slide(const TriMesh& generic, const LandmarkMap& start,
                            const std::vector<DetectedSessionView>& sessions, const LearnSlideOptions& options,
                            LandmarkMap& out, LearnSlideReport* report = nullptr);

}  // namespace lk
