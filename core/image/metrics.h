// Image quality metrics for scoring textures against ground truth
// (tarini2002 Sec. 3.2: the resampled skin texture and its multiresolution
// spline are judged by how close a re-render comes to the truth and by how
// visible the boundaries between photo regions are).
//
//   PSNR: 10 log10(255^2 / MSE) over the colour channels of 8-bit images.
//   SSIM: Wang, Bovik, Sheikh, Simoncelli 2004, "Image quality assessment:
//     from error visibility to structural similarity", Sec. III-B/C: an
//     11x11 circular-symmetric Gaussian window (sigma 1.5, normalized to sum
//     1), C1 = (K1 L)^2, C2 = (K2 L)^2 with K1 = 0.01, K2 = 0.03, L = 255;
//     the mean SSIM (MSSIM, Eq. 17) over window centres. As in the authors'
//     reference code, only windows that fit inside the image are used (the
//     5-pixel border is left out).
//   Seam: a texture-space measure of visible boundaries between regions
//     resampled from different photos (defined at texture_seam below).
//
// Shapes: images width x height x channels, row-major, top row first; masks
// and label maps width * height, same layout (one entry per pixel/texel).
#pragma once
#include "common/status.h"
#include "image/image.h"

#include <cstdint>
#include <vector>

namespace lk {

// One entry per pixel (width * height), non-zero = the pixel is scored.
// An empty mask scores every pixel.
using PixelMask = std::vector<std::uint8_t>;

// Colour channels compared: 1 for gray images, 3 for RGB and RGBA (alpha is
// ignored, so a 4-channel render compares with a 3-channel one).

struct PsnrResult {
  double mse = 0;          // mean squared error per colour sample, in 8-bit units^2
  double psnr_db = 0;      // +infinity when the images are equal on the mask
  long long pixels = 0;    // pixels scored
};

// Fails with InvalidInput when the images differ in size or colour channel
// count, are empty, or the mask has the wrong length; Empty when the mask
// selects no pixel.
Status compute_psnr(const Image& a, const Image& b, const PixelMask& mask, PsnrResult& result);

enum class SsimMode {
  Luminance,   // on Y = 0.299 R + 0.587 G + 0.114 B (Rec. 601, as the authors' rgb2gray)
  PerChannel,  // SSIM of each colour channel, averaged
};

struct SsimOptions {
  SsimMode mode = SsimMode::Luminance;
  int window = 11;       // Gaussian window side, odd (paper: 11)
  double sigma = 1.5;    // Gaussian window standard deviation, pixels (paper: 1.5)
  double k1 = 0.01;      // C1 = (k1 * 255)^2 (paper: 0.01)
  double k2 = 0.03;      // C2 = (k2 * 255)^2 (paper: 0.03)
};

struct SsimResult {
  double ssim = 0;        // mean SSIM over scored window centres, in [-1, 1]; 1 = identical
  long long pixels = 0;   // window centres scored
};

// Mean SSIM over the window centres selected by the mask (windows still see
// unmasked neighbours: the mask chooses where to score, not what to look at).
// Fails like compute_psnr, and with InvalidInput for an even/too small window,
// non-positive sigma or constants, or an image smaller than the window.
Status compute_ssim(const Image& a, const Image& b, const PixelMask& mask, const SsimOptions& options,
                    SsimResult& result);

// Seam measure in texture space. labels: #texels region ids (e.g. the photo
// each texel was resampled from), negative = outside every region (not
// scored). Texel pairs (p, q = p + pair_distance along x or along y) with
// both texels labelled (and inside the chart mask, if given) are "cross"
// pairs when their labels differ and "same" pairs otherwise.
//
// seam: the RMS colour step across region boundaries, in 8-bit units. For
//   each direction and ordered label pair (a, b) ("group"), the mean SIGNED
//   difference colour(q) - colour(p) per colour channel minus the same
//   direction's mean over same-label pairs (the texture's own slope) is that
//   group's step; seam^2 = the cross-pair-weighted mean over groups and
//   channels of step^2 - variance / n (n the group's pairs, variance of its
//   signed differences: what texture detail and noise add to a squared mean
//   on average), clamped at 0. A lighting mismatch between two photos shifts
//   the colour consistently across their boundary, so the signed means keep
//   it while detail averages out: ~0 without a seam, s for a colour step of
//   s, ~s / w when a blend spreads the step into a ramp over w texels.
// abs_excess: the plainer D_cross - D_same, with D = mean over pairs of the
//   channel-mean absolute difference (weighted per direction like seam). It
//   is 0 without a seam too, but noise hides small steps in it: with noise
//   of amplitude n it grows like s^2 / n until s exceeds n, so seam is the
//   number to compare.
struct SeamOptions {
  int pair_distance = 1;  // texels between the two texels of a pair (1 = neighbours)
};

struct SeamResult {
  double seam = 0;           // RMS step measure above, 8-bit units
  double abs_excess = 0;     // D_cross - D_same, 8-bit units
  double cross_mean = 0;     // D_cross pooled over both directions
  double same_mean = 0;      // D_same pooled over both directions
  long long cross_pairs = 0; // pairs across a region boundary
  long long same_pairs = 0;  // pairs inside one region
};

// Fails with InvalidInput on an empty image, labels or chart mask of the
// wrong length, or pair_distance < 1; Empty when no pair crosses a boundary
// or none stays inside a region.
Status texture_seam(const Image& texture, const std::vector<int>& labels, const PixelMask& chart_mask,
                    const SeamOptions& options, SeamResult& result);

}  // namespace lk
