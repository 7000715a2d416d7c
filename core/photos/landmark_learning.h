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

}  // namespace lk
