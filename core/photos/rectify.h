// Rectification of a pair of calibrated photos (fua1998 Sec. 3.1 needs a
// disparity map per pair; correlation along rows needs rectified images).
// The compact method of Fusiello, Trucco and Verri (2000): both cameras
// keep their centres and get one new rotation, x along the baseline (A to
// B), z the two cameras' mean look direction made perpendicular to it, one
// focal and one principal-point row. A world point then projects onto the
// same row in both, and its disparity (column in A - column in B) grows as
// its depth shrinks.
//
// Images are resampled into a frame around a region of interest (3-D points,
// e.g. the head's vertices seen in both photos), downscaled so the frame's
// larger side is at most max_size pixels (box-averaged first: no aliasing
// from a 12-megapixel photo), as grey levels in [0, 1].
//
// Shapes: roi #N world points; rectified images a.width x a.height (A) and
// b.width x b.height (B), one float per pixel.
#pragma once
#include "calib/camera.h"
#include "common/status.h"
#include "image/image.h"

#include <vector>

namespace lk {

// The shared rotation (rows: the new x, y, z axes in world coordinates).
// Fails when the centres coincide or the baseline is along the look direction.
Status rectifying_rotation(const Camera& a, const Camera& b, Mat3& R);

struct RectifiedCameras {
  Camera a, b;          // same R, fx = fy, cy and height; own centre, cx and width; no distortion
  double baseline = 0;  // |centre b - centre a|, world units
};

// Rectified cameras framing `roi` in both views (a margin of `margin_px`
// around its projections), at most max_size pixels on the larger side, never
// finer than the photos. Fails when the roi is empty or behind a camera.
Status rectified_cameras(const Camera& a, const Camera& b, const std::vector<Vec3>& roi, int max_size,
                         int margin_px, RectifiedCameras& out);

// The photo (gray or RGB, camera.width x camera.height) seen by `original`
// resampled into `rect` (same centre): bilinear, after box-averaging by the
// integer part of the scale. `valid` (optional): 1 where the pixel came from
// inside the photo. Fails when the photo's size is not the camera's.
Status resample_rectified(const Image& photo, const Camera& original, const Camera& rect, ImageF& out,
                          std::vector<std::uint8_t>* valid);

// Grey levels in [0, 1] (Rec. 601 weights on the 8-bit values).
ImageF gray_levels(const Image& photo);

}  // namespace lk
