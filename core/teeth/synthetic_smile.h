// Ground truth for the teeth texture (Tarini et al. 2002, Sec. 4.2): a
// synthetic smile of eight upper and eight lower teeth (premolar, canine,
// lateral, central, mirrored), crown heights in the proportions of real
// crowns, arched crown tops (sag 12 % of the width), a yellower band near
// the gums, 3-px dark interdental gaps, a dark bite line between the arches,
// red gums, and lips whose edges can dip over the teeth (a cosine bump over
// the upper left and lower right teeth) to hide parts of them.
//
// Output: an RGB image width x height; masks #width*height.
#pragma once
#include <cstdint>
#include <vector>

#include "image/image.h"

namespace lk {

struct SyntheticSmileOptions {
  int width = 320, height = 160;  // the tooth layout is in pixels for 320 x 160 and scaled to this size
  double upper_dip = 0;           // rows (at 320 x 160) the upper lip reaches down over the teeth at its bump's middle
  double lower_rise = 0;          // rows the lower lip reaches up over the teeth
};

struct SyntheticSmile {
  Image image;                          // RGB
  std::vector<std::uint8_t> tooth;      // 1 = tooth pixel (whether or not a lip covers it)
  std::vector<std::uint8_t> lip;        // 1 = a lip covers the pixel
  int bite_row = 0;                     // the row between the arches
};

SyntheticSmile make_synthetic_smile(const SyntheticSmileOptions& options = {});

}  // namespace lk
