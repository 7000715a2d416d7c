// PSNR, SSIM (Wang et al. 2004) and the texture seam measure (see metrics.h).
#include "image/metrics.h"

#include <cmath>
#include <limits>
#include <map>
#include <utility>
#include <string>

namespace lk {
namespace {

int colour_channels(const Image& im) { return im.channels >= 3 ? 3 : 1; }

std::string size_text(const Image& im) {
  return std::to_string(im.width) + "x" + std::to_string(im.height) + "x" + std::to_string(im.channels);
}

Status check_pair(const Image& a, const Image& b, const PixelMask& mask, const char* what) {
  const std::string name = what;
  if (a.empty() || b.empty()) return Status::error(ErrorCode::InvalidInput, name + ": empty image");
  if (a.channels < 1 || a.channels > 4 || b.channels < 1 || b.channels > 4 ||
      a.pixels.size() != static_cast<size_t>(a.width) * a.height * a.channels ||
      b.pixels.size() != static_cast<size_t>(b.width) * b.height * b.channels)
    return Status::error(ErrorCode::InvalidInput, name + ": pixel buffer does not match the image size");
  if (a.width != b.width || a.height != b.height || colour_channels(a) != colour_channels(b))
    return Status::error(ErrorCode::InvalidInput,
                         name + ": images differ in size or colour channels (" + size_text(a) + " vs " +
                             size_text(b) + ")");
  if (!mask.empty() && mask.size() != static_cast<size_t>(a.width) * a.height)
    return Status::error(ErrorCode::InvalidInput,
                         name + ": mask has " + std::to_string(mask.size()) + " entries, the image " +
                             std::to_string(static_cast<long long>(a.width) * a.height) + " pixels");
  return Status::success();
}

// The scored signal of each pixel: luminance, or one colour channel.
std::vector<double> plane(const Image& im, SsimMode mode, int channel) {
  const size_t n = static_cast<size_t>(im.width) * im.height;
  std::vector<double> out(n);
  const int c = im.channels;
  for (size_t i = 0; i < n; ++i) {
    const std::uint8_t* p = &im.pixels[i * c];
    if (c < 3) out[i] = p[0];
    else if (mode == SsimMode::Luminance) out[i] = 0.299 * p[0] + 0.587 * p[1] + 0.114 * p[2];
    else out[i] = p[channel];
  }
  return out;
}

// Separable Gaussian filter, 'valid' part only: output pixel (x, y) for
// x, y in [r, size - r) is the window average centred there; others are 0.
std::vector<double> gaussian_valid(const std::vector<double>& in, int w, int h, const std::vector<double>& k) {
  const int r = static_cast<int>(k.size()) / 2;
  std::vector<double> tmp(in.size(), 0.0), out(in.size(), 0.0);
  for (int y = 0; y < h; ++y)
    for (int x = r; x < w - r; ++x) {
      double s = 0;
      const double* row = &in[static_cast<size_t>(y) * w + x - r];
      for (size_t i = 0; i < k.size(); ++i) s += k[i] * row[i];
      tmp[static_cast<size_t>(y) * w + x] = s;
    }
  for (int y = r; y < h - r; ++y)
    for (int x = r; x < w - r; ++x) {
      double s = 0;
      for (size_t i = 0; i < k.size(); ++i) s += k[i] * tmp[static_cast<size_t>(y - r + static_cast<int>(i)) * w + x];
      out[static_cast<size_t>(y) * w + x] = s;
    }
  return out;
}

}  // namespace

Status compute_psnr(const Image& a, const Image& b, const PixelMask& mask, PsnrResult& result) {
  Status s = check_pair(a, b, mask, "psnr");
  if (!s) return s;
  const int nc = colour_channels(a);
  const size_t n = static_cast<size_t>(a.width) * a.height;
  double sum = 0;
  long long count = 0;
  for (size_t i = 0; i < n; ++i) {
    if (!mask.empty() && !mask[i]) continue;
    const std::uint8_t* pa = &a.pixels[i * a.channels];
    const std::uint8_t* pb = &b.pixels[i * b.channels];
    for (int c = 0; c < nc; ++c) {
      const double d = static_cast<double>(pa[c]) - pb[c];
      sum += d * d;
    }
    ++count;
  }
  if (count == 0) return Status::error(ErrorCode::Empty, "psnr: the mask selects no pixel");
  result.pixels = count;
  result.mse = sum / (static_cast<double>(count) * nc);
  result.psnr_db = result.mse > 0 ? 10.0 * std::log10(255.0 * 255.0 / result.mse)
                                  : std::numeric_limits<double>::infinity();
  return Status::success();
}

Status compute_ssim(const Image& a, const Image& b, const PixelMask& mask, const SsimOptions& options,
                    SsimResult& result) {
  Status s = check_pair(a, b, mask, "ssim");
  if (!s) return s;
  if (options.window < 3 || options.window % 2 == 0)
    return Status::error(ErrorCode::InvalidInput, "ssim: the window must be odd and at least 3 pixels");
  if (!(options.sigma > 0) || !(options.k1 > 0) || !(options.k2 > 0))
    return Status::error(ErrorCode::InvalidInput, "ssim: sigma, k1 and k2 must be positive");
  const int w = a.width, h = a.height, r = options.window / 2;
  if (w < options.window || h < options.window)
    return Status::error(ErrorCode::InvalidInput, "ssim: image " + size_text(a) + " is smaller than the " +
                                                      std::to_string(options.window) + "-pixel window");

  std::vector<double> kernel(options.window);
  double ksum = 0;
  for (int i = 0; i < options.window; ++i) {
    const double d = i - r;
    kernel[i] = std::exp(-d * d / (2 * options.sigma * options.sigma));
    ksum += kernel[i];
  }
  for (double& k : kernel) k /= ksum;  // 2-D window = outer product, sums to 1

  const double c1 = (options.k1 * 255) * (options.k1 * 255), c2 = (options.k2 * 255) * (options.k2 * 255);
  const int planes = (options.mode == SsimMode::Luminance || colour_channels(a) == 1) ? 1 : 3;
  const size_t n = static_cast<size_t>(w) * h;
  double total = 0;
  long long scored = 0;
  for (int p = 0; p < planes; ++p) {
    const std::vector<double> x = plane(a, options.mode, p), y = plane(b, options.mode, p);
    std::vector<double> xx(n), yy(n), xy(n);
    for (size_t i = 0; i < n; ++i) {
      xx[i] = x[i] * x[i];
      yy[i] = y[i] * y[i];
      xy[i] = x[i] * y[i];
    }
    const std::vector<double> mx = gaussian_valid(x, w, h, kernel), my = gaussian_valid(y, w, h, kernel);
    const std::vector<double> sxx = gaussian_valid(xx, w, h, kernel), syy = gaussian_valid(yy, w, h, kernel),
                              sxy = gaussian_valid(xy, w, h, kernel);
    double sum = 0;
    long long count = 0;
    for (int py = r; py < h - r; ++py)
      for (int px = r; px < w - r; ++px) {
        const size_t i = static_cast<size_t>(py) * w + px;
        if (!mask.empty() && !mask[i]) continue;
        // Eq. 13 with the weighted statistics of Eqs. 14-16.
        const double vx = sxx[i] - mx[i] * mx[i], vy = syy[i] - my[i] * my[i];
        const double cov = sxy[i] - mx[i] * my[i];
        sum += ((2 * mx[i] * my[i] + c1) * (2 * cov + c2)) /
               ((mx[i] * mx[i] + my[i] * my[i] + c1) * (vx + vy + c2));
        ++count;
      }
    if (count == 0)
      return Status::error(ErrorCode::Empty, "ssim: the mask selects no pixel at least " + std::to_string(r) +
                                                 " pixels from the image border");
    total += sum / static_cast<double>(count);
    scored = count;
  }
  result.ssim = total / planes;
  result.pixels = scored;
  return Status::success();
}

Status texture_seam(const Image& texture, const std::vector<int>& labels, const PixelMask& chart_mask,
                    const SeamOptions& options, SeamResult& result) {
  if (texture.empty() || texture.channels < 1 || texture.channels > 4 ||
      texture.pixels.size() != static_cast<size_t>(texture.width) * texture.height * texture.channels)
    return Status::error(ErrorCode::InvalidInput, "seam: empty or inconsistent texture image");
  const int w = texture.width, h = texture.height;
  const size_t n = static_cast<size_t>(w) * h;
  if (labels.size() != n)
    return Status::error(ErrorCode::InvalidInput, "seam: label map has " + std::to_string(labels.size()) +
                                                      " entries, the texture " + std::to_string(n) + " texels");
  if (!chart_mask.empty() && chart_mask.size() != n)
    return Status::error(ErrorCode::InvalidInput, "seam: chart mask has " + std::to_string(chart_mask.size()) +
                                                      " entries, the texture " + std::to_string(n) + " texels");
  if (options.pair_distance < 1)
    return Status::error(ErrorCode::InvalidInput, "seam: pair_distance must be at least 1");

  const int nc = colour_channels(texture), stride = texture.channels, step = options.pair_distance;
  auto inside = [&](size_t i) { return labels[i] >= 0 && (chart_mask.empty() || chart_mask[i]); };

  // Signed per-channel sums of colour(q) - colour(p) and absolute sums.
  struct Sums {
    double signed_sum[3] = {0, 0, 0};
    double square_sum[3] = {0, 0, 0};
    double abs_sum = 0;
    long long count = 0;
  };
  double seam_sum = 0, abs_excess_sum = 0, cross_abs_all = 0, same_abs_all = 0;
  long long seam_pairs = 0, cross_all = 0, same_all = 0;
  for (int dir = 0; dir < 2; ++dir) {
    const int dx = dir == 0 ? step : 0, dy = dir == 0 ? 0 : step;
    Sums same;
    std::map<std::pair<int, int>, Sums> cross;  // by ordered (label p, label q)
    for (int y = 0; y + dy < h; ++y)
      for (int x = 0; x + dx < w; ++x) {
        const size_t i = static_cast<size_t>(y) * w + x, j = static_cast<size_t>(y + dy) * w + x + dx;
        if (!inside(i) || !inside(j)) continue;
        Sums& sums = labels[i] == labels[j] ? same : cross[{labels[i], labels[j]}];
        double abs_mean = 0;
        for (int c = 0; c < nc; ++c) {
          const double d = static_cast<double>(texture.pixels[j * stride + c]) - texture.pixels[i * stride + c];
          sums.signed_sum[c] += d;
          sums.square_sum[c] += d * d;
          abs_mean += std::abs(d);
        }
        sums.abs_sum += abs_mean / nc;
        ++sums.count;
      }
    long long cross_count = 0;
    double cross_abs = 0;
    for (const auto& entry : cross) {
      cross_count += entry.second.count;
      cross_abs += entry.second.abs_sum;
    }
    cross_all += cross_count;
    same_all += same.count;
    cross_abs_all += cross_abs;
    same_abs_all += same.abs_sum;
    // A direction with crossings but no same-label pairs has no reference
    // slope: it is left out.
    if (cross_count == 0 || same.count == 0) continue;
    for (const auto& entry : cross) {
      const Sums& sums = entry.second;
      const double pairs = static_cast<double>(sums.count);
      for (int c = 0; c < nc; ++c) {
        const double mean = sums.signed_sum[c] / pairs;
        const double variance =
            pairs > 1 ? std::max(0.0, (sums.square_sum[c] - pairs * mean * mean) / (pairs - 1)) : 0.0;
        const double step_c = mean - same.signed_sum[c] / same.count;
        // E[mean^2] = step^2 + variance / pairs: remove the noise's share.
        seam_sum += pairs * (step_c * step_c - variance / pairs) / nc;
      }
    }
    abs_excess_sum += cross_abs - static_cast<double>(cross_count) * (same.abs_sum / same.count);
    seam_pairs += cross_count;
  }
  if (seam_pairs == 0)
    return Status::error(ErrorCode::Empty, "seam: no texel pair crosses a region boundary, or none stays inside one");
  result.seam = std::sqrt(std::max(0.0, seam_sum / static_cast<double>(seam_pairs)));
  result.abs_excess = abs_excess_sum / static_cast<double>(seam_pairs);
  result.cross_pairs = cross_all;
  result.same_pairs = same_all;
  result.cross_mean = cross_abs_all / static_cast<double>(cross_all);
  result.same_mean = same_all > 0 ? same_abs_all / static_cast<double>(same_all) : 0.0;
  return Status::success();
}

}  // namespace lk
