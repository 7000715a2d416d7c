// Per-photo 2-D landmarks and the map from landmark index to the generic
// head's surface (issue 37, stage 1). Both are JSON files; the page exports
// the same format (docs/design/photos.md):
//   {"format":"likeness-landmarks","version":1,
//    "image":{"name":..,"width":..,"height":..},
//    "detector":"mediapipe-face-mesh","points":[[x,y] or null, ...]}
//   {"format":"likeness-landmark-map","version":1,
//    "detector":"mediapipe-face-mesh","points":[[x,y,z] or null, ...]}
// Version 2 of the map adds "slide" (landmark_slide.h):
//    {"yaw_range_deg":Y,"pitch_range_deg":P,"terms":[[i,j],...],
//     "shifts":[[[x,y,z] per term] or null, ... #M],
//     "sigma_yaw_deg":[...],"sigma":[[s per yaw] or null, ... #M]}
// (metres); version 1 files are still read (no slide).
// Landmark points are pixels (origin at the top-left pixel corner, y down),
// index = the detector's landmark index. Map points are in the generic head's
// coordinates (metres); at load they are projected onto the head surface
// (triangle + barycentrics), so they follow the head when it deforms.
//
// Shapes: LandmarkPhoto::points and ::present #N (N <= kMaxLandmarks);
// LandmarkMap::points and ::present #M; attached surface points #M.
#pragma once
#include "common/status.h"
#include "mesh/tri_mesh.h"
#include "photos/landmark_slide.h"

#include <string>
#include <vector>

namespace lk {

constexpr size_t kMaxLandmarkFileBytes = size_t(4) << 20;  // 468 points need ~20 kB
constexpr int kMaxLandmarks = 1000;                        // MediaPipe: 468, 478 with irises
constexpr int kMaxLandmarkImageSide = 65535;

// The detector name MediaPipe Face Mesh's points files carry (the contour
// and lid observations use its landmark indices).
inline constexpr const char* kMediaPipeDetector = "mediapipe-face-mesh";

struct LandmarkPhoto {
  std::string name;        // the photo's file name, as written by the exporter
  int width = 0, height = 0;
  std::string detector;
  std::vector<Vec2> points;    // #N, pixels; meaningful where present
  std::vector<char> present;   // #N, 0 = the detector gave no point
  int num_present() const;
};

struct LandmarkMap {
  std::string detector;
  std::vector<Vec3> points;    // #M, generic-head coordinates
  std::vector<char> present;   // #M
  LandmarkSlide slide;         // the detector's view-dependent slide and scatter (version 2; empty in version 1)
};

// In its own inline namespace: fit/closest_point.h defines another
// lk::SurfacePoint (64 bytes, this one 32), and the likeness binary shared
// std::vector<lk::SurfacePoint> members between the two layouts (nm).
inline namespace landmark_points {
// A point on a mesh that keeps its place when the vertices move: a place
// on one triangle plus a constant offset from it (where the map's point
// lies off the control mesh: on the smooth surface, or where the detector
// sees a landmark in front of the skin).
struct SurfacePoint {
  int triangle = -1;               // -1 = no point
  Vec3 barycentric = Vec3::Zero(); // weights of the triangle's corners 0,1,2
  Vec3 offset = Vec3::Zero();      // added to the barycentric point, head coordinates
  bool valid() const { return triangle >= 0; }
};
}  // namespace landmark_points
Vec3 surface_position(const TriMesh& mesh, const SurfacePoint& p);

// Parsers. Every field is checked: format and version, detector a non-empty
// string, width/height integers in 1..kMaxLandmarkImageSide, at most
// kMaxLandmarks points, each null or 2 (3) finite numbers; landmark pixels
// must lie within the image widened by one image size on every side (a
// detector may place a point just outside a cropped face; further out is a
// broken file). Fails with InvalidInput (TooLarge above kMaxLandmarkFileBytes)
// and a message naming the field.
Status parse_landmarks_json(const std::string& text, LandmarkPhoto& out);
Status parse_landmark_map_json(const std::string& text, LandmarkMap& out);
std::string landmarks_to_json(const LandmarkPhoto& photo);
std::string landmark_map_to_json(const LandmarkMap& map);

// Attaches every map point to the mesh: its closest point (triangle +
// barycentrics) and the offset from there to the map's point, so that the
// landmark is where the map says on this mesh and follows it when it
// deforms. A point farther than max_distance from the surface means the
// map was made for another head: InvalidInput naming the index. Fewer than
// 6 mapped points: Empty.
Status attach_landmark_map(const LandmarkMap& map, const TriMesh& head, double max_distance,
                           std::vector<SurfacePoint>& out);

}  // namespace lk
