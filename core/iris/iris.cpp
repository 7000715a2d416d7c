// Tarini et al. 2002, Sec. 4.1: iris finding, pixel removal, polar synthesis.
#include "iris/iris.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

namespace lk {
namespace {

constexpr double kPi = 3.14159265358979323846;

double luminance(const Image& im, int x, int y) {
  const std::uint8_t* p = im.at(x, y);
  if (im.channels < 3) return p[0] / 255.0;
  return (0.299 * p[0] + 0.587 * p[1] + 0.114 * p[2]) / 255.0;
}

Eigen::Vector3d rgb_at(const Image& im, int x, int y) {
  const std::uint8_t* p = im.at(x, y);
  if (im.channels < 3) return Eigen::Vector3d::Constant(p[0] / 255.0);
  return Eigen::Vector3d(p[0], p[1], p[2]) / 255.0;
}

// Bilinear sample, clamped to the border.
Eigen::Vector3d sample_rgb(const Image& im, double x, double y) {
  x = std::clamp(x, 0.0, im.width - 1.0);
  y = std::clamp(y, 0.0, im.height - 1.0);
  const int x0 = std::min(static_cast<int>(x), im.width - 2 < 0 ? 0 : im.width - 2);
  const int y0 = std::min(static_cast<int>(y), im.height - 2 < 0 ? 0 : im.height - 2);
  const int x1 = std::min(x0 + 1, im.width - 1), y1 = std::min(y0 + 1, im.height - 1);
  const double fx = x - x0, fy = y - y0;
  return (1 - fy) * ((1 - fx) * rgb_at(im, x0, y0) + fx * rgb_at(im, x1, y0)) +
         fy * ((1 - fx) * rgb_at(im, x0, y1) + fx * rgb_at(im, x1, y1));
}

double sample_lum(const Image& im, double x, double y) {
  const Eigen::Vector3d c = sample_rgb(im, x, y);
  return 0.299 * c[0] + 0.587 * c[1] + 0.114 * c[2];
}

Status check_photo(const Image& photo) {
  if (photo.empty() || photo.channels < 1 || photo.channels > 4 ||
      photo.pixels.size() != static_cast<size_t>(photo.width) * photo.height * photo.channels)
    return Status::error(ErrorCode::InvalidInput, "the eye photo is empty or malformed");
  if (photo.width < 16 || photo.height < 16)
    return Status::error(ErrorCode::InvalidInput, "the eye photo is smaller than 16x16 pixels");
  return Status::success();
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  const size_t k = std::min(v.size() - 1, static_cast<size_t>(q * (v.size() - 1)));
  std::nth_element(v.begin(), v.begin() + k, v.end());
  return v[k];
}

// Levels that separate the dark iris/pupil from the bright sclera/skin.
struct Levels {
  double dark = 0, bright = 1;
  double threshold(double f) const { return dark + f * (bright - dark); }
};

}  // namespace

Status iris_default_guess(const Image& photo, Vec2& guess) {
  if (Status s = check_photo(photo); !s) return s;
  const int w = photo.width, h = photo.height;
  // Integral image of luminance for box means.
  std::vector<double> integral(static_cast<size_t>(w + 1) * (h + 1), 0.0);
  std::vector<double> all;
  all.reserve(static_cast<size_t>(w) * h);
  for (int y = 0; y < h; ++y) {
    double row = 0;
    for (int x = 0; x < w; ++x) {
      const double l = luminance(photo, x, y);
      all.push_back(l);
      row += l;
      integral[static_cast<size_t>(y + 1) * (w + 1) + x + 1] = integral[static_cast<size_t>(y) * (w + 1) + x + 1] + row;
    }
  }
  const int half = std::max(2, std::min(w, h) / 30);
  auto box = [&](int x, int y) {
    const int x0 = std::max(0, x - half), x1 = std::min(w, x + half + 1);
    const int y0 = std::max(0, y - half), y1 = std::min(h, y + half + 1);
    const double s = integral[static_cast<size_t>(y1) * (w + 1) + x1] - integral[static_cast<size_t>(y0) * (w + 1) + x1] -
                     integral[static_cast<size_t>(y1) * (w + 1) + x0] + integral[static_cast<size_t>(y0) * (w + 1) + x0];
    return s / ((x1 - x0) * (y1 - y0));
  };
  const double cx = 0.5 * (w - 1), cy = 0.5 * (h - 1), diag = std::hypot(w, h);
  double best = 1e300, best_raw = 1;
  for (int y = half; y < h - half; ++y)
    for (int x = half; x < w - half; ++x) {
      const double raw = box(x, y);
      // Why the penalty: eye photos are framed around the eye, while dark
      // hair or lashes may sit at the borders.
      const double cost = raw + 0.3 * std::hypot(x - cx, y - cy) / diag;
      if (cost < best) { best = cost; best_raw = raw; guess = Vec2(x, y); }
    }
  const double bright = percentile(all, 0.95);
  if (best == 1e300 || bright - best_raw < 0.15)
    return Status::error(ErrorCode::NotAHead,
                         "no eye found: the photo has no dark blob (pupil) darker than its bright parts");
  return Status::success();
}

Status find_iris(const Image& photo, const Vec2& guess, const IrisFindOptions& options,
                 IrisCircle& circle) {
  if (Status s = check_photo(photo); !s) return s;
  const int w = photo.width, h = photo.height;
  if (!(guess.x() >= 0 && guess.y() >= 0 && guess.x() <= w - 1 && guess.y() <= h - 1))
    return Status::error(ErrorCode::InvalidInput, "the iris guess lies outside the photo");

  std::vector<double> all;
  all.reserve(static_cast<size_t>(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) all.push_back(luminance(photo, x, y));
  Levels lv;
  lv.bright = percentile(all, 0.95);
  {
    std::vector<double> near;
    for (int dy = -2; dy <= 2; ++dy)
      for (int dx = -2; dx <= 2; ++dx)
        near.push_back(sample_lum(photo, guess.x() + dx, guess.y() + dy));
    lv.dark = percentile(near, 0.5);
  }
  if (lv.bright - lv.dark < 0.15)
    return Status::error(ErrorCode::NotAHead,
                         "no iris found: the guess is not darker than the photo's bright parts "
                         "(uniform image, or a guess outside the pupil/iris)");
  const double thr = lv.threshold(options.bright_level);

  // Growing circle (paper): bright samples push the centre away from them;
  // the growth stops when most of the circle is bright.
  Vec2 c = guess;
  const double max_r = 0.5 * std::min(w, h);
  double r = 1;
  bool stopped = false;
  for (; r < max_r; r += 0.5) {
    const int n = std::max(16, static_cast<int>(2 * kPi * r));
    int bright = 0;
    Vec2 push = Vec2::Zero();
    for (int i = 0; i < n; ++i) {
      const double t = 2 * kPi * i / n;
      const Vec2 d(std::cos(t), std::sin(t));
      const Vec2 p = c + r * d;
      const bool outside = p.x() < 0 || p.y() < 0 || p.x() > w - 1 || p.y() > h - 1;
      if (outside || sample_lum(photo, p.x(), p.y()) > thr) {
        ++bright;
        push -= d;
      }
    }
    const double frac = static_cast<double>(bright) / n;
    if (frac >= options.stop_bright_fraction && r >= options.min_radius) { stopped = true; break; }
    // Move by at most half a pixel per step: the circle follows the dark disk.
    if (bright > 0) c += 0.5 * push / n;
  }
  if (!stopped)
    return Status::error(ErrorCode::NotConverged,
                         "no iris found: the growing circle never met a bright border (no round dark iris)");

  // Sub-pixel refinement: along rays, the first crossing of the threshold
  // between 0.6 r and 1.5 r; a robust (median-trimmed) algebraic circle fit.
  for (int it = 0; it < options.refine_iterations; ++it) {
    std::vector<Vec2> edge;
    const int n = std::max(64, static_cast<int>(2 * kPi * r));
    for (int i = 0; i < n; ++i) {
      const double t = 2 * kPi * i / n;
      const Vec2 d(std::cos(t), std::sin(t));
      double prev = sample_lum(photo, c.x() + 0.6 * r * d.x(), c.y() + 0.6 * r * d.y());
      for (double s = 0.6 * r + 0.25; s <= 1.5 * r; s += 0.25) {
        const Vec2 p = c + s * d;
        if (p.x() < 0 || p.y() < 0 || p.x() > w - 1 || p.y() > h - 1) break;
        const double l = sample_lum(photo, p.x(), p.y());
        if (prev <= thr && l > thr) {
          const double f = (thr - prev) / (l - prev);
          edge.push_back(c + (s - 0.25 + 0.25 * f) * d);
          break;
        }
        prev = l;
      }
    }
    if (edge.size() < 12) break;
    // Eyelids and highlights give edges off the limbus: RANSAC on circles
    // through three edge points, then least squares on the inliers.
    std::mt19937 rng(12345u + static_cast<unsigned>(it));
    std::uniform_int_distribution<size_t> pick(0, edge.size() - 1);
    const double tol = std::max(0.75, 0.02 * r);
    std::vector<Vec2> kept;
    for (int trial = 0; trial < 400; ++trial) {
      const Vec2 p1 = edge[pick(rng)], p2 = edge[pick(rng)], p3 = edge[pick(rng)];
      const double dd = 2 * (p1.x() * (p2.y() - p3.y()) + p2.x() * (p3.y() - p1.y()) + p3.x() * (p1.y() - p2.y()));
      if (std::abs(dd) < 1e-6) continue;
      const double s1 = p1.squaredNorm(), s2 = p2.squaredNorm(), s3 = p3.squaredNorm();
      const Vec2 cc((s1 * (p2.y() - p3.y()) + s2 * (p3.y() - p1.y()) + s3 * (p1.y() - p2.y())) / dd,
                    (s1 * (p3.x() - p2.x()) + s2 * (p1.x() - p3.x()) + s3 * (p2.x() - p1.x())) / dd);
      const double rr = (p1 - cc).norm();
      if (rr < 0.5 * r || rr > 2 * r || (cc - c).norm() > 0.6 * r) continue;
      std::vector<Vec2> in;
      for (const Vec2& e : edge)
        if (std::abs((e - cc).norm() - rr) < tol) in.push_back(e);
      if (in.size() > kept.size()) kept.swap(in);
    }
    if (kept.size() < 12) break;
    Eigen::MatrixXd A(static_cast<Eigen::Index>(kept.size()), 3);
    Eigen::VectorXd b(static_cast<Eigen::Index>(kept.size()));
    for (size_t i = 0; i < kept.size(); ++i) {
      const auto k = static_cast<Eigen::Index>(i);
      A(k, 0) = kept[i].x(); A(k, 1) = kept[i].y(); A(k, 2) = 1;
      b(k) = -(kept[i].squaredNorm());
    }
    const Eigen::Vector3d sol = A.colPivHouseholderQr().solve(b);
    const Vec2 nc(-0.5 * sol[0], -0.5 * sol[1]);
    const double nr2 = nc.squaredNorm() - sol[2];
    if (!(nr2 > 0) || !std::isfinite(nr2)) break;
    const double nr = std::sqrt(nr2);
    if ((nc - c).norm() > 0.5 * r || nr < 0.5 * r || nr > 2 * r) break;  // a wild fit: keep the old
    c = nc;
    r = nr;
  }
  if (r < options.min_radius)
    return Status::error(ErrorCode::NotAHead, "no iris found: the dark disk is too small");

  // Pupil: first crossing from the pupil's darkness towards the iris level.
  std::vector<double> ring;
  for (int i = 0; i < 64; ++i) {
    const double t = 2 * kPi * i / 64;
    ring.push_back(sample_lum(photo, c.x() + 0.75 * r * std::cos(t), c.y() + 0.75 * r * std::sin(t)));
  }
  const double iris_level = percentile(ring, 0.5);
  const double centre_level = sample_lum(photo, c.x(), c.y());
  const double pthr = 0.5 * (iris_level + centre_level);
  std::vector<double> pr;
  if (iris_level - centre_level > 0.04) {
    for (int i = 0; i < 64; ++i) {
      const double t = 2 * kPi * i / 64;
      for (double s = 0.5; s < 0.8 * r; s += 0.25)
        if (sample_lum(photo, c.x() + s * std::cos(t), c.y() + s * std::sin(t)) > pthr) { pr.push_back(s); break; }
    }
  }
  double pupil = pr.empty() ? 0.35 * r : percentile(pr, 0.5);
  pupil = std::clamp(pupil, 0.15 * r, 0.7 * r);
  circle.center = c;
  circle.radius = r;
  circle.pupil_radius = pupil;
  return Status::success();
}

Status iris_to_polar(const Image& photo, const IrisCircle& circle,
                     const IrisValidityOptions& options, PolarIris& polar) {
  if (Status s = check_photo(photo); !s) return s;
  if (!(circle.radius > circle.pupil_radius && circle.pupil_radius >= 0))
    return Status::error(ErrorCode::InvalidInput, "the iris circle has no annulus (radius <= pupil radius)");
  const double band = circle.radius - circle.pupil_radius;
  polar.angles = options.angles > 0
                     ? options.angles
                     : std::clamp(static_cast<int>(std::lround(2 * kPi * circle.radius)), 32, std::max(32, options.max_auto_angles));
  polar.radii = options.radii > 0 ? options.radii
                                  : std::clamp(static_cast<int>(std::lround(band)), 4, std::max(4, options.max_auto_radii));
  polar.rgb.assign(static_cast<size_t>(polar.angles) * polar.radii * 3, 0.f);
  polar.valid.assign(static_cast<size_t>(polar.angles) * polar.radii, 1);
  const int w = photo.width, h = photo.height;

  // Skin colour: median of the photo's outer band.
  std::vector<double> ch[3];
  const int bw = std::max(1, std::min(w, h) * 8 / 100);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      if (x < bw || y < bw || x >= w - bw || y >= h - bw) {
        const Eigen::Vector3d c = rgb_at(photo, x, y);
        for (int k = 0; k < 3; ++k) ch[k].push_back(c[k]);
      }
  const Eigen::Vector3d skin(percentile(ch[0], 0.5), percentile(ch[1], 0.5), percentile(ch[2], 0.5));

  for (int a = 0; a < polar.angles; ++a) {
    // Counter-clockwise on screen: y grows downwards.
    const double t = 2 * kPi * a / polar.angles;
    const Vec2 d(std::cos(t), -std::sin(t));
    for (int r = 0; r < polar.radii; ++r) {
      const double s = circle.pupil_radius + (r + 0.5) * band / polar.radii;
      const Vec2 p = circle.center + s * d;
      float* out = polar.at(a, r);
      const size_t vi = static_cast<size_t>(a) * polar.radii + r;
      if (p.x() < 0 || p.y() < 0 || p.x() > w - 1 || p.y() > h - 1) { polar.valid[vi] = 0; continue; }
      const Eigen::Vector3d c = sample_rgb(photo, p.x(), p.y());
      for (int k = 0; k < 3; ++k) out[k] = static_cast<float>(c[k]);
      if ((c - skin).norm() < options.skin_distance) polar.valid[vi] = 0;
    }
  }
  // Ring statistics: remove pixels beyond alpha standard deviations.
  for (int pass = 0; pass < options.alpha_passes; ++pass) {
    for (int r = 0; r < polar.radii; ++r) {
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      int n = 0;
      for (int a = 0; a < polar.angles; ++a)
        if (polar.valid[static_cast<size_t>(a) * polar.radii + r]) {
          const float* p = polar.at(a, r);
          mean += Eigen::Vector3d(p[0], p[1], p[2]);
          ++n;
        }
      if (n < 3) continue;
      mean /= n;
      double var = 0;
      for (int a = 0; a < polar.angles; ++a)
        if (polar.valid[static_cast<size_t>(a) * polar.radii + r]) {
          const float* p = polar.at(a, r);
          var += (Eigen::Vector3d(p[0], p[1], p[2]) - mean).squaredNorm();
        }
      const double sd = std::sqrt(var / n);
      for (int a = 0; a < polar.angles; ++a) {
        const size_t vi = static_cast<size_t>(a) * polar.radii + r;
        if (!polar.valid[vi]) continue;
        const float* p = polar.at(a, r);
        if ((Eigen::Vector3d(p[0], p[1], p[2]) - mean).norm() > options.alpha * sd) polar.valid[vi] = 0;
      }
    }
  }
  return Status::success();
}

namespace {

// Sum of squared differences between output rows [t-k, t) and reference rows [j-k, j).
double row_neighbourhood_distance(const PolarIris& out, int t, const std::vector<const float*>& ref_rows,
                                  int j, int k, int width) {
  double d = 0;
  for (int i = 1; i <= k; ++i) {
    const float* o = out.at(t - i, 0);
    const float* q = ref_rows[static_cast<size_t>(j - i)];
    for (int x = 0; x < width * 3; ++x) {
      const double e = o[x] - q[x];
      d += e * e;
    }
  }
  return d;
}

}  // namespace

Status iris_synthesize(const PolarIris& input, const IrisSynthesisOptions& options,
                       PolarIris& output, IrisSynthesisReport* report_out, const ProgressFn& progress) {
  const int A = input.angles, R = input.radii;
  if (A < 8 || R < 2 || input.rgb.size() != static_cast<size_t>(A) * R * 3 ||
      input.valid.size() != static_cast<size_t>(A) * R)
    return Status::error(ErrorCode::InvalidInput, "the polar iris is empty or malformed");
  IrisSynthesisReport rep;
  for (auto v : input.valid) rep.valid_pixels += v ? 1 : 0;
  if (rep.valid_pixels < R * 4)
    return Status::error(ErrorCode::NotAHead,
                         "no iris found: too few iris pixels survive the skin and ring-statistics removal");

  // Rows usable for the reference sector.
  std::vector<char> row_ok(static_cast<size_t>(A));
  for (int a = 0; a < A; ++a) {
    int n = 0;
    for (int r = 0; r < R; ++r) n += input.valid[static_cast<size_t>(a) * R + r];
    row_ok[static_cast<size_t>(a)] = n >= options.row_valid_fraction * R;
  }
  // Largest circular run of usable rows.
  int best_begin = 0, best_len = 0;
  {
    int all_ok = 0;
    for (char c : row_ok) all_ok += c;
    if (all_ok == A) { best_len = A; best_begin = 0; }
    else {
      int start = 0;
      while (row_ok[static_cast<size_t>(start)]) ++start;  // a row that is not ok
      int run = 0, run_begin = 0;
      for (int i = 1; i <= A; ++i) {
        const int a = (start + i) % A;
        if (row_ok[static_cast<size_t>(a)]) {
          if (run == 0) run_begin = a;
          ++run;
          if (run > best_len) { best_len = run; best_begin = run_begin; }
        } else {
          run = 0;
        }
      }
    }
  }
  const int max_rows = static_cast<int>(std::lround(options.max_sector_deg / 360.0 * A));
  if (best_len > max_rows) {
    best_begin = (best_begin + (best_len - max_rows) / 2) % A;  // the middle of the run
    best_len = max_rows;
  }
  rep.sector_begin = best_begin;
  rep.sector_rows = best_len;
  rep.sector_deg = 360.0 * best_len / A;

  // Mask scaled from the paper's 3 x 6 for an 80 px iris. The iris diameter
  // in pixels is about the number of angle rows / pi.
  const double scale = (A / kPi) / 80.0;
  const int k_angle = std::max(2, static_cast<int>(std::lround(options.mask_angle * scale)));
  const int k_radius = std::max(1, static_cast<int>(std::lround(options.mask_radius * scale)));

  output.angles = A;
  output.radii = R;
  output.rgb.assign(input.rgb.size(), 0.f);
  output.valid.assign(input.valid.size(), 1);
  std::mt19937 rng(options.seed);

  std::vector<const float*> seam_lead;  // 1-D: reference rows leading into output row 0
  const bool use_2d = options.force_2d || rep.sector_deg < options.min_sector_deg || best_len < 2 * k_angle + 2;
  rep.used_2d = use_2d;
  if (!use_2d) {
    // 1-D Markov chain of rows along the angle axis.
    std::vector<const float*> ref;
    for (int i = 0; i < best_len; ++i) ref.push_back(input.at((best_begin + i) % A, 0));
    const int m = static_cast<int>(ref.size());
    const int k = std::min(k_angle, m / 2);
    // The chain starts a few rows into the sector, so the rows just before its
    // start can close the circle at the seam (below).
    const int lead = std::min(2 * k, std::max(0, m - 2 * k));
    seam_lead.clear();
    std::uniform_int_distribution<int> start_pick(lead, m - k);
    const int s0 = start_pick(rng);
    for (int t = 0; t < k; ++t) std::copy(ref[static_cast<size_t>(s0 + t)], ref[static_cast<size_t>(s0 + t)] + R * 3, output.at(t, 0));
    std::vector<double> dist(static_cast<size_t>(m));
    // Source row of each output row: a row already used within the last few
    // rows is not a candidate, or the chain sticks on one row at the sector's
    // end (its neighbourhood matches itself best) and draws plain rings.
    std::vector<int> source(static_cast<size_t>(A), -1);
    // A longer no-repeat window keeps the chain from cycling through a few
    // rows (visible as periodic spots around the iris).
    const int no_repeat = std::max(k, (m - k) / 3);
    for (int t = 0; t < k; ++t) source[static_cast<size_t>(t)] = s0 + t;
    for (int i = lead; i >= 1; --i) seam_lead.push_back(ref[static_cast<size_t>(s0 - i)]);
    for (int t = k; t < A; ++t) {
      double best = 1e300;
      for (int j = k; j < m; ++j) {
        bool recent = false;
        for (int i = 1; i <= std::min(t, no_repeat); ++i) recent = recent || source[static_cast<size_t>(t - i)] == j;
        if (recent) { dist[static_cast<size_t>(j)] = 1e300; continue; }
        dist[static_cast<size_t>(j)] = row_neighbourhood_distance(output, t, ref, j, k, R);
        best = std::min(best, dist[static_cast<size_t>(j)]);
      }
      std::vector<int> cands;
      for (int j = k; j < m; ++j)
        if (dist[static_cast<size_t>(j)] < 1e300 && dist[static_cast<size_t>(j)] <= best * (1 + options.candidate_slack) + 1e-9) cands.push_back(j);
      std::uniform_int_distribution<size_t> pick(0, cands.size() - 1);
      const int j = cands[pick(rng)];
      source[static_cast<size_t>(t)] = j;
      std::copy(ref[static_cast<size_t>(j)], ref[static_cast<size_t>(j)] + R * 3, output.at(t, 0));
      if ((t & 63) == 0 && !report(progress, "iris synthesis", static_cast<double>(t) / A))
        return Status::error(ErrorCode::Cancelled, "iris synthesis cancelled");
    }
  } else {
    // 2-D: per pixel, causal neighbourhood (k_angle previous rows, +-k_radius
    // columns, plus the earlier columns of the current row), candidates
    // restricted to nearly the same radius.
    struct Cand { int a, r; };
    std::vector<std::vector<Cand>> by_radius(static_cast<size_t>(R));
    for (int a = 0; a < A; ++a)
      for (int r = 0; r < R; ++r) {
        bool ok = true;
        for (int da = -k_angle; da <= 0 && ok; ++da)
          for (int dr = -k_radius; dr <= k_radius && ok; ++dr) {
            const int rr = r + dr;
            if (rr < 0 || rr >= R) continue;
            ok = input.valid[static_cast<size_t>(((a + da) % A + A) % A) * R + rr] != 0;
          }
        if (ok) by_radius[static_cast<size_t>(r)].push_back({a, r});
      }
    // Seed rows: copy valid pixels of the same radius at random.
    for (int t = 0; t < A; ++t)
      for (int r = 0; r < R; ++r) {
        auto& pool = by_radius[static_cast<size_t>(r)];
        if (pool.empty()) {
          // Fall back to any valid pixel of this ring.
          for (int a = 0; a < A; ++a)
            if (input.valid[static_cast<size_t>(a) * R + r]) { pool.push_back({a, r}); break; }
        }
      }
    for (int r = 0; r < R; ++r)
      if (by_radius[static_cast<size_t>(r)].empty())
        return Status::error(ErrorCode::NotAHead, "no iris found: a ring of the iris has no valid pixel");
    for (int t = 0; t < k_angle; ++t)
      for (int r = 0; r < R; ++r) {
        auto& pool = by_radius[static_cast<size_t>(r)];
        std::uniform_int_distribution<size_t> pick(0, pool.size() - 1);
        const Cand c = pool[pick(rng)];
        std::copy(input.at(c.a, c.r), input.at(c.a, c.r) + 3, output.at(t, r));
      }
    for (int t = k_angle; t < A; ++t) {
      for (int r = 0; r < R; ++r) {
        std::vector<Cand> cands;
        for (int rr = std::max(0, r - options.radius_tolerance); rr <= std::min(R - 1, r + options.radius_tolerance); ++rr)
          cands.insert(cands.end(), by_radius[static_cast<size_t>(rr)].begin(), by_radius[static_cast<size_t>(rr)].end());
        if (static_cast<int>(cands.size()) > options.max_candidates) {
          std::shuffle(cands.begin(), cands.end(), rng);
          cands.resize(static_cast<size_t>(options.max_candidates));
        }
        double best = 1e300;
        std::vector<double> dist(cands.size());
        for (size_t ci = 0; ci < cands.size(); ++ci) {
          const Cand c = cands[ci];
          double d = 0;
          for (int da = -k_angle; da <= 0; ++da)
            for (int dr = -k_radius; dr <= k_radius; ++dr) {
              if (da == 0 && dr >= 0) break;  // causal: only already synthesized pixels
              const int ro = r + dr, rc = c.r + dr;
              if (ro < 0 || ro >= R || rc < 0 || rc >= R) continue;
              const float* o = output.at(t + da, ro);
              const float* q = input.at(((c.a + da) % A + A) % A, rc);
              for (int x = 0; x < 3; ++x) { const double e = o[x] - q[x]; d += e * e; }
            }
          dist[ci] = d;
          best = std::min(best, d);
        }
        std::vector<size_t> good;
        for (size_t ci = 0; ci < cands.size(); ++ci)
          if (dist[ci] <= best * (1 + options.candidate_slack) + 1e-9) good.push_back(ci);
        std::uniform_int_distribution<size_t> pick(0, good.size() - 1);
        const Cand c = cands[good[pick(rng)]];
        std::copy(input.at(c.a, c.r), input.at(c.a, c.r) + 3, output.at(t, r));
      }
      if ((t & 15) == 0 && !report(progress, "iris synthesis", static_cast<double>(t) / A))
        return Status::error(ErrorCode::Cancelled, "iris synthesis cancelled");
    }
  }
  // The chain does not close on itself: cross-fade the last rows into the
  // reference rows that lead into row 0 (1-D), or towards row 0 (2-D).
  const int seam = seam_lead.empty() ? std::min(k_angle * 2, A / 8) : static_cast<int>(seam_lead.size());
  for (int i = 0; i < seam; ++i) {
    const int t = A - seam + i;
    const float wgt = static_cast<float>(i + 1) / (seam + 1);
    const float* target = seam_lead.empty() ? output.at(0, 0) : seam_lead[static_cast<size_t>(i)];
    for (int x = 0; x < R * 3; ++x) {
      float& o = output.at(t, 0)[x];
      o = (1 - wgt) * o + wgt * target[x];
    }
  }
  if (report_out) *report_out = rep;
  return Status::success();
}

double eyeball_rho(const Vec3& d) { return std::acos(std::clamp(d.z(), -1.0, 1.0)) / (kPi / 2); }

Vec2 eyeball_uv(const Vec3& d) {
  const double rho = std::min(1.0, eyeball_rho(d));
  const double phi = std::atan2(d.y(), d.x());
  return Vec2(0.5 + 0.5 * rho * std::cos(phi), 0.5 - 0.5 * rho * std::sin(phi));
}

Status eyeball_texture(const PolarIris& iris, double pupil_to_iris_ratio,
                       const EyeballTextureOptions& options, Image& texture) {
  if (iris.angles < 8 || iris.radii < 2 || iris.rgb.size() != static_cast<size_t>(iris.angles) * iris.radii * 3)
    return Status::error(ErrorCode::InvalidInput, "the polar iris is empty or malformed");
  if (options.size < 16 || options.size > 8192)
    return Status::error(ErrorCode::InvalidInput, "eyeball texture size must be within 16..8192");
  if (!(pupil_to_iris_ratio >= 0 && pupil_to_iris_ratio < 1))
    return Status::error(ErrorCode::InvalidInput, "pupil/iris ratio must be within [0,1)");
  const int S = options.size;
  texture = Image::make(S, S, 3);
  const double rho_iris = options.iris_angle_deg / 90.0;
  const double rho_pupil_photo = rho_iris * pupil_to_iris_ratio;
  const double rho_pupil = std::min(0.95 * rho_iris, rho_pupil_photo * options.pupil_scale);

  // Veins: random walks from the hemisphere's rim towards the limbus, stored
  // as polylines in (rho, phi).
  std::mt19937 rng(options.seed);
  std::uniform_real_distribution<double> U(0, 1);
  struct Seg { Vec2 a, b; double width, strength; };
  std::vector<Seg> segs;
  for (int v = 0; v < options.veins; ++v) {
    double phi = 2 * kPi * U(rng);
    // Veins are mostly on the left and right of the visible sclera.
    if (U(rng) < 0.7) phi = (U(rng) < 0.5 ? 0.0 : kPi) + (U(rng) - 0.5) * 1.2;
    double rho = 1.0;
    const double stop = rho_iris + 0.1 + 0.3 * U(rng);
    const double width = 0.002 + 0.003 * U(rng);
    while (rho > stop) {
      const Vec2 a(rho * std::cos(phi), rho * std::sin(phi));
      rho -= 0.02;
      phi += (U(rng) - 0.5) * 0.15;
      const Vec2 b(rho * std::cos(phi), rho * std::sin(phi));
      segs.push_back({a, b, width, (rho - stop) / (1 - stop)});
    }
  }
  const Eigen::Vector3d sclera(0.93, 0.90, 0.87), vein(0.75, 0.25, 0.22);
  for (int y = 0; y < S; ++y)
    for (int x = 0; x < S; ++x) {
      const Vec2 q((x + 0.5) / S * 2 - 1, 1 - (y + 0.5) / S * 2);  // +y up
      const double rho = q.norm();
      const double phi = std::atan2(q.y(), q.x());
      Eigen::Vector3d c = sclera;
      // Faint shading towards the rim, and veins.
      c *= 1.0 - 0.06 * std::clamp(rho, 0.0, 1.0);
      double vein_w = 0;
      for (const Seg& s : segs) {
        if (std::abs(s.a.x() - q.x()) > 0.03 || std::abs(s.a.y() - q.y()) > 0.03) continue;
        const Vec2 ab = s.b - s.a;
        const double t = std::clamp((q - s.a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
        const double d = (s.a + t * ab - q).norm();
        if (d < s.width) vein_w = std::max(vein_w, 0.5 * s.strength * (1 - d / s.width));
      }
      c = (1 - vein_w) * c + vein_w * vein;
      const double limbus = options.limbus_width * rho_iris;
      if (rho < rho_iris + limbus) {
        // Iris sample, with the pupil scaled (dilation) and the band mapped.
        const double f = std::clamp((rho - rho_pupil) / (rho_iris - rho_pupil), 0.0, 1.0);
        const double rr = std::clamp(f * iris.radii - 0.5, 0.0, iris.radii - 1.0);
        double aa = phi / (2 * kPi) * iris.angles;
        if (aa < 0) aa += iris.angles;
        const int a0 = static_cast<int>(aa) % iris.angles, a1 = (a0 + 1) % iris.angles;
        const int r0 = static_cast<int>(rr), r1 = std::min(r0 + 1, iris.radii - 1);
        const double fa = aa - std::floor(aa), fr = rr - r0;
        Eigen::Vector3d ic = Eigen::Vector3d::Zero();
        auto px = [&](int a, int r) { const float* p = iris.at(a, r); return Eigen::Vector3d(p[0], p[1], p[2]); };
        ic = (1 - fa) * ((1 - fr) * px(a0, r0) + fr * px(a0, r1)) + fa * ((1 - fr) * px(a1, r0) + fr * px(a1, r1));
        // Limbus: darker towards the edge, then a soft blend into the sclera.
        const double dark = std::clamp((rho - (rho_iris - limbus)) / limbus, 0.0, 1.0);
        ic *= 1.0 - 0.45 * dark;
        const double blend = std::clamp((rho - rho_iris) / limbus, 0.0, 1.0);
        c = (1 - blend) * ic + blend * c * (0.85 + 0.15 * blend);
        // Pupil, with a one-texel soft edge.
        const double texel = 2.0 / S;
        const double pw = std::clamp((rho_pupil + texel - rho) / (2 * texel), 0.0, 1.0);
        c = (1 - pw) * c + pw * Eigen::Vector3d(0.02, 0.02, 0.025);
      }
      std::uint8_t* o = texture.at(x, y);
      for (int k = 0; k < 3; ++k) o[k] = static_cast<std::uint8_t>(std::lround(std::clamp(c[k], 0.0, 1.0) * 255));
    }
  return Status::success();
}

namespace {

// The photo reduced by an integer factor (box filter): its long side at
// most max_side. factor 1 returns it unchanged.
Image reduce(const Image& photo, int max_side, int& factor) {
  factor = 1;
  while (max_side > 0 && std::max(photo.width, photo.height) > factor * max_side) ++factor;
  if (factor == 1) return photo;
  const int w = photo.width / factor, h = photo.height / factor, c = photo.channels;
  Image out = Image::make(w, h, c);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int k = 0; k < c; ++k) {
        int sum = 0;
        for (int dy = 0; dy < factor; ++dy)
          for (int dx = 0; dx < factor; ++dx) sum += photo.at(x * factor + dx, y * factor + dy)[k];
        out.at(x, y)[k] = static_cast<std::uint8_t>((sum + factor * factor / 2) / (factor * factor));
      }
  return out;
}

double median(std::vector<double> v) { return percentile(std::move(v), 0.5); }

}  // namespace

Status check_eye_closeup(const Image& photo, const IrisCircle& circle) {
  if (Status s = check_photo(photo); !s) return s;
  const double r = circle.radius;
  const Vec2 c = circle.center;
  if (!(r > 0)) return Status::error(ErrorCode::InvalidInput, "the iris circle has no radius");
  // Round limbus: the strongest step along each ray, outwards.
  constexpr int kRays = 180;
  int round = 0;
  for (int i = 0; i < kRays; ++i) {
    const Vec2 d(std::cos(2 * kPi * i / kRays), std::sin(2 * kPi * i / kRays));
    double best = 0, at = 0;
    for (double f = 0.6; f <= 1.5 + 1e-9; f += 0.02) {
      const Vec2 a = c + (f - 0.04) * r * d, b = c + (f + 0.04) * r * d;
      const double step = sample_lum(photo, b.x(), b.y()) - sample_lum(photo, a.x(), a.y());
      if (step > best) { best = step; at = f; }
    }
    if (best > 0.05 && std::abs(at - 1) < 0.1) ++round;
  }
  const double round_fraction = static_cast<double>(round) / kRays;
  // A pupil darker than the iris.
  std::vector<double> ring, centre;
  for (int i = 0; i < 90; ++i) {
    const Vec2 d(std::cos(2 * kPi * i / 90), std::sin(2 * kPi * i / 90));
    const Vec2 p = c + 0.6 * r * d;
    ring.push_back(sample_lum(photo, p.x(), p.y()));
    for (double f : {0.05, 0.1}) centre.push_back(sample_lum(photo, c.x() + f * r * d.x(), c.y() + f * r * d.y()));
  }
  const double pupil_contrast = median(ring) - median(centre);
  auto pct = [](double v) { return std::to_string(static_cast<int>(std::lround(100 * v))) + " %"; };
  if (r > 0.4 * std::min(photo.width, photo.height))
    return Status::error(ErrorCode::NotAHead,
                         "no eye close-up: the dark round patch found spans " +
                             pct(2 * r / std::min(photo.width, photo.height)) +
                             " of the photo's short side (80 % at most: an eye photo shows the eye's white or lids "
                             "beside the iris); an eye photo is a close-up of one open eye, the iris near the middle");
  if (round_fraction < 0.38)
    return Status::error(ErrorCode::NotAHead,
                         "no eye close-up: the dark patch found has no round iris edge (" + pct(round_fraction) +
                             " of its border, 38 % needed); "
                             "an eye photo is a close-up of one open eye, the iris near the middle");
  if (pupil_contrast < 0.12)
    return Status::error(ErrorCode::NotAHead,
                         "no eye close-up: the round patch found has no pupil darker than its iris (contrast " +
                             pct(pupil_contrast) + ", 12 % needed); an eye photo is a close-up of one open eye");
  return Status::success();
}

Status iris_texture_from_photo(const Image& photo, const Vec2* guess, IrisResult& result,
                               const EyeballTextureOptions& texture_options, const ProgressFn& progress, int max_side) {
  if (Status s = check_photo(photo); !s) return s;
  int factor = 1;
  const Image small = reduce(photo, max_side, factor);
  Vec2 g;
  if (guess) g = (*guess + Vec2::Constant(0.5)) / factor - Vec2::Constant(0.5);
  else if (Status s = iris_default_guess(small, g); !s) return s;
  if (!report(progress, "iris", 0.1)) return Status::error(ErrorCode::Cancelled, "iris: cancelled");
  if (Status s = find_iris(small, g, {}, result.circle); !s) return s;
  if (Status s = check_eye_closeup(small, result.circle); !s) return s;
  if (Status s = iris_texture_from_circle(small, result.circle, result, texture_options, progress); !s) return s;
  // The circle in the photo's own pixels.
  result.circle.center = (result.circle.center + Vec2::Constant(0.5)) * factor - Vec2::Constant(0.5);
  result.circle.radius *= factor;
  result.circle.pupil_radius *= factor;
  return Status::success();
}

Status iris_texture_from_circle(const Image& photo, const IrisCircle& circle, IrisResult& result,
                                const EyeballTextureOptions& texture_options, const ProgressFn& progress) {
  result.circle = circle;
  if (!report(progress, "iris", 0.2)) return Status::error(ErrorCode::Cancelled, "iris: cancelled");
  if (Status s = iris_to_polar(photo, circle, {}, result.input_polar); !s) return s;
  const ProgressFn synthesis = [&progress](const char*, double f) { return report(progress, "iris", 0.25 + 0.7 * f); };
  if (Status s = iris_synthesize(result.input_polar, {}, result.synthesized, &result.report, synthesis); !s) return s;
  return eyeball_texture(result.synthesized, circle.pupil_radius / circle.radius, texture_options, result.texture);
}

namespace {

// Median luminance along the circle (c, r) over the angles (radians, image
// y down), n samples per arc.
double arc_median(const Image& im, const Vec2& c, double r, const std::vector<Vec2>& dirs, std::vector<double>& buf) {
  buf.clear();
  for (const Vec2& d : dirs) buf.push_back(sample_lum(im, c.x() + r * d.x(), c.y() + r * d.y()));
  std::nth_element(buf.begin(), buf.begin() + long(buf.size() / 2), buf.end());
  return buf[buf.size() / 2];
}

}  // namespace

Status find_iris_near(const Image& photo, const Vec2& guess, double search_px, double min_radius,
                      double max_radius, IrisCircle& circle) {
  if (Status s = check_photo(photo); !s) return s;
  if (!(min_radius >= 2 && max_radius > min_radius && search_px >= 0 && max_radius < 4096 && search_px < 4096))
    return Status::error(ErrorCode::InvalidInput, "iris search: bad radius range or search distance");
  // The lateral arcs: 50 deg either side of horizontal, left and right.
  std::vector<Vec2> right, left, full;
  for (int i = 0; i < 40; ++i) {
    const double t = (-50 + 100.0 * (i + 0.5) / 40) * kPi / 180;
    right.emplace_back(std::cos(t), std::sin(t));
    left.emplace_back(-std::cos(t), std::sin(t));
  }
  for (int i = 0; i < 96; ++i) full.emplace_back(std::cos(2 * kPi * i / 96), std::sin(2 * kPi * i / 96));
  constexpr double kStep = 1.5;  // the radial derivative's half width, pixels
  const int k = static_cast<int>(std::lround(2 * kStep));  // kStep in 0.5 px samples
  std::vector<double> buf, level_left, level_right;
  double best = -1;
  Vec2 best_c = guess;
  double best_r = 0;
  // A limbus steps from dark to bright on both sides: the score is the
  // smaller of the two arcs' steps (a catchlight or a lid edge gives one).
  auto scan = [&](const Vec2& around, double reach, double step) {
    const Vec2 start = around;
    for (double dy = -reach; dy <= reach + 1e-9; dy += step)
      for (double dx = -reach; dx <= reach + 1e-9; dx += step) {
        const Vec2 c = start + Vec2(dx, dy);
        level_left.clear();
        level_right.clear();
        for (double r = min_radius - kStep; r <= max_radius + kStep + 1e-9; r += 0.5) {
          level_left.push_back(arc_median(photo, c, r, left, buf));
          level_right.push_back(arc_median(photo, c, r, right, buf));
        }
        for (int i = k; i + k < static_cast<int>(level_left.size()); ++i) {
          const double step_value = std::min(level_left[size_t(i + k)] - level_left[size_t(i - k)],
                                             level_right[size_t(i + k)] - level_right[size_t(i - k)]);
          if (step_value > best) {
            best = step_value;
            best_c = c;
            best_r = min_radius - kStep + 0.5 * i;
          }
        }
      }
  };
  scan(guess, search_px, 2.0);
  scan(best_c, 2.0, 0.5);
  if (best < 0.04)
    return Status::error(ErrorCode::NotAHead, "no iris edge near the eye's place (the strongest step is " +
                                                  std::to_string(static_cast<int>(std::lround(100 * std::max(0.0, best)))) +
                                                  " % of the luminance range, 4 % needed)");
  // The pupil: the strongest dark-to-bright step on full circles inside.
  double pupil = 0.35 * best_r, pupil_step = 0;
  std::vector<double>& level = level_left;
  level.clear();
  const double p0 = 0.15 * best_r, p1 = 0.7 * best_r;
  for (double r = p0 - kStep; r <= p1 + kStep + 1e-9; r += 0.5) level.push_back(arc_median(photo, best_c, std::max(0.5, r), full, buf));
  for (int i = k; i + k < static_cast<int>(level.size()); ++i) {
    const double v = level[size_t(i + k)] - level[size_t(i - k)];
    if (v > pupil_step) {
      pupil_step = v;
      pupil = p0 - kStep + 0.5 * i;
    }
  }
  if (pupil_step < 0.04) pupil = 0.35 * best_r;
  circle.center = best_c;
  circle.radius = best_r;
  circle.pupil_radius = std::clamp(pupil, 0.15 * best_r, 0.7 * best_r);
  return Status::success();
}

}  // namespace lk
