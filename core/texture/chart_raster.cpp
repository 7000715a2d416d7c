#include "texture/chart_raster.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <unordered_map>

namespace lk {
namespace {

// Texel-space coordinates in fixed point: 1/256 texel. Edge functions are
// then exact integers, so two triangles sharing an edge agree on which side
// every texel centre lies: no texel is skipped or claimed twice.
constexpr std::int64_t kSub = 256;

struct FixedPoint {
  std::int64_t x, y;
};

FixedPoint to_fixed(const Vec2& uv, int width, int height) {
  const double tx = uv.x() * width - 0.5, ty = (1.0 - uv.y()) * height - 0.5;
  return {static_cast<std::int64_t>(std::llround(tx * kSub)), static_cast<std::int64_t>(std::llround(ty * kSub))};
}

// Twice the signed area of (a, b, p).
inline std::int64_t edge(const FixedPoint& a, const FixedPoint& b, std::int64_t px, std::int64_t py) {
  return (b.x - a.x) * (py - a.y) - (b.y - a.y) * (px - a.x);
}

// Top-left rule for a triangle of positive orientation in a y-down grid:
// a texel centre on an edge belongs to the triangle when the edge is a
// "top" edge (horizontal, interior below) or a "left" edge. With positive
// area (counter-clockwise in these coordinates), edge a->b is top when
// dy == 0 and dx < 0, left when dy > 0.
inline bool top_left(const FixedPoint& a, const FixedPoint& b) {
  const std::int64_t dx = b.x - a.x, dy = b.y - a.y;
  return (dy == 0 && dx < 0) || dy > 0;
}

// Squared distance from p to segment ab.
double segment_distance2(const Vec2& p, const Vec2& a, const Vec2& b) {
  const Vec2 ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (a + t * ab - p).squaredNorm();
}

}  // namespace

bool uv_barycentric(const Vec2& p, const Vec2& a, const Vec2& b, const Vec2& c, Vec3& weights) {
  const Vec2 v0 = b - a, v1 = c - a, v2 = p - a;
  const double det = v0.x() * v1.y() - v1.x() * v0.y();
  if (!(std::abs(det) > 1e-300)) return false;
  const double wb = (v2.x() * v1.y() - v1.x() * v2.y()) / det;
  const double wc = (v0.x() * v2.y() - v2.x() * v0.y()) / det;
  weights = Vec3(1.0 - wb - wc, wb, wc);
  return true;
}

Status rasterize_chart(const std::vector<Vec2>& uv, const std::vector<Tri>& triangles, int width,
                       int height, ChartRaster& raster, double conservative_texels) {
  if (width < 1 || height < 1 || width > 16384 || height > 16384)
    return Status::error(ErrorCode::InvalidInput, "texture size " + std::to_string(width) + "x" +
                                                      std::to_string(height) + " is outside 1..16384");
  const int nv = static_cast<int>(uv.size());
  for (const Vec2& t : uv)
    if (!std::isfinite(t.x()) || !std::isfinite(t.y()))
      return Status::error(ErrorCode::InvalidInput, "uv coordinates contain NaN or infinity");
  for (const Tri& t : triangles)
    for (int k = 0; k < 3; ++k)
      if (t[k] < 0 || t[k] >= nv)
        return Status::error(ErrorCode::InvalidInput, "a triangle refers to vertex " + std::to_string(t[k]) +
                                                          " but there are " + std::to_string(nv) + " uvs");
  raster.width = width;
  raster.height = height;
  raster.triangle.assign(static_cast<size_t>(width) * height, -1);
  raster.covered = 0;

  std::vector<FixedPoint> fixed(uv.size());
  for (int v = 0; v < nv; ++v) fixed[v] = to_fixed(uv[v], width, height);

  for (int f = 0; f < static_cast<int>(triangles.size()); ++f) {
    FixedPoint a = fixed[triangles[f][0]], b = fixed[triangles[f][1]], c = fixed[triangles[f][2]];
    std::int64_t area = edge(a, b, c.x, c.y);
    if (area == 0) continue;
    if (area < 0) {
      // Flipped in the y-down grid (uv's v axis points up): reorder.
      std::swap(b, c);
      area = -area;
    }
    const std::int64_t min_x = std::min({a.x, b.x, c.x}), max_x = std::max({a.x, b.x, c.x});
    const std::int64_t min_y = std::min({a.y, b.y, c.y}), max_y = std::max({a.y, b.y, c.y});
    // Texel centres are at integer texel coordinates: ceil/floor in texels.
    const int x0 = static_cast<int>(std::max<std::int64_t>(0, (min_x + kSub - 1) >> 8));
    const int x1 = static_cast<int>(std::min<std::int64_t>(width - 1, max_x >> 8));
    const int y0 = static_cast<int>(std::max<std::int64_t>(0, (min_y + kSub - 1) >> 8));
    const int y1 = static_cast<int>(std::min<std::int64_t>(height - 1, max_y >> 8));
    const bool tl_ab = top_left(a, b), tl_bc = top_left(b, c), tl_ca = top_left(c, a);
    for (int y = y0; y <= y1; ++y) {
      const std::int64_t py = static_cast<std::int64_t>(y) * kSub;
      int* row = &raster.triangle[static_cast<size_t>(y) * width];
      for (int x = x0; x <= x1; ++x) {
        const std::int64_t px = static_cast<std::int64_t>(x) * kSub;
        const std::int64_t e0 = edge(b, c, px, py), e1 = edge(c, a, px, py), e2 = edge(a, b, px, py);
        // Orientation: positive area means each edge function is >= 0 inside.
        if (e0 < 0 || e1 < 0 || e2 < 0) continue;
        if ((e0 == 0 && !tl_bc) || (e1 == 0 && !tl_ca) || (e2 == 0 && !tl_ab)) continue;
        if (row[x] < 0) ++raster.covered;
        row[x] = f;
      }
    }
  }

  if (conservative_texels <= 0) return Status::success();
  // Border texels: only triangles with an edge on the chart boundary can
  // border empty texels (the chart is one disk), so only those are visited.
  std::unordered_map<std::uint64_t, int> edge_count;
  edge_count.reserve(triangles.size() * 3);
  auto key = [](int i, int j) {
    return (static_cast<std::uint64_t>(std::min(i, j)) << 32) | static_cast<std::uint32_t>(std::max(i, j));
  };
  for (const Tri& t : triangles)
    for (int k = 0; k < 3; ++k) ++edge_count[key(t[k], t[(k + 1) % 3])];
  std::vector<float> best;  // per texel: squared distance of its nearest triangle so far
  const double limit2 = conservative_texels * conservative_texels;
  const int reach = static_cast<int>(std::ceil(conservative_texels));
  for (int f = 0; f < static_cast<int>(triangles.size()); ++f) {
    const Tri& t = triangles[f];
    bool on_border = false;
    for (int k = 0; k < 3; ++k) on_border |= edge_count[key(t[k], t[(k + 1) % 3])] == 1;
    if (!on_border) continue;
    Vec2 p[3];
    for (int k = 0; k < 3; ++k) p[k] = Vec2(uv[t[k]].x() * width - 0.5, (1.0 - uv[t[k]].y()) * height - 0.5);
    const int x0 = std::max(0, static_cast<int>(std::floor(std::min({p[0].x(), p[1].x(), p[2].x()}))) - reach);
    const int x1 = std::min(width - 1, static_cast<int>(std::ceil(std::max({p[0].x(), p[1].x(), p[2].x()}))) + reach);
    const int y0 = std::max(0, static_cast<int>(std::floor(std::min({p[0].y(), p[1].y(), p[2].y()}))) - reach);
    const int y1 = std::min(height - 1, static_cast<int>(std::ceil(std::max({p[0].y(), p[1].y(), p[2].y()}))) + reach);
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        const size_t i = static_cast<size_t>(y) * width + x;
        if (raster.triangle[i] >= 0 && best.empty()) continue;
        if (raster.triangle[i] >= 0 && (best[i] < 0)) continue;  // covered by rasterization proper
        const Vec2 q(x, y);
        const double d2 = std::min({segment_distance2(q, p[0], p[1]), segment_distance2(q, p[1], p[2]),
                                    segment_distance2(q, p[2], p[0])});
        if (d2 > limit2) continue;
        if (best.empty()) {
          // Lazily: -1 marks texels the exact pass covered.
          best.assign(raster.triangle.size(), 1e30f);
          for (size_t j = 0; j < best.size(); ++j)
            if (raster.triangle[j] >= 0) best[j] = -1.f;
        }
        if (best[i] < 0 || d2 >= best[i]) continue;
        if (raster.triangle[i] < 0) ++raster.covered;
        best[i] = static_cast<float>(d2);
        raster.triangle[i] = f;
      }
    }
  }
  return Status::success();
}

}  // namespace lk
