// CPU silhouettes for jeong2002 Sec. 4.1; see silhouette.h.
#include "align/silhouette.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace lk {

const char* to_string(SilhouetteView view) {
  switch (view) {
    case SilhouetteView::Front: return "front";
    case SilhouetteView::Side: return "side";
    case SilhouetteView::Top: return "top";
  }
  return "?";
}

SilhouetteMask SilhouetteMask::make(int n) {
  SilhouetteMask m;
  m.size = std::max(0, n);
  m.words_per_row = (m.size + 63) / 64;
  m.bits.assign(static_cast<size_t>(m.size) * m.words_per_row, 0);
  return m;
}

void SilhouetteMask::set_span(int y, int x0, int x1) {
  if (y < 0 || y >= size) return;
  x0 = std::max(x0, 0);
  x1 = std::min(x1, size);
  if (x0 >= x1) return;
  std::uint64_t* row = &bits[static_cast<size_t>(y) * words_per_row];
  const int w0 = x0 >> 6, w1 = (x1 - 1) >> 6;
  const std::uint64_t first = ~std::uint64_t(0) << (x0 & 63);
  const std::uint64_t last = ~std::uint64_t(0) >> (63 - ((x1 - 1) & 63));
  if (w0 == w1) {
    row[w0] |= first & last;
    return;
  }
  row[w0] |= first;
  for (int w = w0 + 1; w < w1; ++w) row[w] = ~std::uint64_t(0);
  row[w1] |= last;
}

void SilhouetteMask::clear() { std::fill(bits.begin(), bits.end(), 0); }

int SilhouetteMask::count() const {
  long long n = 0;
  for (std::uint64_t w : bits) n += __builtin_popcountll(w);
  return static_cast<int>(n);
}

int xor_count(const SilhouetteMask& a, const SilhouetteMask& b) {
  if (a.bits.size() != b.bits.size()) return -1;
  long long n = 0;
  for (size_t i = 0; i < a.bits.size(); ++i) n += __builtin_popcountll(a.bits[i] ^ b.bits[i]);
  return static_cast<int>(n);
}

int union_xor_count(const SilhouetteMask& a1, const SilhouetteMask& a2, const SilhouetteMask& b) {
  if (a1.bits.size() != b.bits.size() || a2.bits.size() != b.bits.size()) return -1;
  long long n = 0;
  for (size_t i = 0; i < b.bits.size(); ++i) n += __builtin_popcountll((a1.bits[i] | a2.bits[i]) ^ b.bits[i]);
  return static_cast<int>(n);
}

namespace {

// Which world axis feeds the column and row of each view, with signs.
struct ViewAxes { int col_axis; double col_sign; int row_axis; double row_sign; };
constexpr ViewAxes kViewAxes[kSilhouetteViews] = {
    {0, +1.0, 1, -1.0},  // front
    {2, +1.0, 1, -1.0},  // side
    {0, +1.0, 2, +1.0},  // top
};

}  // namespace

Vec2 ViewWindow::project(const Vec3& p, SilhouetteView view) const {
  const ViewAxes& a = kViewAxes[static_cast<int>(view)];
  const double scale = resolution / (2.0 * half_size);
  return Vec2((a.col_sign * (p[a.col_axis] - center[a.col_axis]) + half_size) * scale,
              (a.row_sign * (p[a.row_axis] - center[a.row_axis]) + half_size) * scale);
}

ViewWindow make_view_window(const BBox& box, double margin, int resolution) {
  ViewWindow w;
  w.center = box.center();
  const double side = box.valid() ? box.size().maxCoeff() : 0.0;
  w.half_size = 0.5 * side * (1.0 + 2.0 * margin);
  if (!(w.half_size > 0.0)) w.half_size = 1.0;
  w.resolution = resolution;
  return w;
}

void rasterize_triangle(const Vec2& a, const Vec2& b, const Vec2& c, SilhouetteMask& mask) {
  const int n = mask.size;
  // Sort by y: top (t), middle (m), bottom (b). Rows whose centre j + 0.5
  // lies in [y_t, y_m) are bounded by the long edge t-b and the edge t-m;
  // rows in [y_m, y_b) by t-b and m-b. Half-open in y, so a vertex on a
  // scan line counts once and triangles sharing an edge leave no gap.
  if (!a.allFinite() || !b.allFinite() || !c.allFinite()) return;
  const Vec2* v0 = &a;
  const Vec2* v1 = &b;
  const Vec2* v2 = &c;
  if (v1->y() < v0->y()) std::swap(v0, v1);
  if (v2->y() < v1->y()) std::swap(v1, v2);
  if (v1->y() < v0->y()) std::swap(v0, v1);
  const double y0 = v0->y(), y1 = v1->y(), y2 = v2->y();
  if (!(y2 > y0)) return;  // flat, or NaN
  // Row range, clamped before any int conversion so far-away vertices
  // cannot overflow.
  auto first_row = [n](double y) {
    return static_cast<int>(std::ceil(std::clamp(y - 0.5, -1.0, n + 1.0)));
  };
  const int j_top = std::max(first_row(y0), 0);
  const int j_mid = std::clamp(first_row(y1), 0, n);
  const int j_end = std::min(first_row(y2), n);
  if (j_top >= j_end) return;
  const double x0 = v0->x(), x1 = v1->x(), x2 = v2->x();
  const double slope_long = (x2 - x0) / (y2 - y0);
  auto fill = [&](int j, double xa, double xb) {
    if (xa > xb) std::swap(xa, xb);
    xa = std::clamp(xa - 0.5, -1.0, n + 1.0);
    xb = std::clamp(xb - 0.5, -1.0, n + 1.0);
    mask.set_span(j, static_cast<int>(std::ceil(xa)), static_cast<int>(std::ceil(xb)));
  };
  if (y1 > y0) {
    const double slope = (x1 - x0) / (y1 - y0);
    for (int j = j_top; j < j_mid; ++j) {
      const double dy = j + 0.5 - y0;
      fill(j, x0 + dy * slope_long, x0 + dy * slope);
    }
  }
  if (y2 > y1) {
    const double slope = (x2 - x1) / (y2 - y1);
    for (int j = std::max(j_mid, j_top); j < j_end; ++j) {
      const double yc = j + 0.5;
      fill(j, x0 + (yc - y0) * slope_long, x1 + (yc - y1) * slope);
    }
  }
}

namespace {

void reset_masks(int n, std::array<SilhouetteMask, kSilhouetteViews>& out) {
  for (auto& m : out) {
    if (m.size != n) m = SilhouetteMask::make(n);
    else m.clear();
  }
}

// Sutherland-Hodgman: keeps the part of the polygon with distance >= 0.
int clip_polygon(const Vec3* in, int count, const ClipPlane& plane, Vec3* out) {
  int m = 0;
  for (int i = 0; i < count; ++i) {
    const Vec3& p = in[i];
    const Vec3& q = in[(i + 1) % count];
    const double dp = plane.normal.dot(p - plane.point);
    const double dq = plane.normal.dot(q - plane.point);
    if (dp >= 0) out[m++] = p;
    if ((dp >= 0) != (dq >= 0)) out[m++] = p + (dp / (dp - dq)) * (q - p);
  }
  return m;
}

}  // namespace

void rasterize_mesh_silhouettes(const std::vector<Vec3>& positions, const std::vector<Tri>& triangles,
                                const ViewWindow& window, const std::vector<ClipPlane>& clips,
                                std::array<SilhouetteMask, kSilhouetteViews>& out,
                                bool cull_back_faces, TriangleRange range) {
  reset_masks(window.resolution, out);
  const int nv = static_cast<int>(positions.size());
  const int nc = static_cast<int>(clips.size());
  // Per vertex: projections into each view, and a bit per plane it falls behind.
  std::vector<Vec2> projected(static_cast<size_t>(nv) * kSilhouetteViews);
  std::vector<unsigned> behind(nv, 0u);
  for (int i = 0; i < nv; ++i) {
    for (int v = 0; v < kSilhouetteViews; ++v)
      projected[static_cast<size_t>(i) * kSilhouetteViews + v] =
          window.project(positions[i], static_cast<SilhouetteView>(v));
    for (int c = 0; c < nc && c < 32; ++c)
      if (!clips[c].keeps(positions[i])) behind[i] |= 1u << c;
  }
  // Culling per view; off where a clip plane's cut side faces the viewer.
  const Vec3 view_direction[kSilhouetteViews] = {Vec3(0, 0, -1), Vec3(1, 0, 0), Vec3(0, -1, 0)};
  bool cull[kSilhouetteViews];
  for (int v = 0; v < kSilhouetteViews; ++v) {
    cull[v] = cull_back_faces;
    for (const ClipPlane& c : clips)
      if (c.normal.dot(view_direction[v]) > 1e-12) cull[v] = false;
  }
  Vec3 poly[2][3 + 32];
  const int num_triangles = static_cast<int>(triangles.size());
  for (int f = std::clamp(range.begin, 0, num_triangles); f < std::clamp(range.end, 0, num_triangles); ++f) {
    const Tri& t = triangles[f];
    if (t[0] < 0 || t[1] < 0 || t[2] < 0 || t[0] >= nv || t[1] >= nv || t[2] >= nv) continue;
    const unsigned all_behind = behind[t[0]] & behind[t[1]] & behind[t[2]];
    if (all_behind) continue;
    // Which views see the triangle's front: the view directions are -z, +x
    // and -y, so the sign of one normal component decides each.
    bool seen[kSilhouetteViews] = {true, true, true};
    if (cull_back_faces) {
      const Vec3 normal = (positions[t[1]] - positions[t[0]]).cross(positions[t[2]] - positions[t[0]]);
      for (int v = 0; v < kSilhouetteViews; ++v)
        seen[v] = !cull[v] || normal.dot(view_direction[v]) < 0.0;
    }
    const unsigned any_behind = behind[t[0]] | behind[t[1]] | behind[t[2]];
    if (!any_behind) {
      for (int v = 0; v < kSilhouetteViews; ++v)
        if (seen[v])
          rasterize_triangle(projected[static_cast<size_t>(t[0]) * kSilhouetteViews + v],
                           projected[static_cast<size_t>(t[1]) * kSilhouetteViews + v],
                           projected[static_cast<size_t>(t[2]) * kSilhouetteViews + v], out[v]);
      continue;
    }
    // Straddles a plane: clip exactly, then fan-triangulate.
    int count = 3;
    for (int k = 0; k < 3; ++k) poly[0][k] = positions[t[k]];
    int cur = 0;
    for (int c = 0; c < nc && c < 32 && count >= 3; ++c) {
      if (!((any_behind >> c) & 1u)) continue;
      count = clip_polygon(poly[cur], count, clips[c], poly[1 - cur]);
      cur = 1 - cur;
    }
    if (count < 3) continue;
    for (int v = 0; v < kSilhouetteViews; ++v) {
      if (!seen[v]) continue;
      const auto view = static_cast<SilhouetteView>(v);
      const Vec2 p0 = window.project(poly[cur][0], view);
      for (int k = 1; k + 1 < count; ++k)
        rasterize_triangle(p0, window.project(poly[cur][k], view), window.project(poly[cur][k + 1], view),
                           out[v]);
    }
  }
}

namespace {

constexpr double kFar = 1e12;  // "no feature": larger than any squared distance in a mask

// Felzenszwalb-Huttenlocher 1D squared distance transform of f (n samples):
// the lower envelope of the parabolas rooted at each sample.
void distance_1d(const double* f, int n, double* d, int* v, double* z) {
  const double inf = std::numeric_limits<double>::infinity();
  int k = 0;
  v[0] = 0;
  z[0] = -inf;
  z[1] = inf;
  for (int q = 1; q < n; ++q) {
    double s = ((f[q] + double(q) * q) - (f[v[k]] + double(v[k]) * v[k])) / (2.0 * q - 2.0 * v[k]);
    while (s <= z[k]) {
      --k;
      s = ((f[q] + double(q) * q) - (f[v[k]] + double(v[k]) * v[k])) / (2.0 * q - 2.0 * v[k]);
    }
    ++k;
    v[k] = q;
    z[k] = s;
    z[k + 1] = inf;
  }
  k = 0;
  for (int q = 0; q < n; ++q) {
    while (z[k + 1] < q) ++k;
    d[q] = double(q - v[k]) * (q - v[k]) + f[v[k]];
  }
}

// Squared Euclidean distance from every cell of an n x n grid to the nearest
// cell where feature is true.
void squared_distance_2d(const std::vector<char>& feature, int n, std::vector<double>& out) {
  out.assign(static_cast<size_t>(n) * n, kFar);
  std::vector<double> f(n), d(n), z(n + 1);
  std::vector<int> v(n);
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) f[x] = feature[static_cast<size_t>(y) * n + x] ? 0.0 : kFar;
    distance_1d(f.data(), n, d.data(), v.data(), z.data());
    for (int x = 0; x < n; ++x) out[static_cast<size_t>(y) * n + x] = d[x];
  }
  for (int x = 0; x < n; ++x) {
    for (int y = 0; y < n; ++y) f[y] = out[static_cast<size_t>(y) * n + x];
    distance_1d(f.data(), n, d.data(), v.data(), z.data());
    for (int y = 0; y < n; ++y) out[static_cast<size_t>(y) * n + x] = d[y];
  }
}

}  // namespace

namespace {

// Squared distances from every cell of the (n+2)^2 padded grid to the
// nearest covered pixel; the one-pixel empty border stands for "outside the
// mask is empty".
std::vector<double> distance_to_covered(const SilhouetteMask& mask) {
  const int n = mask.size, g = n + 2;
  std::vector<char> feature(static_cast<size_t>(g) * g, 0);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) feature[static_cast<size_t>(y + 1) * g + x + 1] = mask.get(x, y);
  std::vector<double> dist;
  squared_distance_2d(feature, g, dist);
  return dist;
}

// Closing from the distances above: the dilation is every cell within the
// radius of a covered pixel; its erosion keeps the cells farther than the
// radius from any cell outside the dilation.
SilhouetteMask closing_from_distance(const std::vector<double>& to_covered, int n, double radius_px) {
  const int g = n + 2;
  const double r2 = radius_px * radius_px;
  std::vector<char> outside(to_covered.size());
  for (size_t i = 0; i < outside.size(); ++i) outside[i] = !(to_covered[i] <= r2);
  std::vector<double> dist;
  squared_distance_2d(outside, g, dist);
  SilhouetteMask closed = SilhouetteMask::make(n);
  for (int y = 0; y < n; ++y) {
    const double* row = &dist[static_cast<size_t>(y + 1) * g + 1];
    for (int x = 0; x < n; ++x)
      if (row[x] > r2) closed.set(x, y);
  }
  return closed;
}

}  // namespace

SilhouetteMask close_mask(const SilhouetteMask& mask, double radius_px) {
  if (!(radius_px > 0.0) || mask.size == 0) return mask;
  return closing_from_distance(distance_to_covered(mask), mask.size, radius_px);
}

void rasterize_point_silhouettes(const std::vector<Vec3>& points, const ViewWindow& window,
                                 const std::vector<ClipPlane>& clips, const PointSplatOptions& options,
                                 std::array<SilhouetteMask, kSilhouetteViews>& out,
                                 PointSilhouetteInfo* info) {
  const int n = window.resolution;
  std::array<SilhouetteMask, kSilhouetteViews> raw;
  reset_masks(n, raw);
  int kept = 0;
  for (const Vec3& p : points) {
    bool keep = p.allFinite();
    for (const ClipPlane& c : clips) keep = keep && c.keeps(p);
    if (!keep) continue;
    ++kept;
    for (int v = 0; v < kSilhouetteViews; ++v) {
      const Vec2 q = window.project(p, static_cast<SilhouetteView>(v));
      if (!(q.x() >= 0.0 && q.y() >= 0.0 && q.x() < n && q.y() < n)) continue;
      raw[v].set(static_cast<int>(q.x()), static_cast<int>(q.y()));
    }
  }
  const std::vector<double> radii = options.closing_radii_px.empty() ? std::vector<double>{0.0}
                                                                        : options.closing_radii_px;
  // Try every radius: filling sampling holes adds a lot of area at once
  // (often only from some radius on, when the gaps between points close),
  // while filling true concavities of the outline adds little per step.
  // The largest radius that still added much is the one that closed the
  // holes (footnote 1's "fully covered silhouette").
  std::array<std::vector<double>, kSilhouetteViews> to_covered;
  std::array<double, kSilhouetteViews> chosen{};
  auto closed = [&](int v, double r) { return r > 0.0 ? closing_from_distance(to_covered[v], n, r) : raw[v]; };
  for (int v = 0; v < kSilhouetteViews; ++v) {
    to_covered[v] = distance_to_covered(raw[v]);
    chosen[v] = radii[0];
    int previous_count = closed(v, radii[0]).count();
    for (size_t k = 1; k < radii.size(); ++k) {
      const int next_count = closed(v, radii[k]).count();
      if (next_count - previous_count >= options.hole_tolerance * next_count) chosen[v] = radii[k];
      previous_count = next_count;
    }
  }
  // The gaps between points are a property of the cloud, and all views have
  // the same pixel size: the median radius keeps one view whose outline has
  // a real opening (e.g. looking into a cut-away back of the head from
  // above) from filling it in.
  if (options.same_radius_in_all_views) {
    std::array<double, kSilhouetteViews> sorted = chosen;
    std::sort(sorted.begin(), sorted.end());
    chosen.fill(sorted[kSilhouetteViews / 2]);
  }
  for (int v = 0; v < kSilhouetteViews; ++v) {
    out[v] = closed(v, chosen[v]);
    if (info) {
      info->closing_radius_px[v] = chosen[v];
      info->raw_pixels[v] = raw[v].count();
      info->covered_pixels[v] = out[v].count();
    }
  }
  if (info) info->points_kept = kept;
}

OutlineField make_outline_field(const SilhouetteMask& mask, double cap_px) {
  OutlineField f;
  const int n = mask.size, g = n + 2;
  f.size = n;
  f.cap_px = cap_px > 0.0 ? cap_px : 1.0;
  // Distances (padded grid: outside the window is uncovered) from every
  // pixel centre to the nearest covered and the nearest uncovered centre;
  // half a pixel less is the distance to the pixel edges between them.
  std::vector<char> covered(static_cast<size_t>(g) * g, 0), uncovered(covered.size(), 1);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const size_t i = static_cast<size_t>(y + 1) * g + x + 1;
      covered[i] = mask.get(x, y);
      uncovered[i] = !covered[i];
    }
  std::vector<double> to_covered, to_uncovered;
  squared_distance_2d(covered, g, to_covered);
  squared_distance_2d(uncovered, g, to_uncovered);
  f.signed_distance.resize(static_cast<size_t>(n) * n);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const size_t i = static_cast<size_t>(y + 1) * g + x + 1;
      f.signed_distance[static_cast<size_t>(y) * n + x] =
          covered[i] ? static_cast<float>(0.5 - std::sqrt(to_uncovered[i]))
                     : static_cast<float>(std::sqrt(std::min(to_covered[i], 4.0 * g * g)) - 0.5);
    }
  static const int kDx[4] = {1, -1, 0, 0}, kDy[4] = {0, 0, 1, -1};
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      if (!mask.get(x, y)) continue;
      for (int k = 0; k < 4; ++k) {
        const int xn = x + kDx[k], yn = y + kDy[k];
        if (xn >= 0 && yn >= 0 && xn < n && yn < n && mask.get(xn, yn)) continue;
        f.edge_points.emplace_back(x + 0.5 + 0.5 * kDx[k], y + 0.5 + 0.5 * kDy[k]);
      }
    }
  return f;
}

double outline_distance_at(const OutlineField& f, const Vec2& p) {
  const int n = f.size;
  if (n == 0) return 0.0;
  // Bilinear between pixel centres, clamped to the window; beyond it the
  // distance grows by the excess.
  const double u = p.x() - 0.5, v = p.y() - 0.5;
  const double uc = std::clamp(u, 0.0, n - 1.0), vc = std::clamp(v, 0.0, n - 1.0);
  const int x0 = std::min(static_cast<int>(uc), n - 2 < 0 ? 0 : n - 2), y0 = std::min(static_cast<int>(vc), n - 2 < 0 ? 0 : n - 2);
  const int x1 = std::min(x0 + 1, n - 1), y1 = std::min(y0 + 1, n - 1);
  const double ax = uc - x0, ay = vc - y0;
  auto at = [&](int x, int y) { return static_cast<double>(f.signed_distance[static_cast<size_t>(y) * n + x]); };
  const double s = (1 - ay) * ((1 - ax) * at(x0, y0) + ax * at(x1, y0)) + ay * ((1 - ax) * at(x0, y1) + ax * at(x1, y1));
  return std::fabs(s) + std::hypot(u - uc, v - vc);
}

void mesh_outline_points(const std::vector<Vec3>& positions, const std::vector<Tri>& triangles,
                         const std::vector<Edge>& edges, const ViewWindow& window,
                         const std::vector<ClipPlane>& clips,
                         const std::array<SilhouetteMask, kSilhouetteViews>& masks,
                         std::array<std::vector<Vec2>, kSilhouetteViews>& out) {
  const int n = window.resolution;
  const int nv = static_cast<int>(positions.size());
  // The world direction each view looks from (only the sign matters).
  const int view_axis[kSilhouetteViews] = {2, 0, 1};
  std::vector<unsigned char> facing(triangles.size());  // bit v: faces view v
  for (size_t t = 0; t < triangles.size(); ++t) {
    const Tri& tri = triangles[t];
    const Vec3 normal = (positions[tri[1]] - positions[tri[0]]).cross(positions[tri[2]] - positions[tri[0]]);
    unsigned char bits = 0;
    for (int v = 0; v < kSilhouetteViews; ++v)
      if (normal[view_axis[v]] > 0) bits |= 1u << v;
    facing[t] = bits;
  }
  auto kept = [&](const Vec3& p, int skip) {
    for (int c = 0; c < static_cast<int>(clips.size()); ++c)
      if (c != skip && !clips[c].keeps(p)) return false;
    return true;
  };
  // Next to the mask's outline: the point's pixel differs from one of its
  // 8 neighbours (outside the window counts as uncovered, and points
  // outside the window are kept).
  auto on_outline = [&](int v, const Vec2& q) {
    const int x = static_cast<int>(std::floor(q.x())), y = static_cast<int>(std::floor(q.y()));
    if (x < 0 || y < 0 || x >= n || y >= n) return true;
    auto get = [&](int xx, int yy) { return xx >= 0 && yy >= 0 && xx < n && yy < n && masks[v].get(xx, yy); };
    const bool centre = get(x, y);
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx)
        if (get(x + dx, y + dy) != centre) return true;
    return false;
  };
  std::vector<unsigned char> added(static_cast<size_t>(nv), 0);
  for (int v = 0; v < kSilhouetteViews; ++v) out[v].clear();
  auto add_vertex = [&](int i, int v) {
    if (added[i] & (1u << v)) return;
    added[i] |= 1u << v;
    if (!kept(positions[i], -1)) return;
    const Vec2 q = window.project(positions[i], static_cast<SilhouetteView>(v));
    if (on_outline(v, q)) out[v].push_back(q);
  };
  for (const Edge& e : edges) {
    for (int v = 0; v < kSilhouetteViews; ++v) {
      const bool contour = e.boundary() || ((facing[e.f0] ^ facing[e.f1]) & (1u << v));
      if (!contour) continue;
      add_vertex(e.v0, v);
      add_vertex(e.v1, v);
    }
    // Where the edge crosses a clip plane: the cut's outline.
    const Vec3& pa = positions[e.v0];
    const Vec3& pb = positions[e.v1];
    for (int c = 0; c < static_cast<int>(clips.size()); ++c) {
      const double da = clips[c].normal.dot(pa - clips[c].point), db = clips[c].normal.dot(pb - clips[c].point);
      if ((da >= 0) == (db >= 0)) continue;
      const Vec3 x = pa + (da / (da - db)) * (pb - pa);
      if (!kept(x, c)) continue;
      for (int v = 0; v < kSilhouetteViews; ++v) {
        const Vec2 q = window.project(x, static_cast<SilhouetteView>(v));
        if (on_outline(v, q)) out[v].push_back(q);
      }
    }
  }
}

double outline_chamfer(const OutlineField& f, const std::vector<Vec2>& points) {
  const double cap = f.cap_px;
  const double edge_count = static_cast<double>(f.edge_points.size());
  if (points.empty()) return 2.0 * cap * edge_count;
  // Forward: the outline points' distance to the field's outline.
  double forward = 0.0;
  for (const Vec2& p : points) forward += outline_distance_at(f, p);
  forward *= edge_count / static_cast<double>(points.size());
  // Reverse: each edge point to the nearest outline point, capped; the
  // points are bucketed in cells of cap_px (clamped to the window), so the
  // 3 x 3 cells around an edge point hold every point within the cap.
  const int cells = std::max(1, static_cast<int>(std::ceil(f.size / cap)));
  auto cell_of = [&](double c) { return std::clamp(static_cast<int>(std::floor(c / cap)), 0, cells - 1); };
  std::vector<int> start(static_cast<size_t>(cells) * cells + 1, 0), order(points.size());
  for (const Vec2& p : points) ++start[static_cast<size_t>(cell_of(p.y())) * cells + cell_of(p.x()) + 1];
  for (size_t i = 1; i < start.size(); ++i) start[i] += start[i - 1];
  std::vector<int> fill(start.begin(), start.end() - 1);
  for (size_t i = 0; i < points.size(); ++i)
    order[fill[static_cast<size_t>(cell_of(points[i].y())) * cells + cell_of(points[i].x())]++] = static_cast<int>(i);
  double reverse = 0.0;
  for (const Vec2& e : f.edge_points) {
    const int cx = cell_of(e.x()), cy = cell_of(e.y());
    double best = cap * cap;
    for (int y = std::max(0, cy - 1); y <= std::min(cells - 1, cy + 1); ++y)
      for (int x = std::max(0, cx - 1); x <= std::min(cells - 1, cx + 1); ++x) {
        const size_t c = static_cast<size_t>(y) * cells + x;
        for (int k = start[c]; k < start[c + 1]; ++k) best = std::min(best, (points[order[k]] - e).squaredNorm());
      }
    reverse += std::sqrt(best);
  }
  return forward + reverse;
}

}  // namespace lk
