// Resampling the texture mesh from the photographs (tarini2002 Sec. 3.2).
// Each triangle of the chart falls in one of the paper's three cases:
//   1. its three vertices have at least one common valid photo ("white"):
//      every texel is coloured from all common photos, weighted by
//      <N, V_i> with N the barycentric interpolation of the vertex normals
//      and V_i the unit direction from the texel's surface point to camera i;
//   2. every vertex is bound but there is no common photo ("light grey"):
//      each vertex gets its own <N(v), V_i>-weighted colour over its valid
//      photos and the texels interpolate these three colours;
//   3. some vertex is unbound ("dark grey"): as case 2 once hole filling
//      (hole_fill.h) has given every vertex a colour.
// Photo lookups are bilinear, in linear light (color.h): the four pixels are
// decoded from sRGB before they are interpolated, so the photos stay 8-bit in
// memory (five 3000x2000 photos as floats would take 360 MB of wasm heap).
//
// Regions (for the multiresolution spline's masks and for seam measurement):
// a case-1 triangle belongs to its common photo with the largest summed
// <N(v), V_i> over its corners (the corners' main photo when they share one);
// case-2/3 triangles belong to no photo (kRegionFilled).
//
// Shapes: mesh #V / #F; photos #P (8-bit sRGB gray/RGB/RGBA, same order as
// the cameras of the binding); texture width * height * 3 floats, linear.
#pragma once
#include "calib/camera.h"
#include "common/status.h"
#include "image/image.h"
#include "mesh/tri_mesh.h"
#include "texture/binding.h"
#include "texture/chart_raster.h"

#include <vector>

namespace lk {

constexpr int kRegionBackground = -1;  // texel outside the chart
constexpr int kRegionFilled = -2;      // coloured by interpolation (cases 2 and 3)
constexpr int kRegionBlended = -3;     // fine detail blended from two or more photos (texture.h source)

enum class TriangleCase : signed char { CommonPhoto = 1, AllBound = 2, SomeUnbound = 3 };

// A photo with its calibrated camera (camera.width/height == image size).
struct TexturePhoto {
  Image image;    // 8-bit sRGB, 1 (gray), 3 (RGB) or 4 (RGBA, alpha ignored) channels
  Camera camera;
};

// Bilinear lookup at pixel position (u, v) (pixel centres at integer + 0.5,
// as Camera::project's top-left-corner origin implies), in linear light.
// Positions are clamped to the image. rgb gets 3 floats.
void sample_bilinear(const Image& image, double u, double v, float* rgb);

// Classification of every triangle and its region (see above). #F each.
void classify_triangles(const TriMesh& mesh, const VertexBinding& binding,
                        std::vector<TriangleCase>& cases, std::vector<int>& region);

// Per-vertex colour (linear RGB) from the vertex's valid photos, weighted by
// <N(v), V_i> (the paper's case 2). colored[v] = 1 for bound vertices; an
// unbound vertex gets (0,0,0) and colored 0. #V each.
void bound_vertex_colors(const TriMesh& mesh, const std::vector<Vec3>& normals,
                         const VertexBinding& binding, const std::vector<TexturePhoto>& photos,
                         std::vector<Vec3>& colors, std::vector<char>& colored);

struct ResampleStats {
  long texels_case[3] = {0, 0, 0};    // texels coloured in cases 1, 2, 3
  int triangles_case[3] = {0, 0, 0};  // triangles in cases 1, 2, 3
  std::vector<long> texels_region;    // #P: texels of case-1 triangles in each photo's region
};

// The blended texture (every chart texel coloured): case 1 from the photos,
// cases 2 and 3 by barycentric interpolation of vertex_colors (which hole
// filling must have completed: every vertex used by a case-2/3 triangle
// needs a colour). Background texels are left at 0. region_map (optional,
// width * height) gets each texel's region: photo index, kRegionFilled or
// kRegionBackground. Fails with InvalidInput on inconsistent sizes.
Status resample_texture(const TriMesh& mesh, const std::vector<Vec3>& normals,
                        const std::vector<Vec2>& uv, const VertexBinding& binding,
                        const std::vector<TexturePhoto>& photos, const ChartRaster& raster,
                        const std::vector<Vec3>& vertex_colors, ImageF& texture,
                        ResampleStats& stats, std::vector<int>* region_map = nullptr);

// The texture "as if coloured only from photo `photo`": the texels of every
// triangle whose three corners are all valid for that photo are overwritten
// with that photo's colour alone; every other texel keeps the value already
// in `texture`. Returns the number of texels written; written (optional,
// width * height) gets 1 on them. These are the images the multiresolution
// spline blends under each photo's mask.
long resample_single_photo(const TriMesh& mesh, const std::vector<Vec2>& uv,
                           const VertexBinding& binding, const std::vector<TexturePhoto>& photos,
                           int photo, const ChartRaster& raster, ImageF& texture,
                           std::vector<char>* written = nullptr);

// A seam-free variant of the blended texture (ours, not the paper's), used
// as the spline's complement image. Each corner v_k of a texel's triangle
// colours the texel's surface point P with its own weights,
//   C_k(P) = sum_i <N(v_k), V_i> Color_i(P) / sum_i <N(v_k), V_i> over v_k's
// valid photos (an unbound corner gives its hole-filled colour), and the
// texel gets sum_k b_k C_k(P). Photo weights thus vary continuously over the
// surface (they are shared along edges), so gain differences between photos
// give no jumps at triangle edges, while P keeps the photos' full detail.
// The paper's blended texture switches weights per triangle, and the gap
// band the shrunk masks leave between regions would carry those jumps
// through the spline's finest levels. Same inputs and failures as
// resample_texture.
Status resample_feathered(const TriMesh& mesh, const std::vector<Vec2>& uv, const VertexBinding& binding,
                          const std::vector<TexturePhoto>& photos, const ChartRaster& raster,
                          const std::vector<Vec3>& vertex_colors, ImageF& texture);

}  // namespace lk
