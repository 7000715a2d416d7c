// First commit: the public API compiles and links; every step still reports
// NotImplemented-style errors (ErrorCode::Unsupported) until implemented.
#include "texture/texture.h"
#include "texture/color.h"
#include "texture/dilate.h"
#include "texture/pyramid.h"

namespace lk {
namespace {
Status not_yet(const char* what) {
  return Status::error(ErrorCode::Unsupported, std::string(what) + ": not implemented yet");
}
}  // namespace

float srgb8_to_linear(std::uint8_t) { return 0.f; }
std::uint8_t linear_to_srgb8(float) { return 0; }
ImageF srgb_to_linear(const Image&) { return {}; }
Image linear_to_srgb(const ImageF&) { return {}; }

Status bind_vertices(const TriMesh&, const std::vector<Vec3>&, const MeshBvh&, const std::vector<Camera>&,
                     const BindingOptions&, VertexBinding&) { return not_yet("bind_vertices"); }
bool uv_barycentric(const Vec2&, const Vec2&, const Vec2&, const Vec2&, Vec3&) { return false; }
Status rasterize_chart(const std::vector<Vec2>&, const std::vector<Tri>&, int, int, ChartRaster&, double) {
  return not_yet("rasterize_chart");
}
void sample_bilinear(const Image&, double, double, float* rgb) { rgb[0] = rgb[1] = rgb[2] = 0.f; }
void classify_triangles(const TriMesh&, const VertexBinding&, std::vector<TriangleCase>&, std::vector<int>&) {}
void bound_vertex_colors(const TriMesh&, const std::vector<Vec3>&, const VertexBinding&,
                         const std::vector<TexturePhoto>&, std::vector<Vec3>&, std::vector<char>&) {}
Status resample_texture(const TriMesh&, const std::vector<Vec3>&, const std::vector<Vec2>&, const VertexBinding&,
                        const std::vector<TexturePhoto>&, const ChartRaster&, const std::vector<Vec3>&, ImageF&,
                        ResampleStats&, std::vector<int>*) { return not_yet("resample_texture"); }
long resample_single_photo(const TriMesh&, const std::vector<Vec2>&, const VertexBinding&,
                           const std::vector<TexturePhoto>&, int, const ChartRaster&, ImageF&) { return 0; }
Status fill_vertex_colors(const MeshTopology&, std::vector<Vec3>&, std::vector<char>&, const HoleFillOptions&,
                          HoleFillReport&, std::vector<int>*) { return not_yet("fill_vertex_colors"); }
void pyramid_reduce(const ImageF&, ImageF&) {}
void pyramid_expand(const ImageF&, int, int, ImageF&) {}
int max_pyramid_levels(int, int) { return 1; }
void gaussian_pyramid(const ImageF&, int, std::vector<ImageF>&) {}
void laplacian_pyramid(const ImageF&, int, std::vector<ImageF>&) {}
void collapse_laplacian(const std::vector<ImageF>&, ImageF&) {}
Status SplineBlender::begin(int, int, int, int) { return not_yet("SplineBlender"); }
Status SplineBlender::add(const ImageF&, const ImageF&) { return not_yet("SplineBlender"); }
Status SplineBlender::finish(ImageF&) { return not_yet("SplineBlender"); }
Status multiresolution_spline(const std::vector<ImageF>&, const std::vector<ImageF>&, int, ImageF&) {
  return not_yet("multiresolution_spline");
}
long dilate_rings(ImageF&, std::vector<char>&, int) { return 0; }
long push_pull_fill(ImageF&, const std::vector<char>&) { return 0; }
Status calibrate_photos(const std::vector<std::vector<Correspondence>>&, const std::vector<std::array<int, 2>>&,
                        const CalibOptions&, std::vector<CalibResult>&) { return not_yet("calibrate_photos"); }
Status texture_head(const TriMesh&, const std::vector<TexturePhoto>&, const TextureOptions&, TexturedHead&,
                    const ProgressFn&) { return not_yet("texture_head"); }

}  // namespace lk
