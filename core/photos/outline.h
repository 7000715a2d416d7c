// The head's outline in a photo (issue 37 stage 4, fua1998 Sec. 3.2's
// silhouette edges), from a mask per photo: a binary or alpha image, the
// person white (or opaque), the background black (or transparent). Where the
// masks come from is the caller's business (a segmentation in the page, a
// renderer's exact coverage in the synthetic bench, a file on the CLI).
//
// The outline is the border of the mask's largest 8-connected component
// with its holes filled (an earring, a gap under the arm are not the head's
// outline), sampled at about `spacing_px`, each point with its outward
// normal (the mask's local first moment). Points within `border_px` of the
// image border are dropped: a mask cut by the frame (shoulders, a cropped
// crown) is the frame's edge, not a silhouette. What remains below the chin
// (neck, shoulders, clothes) is dropped later, against the head's own rim
// (silhouette_obs.h), since only the camera knows where the chin is.
//
// Pixel convention: origin at the top-left pixel corner, y down; an outline
// point lies on the edge between a foreground and a background pixel.
// Shapes: mask width * height, row-major; outline points #K.
#pragma once
#include "common/status.h"
#include "common/types.h"
#include "image/image.h"

#include <cstdint>
#include <vector>

namespace lk {

struct OutlinePoint {
  Vec2 pixel = Vec2::Zero();
  Vec2 normal = Vec2::Zero();  // unit, pointing out of the mask
};

struct PhotoOutline {
  int width = 0, height = 0;         // the mask's (= the photo's) size
  std::vector<OutlinePoint> points;  // #K
  double foreground_share = 0;       // of the image, after the largest component and hole filling
};

struct OutlineOptions {
  double spacing_px = 6;     // about one point per this many pixels of outline
  double border_px = 3;      // points this close to the image border are dropped
  int normal_radius_px = 6;  // window of the normal's first moment
  int min_points = 20;       // fewer: refused (a speck, not a head)
  double max_foreground_share = 0.97;  // more: refused (an all-white mask)
};

// A mask from an image: the alpha channel when the image has one that is
// not uniformly opaque, else the grey level (RGB: mean of the channels);
// foreground where the value is >= 128. Row-major width * height, 0 or 1.
std::vector<std::uint8_t> mask_from_image(const Image& image);

// A mask from the photo itself, for a plain background only: the
// background's colour is the median of the image's outer frame (frame_px
// wide), its spread the median distance of the frame's pixels from it;
// foreground where a pixel is farther from that colour than
// max(min_distance, spread_factor * spread) (8-bit RGB units). The person
// must not touch most of the frame. Fails with InvalidInput when the frame
// is not one colour (spread above max_spread: a room, a window, a sofa)
// or the foreground covers more than max_frame_share of the frame.
// Where it fails even so: hair or clothes of the background's colour
// (holes or bites in the outline), shadows cast on the backdrop (lumps).
struct PlainBackgroundOptions {
  int frame_px = 4;
  double min_distance = 30;
  double spread_factor = 6;
  double max_spread = 12;
  double max_frame_share = 0.35;
};
Status mask_from_plain_background(const Image& photo, const PlainBackgroundOptions& options,
                                  std::vector<std::uint8_t>& mask);

// Fails with InvalidInput, saying why, for a mask of the wrong size (it must
// be expected_width x expected_height, the photo's), with no foreground,
// covering (nearly) the whole image, or leaving fewer than min_points.
Status extract_outline(const std::vector<std::uint8_t>& mask, int width, int height, int expected_width,
                       int expected_height, const OutlineOptions& options, PhotoOutline& out);

// The outline of a photo with a plain background, as `likeness photos
// --photos` and the page find it. `image` is the photo, or a copy
// of it shrunk to any size (the page passes the one its face detector got);
// one larger than max_side pixels on its longer side is shrunk to that first
// (stb_image_resize). The background's mask and the outline are found there
// (mask_from_plain_background, extract_outline) and the points put in the
// photo's own pixels, photo_width x photo_height. A 12-megapixel photo's
// outline so costs what a 1280-px one does; the 6-px spacing at 1280 px is
// far finer than the silhouettes' 10-mm reach. max_side <= 0: no shrinking.
inline constexpr int kPlainOutlineMaxSide = 1280;
Status outline_from_plain_photo(const Image& image, int photo_width, int photo_height, int max_side,
                                const PlainBackgroundOptions& background, const OutlineOptions& options,
                                PhotoOutline& out);

// Convenience: mask_from_image + extract_outline, the size checked against
// the photo's.
Status outline_from_mask_image(const Image& mask_image, int photo_width, int photo_height,
                               const OutlineOptions& options, PhotoOutline& out);

}  // namespace lk
