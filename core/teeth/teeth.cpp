// Tarini et al. 2002, Sec. 4.2: teeth texture from one photo.
#include "teeth/teeth.h"

#include <algorithm>
#include <cmath>

namespace lk {
namespace {

double dist3(const double c[3], const float t[3]) {
  return std::sqrt((c[0] - t[0]) * (c[0] - t[0]) + (c[1] - t[1]) * (c[1] - t[1]) + (c[2] - t[2]) * (c[2] - t[2]));
}
double luma(const double c[3]) { return 0.299 * c[0] + 0.587 * c[1] + 0.114 * c[2]; }

}  // namespace

double histogram_jump_threshold(const std::vector<double>& d, int bins, bool rising) {
  if (d.empty() || bins < 4) return 0;
  // A fixed range (RGB distances are at most sqrt 3), so a photo with one
  // colour cannot stretch its spread over the whole histogram.
  const double hi = std::sqrt(3.0) + 1e-9;
  std::vector<double> h(static_cast<size_t>(bins), 0.0);
  for (double v : d) h[std::min(static_cast<size_t>(bins - 1), static_cast<size_t>(v / hi * bins))] += 1;
  // Smoothed, so single-bin noise does not count as a jump.
  std::vector<double> s(h.size());
  for (int i = 0; i < bins; ++i) {
    double acc = 0, n = 0;
    for (int k = -1; k <= 1; ++k)
      if (i + k >= 0 && i + k < bins) { acc += h[static_cast<size_t>(i + k)]; n += 1; }
    s[static_cast<size_t>(i)] = acc / n;
  }
  // The near-target mode: the first local peak holding a visible share of
  // the pixels. Its end is where its biggest drop runs out into a valley.
  (void)rising;
  const double floor_count = 0.002 * static_cast<double>(d.size());
  int peak = 0;
  while (peak + 1 < bins && (s[static_cast<size_t>(peak)] < floor_count ||
                             s[static_cast<size_t>(peak + 1)] >= s[static_cast<size_t>(peak)]))
    ++peak;
  int best = peak;
  while (best + 1 < bins && s[static_cast<size_t>(best + 1)] < s[static_cast<size_t>(best)]) ++best;
  return (best + 1.0) / bins * hi;
}

Status teeth_texture_from_photo(const Image& photo, const TeethOptions& o, TeethResult& res) {
  if (photo.empty() || photo.channels < 3 ||
      photo.pixels.size() != static_cast<size_t>(photo.width) * photo.height * photo.channels)
    return Status::error(ErrorCode::InvalidInput, "the teeth photo is empty, malformed or not colour (RGB needed)");
  if (o.stripes < 1) return Status::error(ErrorCode::InvalidInput, "stripes must be >= 1");
  const int w = photo.width, h = photo.height;
  const size_t n = static_cast<size_t>(w) * h;
  std::vector<double> dv(n), dg(n);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::uint8_t* p = photo.at(x, y);
      const double c[3] = {p[0] / 255.0, p[1] / 255.0, p[2] / 255.0};
      dv[static_cast<size_t>(y) * w + x] = dist3(c, o.void_target);
      dg[static_cast<size_t>(y) * w + x] = dist3(c, o.gum_target);
    }
  res.void_threshold = std::min(o.max_void_distance, histogram_jump_threshold(dv, o.histogram_bins, true));
  res.gum_threshold = std::min(o.max_gum_distance, histogram_jump_threshold(dg, o.histogram_bins, false));
  res.classes.assign(n, TeethClass::Tooth);
  res.texture = Image::make(w, h, 4);
  double sum[3] = {0, 0, 0};
  res.teeth_pixels = 0;
  for (size_t i = 0; i < n; ++i) {
    if (dv[i] < res.void_threshold) res.classes[i] = TeethClass::Void;
    else if (dg[i] < res.gum_threshold) res.classes[i] = TeethClass::Gum;
    if (res.classes[i] == TeethClass::Tooth) {
      const std::uint8_t* p = &photo.pixels[i * static_cast<size_t>(photo.channels)];
      for (int k = 0; k < 3; ++k) sum[k] += p[k] / 255.0;
      ++res.teeth_pixels;
    }
  }
  if (res.teeth_pixels < o.min_teeth_fraction * static_cast<double>(n))
    return Status::error(ErrorCode::NotAHead, "no teeth found: too few bright, non-red, non-dark pixels");
  // Target colour: the teeth's mean hue at a fixed brightness.
  double mean[3] = {sum[0] / res.teeth_pixels, sum[1] / res.teeth_pixels, sum[2] / res.teeth_pixels};
  const double ml = std::max(1e-3, luma(mean));
  for (int k = 0; k < 3; ++k) res.target_color[k] = static_cast<float>(std::min(1.0, mean[k] * o.target_brightness / ml));

  // Gum shading is kept relative to the gums' mean brightness.
  double gum_luma = 0;
  size_t gum_count = 0;
  for (size_t i = 0; i < n; ++i)
    if (res.classes[i] == TeethClass::Gum) {
      const std::uint8_t* p = &photo.pixels[i * static_cast<size_t>(photo.channels)];
      const double c[3] = {p[0] / 255.0, p[1] / 255.0, p[2] / 255.0};
      gum_luma += luma(c);
      ++gum_count;
    }
  gum_luma = gum_count ? gum_luma / gum_count : 0.5;

  // Six stripes: per-stripe mean teeth colour; corrections at stripe centres,
  // linear between centres (continuity), constant beyond the outer ones.
  const int S = o.stripes;
  std::vector<double> corr(static_cast<size_t>(S) * 3, 0.0);
  for (int s = 0; s < S; ++s) {
    double acc[3] = {0, 0, 0};
    int cnt = 0;
    for (int y = 0; y < h; ++y)
      for (int x = s * w / S; x < (s + 1) * w / S; ++x)
        if (res.classes[static_cast<size_t>(y) * w + x] == TeethClass::Tooth) {
          for (int k = 0; k < 3; ++k) acc[k] += photo.at(x, y)[k] / 255.0;
          ++cnt;
        }
    for (int k = 0; k < 3; ++k)
      corr[static_cast<size_t>(s) * 3 + k] = cnt ? res.target_color[k] - acc[k] / cnt : res.target_color[k] - mean[k];
  }
  for (int x = 0; x < w; ++x) {
    const double u = (x + 0.5) / w * S - 0.5;  // stripe-centre coordinate
    const int s0 = std::clamp(static_cast<int>(std::floor(u)), 0, S - 1), s1 = std::min(s0 + 1, S - 1);
    const double f = std::clamp(u - s0, 0.0, 1.0);
    double c[3];
    for (int k = 0; k < 3; ++k) c[k] = (1 - f) * corr[static_cast<size_t>(s0) * 3 + k] + f * corr[static_cast<size_t>(s1) * 3 + k];
    for (int y = 0; y < h; ++y) {
      const size_t i = static_cast<size_t>(y) * w + x;
      const std::uint8_t* p = photo.at(x, y);
      std::uint8_t* q = res.texture.at(x, y);
      double out[3] = {p[0] / 255.0, p[1] / 255.0, p[2] / 255.0};
      q[3] = 255;
      if (res.classes[i] == TeethClass::Void) {
        q[3] = 0;
        out[0] = 0; out[1] = 0; out[2] = 1;  // colour-coded blue, as in the paper
      } else if (res.classes[i] == TeethClass::Gum) {
        // Standard gum colour, keeping the photo's shading.
        const double shade = std::clamp(luma(out) / std::max(1e-3, gum_luma), 0.5, 1.25);
        for (int k = 0; k < 3; ++k) out[k] = o.gum_color[k] * shade;
      } else {
        for (int k = 0; k < 3; ++k) out[k] += c[k];
      }
      for (int k = 0; k < 3; ++k) q[k] = static_cast<std::uint8_t>(std::lround(std::clamp(out[k], 0.0, 1.0) * 255));
    }
  }
  return Status::success();
}

}  // namespace lk
