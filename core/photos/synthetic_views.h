// Synthetic photo sessions with ground truth for the photos-to-head stages
// (issue 37's checks; not from the paper): phone-like cameras around a
// synthetic head (core/synth), and the "detected" landmarks = the mapped
// surface points of that head projected by the known cameras plus Gaussian
// pixel noise, null where the point is hidden (self-occluded or facing
// away) or outside the image.
//
// placeholder_landmark_map: a stand-in for the real MediaPipe map (made in
// the browser with the detector, same file format): `count` generic-head
// vertices spread over the face (farthest-point sampling of the face
// vertices seen by a frontal camera). Nothing downstream depends on which
// map is used.
//
// Shapes: landmarks #M; session cameras and photos #C.
#pragma once
#include "calib/camera.h"
#include "common/status.h"
#include "head/head_model.h"
#include "photos/landmarks.h"

#include <cstdint>
#include <vector>

namespace lk {

Status placeholder_landmark_map(const GenericHead& generic, int count, LandmarkMap& out);
// The placeholder map's and the synthetic photos' detector name: not
// MediaPipe's, so synthetic points files are never read with the real map.
inline constexpr const char* kPlaceholderDetector = "likeness-placeholder-vertices";

struct SyntheticViewsOptions {
  int num_cameras = 10;
  int width = 1200, height = 1600;  // portrait phone photo
  double focal_px = 1250;           // ~26 mm equivalent at this size
  double distance_m = 0.6;          // camera to face centre, +-10 % per photo
  double azimuth_deg = 90;          // cameras from -azimuth (right profile) to +azimuth
  double elevation_deg = 12;        // alternately above and below, +-
  double roll_deg = 5;              // phone held slightly tilted, +-
  double noise_px = 2.0;            // landmark noise per coordinate (Gaussian sigma)
};

struct SyntheticSession {
  std::vector<Camera> cameras;       // #C, the truth
  std::vector<LandmarkPhoto> photos; // #C, detector kPlaceholderDetector, names view_XX.png
};

// head: the person (same topology as the head the landmarks were attached
// to); landmarks: surface points on it. Deterministic for a seed.
Status make_synthetic_views(const GenericHead& head, const std::vector<SurfacePoint>& landmarks,
                            std::uint32_t seed, const SyntheticViewsOptions& options, SyntheticSession& out);

}  // namespace lk
