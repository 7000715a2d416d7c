// Teeth texture from one photo: Tarini, Yamauchi, Haber, Seidel, "Texturing
// Faces", Graphics Interface 2002, Sec. 4.2 (classification, void
// transparency, gum recolouring, six-stripe colour equalization).
// teeth_composite_generic puts the result into a procedurally generated
// generic teeth texture (side teeth recoloured with the target colour) along
// a curved (elliptic) boundary. Not yet implemented from Sec. 4.2:
// reconstruction of tooth parts hidden by the lips.
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
};

struct TeethResult {
  Image texture;                     // RGBA
  std::vector<TeethClass> classes;   // width * height
  double void_threshold = 0, gum_threshold = 0;  // colour distances (0..sqrt(3))
  float target_color[3] = {0, 0, 0};
  int teeth_pixels = 0;
};

// Threshold from a histogram of colour distances to a target (black for
// voids, red for gums): the pixels near the target form the first mode; the
// threshold is where that mode's falling edge (its biggest jump down) ends in
// a valley. `rising` is unused and kept for call-site clarity.
double histogram_jump_threshold(const std::vector<double>& distances, int bins, bool rising);

Status teeth_texture_from_photo(const Image& photo, const TeethOptions& options, TeethResult& result);

struct TeethCompositeOptions {
  int width = 1024, height = 512;   // output RGBA texture
  double middle_width = 0.5;        // share of the width given to the photo's teeth
  double boundary_softness = 0.04;  // blend width across the curved boundary (fraction of width)
  int side_teeth = 5;               // generic teeth on each side (paper: 4-5)
};

// Generic texture: upper teeth in the top half, lower teeth in the bottom
// half, gums beyond; the photo result (scaled to the middle) is composited
// inside an ellipse whose sides follow the canines' silhouettes.
// mask (optional, width*height): 1 where the photo was used.
Status teeth_composite_generic(const TeethResult& teeth, const TeethOptions& options,
                               const TeethCompositeOptions& composite, Image& texture,
                               std::vector<float>* mask = nullptr);

}  // namespace lk
