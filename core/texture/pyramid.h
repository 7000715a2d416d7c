// Gaussian and Laplacian pyramids and the multiresolution spline
// (Burt & Adelson 1983, "A multiresolution spline with application to image
// mosaics", used by tarini2002 Sec. 3.2 to remove the boundaries between
// texture regions resampled from photos taken under different light).
//
// Filter: the separable 5-tap generating kernel w = (1/4 - a/2, 1/4, a,
// 1/4, 1/4 - a/2) with a = 0.4, borders by reflection (x[-1] = x[1]).
// REDUCE filters and keeps every other sample: a level of size n has a
// coarser level of size (n + 1) / 2. EXPAND interpolates a coarse level back
// to the finer level's exact size with the same kernel (times 4 in 2-D).
// Laplacian level k = G_k - EXPAND(G_{k+1}); the last level is the coarsest
// Gaussian, so collapse(laplacian(x)) == x up to float rounding.
//
// Spline: with images I_j and masks M_j (sum_j M_j = 1 at every texel),
//   L_k(out) = sum_j G_k(M_j) * L_k(I_j), out = collapse(L(out)).
// Each image's pyramid is needed only while it is added, so SplineBlender
// keeps one output pyramid and two temporary ones, whatever the number of
// images (five photos + the complement at 2048^2 fit in wasm memory).
//
// Shapes: images width * height * channels floats; masks width * height * 1.
#pragma once
#include "common/status.h"
#include "image/image.h"

#include <vector>

namespace lk {

// One level down: filter then subsample; out is ((w + 1) / 2, (h + 1) / 2).
void pyramid_reduce(const ImageF& in, ImageF& out);
// One level up to the given size (the finer level's): upsample then filter.
void pyramid_expand(const ImageF& coarse, int width, int height, ImageF& out);

// Largest useful number of levels: until the coarsest side reaches ~8 texels.
int max_pyramid_levels(int width, int height);

// levels >= 1 images, level 0 = the input.
void gaussian_pyramid(const ImageF& image, int levels, std::vector<ImageF>& pyramid);
void laplacian_pyramid(const ImageF& image, int levels, std::vector<ImageF>& pyramid);
void collapse_laplacian(const std::vector<ImageF>& pyramid, ImageF& image);

// Accumulates sum_j G(M_j) * L(I_j) level by level; finish() collapses it.
class SplineBlender {
 public:
  // levels <= 0 or above max_pyramid_levels: max_pyramid_levels.
  Status begin(int width, int height, int channels, int levels);
  // Adds one image under its mask (same size; mask has 1 channel).
  Status add(const ImageF& image, const ImageF& mask);
  Status finish(ImageF& out);
  int levels() const { return levels_; }

 private:
  int width_ = 0, height_ = 0, channels_ = 0, levels_ = 0;
  std::vector<ImageF> sum_;                  // the output's Laplacian pyramid
  std::vector<ImageF> image_pyr_, mask_pyr_;  // per-add scratch, reused
  ImageF expanded_, half_;                    // filter scratch, reused
};

// All at once: images and masks of the same size, masks summing to 1.
Status multiresolution_spline(const std::vector<ImageF>& images, const std::vector<ImageF>& masks,
                              int levels, ImageF& out);

}  // namespace lk
