#include "texture/resample.h"

#include "texture/color.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

namespace lk {
namespace {

// Texel -> barycentric map of one chart triangle: b1, b2 are affine in the
// texel coordinates (x, y); b0 = 1 - b1 - b2.
struct TexelToBary {
  double ox = 0, oy = 0;                // corner 0 in texel coordinates
  double m00 = 0, m01 = 0, m10 = 0, m11 = 0;
  bool ok = false;

  Vec3 at(int x, int y) const {
    const double dx = x - ox, dy = y - oy;
    const double b1 = m00 * dx + m01 * dy, b2 = m10 * dx + m11 * dy;
    Vec3 b(1.0 - b1 - b2, b1, b2);
    // Texels given to the triangle by the conservative border pass lie just
    // outside it: use the nearest point's weights instead of extrapolating.
    if (b.minCoeff() < 0) {
      b = b.cwiseMax(0.0);
      const double s = b.sum();
      b = s > 0 ? Vec3(b / s) : Vec3(1.0 / 3, 1.0 / 3, 1.0 / 3);
    }
    return b;
  }
};

std::vector<TexelToBary> texel_maps(const std::vector<Vec2>& uv, const std::vector<Tri>& triangles, int width,
                                    int height) {
  std::vector<TexelToBary> maps(triangles.size());
  for (size_t f = 0; f < triangles.size(); ++f) {
    Vec2 p[3];
    for (int k = 0; k < 3; ++k) {
      const Vec2& t = uv[triangles[f][k]];
      p[k] = Vec2(t.x() * width - 0.5, (1.0 - t.y()) * height - 0.5);
    }
    const Vec2 e1 = p[1] - p[0], e2 = p[2] - p[0];
    const double det = e1.x() * e2.y() - e2.x() * e1.y();
    TexelToBary& m = maps[f];
    m.ox = p[0].x();
    m.oy = p[0].y();
    if (!(std::abs(det) > 1e-18)) continue;
    // Inverse of [e1 e2].
    m.m00 = e2.y() / det;
    m.m01 = -e2.x() / det;
    m.m10 = -e1.y() / det;
    m.m11 = e1.x() / det;
    m.ok = true;
  }
  return maps;
}

// Bilinear lookup with a decoding table at hand (the hot loop's version).
inline void sample_linear(const Image& image, const float* decode, double u, double v, float* rgb) {
  const int w = image.width, h = image.height, c = image.channels;
  double x = u - 0.5, y = v - 0.5;
  x = std::clamp(x, 0.0, static_cast<double>(w - 1));
  y = std::clamp(y, 0.0, static_cast<double>(h - 1));
  const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
  const int x1 = std::min(x0 + 1, w - 1), y1 = std::min(y0 + 1, h - 1);
  const float tx = static_cast<float>(x - x0), ty = static_cast<float>(y - y0);
  const std::uint8_t* a = image.at(x0, y0);
  const std::uint8_t* b = image.at(x1, y0);
  const std::uint8_t* d = image.at(x0, y1);
  const std::uint8_t* e = image.at(x1, y1);
  const float wa = (1 - tx) * (1 - ty), wb = tx * (1 - ty), wd = (1 - tx) * ty, we = tx * ty;
  if (c >= 3) {
    for (int k = 0; k < 3; ++k)
      rgb[k] = wa * decode[a[k]] + wb * decode[b[k]] + wd * decode[d[k]] + we * decode[e[k]];
  } else {
    const float g = wa * decode[a[0]] + wb * decode[b[0]] + wd * decode[d[0]] + we * decode[e[0]];
    rgb[0] = rgb[1] = rgb[2] = g;
  }
}

std::array<float, 256> decode_table() {
  std::array<float, 256> t{};
  for (int i = 0; i < 256; ++i) t[i] = srgb8_to_linear(static_cast<std::uint8_t>(i));
  return t;
}

Status check_inputs(const TriMesh& mesh, const VertexBinding& binding, const std::vector<TexturePhoto>& photos) {
  const size_t nv = mesh.positions.size();
  if (binding.valid.size() != nv || binding.main_photo.size() != nv ||
      binding.num_photos != static_cast<int>(photos.size()) ||
      binding.facing.size() != nv * photos.size())
    return Status::error(ErrorCode::InvalidInput, "resample: the binding does not match the mesh and photos");
  for (size_t i = 0; i < photos.size(); ++i) {
    const Image& im = photos[i].image;
    if (im.empty() || im.channels < 1 || im.channels > 4 ||
        im.pixels.size() != static_cast<size_t>(im.width) * im.height * im.channels)
      return Status::error(ErrorCode::InvalidInput, "resample: photo " + std::to_string(i) + " is empty or inconsistent");
  }
  return Status::success();
}

}  // namespace

void sample_bilinear(const Image& image, double u, double v, float* rgb) {
  static const std::array<float, 256> table = decode_table();
  if (image.empty()) {
    rgb[0] = rgb[1] = rgb[2] = 0.f;
    return;
  }
  sample_linear(image, table.data(), u, v, rgb);
}

void classify_triangles(const TriMesh& mesh, const VertexBinding& binding, std::vector<TriangleCase>& cases,
                        std::vector<int>& region) {
  const int nf = mesh.num_triangles(), np = binding.num_photos;
  cases.assign(nf, TriangleCase::SomeUnbound);
  region.assign(nf, kRegionFilled);
  for (int f = 0; f < nf; ++f) {
    const Tri& t = mesh.triangles[f];
    const std::uint64_t common = binding.valid[t[0]] & binding.valid[t[1]] & binding.valid[t[2]];
    if (common != 0) {
      cases[f] = TriangleCase::CommonPhoto;
      double best = -1;
      for (int i = 0; i < np; ++i) {
        if (!((common >> i) & 1u)) continue;
        double sum = 0;
        for (int k = 0; k < 3; ++k) sum += binding.facing[static_cast<size_t>(t[k]) * np + i];
        if (sum > best) {
          best = sum;
          region[f] = i;
        }
      }
    } else if (binding.bound(t[0]) && binding.bound(t[1]) && binding.bound(t[2])) {
      cases[f] = TriangleCase::AllBound;
    }
  }
}

void bound_vertex_colors(const TriMesh& mesh, const std::vector<Vec3>& /*normals*/, const VertexBinding& binding,
                         const std::vector<TexturePhoto>& photos, std::vector<Vec3>& colors,
                         std::vector<char>& colored) {
  // The weights <N(v), V_i> were computed by the binding from these normals.
  const int nv = mesh.num_vertices(), np = binding.num_photos;
  colors.assign(nv, Vec3::Zero());
  colored.assign(nv, 0);
  const std::array<float, 256> table = decode_table();
  for (int v = 0; v < nv; ++v) {
    if (!binding.bound(v)) continue;
    Vec3 sum = Vec3::Zero();
    double weight = 0;
    for (int i = 0; i < np && i < static_cast<int>(photos.size()); ++i) {
      if (!binding.is_valid(v, i)) continue;
      Vec2 px;
      if (!photos[i].camera.project(mesh.positions[v], px)) continue;
      float rgb[3];
      sample_linear(photos[i].image, table.data(), px.x(), px.y(), rgb);
      const double w = binding.facing[static_cast<size_t>(v) * np + i];
      sum += w * Vec3(rgb[0], rgb[1], rgb[2]);
      weight += w;
    }
    if (weight > 0) {
      colors[v] = sum / weight;
      colored[v] = 1;
    }
  }
}

Status resample_texture(const TriMesh& mesh, const std::vector<Vec3>& normals, const std::vector<Vec2>& uv,
                        const VertexBinding& binding, const std::vector<TexturePhoto>& photos,
                        const ChartRaster& raster, const std::vector<Vec3>& vertex_colors, ImageF& texture,
                        ResampleStats& stats, std::vector<int>* region_map) {
  Status s = check_inputs(mesh, binding, photos);
  if (!s) return s;
  const size_t nv = mesh.positions.size();
  if (normals.size() != nv || uv.size() != nv || vertex_colors.size() != nv)
    return Status::error(ErrorCode::InvalidInput, "resample: normals, uvs and vertex colours need one entry per vertex");
  const int w = raster.width, h = raster.height, np = binding.num_photos;
  if (w <= 0 || h <= 0 || raster.triangle.size() != static_cast<size_t>(w) * h)
    return Status::error(ErrorCode::InvalidInput, "resample: empty or inconsistent chart raster");

  std::vector<TriangleCase> cases;
  std::vector<int> region;
  classify_triangles(mesh, binding, cases, region);
  const std::vector<TexelToBary> maps = texel_maps(uv, mesh.triangles, w, h);
  const std::array<float, 256> table = decode_table();
  std::vector<Vec3> eyes(np);
  for (int i = 0; i < np; ++i) eyes[i] = photos[i].camera.center();

  stats = ResampleStats();
  stats.texels_region.assign(np, 0);
  for (int f = 0; f < mesh.num_triangles(); ++f) ++stats.triangles_case[static_cast<int>(cases[f]) - 1];
  texture = ImageF::make(w, h, 3, 0.f);
  if (region_map) region_map->assign(static_cast<size_t>(w) * h, kRegionBackground);

  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const size_t idx = static_cast<size_t>(y) * w + x;
      const int f = raster.triangle[idx];
      if (f < 0) continue;
      const Tri& t = mesh.triangles[f];
      const Vec3 b = maps[f].ok ? maps[f].at(x, y) : Vec3(1.0 / 3, 1.0 / 3, 1.0 / 3);
      float* out = texture.at(x, y);
      bool done = false;
      if (cases[f] == TriangleCase::CommonPhoto) {
        const std::uint64_t common = binding.valid[t[0]] & binding.valid[t[1]] & binding.valid[t[2]];
        const Vec3 p = b[0] * mesh.positions[t[0]] + b[1] * mesh.positions[t[1]] + b[2] * mesh.positions[t[2]];
        Vec3 n = b[0] * normals[t[0]] + b[1] * normals[t[1]] + b[2] * normals[t[2]];
        const double len = n.norm();
        if (len > 0) n /= len;
        float sum[3] = {0, 0, 0};
        double weight = 0;
        for (int i = 0; i < np; ++i) {
          if (!((common >> i) & 1u)) continue;
          const Vec3 to_eye = eyes[i] - p;
          const double wi = n.dot(to_eye) / to_eye.norm();
          if (!(wi > 0)) continue;  // the interpolated normal can turn away inside a valid triangle
          Vec2 px;
          if (!photos[i].camera.project(p, px)) continue;
          float rgb[3];
          sample_linear(photos[i].image, table.data(), px.x(), px.y(), rgb);
          for (int k = 0; k < 3; ++k) sum[k] += static_cast<float>(wi) * rgb[k];
          weight += wi;
        }
        if (weight > 0) {
          for (int k = 0; k < 3; ++k) out[k] = static_cast<float>(sum[k] / weight);
          done = true;
          ++stats.texels_case[0];
          ++stats.texels_region[region[f]];
        }
      }
      if (!done) {
        const Vec3 c = b[0] * vertex_colors[t[0]] + b[1] * vertex_colors[t[1]] + b[2] * vertex_colors[t[2]];
        for (int k = 0; k < 3; ++k) out[k] = static_cast<float>(c[k]);
        // A case-1 triangle whose photos all turned away at this texel is
        // coloured like case 2 and counted there.
        const int counted_case = cases[f] == TriangleCase::CommonPhoto ? 2 : static_cast<int>(cases[f]);
        ++stats.texels_case[counted_case - 1];
      }
      if (region_map) (*region_map)[idx] = done ? region[f] : kRegionFilled;
    }
  }
  return Status::success();
}

long resample_single_photo(const TriMesh& mesh, const std::vector<Vec2>& uv, const VertexBinding& binding,
                           const std::vector<TexturePhoto>& photos, int photo, const ChartRaster& raster,
                           ImageF& texture, std::vector<char>* written_mask) {
  if (!check_inputs(mesh, binding, photos) || photo < 0 || photo >= binding.num_photos ||
      uv.size() != mesh.positions.size() || texture.width != raster.width || texture.height != raster.height ||
      texture.channels != 3 || raster.triangle.size() != texture.pixels.size() / 3)
    return 0;
  const int w = raster.width, h = raster.height, nf = mesh.num_triangles();
  std::vector<char> seen(nf, 0);
  for (int f = 0; f < nf; ++f) {
    const Tri& t = mesh.triangles[f];
    seen[f] = binding.is_valid(t[0], photo) && binding.is_valid(t[1], photo) && binding.is_valid(t[2], photo);
  }
  const std::vector<TexelToBary> maps = texel_maps(uv, mesh.triangles, w, h);
  const std::array<float, 256> table = decode_table();
  const TexturePhoto& ph = photos[photo];
  long written = 0;
  if (written_mask) written_mask->assign(raster.triangle.size(), 0);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const int f = raster.triangle[static_cast<size_t>(y) * w + x];
      if (f < 0 || !seen[f]) continue;
      const Tri& t = mesh.triangles[f];
      const Vec3 b = maps[f].ok ? maps[f].at(x, y) : Vec3(1.0 / 3, 1.0 / 3, 1.0 / 3);
      const Vec3 p = b[0] * mesh.positions[t[0]] + b[1] * mesh.positions[t[1]] + b[2] * mesh.positions[t[2]];
      Vec2 px;
      if (!ph.camera.project(p, px)) continue;
      sample_linear(ph.image, table.data(), px.x(), px.y(), texture.at(x, y));
      ++written;
      if (written_mask) (*written_mask)[static_cast<size_t>(y) * w + x] = 1;
    }
  }
  return written;
}

Status resample_feathered(const TriMesh& mesh, const std::vector<Vec2>& uv, const VertexBinding& binding,
                          const std::vector<TexturePhoto>& photos, const ChartRaster& raster,
                          const std::vector<Vec3>& vertex_colors, ImageF& texture) {
  Status s = check_inputs(mesh, binding, photos);
  if (!s) return s;
  const size_t nv = mesh.positions.size();
  if (uv.size() != nv || vertex_colors.size() != nv)
    return Status::error(ErrorCode::InvalidInput, "resample: uvs and vertex colours need one entry per vertex");
  const int w = raster.width, h = raster.height, np = binding.num_photos;
  if (w <= 0 || h <= 0 || raster.triangle.size() != static_cast<size_t>(w) * h)
    return Status::error(ErrorCode::InvalidInput, "resample: empty or inconsistent chart raster");
  const std::vector<TexelToBary> maps = texel_maps(uv, mesh.triangles, w, h);
  const std::array<float, 256> table = decode_table();
  texture = ImageF::make(w, h, 3, 0.f);
  std::vector<float> lookups(static_cast<size_t>(np) * 3);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const int f = raster.triangle[static_cast<size_t>(y) * w + x];
      if (f < 0) continue;
      const Tri& t = mesh.triangles[f];
      const Vec3 b = maps[f].ok ? maps[f].at(x, y) : Vec3(1.0 / 3, 1.0 / 3, 1.0 / 3);
      const Vec3 p = b[0] * mesh.positions[t[0]] + b[1] * mesh.positions[t[1]] + b[2] * mesh.positions[t[2]];
      // A triangle with an unbound corner (case 3) lies, at least partly,
      // where no photo sees the surface: photo lookups inside it could read
      // whatever occludes it. It keeps the hole-filled interpolation.
      if (!binding.bound(t[0]) || !binding.bound(t[1]) || !binding.bound(t[2])) {
        const Vec3 c = b[0] * vertex_colors[t[0]] + b[1] * vertex_colors[t[1]] + b[2] * vertex_colors[t[2]];
        float* out = texture.at(x, y);
        for (int k = 0; k < 3; ++k) out[k] = static_cast<float>(c[k]);
        continue;
      }
      const std::uint64_t any = binding.valid[t[0]] | binding.valid[t[1]] | binding.valid[t[2]];
      // One lookup per photo valid at any corner; a photo that cannot
      // project P is dropped from every corner's sum.
      std::uint64_t usable = 0;
      for (int i = 0; i < np; ++i) {
        if (!((any >> i) & 1u)) continue;
        Vec2 px;
        if (!photos[i].camera.project(p, px)) continue;
        sample_linear(photos[i].image, table.data(), px.x(), px.y(), &lookups[static_cast<size_t>(i) * 3]);
        usable |= std::uint64_t{1} << i;
      }
      Vec3 color = Vec3::Zero();
      for (int k = 0; k < 3; ++k) {
        const int v = t[k];
        const std::uint64_t mine = binding.valid[v] & usable;
        Vec3 corner = vertex_colors[v];
        if (mine != 0) {
          Vec3 sum = Vec3::Zero();
          double weight = 0;
          for (int i = 0; i < np; ++i) {
            if (!((mine >> i) & 1u)) continue;
            const double wi = binding.facing[static_cast<size_t>(v) * np + i];
            const float* l = &lookups[static_cast<size_t>(i) * 3];
            sum += wi * Vec3(l[0], l[1], l[2]);
            weight += wi;
          }
          if (weight > 0) corner = sum / weight;
        }
        color += b[k] * corner;
      }
      float* out = texture.at(x, y);
      for (int k = 0; k < 3; ++k) out[k] = static_cast<float>(color[k]);
    }
  }
  return Status::success();
}

}  // namespace lk
