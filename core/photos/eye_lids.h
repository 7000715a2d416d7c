// The lid opening of a head seen in a photo, against the detector's lid
// points there (issue 37: a head from photos showed too much eyeball).
//
// An opening is measured in the image: its width (corner to corner) and its
// gap (upper lid to lower lid along the line through the iris centre,
// perpendicular to the corner line). The head's is its eye rim (the crease
// loop, refined to the level asked) projected by the photo's camera; the
// detector's is MediaPipe Face Mesh's lid contour (corners 263/362 and
// 33/133, upper lids 386 and 159 at the middle). Eye 0 is the head's left
// (+x), as in components.h.
#pragma once
#include "calib/camera.h"
#include "common/status.h"
#include "head/head_model.h"
#include "photos/landmarks.h"
#include "photos/self_calibration.h"

#include <array>
#include <vector>

namespace lk {

struct LidOpening {
  double gap_px = 0;    // upper to lower lid across the iris centre
  double width_px = 0;  // corner to corner
  double ratio() const { return width_px > 0 ? gap_px / width_px : 0; }
};

// MediaPipe Face Mesh's lid contour of one eye: the outer and inner corner,
// the upper and the lower lid from the outer corner inwards.
struct LidContour {
  int outer = 0, inner = 0;
  std::array<int, 7> upper{}, lower{};
  // Where each lid point lies from the outer corner (0) to the inner one
  // (1) along the corner line: the shipped map's x of these points, the two
  // eyes averaged (its 385 is out of order and takes 158's).
  std::array<double, 7> upper_at{}, lower_at{};
};
const LidContour& mediapipe_lid_contour(int eye);

// The gap of a closed 2-D outline across `centre`, perpendicular to the
// line between corners a and b: the span of its crossings with that line.
// 0 when the line meets the outline fewer than twice.
double opening_gap(const std::vector<Vec2>& outline, const Vec2& a, const Vec2& b, const Vec2& centre);

// The detector's opening of `eye` in one photo, across `centre` (pixels:
// e.g. the eyeball's centre projected). Fails (InvalidInput) when the photo
// lacks a contour point of that eye.
Status landmark_lid_opening(const LandmarkPhoto& photo, int eye, const Vec2& centre, LidOpening& out);

// The head's opening of `eye` (its eye rim refined to `level`, the generic
// head's creases, both corners crease corners) projected by `camera`,
// across `centre`. head: a control mesh of the generic head's topology.
// Fails on another topology, a bad level or a rim behind the camera.
Status head_lid_opening(const TriMesh& head, const GenericHead& generic, int eye, int level, const Camera& camera,
                        const Vec2& centre, LidOpening& out);

// Where MediaPipe's lid contour lies on the head: on the eye rim, the lid
// margin that bounds the visible eyeball in a real photo. The shipped map
// (head/data) learned those points from the detector on renders without
// eyeballs, where it put the lids about 4 mm closer than the rim (a gap of
// 0.27 of the width against the rim's 0.44): fitted to real eyes through
// that map, the lids opened too wide. Each of the 32 contour landmarks
// (both eyes' corners and lids) becomes a point on a rim edge (no offset):
// a corner at its canthus, a lid point on its half of the rim where the
// rim reaches its share of the way between the corners (LidContour::*_at). out: #landmarks, valid only at those indices (and where the
// landmark is). Fails on a head without eye rims.
Status lid_margin_points(const GenericHead& generic, const std::vector<SurfacePoint>& landmarks,
                         std::vector<SurfacePoint>& out);

// Which eye a MediaPipe landmark's lid contour belongs to: 0, 1, or -1.
int lid_contour_eye(int landmark);
// Whether `camera` sees the rim of `eye` of the generic head well enough to
// mark its lids: from within 30 deg of the eye's look direction (the
// calibration's visibility test uses the map's points, which for the lids
// sit off the rim, and drops some of the middle lid points of a frontal photo).
bool camera_sees_lids(const GenericHead& generic, int eye, const Camera& camera);

// The lids' opening is a pose, not a shape: the thin-plate stiffness of the
// shape fit holds a 2 mm change across a 12 mm lid back (on a synthetic
// person with narrower lids the fitted opening stayed 0.04-0.10 of the
// width too open). So after the shape fit each eye's lids are turned about
// the eyeball's centre as the face rig turns them (anim/face_rig.h: a lid
// vertex keeps its distance to the centre, it slides over the eyeball), by
// one value per eye (g > 0 closes upper and lower lid by g, g < 0 opens the
// upper lid: the rig lowers no lower lid), so that the rim's opening across
// each lid column (upper contour point k to lower point k, lid_margin_points)
// is the photos' in every used photo that sees the eye (camera_sees_lids);
// the posed lids become the head's rest. The gaps only, not the places:
// fitting the places opened one lid and closed the other to shift Kira's
// openings by 5-10 px. Least squares in pixels with Huber weights (huber_px),
// Powell.
struct LidPoseResult {
  std::array<double, 2> upper{}, lower{};  // the rig's kLid*, kLowerLid* per eye (0 = left)
  double rms_before_px = 0, rms_after_px = 0;  // the columns' gap error, all used photos
  int observations = 0;                        // lid columns seen
};
Status fit_lid_pose(const GenericHead& generic, const std::vector<SurfacePoint>& lid_points,
                    const std::vector<LandmarkPhoto>& photos, const SelfCalibResult& calib, TriMesh& head,
                    LidPoseResult& out, double huber_px = 4.0);

// The eye rim of `eye` refined `level` times (the loop of the level mesh's
// rim vertices, in order) and its positions, from the control mesh.
Status refined_eye_rim(const TriMesh& head, const GenericHead& generic, int eye, int level, std::vector<Vec3>& rim);

}  // namespace lk
