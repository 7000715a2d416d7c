// Teeth texture from one photo: Tarini, Yamauchi, Haber, Seidel, "Texturing
// Faces", Graphics Interface 2002, Sec. 4.2 (classification, void
// transparency, gum recolouring, six-stripe colour equalization).
// teeth_composite_generic puts the result into a procedurally generated
// generic teeth texture (side teeth recoloured with the target colour) along
// a curved (elliptic) boundary.
//
// Hidden parts (Sec. 4.2: "we expand teeth into those parts of the gums that
// have been covered by the lips ... some simple heuristics to include the
// missing part of the tooth roots"): the upper teeth are the run of non-gum
// pixels above the occlusal (bite) row, the lower ones the run below it. A
// tooth is a run of columns between interdental gap columns (or marked
// minima of the visible height: papillae between teeth in contact). Its
// visible end is fitted by a parabola through its upper points only, so
// columns a lip cuts short do not pull it down; those columns are filled up
// to the fit. A tooth whose end is flat or concave (a lip's edge, not an
// arched gum line) may be hidden across its whole width: it is raised to
// neighbour_height_factor of its neighbours' median height, with a generic
// crown arc (sag crown_arc * width). Fills take the colour of the column's
// own outermost visible tooth pixels (void where that end is a gap).
// Photos whose gums are visible (intraoral, retracted lips) have nothing
// hidden; there the fill invents 1.6-2.8 % of the teeth pixels (premolars).
//
// Input: RGB(A) photo, width x height. Output: RGBA texture of the same size,
// voids transparent (alpha 0), gums/lips recoloured, teeth equalized.
#pragma once
#include <cstdint>
#include <vector>

#include "common/status.h"
#include "image/image.h"

namespace lk {

enum class TeethClass : std::uint8_t { Tooth = 0, Gum = 1, Void = 2 };

struct TeethOptions {
  float void_target[3] = {0, 0, 0};          // voids: near black
  float gum_target[3] = {0.80f, 0.25f, 0.25f};  // gums/lips/skin: near red
  float gum_color[3] = {0.76f, 0.38f, 0.38f};   // the standard gum colour painted over gums
  int histogram_bins = 96;
  // Upper bounds on the found thresholds: a photo without dark voids (or
  // without gums) has its first mode elsewhere, which must not become void/gum.
  double max_void_distance = 0.30;
  double max_gum_distance = 0.55;
  double target_brightness = 0.82;  // luminance of the teeth target colour (hue kept)
  int stripes = 6;                  // paper: six vertical stripes
  double min_teeth_fraction = 0.02; // fewer teeth pixels than this: "no teeth found"
  // Hidden tooth parts.
  bool reconstruct_hidden = true;
  int bite_row = -1;                // occlusal row between upper and lower teeth; -1 = estimated
  double gap_void_fraction = 0.5;   // a column whose visible run is at least this void is an interdental gap
  double max_tooth_width = 0.25;    // a tooth spans at most this share of the photo width (no gaps found: windows)
  double crown_arc = 0.15;          // sag of the crown outline at the tooth's sides, fraction of its width
  // A tooth is at least this share of the (lower) median visible height of
  // its two neighbours on each side: a lip can hide a whole tooth's top.
  // Crowns differ (upper laterals ~85 % of the centrals, premolars ~80 %),
  // so a lower share invents less. 0 = each tooth from its own pixels only.
  double neighbour_height_factor = 0.85;
  int colour_rows = 6;              // outermost visible tooth pixels of a column averaged for its fill colour
};

struct TeethResult {
  Image texture;                     // RGBA
  std::vector<TeethClass> classes;   // width * height
  double void_threshold = 0, gum_threshold = 0;  // colour distances (0..sqrt(3))
  float target_color[3] = {0, 0, 0};
  int teeth_pixels = 0;              // visible teeth pixels (before reconstruction)
  int bite_row = -1;                 // the occlusal row (given or estimated)
  std::vector<std::uint8_t> reconstructed;  // width * height, 1 = hidden part filled in (tooth or gap)
  int reconstructed_pixels = 0;
};

// Threshold from a histogram of colour distances to a target (black for
// voids, red for gums): the pixels near the target form the first mode; the
// threshold is where that mode's falling edge (its biggest jump down) ends in
// a valley. `rising` is unused and kept for call-site clarity.
double histogram_jump_threshold(const std::vector<double>& distances, int bins, bool rising);

Status teeth_texture_from_photo(const Image& photo, const TeethOptions& options, TeethResult& result);

// The hidden-part step alone, on classes (width * height) and a float RGB
// buffer (width * height * 3, 0..1) that it updates in place; used by
// teeth_texture_from_photo when options.reconstruct_hidden. Returns the bite
// row used; `filled` (width * height) marks the changed pixels.
int reconstruct_hidden_teeth(int width, int height, const TeethOptions& options, std::vector<TeethClass>& classes,
                             std::vector<float>& rgb, std::vector<std::uint8_t>& filled);

// Whether the classified photo is a close-up of an open mouth (a smile
// photo), not a face, a closed mouth or a background: NotAHead with the
// reason unless
//  - lips and gums (the Gum class) cover at least 0.95 times the teeth's
//    pixels: in a close-up the teeth sit between lips or gums, while in a
//    portrait the bright non-red pixels (walls, skin, clothes) dominate;
//  - the teeth are solid: fewer than 0.1 tooth-void borders (horizontal
//    neighbours) per tooth pixel; speckle among dark pixels (hair,
//    shadows) is not teeth.
// Measured (docs/design/untrusted_images.md): the two intraoral photos
// (1.06 and 1.39; 0.001 and 0.002) and the synthetic smile (1.49; 0.028)
// pass; the ten portraits of multiview_faces, an eye close-up, a face
// atlas and a scanner texture each fail one (the best 0.86; 0.31 and 0.30).
// A stopgap until the face landmarks (issue 37) locate the mouth.
Status check_smile_closeup(const TeethResult& teeth, int width, int height);

struct TeethCompositeOptions {
  int width = 1024, height = 512;   // output RGBA texture
  double middle_width = 0.5;        // share of the width given to the photo's teeth
  double boundary_softness = 0.04;  // blend width across the curved boundary (fraction of width)
  int side_teeth = 5;               // generic teeth on each side (paper: 4-5)
};

// Generic texture: upper teeth in the top half, lower teeth in the bottom
// half, gums beyond; the photo result (scaled to the middle) is composited
// inside an ellipse whose sides follow the canines' silhouettes; the photo's
// bite row (TeethResult::bite_row, when >= 0) is put on the bite line H / 2.
// mask (optional, width*height): 1 where the photo was used.
Status teeth_composite_generic(const TeethResult& teeth, const TeethOptions& options,
                               const TeethCompositeOptions& composite, Image& texture,
                               std::vector<float>* mask = nullptr);

}  // namespace lk
