// A small EXIF reader for JPEG photos: just the tags that give a focal length
// in pixels, the prior of the calibration (calib/calibrate.h,
// CalibOptions::focal_prior) against the focal/distance ambiguity of
// tarini2002 Sec. 3's 12-15 clicked points.
//
// Reads the JPEG's APP1 "Exif" segment (a TIFF structure: IFD0 and the Exif
// sub-IFD), big or little endian. Every offset and count is checked against
// the segment's bytes; IFD loops and absurd entry counts are refused.
// Parsing stops at the start of the image data (SOS), so the scan is cheap.
#pragma once
#include "common/status.h"

#include <cstddef>
#include <cstdint>
#include <string>

namespace lk {

struct ExifInfo {
  bool present = false;              // the JPEG has an APP1 Exif segment
  std::string make, model;           // 0x010F, 0x0110
  int orientation = 0;               // 0x0112 (1 = upright), 0 = absent
  double focal_length_mm = 0;        // 0x920A FocalLength, 0 = absent
  int focal_length_35mm = 0;         // 0xA405 FocalLengthIn35mmFilm, 0 = absent
  double focal_plane_x_resolution = 0;  // 0xA20E, pixels per resolution unit on the sensor
  double focal_plane_y_resolution = 0;  // 0xA20F
  int focal_plane_resolution_unit = 0;  // 0xA210: 2 = inch (default), 3 = cm, 4 = mm, 5 = um
  int pixel_x_dimension = 0, pixel_y_dimension = 0;  // 0xA002/0xA003: the image size the tags refer to
};

// Fails with InvalidInput when the bytes are not a JPEG, Truncated when a
// segment or the EXIF structure runs past the data. A JPEG without EXIF is a
// success with present == false.
Status read_jpeg_exif(const std::uint8_t* data, size_t size, ExifInfo& out);

// Focal length in pixels for an image of width x height (the decoded photo,
// possibly downscaled from the camera's size). In order of precision:
//  1. sensor_width_mm > 0 (the user knows the sensor) and FocalLength:
//     f_mm / sensor_width_mm * width (width along the sensor's long side);
//  2. FocalLength and FocalPlaneXResolution: f_mm * pixels-per-mm, scaled by
//     width / PixelXDimension when the photo was resized;
//  3. FocalLengthIn35mmFilm: f35 / 43.27 mm (the 35-mm frame's diagonal) *
//     the image diagonal in pixels.
// Returns 0 when the tags give no focal. `source` (optional) names the rule used.
double exif_focal_pixels(const ExifInfo& exif, int width, int height, double sensor_width_mm = 0,
                         std::string* source = nullptr);

}  // namespace lk
