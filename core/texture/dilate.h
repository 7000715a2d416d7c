// Filling the texture space the chart does not use, so that bilinear and
// mipmapped lookups near the chart border average chart colours instead of
// the black background (which shows as a dark seam along the neck boundary
// and, at coarse mip levels, as a darkening of the whole border).
//
// Two ways: ring-by-ring dilation (each background texel next to a filled
// one takes the average of its filled 8-neighbours, `texels` rings), or a
// push-pull fill of the whole background (Gortler et al. 1996, "The
// Lumigraph", Sec. 3.3.2: average the known texels down a pyramid, then
// fill each unknown texel from the coarser level), which is smooth and
// costs about two passes over the image.
//
// Shapes: image width * height * channels floats; known width * height.
#pragma once
#include "image/image.h"

#include <vector>

namespace lk {

// Dilates by `texels` rings; known is updated (newly filled texels become
// known). Returns the number of texels filled.
long dilate_rings(ImageF& image, std::vector<char>& known, int texels);

// Fills every unknown texel; known texels are left unchanged. Returns the
// number of texels filled (0 when nothing is known: the image is unchanged).
long push_pull_fill(ImageF& image, const std::vector<char>& known);

}  // namespace lk
