// Resampling (tarini2002 Sec. 3.2) against ground truth: photos rendered
// from a known 3-D colour field by known cameras must give back the field's
// colours in every texel, and chart rasterization must cover the chart once.
#include "fixtures.h"
#include "mesh/geometry.h"
#include "raycast/bvh.h"
#include "texture/chart_raster.h"
#include "texture/color.h"
#include "texture/resample.h"

#include <catch2/catch.hpp>

using namespace lk;
using namespace lk::test;

TEST_CASE("chart rasterization covers each texel of a chart exactly once") {
  // Two triangles sharing the diagonal, uv over [0.1, 0.9]^2: the covered
  // texel count must equal the square's texel count, with no double cover.
  std::vector<Vec2> uv = {{0.1, 0.1}, {0.9, 0.1}, {0.9, 0.9}, {0.1, 0.9}};
  std::vector<Tri> tris = {{0, 1, 2}, {0, 2, 3}};
  ChartRaster r;
  REQUIRE(rasterize_chart(uv, tris, 100, 100, r, 0.0).ok());
  // Texel centres (x + 0.5) / 100 in [0.1, 0.9): x = 10..89 (80 per side);
  // the closed square's top/right edges fall between centres.
  CHECK(r.covered == 80 * 80);
  CHECK(r.inside(10, 10));
  CHECK_FALSE(r.inside(9, 50));
  CHECK_FALSE(r.inside(90, 50));
  // Both triangles are used, the diagonal split by the top-left rule.
  long t0 = 0, t1 = 0;
  for (int t : r.triangle) t0 += t == 0, t1 += t == 1;
  CHECK(t0 + t1 == 80 * 80);
  CHECK(std::abs(t0 - t1) <= 80);
  // Conservative: a border ring within 0.75 texel is added.
  ChartRaster c;
  REQUIRE(rasterize_chart(uv, tris, 100, 100, c, 0.75).ok());
  CHECK(c.covered > r.covered);
  CHECK(c.covered <= 82 * 82);
  // Bad inputs.
  CHECK(rasterize_chart(uv, tris, 0, 100, r).code == ErrorCode::InvalidInput);
  CHECK(rasterize_chart(uv, {{0, 1, 7}}, 64, 64, r).code == ErrorCode::InvalidInput);
  std::vector<Vec2> nan_uv = uv;
  nan_uv[2].x() = std::nan("");
  CHECK(rasterize_chart(nan_uv, tris, 64, 64, r).code == ErrorCode::InvalidInput);
}

TEST_CASE("sRGB decoding and encoding round-trip every 8-bit value") {
  for (int i = 0; i < 256; ++i) CHECK(linear_to_srgb8(srgb8_to_linear(std::uint8_t(i))) == i);
  CHECK(srgb8_to_linear(255) == Approx(1.0f));
  CHECK(srgb8_to_linear(128) == Approx(0.2158605f).epsilon(1e-5));
  CHECK(linear_to_srgb8(-1.f) == 0);
  CHECK(linear_to_srgb8(2.f) == 255);
  CHECK(linear_to_srgb8(std::nanf("")) == 0);
}

TEST_CASE("resampling a plane from two known cameras reproduces the colour field") {
  const TriMesh plane = plane_grid(16, -0.5, 0.5, -0.5, 0.5, 0.0);
  const double scale = 0.12;
  const SurfaceColorFn field = [scale](const Vec3& p, const Vec3&) { return procedural_color_field(p, scale); };
  std::vector<TexturePhoto> photos(2);
  photos[0].camera = look_at_camera(Vec3(0, 0, 3), Vec3::Zero(), Vec3::UnitY(), 900, 640, 480);
  photos[1].camera = look_at_camera(Vec3(1.6, 0.3, 2.5), Vec3::Zero(), Vec3::UnitY(), 900, 640, 480);
  // The photographed surface extends past the textured one, as a head goes
  // on past the chart's neck border: at a surface's own border in a photo,
  // bilinear lookups mix in the background.
  const TriMesh wider = plane_grid(16, -0.7, 0.7, -0.7, 0.7, 0.0);
  for (auto& ph : photos) REQUIRE(render_synthetic_photo(wider, ph.camera, field, Vec3(0, 0, 0), ph.image).ok());

  const std::vector<Vec3> normals = vertex_normals(plane);
  MeshBvh bvh;
  REQUIRE(build_bvh(plane, bvh).ok());
  VertexBinding binding;
  REQUIRE(bind_vertices(plane, normals, bvh, {photos[0].camera, photos[1].camera}, BindingOptions(), binding).ok());
  std::vector<Vec3> vcol;
  std::vector<char> colored;
  bound_vertex_colors(plane, normals, binding, photos, vcol, colored);
  for (char c : colored) REQUIRE(c);  // both cameras see the whole plane

  const int size = 256;
  ChartRaster raster;
  REQUIRE(rasterize_chart(plane.uvs, plane.triangles, size, size, raster).ok());
  ImageF tex;
  ResampleStats stats;
  std::vector<int> region;
  REQUIRE(resample_texture(plane, normals, plane.uvs, binding, photos, raster, vcol, tex, stats, &region).ok());
  CHECK(stats.triangles_case[0] == plane.num_triangles());
  CHECK(stats.texels_case[0] == raster.covered);
  CHECK(stats.texels_region[0] == raster.covered);  // the frontal photo faces every triangle best

  double se = 0;
  long n = 0;
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const int f = raster.triangle[size_t(y) * size + x];
      if (f < 0) continue;
      CHECK(region[size_t(y) * size + x] == 0);
      const Tri& t = plane.triangles[f];
      Vec3 b;
      REQUIRE(uv_barycentric(texel_uv(x, y, size, size), plane.uvs[t[0]], plane.uvs[t[1]], plane.uvs[t[2]], b));
      b = b.cwiseMax(0.0) / b.cwiseMax(0.0).sum();
      const Vec3 p = b[0] * plane.positions[t[0]] + b[1] * plane.positions[t[1]] + b[2] * plane.positions[t[2]];
      const Vec3 want = procedural_color_field(p, scale);
      for (int k = 0; k < 3; ++k) se += std::pow(tex.at(x, y)[k] - want[k], 2);
      n += 3;
    }
  const double psnr = psnr_from_mse(se / n);
  WARN("plane resampling PSNR " << psnr << " dB over " << n / 3 << " texels");
  CHECK(psnr > 35);

  // Single-photo resampling: the slanted photo alone also reproduces it.
  ImageF alone = ImageF::make(size, size, 3, 0.f);
  const long written = resample_single_photo(plane, plane.uvs, binding, photos, 1, raster, alone);
  CHECK(written == raster.covered);
  double se1 = 0;
  for (size_t i = 0; i < tex.pixels.size(); ++i) se1 += std::pow(alone.pixels[i] - tex.pixels[i], 2);
  CHECK(psnr_from_mse(se1 / n) > 33);
}

TEST_CASE("resampling: case 2 and 3 triangles interpolate the vertex colours") {
  // Two photos each seeing one half of a strip: the middle triangles have
  // corners bound to different photos only (case 2).
  const TriMesh plane = plane_grid(8, -0.5, 0.5, -0.5, 0.5, 0.0);
  VertexBinding b;
  b.num_photos = 2;
  const int nv = plane.num_vertices();
  b.valid.assign(nv, 0);
  b.facing.assign(size_t(nv) * 2, 0.f);
  b.main_photo.assign(nv, -1);
  for (int v = 0; v < nv; ++v) {
    const double x = plane.positions[v].x();
    const int photo = x < 0 ? 0 : (x > 0 ? 1 : -1);  // x == 0 column unbound: case 3
    if (photo < 0) continue;
    b.valid[v] = 1u << photo;
    b.facing[size_t(v) * 2 + photo] = 1.f;
    b.main_photo[v] = photo;
  }
  std::vector<TriangleCase> cases;
  std::vector<int> region;
  classify_triangles(plane, b, cases, region);
  int c1 = 0, c3 = 0;
  for (int f = 0; f < plane.num_triangles(); ++f) {
    c1 += cases[f] == TriangleCase::CommonPhoto;
    c3 += cases[f] == TriangleCase::SomeUnbound;
    if (cases[f] != TriangleCase::CommonPhoto) CHECK(region[f] == kRegionFilled);
  }
  CHECK(c3 == 32);  // the two columns of quads touching x = 0
  CHECK(c1 == plane.num_triangles() - 32);
  // Case 2: shift the unbound column to "bound to both sides separately".
  VertexBinding b2 = b;
  for (int v = 0; v < nv; ++v)
    if (b2.valid[v] == 0) {
      b2.valid[v] = (plane.positions[v].y() > 0) ? 1u : 2u;
      b2.main_photo[v] = int(b2.valid[v]) - 1;
    }
  classify_triangles(plane, b2, cases, region);
  int c2 = 0;
  for (auto c : cases) c2 += c == TriangleCase::AllBound;
  CHECK(c2 > 0);
}
