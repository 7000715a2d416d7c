// Rasterization of a UV chart into a texture grid: which triangle covers
// each texel centre (tarini2002 Sec. 3.2: "we rasterize each triangle in
// texture space"). Shared by resampling, masks, hole filling and dilation,
// so each of them needs no geometry of its own.
//
// Conventions: texel (x, y) of a width x height texture, row 0 on top, has
// its centre at uv = ((x + 0.5) / width, 1 - (y + 0.5) / height): uv (0, 0)
// is the image's lower-left corner, as in OBJ files and in our renderer.
//
// Shapes: uv #V by 2 (per vertex), triangles #F by 3; triangle map
// width * height (row-major), -1 = outside the chart.
#pragma once
#include "common/status.h"
#include "common/types.h"

#include <vector>

namespace lk {

struct ChartRaster {
  int width = 0, height = 0;
  std::vector<int> triangle;  // width * height: covering triangle, -1 = background
  long covered = 0;           // texels with a triangle

  bool inside(int x, int y) const { return triangle[static_cast<size_t>(y) * width + x] >= 0; }
};

// Texel-centre uv.
inline Vec2 texel_uv(int x, int y, int width, int height) {
  return Vec2((x + 0.5) / width, 1.0 - (y + 0.5) / height);
}

// Barycentric weights of point p in the uv triangle (a, b, c). Returns false
// for a degenerate (zero-area) triangle.
bool uv_barycentric(const Vec2& p, const Vec2& a, const Vec2& b, const Vec2& c, Vec3& weights);

// Fills raster with the triangle covering each texel centre (top-left fill
// rule, so a texel on a shared edge belongs to exactly one triangle). Texels
// the chart misses by less than `conservative_texels` of a texel (thin slivers
// along the chart border) are given to the nearest triangle, so the border
// texels a bilinear lookup touches are coloured too. Fails with InvalidInput
// on a size outside [1, 16384], uv count != #V, NaN uvs or out-of-range indices.
Status rasterize_chart(const std::vector<Vec2>& uv, const std::vector<Tri>& triangles, int width,
                       int height, ChartRaster& raster, double conservative_texels = 0.75);

}  // namespace lk
