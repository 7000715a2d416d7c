// Tarini et al. 2002, Sec. 4.2: teeth texture from one photo.
#include "teeth/teeth.h"

#include <Eigen/Dense>
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

namespace {

// The occlusal row: the row of the teeth region where the most central
// columns are void (the dark line between upper and lower incisal edges);
// without such a line (teeth in tight occlusion), the middle of the region.
int estimate_bite_row(int w, int h, const std::vector<TeethClass>& classes) {
  const int x0 = w / 5, x1 = w - w / 5, span = std::max(1, x1 - x0);
  std::vector<int> voids(static_cast<size_t>(h), 0), teeth(static_cast<size_t>(h), 0);
  for (int y = 0; y < h; ++y)
    for (int x = x0; x < x1; ++x) {
      const TeethClass c = classes[static_cast<size_t>(y) * w + x];
      voids[static_cast<size_t>(y)] += c == TeethClass::Void;
      teeth[static_cast<size_t>(y)] += c == TeethClass::Tooth;
    }
  int top = -1, bottom = -1;
  for (int y = 0; y < h; ++y)
    if (teeth[static_cast<size_t>(y)] > span / 20) { if (top < 0) top = y; bottom = y; }
  if (top < 0) return h / 2;
  int best = top;
  for (int y = top; y <= bottom; ++y)
    if (voids[static_cast<size_t>(y)] > voids[static_cast<size_t>(best)]) best = y;
  if (voids[static_cast<size_t>(best)] < 0.3 * span) return (top + bottom) / 2;
  // The middle of the dark line's rows.
  int a = best, b = best;
  const double near = 0.9 * voids[static_cast<size_t>(best)];
  while (a > top && voids[static_cast<size_t>(a - 1)] >= near) --a;
  while (b < bottom && voids[static_cast<size_t>(b + 1)] >= near) ++b;
  return (a + b) / 2;
}

}  // namespace

int reconstruct_hidden_teeth(int w, int h, const TeethOptions& o, std::vector<TeethClass>& classes,
                             std::vector<float>& rgb, std::vector<std::uint8_t>& filled) {
  filled.assign(static_cast<size_t>(w) * h, 0);
  if (w < 2 || h < 2) return 0;
  const int bite = o.bite_row >= 0 && o.bite_row < h ? o.bite_row : estimate_bite_row(w, h, classes);
  auto cls = [&](int x, int y) -> TeethClass& { return classes[static_cast<size_t>(y) * w + x]; };
  const int window = std::max(2, static_cast<int>(o.max_tooth_width * w));
  for (int dir : {-1, +1}) {  // upper teeth (rows above the bite), lower teeth
    const int start = dir < 0 ? bite : bite + 1;
    if (start < 0 || start >= h) continue;
    // Each column's visible run of teeth/voids away from the bite.
    std::vector<int> run(static_cast<size_t>(w), 0);
    std::vector<char> gap(static_cast<size_t>(w), 1);
    for (int x = 0; x < w; ++x) {
      int n = 0, voids = 0;
      for (int y = start; y >= 0 && y < h && cls(x, y) != TeethClass::Gum; y += dir) {
        ++n;
        voids += cls(x, y) == TeethClass::Void;
      }
      run[static_cast<size_t>(x)] = n;
      gap[static_cast<size_t>(x)] = n == 0 || voids >= o.gap_void_fraction * n;
    }
    // Teeth: runs of non-gap columns, split where the visible height has a
    // marked local minimum (the gum papilla between two teeth in tight
    // contact) and cut into windows when nothing separates them.
    struct Tooth { int a, b, tallest; double fit[3]; bool arched; };
    std::vector<Tooth> teeth;
    const int radius = std::max(1, w / 200), min_width = std::max(3, w / 50);
    std::vector<double> smooth(static_cast<size_t>(w), 0.0);
    for (int x = 0; x < w; ++x) {
      double acc = 0;
      int n = 0;
      for (int k = std::max(0, x - radius); k <= std::min(w - 1, x + radius); ++k) { acc += run[static_cast<size_t>(k)]; ++n; }
      smooth[static_cast<size_t>(x)] = acc / n;
    }
    auto is_split = [&](int x, int lo, int hi) {
      if (x - lo < min_width || hi - x < min_width) return false;
      double left = 0, right = 0;
      const double here = smooth[static_cast<size_t>(x)];
      for (int k = x - min_width; k <= x + min_width; ++k) {
        if (smooth[static_cast<size_t>(k)] < here) return false;  // not the minimum of its neighbourhood
        (k < x ? left : right) = std::max(k < x ? left : right, smooth[static_cast<size_t>(k)]);
      }
      return std::min(left, right) - here > 0.1 * std::max(left, right);
    };
    for (int a = 0; a < w;) {
      if (gap[static_cast<size_t>(a)]) { ++a; continue; }
      int end = a;
      while (end + 1 < w && !gap[static_cast<size_t>(end + 1)]) ++end;
      for (int lo = a; lo <= end;) {
        int hi = lo;
        while (hi + 1 <= end && hi + 1 - lo < window && !is_split(hi + 1, lo, end)) ++hi;
        Tooth t{lo, hi, 0, {0, 0, 0}, false};
        for (int x = lo; x <= hi; ++x) t.tallest = std::max(t.tallest, run[static_cast<size_t>(x)]);
        teeth.push_back(t);
        lo = hi + 1;
      }
      a = end + 1;
    }
    // Each tooth's end as seen: a parabola (in the column offset across the
    // tooth) fitted to its upper points only, so columns a lip cuts lower do
    // not pull it down. A crown whose gum line is visible is arched (higher in
    // its middle); a lip's edge runs flat or concave across a tooth.
    for (Tooth& t : teeth) {
      const double centre = 0.5 * (t.a + t.b), half = std::max(0.5, 0.5 * (t.b - t.a + 1));
      const double tol = std::max(2.0, 0.03 * t.tallest);
      std::vector<char> use(static_cast<size_t>(t.b - t.a + 1), 1);
      for (int iter = 0; iter < 6; ++iter) {
        Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
        Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
        for (int x = t.a; x <= t.b; ++x) {
          if (!use[static_cast<size_t>(x - t.a)]) continue;
          const double u = (x - centre) / half;
          const Eigen::Vector3d phi(1, u, u * u);
          A += phi * phi.transpose();
          rhs += phi * run[static_cast<size_t>(x)];
        }
        Eigen::Vector3d c = A.ldlt().solve(rhs);
        if (!c.allFinite()) c = Eigen::Vector3d(t.tallest, 0, 0);
        if (c[2] > 0) {  // concave: a lip's edge; keep the line through it
          Eigen::Matrix2d A2 = A.topLeftCorner<2, 2>();
          const Eigen::Vector2d l = A2.ldlt().solve(rhs.head<2>());
          c = l.allFinite() ? Eigen::Vector3d(l[0], l[1], 0) : Eigen::Vector3d(t.tallest, 0, 0);
        }
        for (int k = 0; k < 3; ++k) t.fit[k] = c[k];
        bool changed = false;
        for (int x = t.a; x <= t.b; ++x) {
          const double u = (x - centre) / half;
          const char keep = run[static_cast<size_t>(x)] >= c[0] + c[1] * u + c[2] * u * u - tol;
          changed |= keep != use[static_cast<size_t>(x - t.a)];
          use[static_cast<size_t>(x - t.a)] = keep;
        }
        if (!changed) break;
      }
      t.arched = -t.fit[2] > 0.3 * o.crown_arc * (t.b - t.a + 1);
    }
    std::vector<int> outline(static_cast<size_t>(w), 0);
    std::vector<double> tolerance(static_cast<size_t>(w), 0.0);
    for (size_t t = 0; t < teeth.size(); ++t) {
      const Tooth& tooth = teeth[t];
      const double centre = 0.5 * (tooth.a + tooth.b), half = std::max(0.5, 0.5 * (tooth.b - tooth.a + 1));
      // A flat-topped tooth may be hidden across its whole width: its
      // neighbours (two on each side) tell how tall it should be; the crown
      // outline then is the generic arc.
      double generic = 0;
      if (!tooth.arched && o.neighbour_height_factor > 0) {
        std::vector<int> near;
        for (size_t u = t >= 2 ? t - 2 : 0; u <= std::min(teeth.size() - 1, t + 2); ++u)
          if (u != t) near.push_back(teeth[u].tallest);
        if (!near.empty()) {
          const size_t m = (near.size() - 1) / 2;  // the lower median: with two neighbours, the shorter
          std::nth_element(near.begin(), near.begin() + static_cast<long>(m), near.end());
          generic = std::max<double>(tooth.tallest, o.neighbour_height_factor * near[m]);
        }
      }
      for (int x = tooth.a; x <= tooth.b; ++x) {
        const double u = (x - centre) / half;
        const double fitted = tooth.fit[0] + tooth.fit[1] * u + tooth.fit[2] * u * u;
        const double arc = generic - o.crown_arc * (tooth.b - tooth.a + 1) * u * u;
        // Never above the tooth's own tallest column unless the neighbours
        // vouch for it (a fitted parabola can overshoot at the sides).
        const double limit = std::max<double>(tooth.tallest, generic);
        outline[static_cast<size_t>(x)] = static_cast<int>(std::lround(std::min(limit, std::max(fitted, arc))));
        // A visible gum line is not a parabola exactly: columns within the
        // fit's tolerance are as seen.
        tolerance[static_cast<size_t>(x)] = std::max(2.0, 0.03 * tooth.tallest);
      }
    }
    for (int x = 0; x < w; ++x) {
      {
        const int seen = run[static_cast<size_t>(x)];
        const int outline_x = outline[static_cast<size_t>(x)];
        if (gap[static_cast<size_t>(x)] || outline_x <= seen + tolerance[static_cast<size_t>(x)]) continue;
        // Fill colour: the column's outermost visible tooth pixels.
        double c[3] = {0, 0, 0};
        int k = 0;
        for (int i = seen - 1; i >= 0 && k < o.colour_rows; --i) {
          const int y = start + dir * i;
          if (cls(x, y) != TeethClass::Tooth) continue;
          for (int j = 0; j < 3; ++j) c[j] += rgb[(static_cast<size_t>(y) * w + x) * 3 + j];
          ++k;
        }
        const int outer_y = start + dir * (seen - 1);
        const TeethClass fill = cls(x, outer_y) == TeethClass::Void || k == 0 ? TeethClass::Void : TeethClass::Tooth;
        for (int i = seen; i < outline_x; ++i) {
          const int y = start + dir * i;
          if (y < 0 || y >= h || cls(x, y) != TeethClass::Gum) break;
          const size_t id = static_cast<size_t>(y) * w + x;
          cls(x, y) = fill;
          filled[id] = 1;
          if (fill == TeethClass::Tooth)
            for (int j = 0; j < 3; ++j) rgb[id * 3 + j] = static_cast<float>(c[j] / k);
        }
      }
    }
  }
  return bite;
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
  // Working colours (0..1); the hidden-part step paints into them.
  std::vector<float> rgb(n * 3);
  for (size_t i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) rgb[i * 3 + k] = photo.pixels[i * static_cast<size_t>(photo.channels) + k] / 255.f;
  res.reconstructed.assign(n, 0);
  res.reconstructed_pixels = 0;
  if (o.reconstruct_hidden) {
    res.bite_row = reconstruct_hidden_teeth(w, h, o, res.classes, rgb, res.reconstructed);
    for (std::uint8_t f : res.reconstructed) res.reconstructed_pixels += f;
  } else {
    // Still wanted: the composite puts this row on the texture's bite line.
    res.bite_row = o.bite_row >= 0 && o.bite_row < h ? o.bite_row : estimate_bite_row(w, h, res.classes);
  }
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
        if (res.classes[static_cast<size_t>(y) * w + x] == TeethClass::Tooth &&
            !res.reconstructed[static_cast<size_t>(y) * w + x]) {  // visible teeth only
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
      std::uint8_t* q = res.texture.at(x, y);
      double out[3] = {rgb[i * 3], rgb[i * 3 + 1], rgb[i * 3 + 2]};
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

Status teeth_composite_generic(const TeethResult& teeth, const TeethOptions& o,
                               const TeethCompositeOptions& co, Image& out, std::vector<float>* mask) {
  const Image& src = teeth.texture;
  if (src.empty() || src.channels != 4) return Status::error(ErrorCode::InvalidInput, "no teeth texture to composite");
  if (co.width < 16 || co.height < 16 || co.width > 8192 || co.height > 8192 ||
      !(co.middle_width > 0 && co.middle_width <= 1) || co.side_teeth < 1)
    return Status::error(ErrorCode::InvalidInput, "composite options out of range");
  const int W = co.width, H = co.height;
  out = Image::make(W, H, 4);
  if (mask) mask->assign(static_cast<size_t>(W) * H, 0.f);
  // The middle region (photo) keeps the photo's aspect ratio: its height is H.
  const double mid_w = co.middle_width * W;
  const double cx = 0.5 * W, cy = 0.5 * H;
  const double side_w = (W - mid_w) / 2 / co.side_teeth;
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      // Generic part: rounded teeth along the occlusal line (y = H/2), gums beyond.
      const bool upper = y < cy;
      const double v = upper ? (cy - y) / cy : (y - cy) / cy;  // 0 at the bite, 1 at the gum line far end
      const double dx_mid = std::abs(x - cx) - mid_w / 2;
      const double along = dx_mid > 0 ? std::fmod(dx_mid, side_w) / side_w : 0.5;  // within one tooth
      // Side teeth get shorter towards the back of the mouth.
      const double tooth_len = 0.75 - 0.25 * std::clamp(dx_mid / ((W - mid_w) / 2), 0.0, 1.0);
      const double edge = std::min(along, 1 - along);
      double g[4] = {o.gum_color[0], o.gum_color[1], o.gum_color[2], 1.0};
      if (dx_mid <= 0) {
        // Behind the photo's region: gums (only visible through the soft boundary).
      } else if (v < tooth_len * (0.8 + 0.2 * std::sqrt(std::max(0.0, edge * 2))) && edge > 0.04) {
        const double shade = 0.85 + 0.15 * std::sin(3.14159265 * along);
        for (int k = 0; k < 3; ++k) g[k] = teeth.target_color[k] * shade;
      } else if (v < 0.8 * tooth_len && edge <= 0.04) {
        // Interdental gap below the contact: transparent. Above the rounded
        // crown tops the gums stay (an opaque papilla, as in a mouth).
        g[0] = g[1] = g[2] = 0; g[3] = 0;
      }
      // Curved boundary: an ellipse through the middle region's corners' sides.
      const double ex = (x - cx) / (mid_w / 2), ey = (y - cy) / (0.5 * H * 1.15);
      const double e = std::sqrt(ex * ex + ey * ey);
      const double soft = co.boundary_softness * W / (mid_w / 2);
      const double wellipse = std::clamp((1 - e) / soft + 0.5, 0.0, 1.0);
      double c[4] = {g[0], g[1], g[2], g[3]};
      // Photo row: the photo's height spans the texture's; its bite row (when
      // known) lands on the texture's bite line (H / 2), where the teeth
      // model's billboard has its bite edge.
      const double bite = teeth.bite_row >= 0 ? teeth.bite_row + 0.5 : 0.5 * src.height;
      const double sy_f = bite + (y + 0.5 - cy) * src.height / H;
      const double wphoto = sy_f >= 0 && sy_f < src.height ? wellipse : 0.0;
      if (wphoto > 0) {
        // Photo sample: the middle region spans the photo's width.
        const double u = (x - (cx - mid_w / 2)) / mid_w;
        const int sx = std::clamp(static_cast<int>(u * src.width), 0, src.width - 1);
        const int sy = std::clamp(static_cast<int>(sy_f), 0, src.height - 1);
        const std::uint8_t* p = src.at(sx, sy);
        for (int k = 0; k < 4; ++k) c[k] = (1 - wphoto) * g[k] + wphoto * (p[k] / 255.0);
      }
      if (mask) (*mask)[static_cast<size_t>(y) * W + x] = static_cast<float>(wphoto);
      std::uint8_t* q = out.at(x, y);
      for (int k = 0; k < 4; ++k) q[k] = static_cast<std::uint8_t>(std::lround(std::clamp(c[k], 0.0, 1.0) * 255));
    }
  return Status::success();
}

Status check_smile_closeup(const TeethResult& r, int width, int height) {
  const size_t n = static_cast<size_t>(std::max(0, width)) * static_cast<size_t>(std::max(0, height));
  if (n == 0 || r.classes.size() != n)
    return Status::error(ErrorCode::InvalidInput, "check_smile_closeup: the classes do not match the photo's size");
  size_t gums = 0, teeth = 0, borders = 0;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const TeethClass c = r.classes[static_cast<size_t>(y) * width + x];
      gums += c == TeethClass::Gum;
      teeth += c == TeethClass::Tooth;
      if (x + 1 < width) {
        const TeethClass d = r.classes[static_cast<size_t>(y) * width + x + 1];
        borders += (c == TeethClass::Tooth && d == TeethClass::Void) || (c == TeethClass::Void && d == TeethClass::Tooth);
      }
    }
  if (teeth == 0) return Status::error(ErrorCode::NotAHead, "no teeth found");
  auto pct = [](double v) { return std::to_string(static_cast<int>(std::lround(100 * v))) + " %"; };
  const double gum_ratio = static_cast<double>(gums) / static_cast<double>(teeth);
  if (gum_ratio < 0.95)
    return Status::error(ErrorCode::NotAHead,
                         "no open mouth in close-up: the bright non-red pixels taken for teeth cover " +
                             pct(static_cast<double>(teeth) / n) + " of the photo and lips or gums only " +
                             pct(static_cast<double>(gums) / n) +
                             "; a smile photo shows the front teeth, lips apart, filling most of the picture");
  const double speckle = static_cast<double>(borders) / static_cast<double>(teeth);
  if (speckle >= 0.1)
    return Status::error(ErrorCode::NotAHead,
                         "no open mouth in close-up: the pixels taken for teeth are speckle among dark ones (" +
                             std::to_string(speckle).substr(0, 4) +
                             " dark borders per pixel, under 0.1 expected), not solid teeth");
  return Status::success();
}

}  // namespace lk
