#include "texture/texture.h"

#include "mesh/geometry.h"
#include "mesh/topology.h"
#include "raycast/bvh.h"
#include "texture/chart_raster.h"
#include "texture/color.h"
#include "texture/dilate.h"
#include "texture/pyramid.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace lk {
namespace {

Status cancelled(const char* step) {
  return Status::error(ErrorCode::Cancelled, std::string("texturing cancelled during ") + step);
}

// Region of each vertex when all its triangles agree, else kMixed: the
// shrunk mask of photo i keeps the triangles of region i whose three corners
// are all pure i, i.e. it drops the outermost ring of triangles (paper,
// Fig. 5), so the pyramids find photo i's colours just outside every mask.
constexpr int kUnset = -100, kMixed = -101;

std::vector<char> shrunk_region_triangles(const TriMesh& mesh, const std::vector<int>& region, int photo) {
  std::vector<int> vertex_region(mesh.num_vertices(), kUnset);
  for (int f = 0; f < mesh.num_triangles(); ++f)
    for (int v : mesh.triangles[f]) {
      int& r = vertex_region[v];
      if (r == kUnset) r = region[f];
      else if (r != region[f]) r = kMixed;
    }
  std::vector<char> keep(mesh.num_triangles(), 0);
  for (int f = 0; f < mesh.num_triangles(); ++f) {
    const Tri& t = mesh.triangles[f];
    keep[f] = region[f] == photo && vertex_region[t[0]] == photo && vertex_region[t[1]] == photo &&
              vertex_region[t[2]] == photo;
  }
  return keep;
}

Status check_inputs(const TriMesh& mesh, const std::vector<TexturePhoto>& photos, const TextureOptions& options) {
  std::string why;
  if (mesh.num_vertices() == 0 || mesh.num_triangles() == 0)
    return Status::error(ErrorCode::Empty, "the head mesh is empty");
  if (!is_valid(mesh, &why)) return Status::error(ErrorCode::InvalidInput, "head mesh: " + why);
  if (mesh.uv_per_corner)
    return Status::error(ErrorCode::InvalidInput,
                         "the head mesh has per-corner uvs (a chart with seams); texturing needs one chart with "
                         "per-vertex uvs, or none (then it is parameterized here)");
  if (!mesh.uvs.empty()) {
    if (mesh.uvs.size() != mesh.positions.size())
      return Status::error(ErrorCode::InvalidInput, "the head mesh has " + std::to_string(mesh.uvs.size()) +
                                                        " uvs for " + std::to_string(mesh.num_vertices()) + " vertices");
    for (const Vec2& t : mesh.uvs)
      if (!std::isfinite(t.x()) || !std::isfinite(t.y()))
        return Status::error(ErrorCode::InvalidInput, "the head mesh's uvs contain NaN or infinity");
  }
  if (photos.empty()) return Status::error(ErrorCode::InvalidInput, "no photos to texture from");
  if (static_cast<int>(photos.size()) > kMaxTexturePhotos)
    return Status::error(ErrorCode::InvalidInput, std::to_string(photos.size()) + " photos, at most " +
                                                      std::to_string(kMaxTexturePhotos) + " are supported");
  for (size_t i = 0; i < photos.size(); ++i) {
    const Image& im = photos[i].image;
    const std::string name = "photo " + std::to_string(i);
    if (im.empty()) return Status::error(ErrorCode::InvalidInput, name + " is empty");
    if (im.channels < 1 || im.channels > 4 ||
        im.pixels.size() != static_cast<size_t>(im.width) * im.height * im.channels)
      return Status::error(ErrorCode::InvalidInput, name + " has inconsistent size or channels");
    if (photos[i].camera.width != im.width || photos[i].camera.height != im.height)
      return Status::error(ErrorCode::InvalidInput,
                           name + ": camera calibrated for " + std::to_string(photos[i].camera.width) + "x" +
                               std::to_string(photos[i].camera.height) + " but the image is " +
                               std::to_string(im.width) + "x" + std::to_string(im.height));
  }
  if (options.size < 16)
    return Status::error(ErrorCode::InvalidInput, "texture size " + std::to_string(options.size) + " is below 16");
  // About 120 bytes per texel at the spline's peak (float images and
  // pyramids; measured 612 MB peak RSS for 2048^2 with five 3000x2000
  // photos and an 85k-vertex head): ~2 GB at 4096^2.
  if (options.size > 4096)
    return Status::error(ErrorCode::TooLarge, "texture size " + std::to_string(options.size) +
                                                  " is above 4096 (the spline needs ~120 bytes per texel)");
  return Status::success();
}

}  // namespace

bool photos_look_like_one_camera(const std::vector<std::array<int, 2>>& image_sizes) {
  if (image_sizes.size() < 2) return false;
  const std::array<int, 2> first = image_sizes[0], turned = {first[1], first[0]};
  for (const auto& size : image_sizes)
    if (size != first && size != turned) return false;
  return true;
}

Status calibrate_photos(const std::vector<std::vector<Correspondence>>& correspondences,
                        const std::vector<std::array<int, 2>>& image_sizes, const CalibOptions& options,
                        std::vector<CalibResult>& results, bool same_camera) {
  if (correspondences.size() != image_sizes.size())
    return Status::error(ErrorCode::InvalidInput,
                         std::to_string(correspondences.size()) + " sets of correspondences for " +
                             std::to_string(image_sizes.size()) + " photos");
  if (same_camera && correspondences.size() > 1) {
    // Each photo alone first, so a failure names its photo.
    for (size_t i = 0; i < correspondences.size(); ++i)
      if (correspondences[i].size() < 6)
        return Status::error(ErrorCode::InvalidInput, "photo " + std::to_string(i) + ": " +
                                                          std::to_string(correspondences[i].size()) +
                                                          " correspondences, at least 6 are needed");
    SharedCalibResult shared;
    Status s = calibrate_cameras_shared(correspondences, image_sizes, options, shared);
    if (!s) return s;
    results = std::move(shared.photos);
    return Status::success();
  }
  results.assign(correspondences.size(), CalibResult());
  for (size_t i = 0; i < correspondences.size(); ++i) {
    Status s = calibrate_camera(correspondences[i], image_sizes[i][0], image_sizes[i][1], options, results[i]);
    if (!s) return with_context(s, "photo " + std::to_string(i));
  }
  return Status::success();
}

Status texture_head(const TriMesh& mesh, const std::vector<TexturePhoto>& photos, const TextureOptions& options,
                    TexturedHead& out, const ProgressFn& progress) {
  Status s = check_inputs(mesh, photos, options);
  if (!s) return s;
  out = TexturedHead();
  TextureReport& rep = out.report;
  const int np = static_cast<int>(photos.size()), size = options.size;
  rep.vertices = mesh.num_vertices();
  rep.triangles = mesh.num_triangles();
  out.mesh = mesh;
  out.mesh.texture_name = "skin.png";

  // 1. Parameterization (Sec. 3.1) unless the mesh brings its chart.
  if (!report(progress, "parameterize", 0)) return cancelled("parameterize");
  if (mesh.uvs.empty()) {
    ProgressFn forward;
    if (progress) forward = [&progress](const char*, double f) { return progress("parameterize", f); };
    s = parameterize_stretch(mesh, options.uv, out.mesh.uvs, rep.uv, forward);
    if (!s) return with_context(s, "parameterization");
    rep.parameterized = true;
  } else {
    s = measure_stretch(mesh, mesh.uvs, options.uv, rep.uv);
    if (!s) return with_context(s, "the mesh's uvs");
  }
  if (!report(progress, "parameterize", 1)) return cancelled("parameterize");
  const std::vector<Vec2>& uv = out.mesh.uvs;

  // 2. Vertex-to-photo binding.
  if (!report(progress, "bind", 0)) return cancelled("bind");
  const std::vector<Vec3> normals = vertex_normals(mesh);
  MeshBvh bvh;
  s = build_bvh(mesh, bvh);
  if (!s) return s;
  std::vector<Camera> cameras(np);
  for (int i = 0; i < np; ++i) cameras[i] = photos[i].camera;
  VertexBinding binding;
  s = bind_vertices(mesh, normals, bvh, cameras, options.binding, binding);
  if (!s) return s;
  auto count_bound = [&] {
    rep.vertices_unbound = 0;
    rep.photos.assign(np, TexturePhotoReport());
    for (int v = 0; v < mesh.num_vertices(); ++v) {
      if (!binding.bound(v)) ++rep.vertices_unbound;
      else ++rep.photos[binding.main_photo[v]].vertices_main;
      for (int i = 0; i < np; ++i) rep.photos[i].vertices_valid += binding.is_valid(v, i);
    }
  };
  count_bound();
  for (int i = 0; i < np; ++i)
    if (rep.photos[i].vertices_valid == 0)
      return Status::error(ErrorCode::NotAHead,
                           "photo " + std::to_string(i) +
                               " sees no vertex of the head (wrong calibration, points or photo?)");
  if (!report(progress, "bind", 1)) return cancelled("bind");

  // 2b. Re-registration: photos whose cameras and surface disagree by a few
  // pixels would put features twice into the blend.
  std::vector<TexturePhoto> registered;
  const std::vector<TexturePhoto>* used_photos = &photos;
  if (options.register_photos && np >= 2) {
    if (!report(progress, "register", 0)) return cancelled("register");
    s = register_photos(mesh, normals, binding, photos, options.registration, rep.registration);
    if (s) {
      registered = photos;
      for (int i = 0; i < np; ++i) {
        apply_registration(rep.registration.photos[i], registered[i]);
        cameras[i] = registered[i].camera;
      }
      used_photos = &registered;
      rep.registered = true;
      s = bind_vertices(mesh, normals, bvh, cameras, options.binding, binding);
      if (!s) return s;
      count_bound();
    } else if (s.code != ErrorCode::Empty) {
      return with_context(s, "registration");
    }
    if (!report(progress, "register", 1)) return cancelled("register");
  }

  // 3-4. Vertex colours, hole filling, resampling of the chart.
  if (!report(progress, "fill holes", 0)) return cancelled("fill holes");
  std::vector<Vec3> vertex_colors;
  std::vector<char> colored;
  bound_vertex_colors(mesh, normals, binding, *used_photos, vertex_colors, colored);
  MeshTopology topology;
  s = build_topology(mesh, topology);
  if (!s) return with_context(s, "head mesh");
  s = fill_vertex_colors(topology, vertex_colors, colored, options.hole_fill, rep.hole_fill);
  if (!s) return s;
  if (!report(progress, "fill holes", 1)) return cancelled("fill holes");

  if (!report(progress, "resample", 0)) return cancelled("resample");
  ChartRaster raster;
  s = rasterize_chart(uv, mesh.triangles, size, size, raster, options.conservative_texels);
  if (!s) return s;
  rep.chart_texels = raster.covered;
  ImageF blended;
  ResampleStats stats;
  s = resample_texture(mesh, normals, uv, binding, *used_photos, raster, vertex_colors, blended, stats, &out.region);
  if (!s) return s;
  for (int k = 0; k < 3; ++k) {
    rep.triangles_case[k] = stats.triangles_case[k];
    rep.texels_case[k] = stats.texels_case[k];
  }
  for (int i = 0; i < np; ++i) rep.photos[i].texels_colored = stats.texels_region[i];
  std::vector<char> chart(raster.triangle.size());
  for (size_t j = 0; j < chart.size(); ++j) chart[j] = raster.triangle[j] >= 0;
  if (!report(progress, "resample", 1)) return cancelled("resample");

  // Every image the spline sees needs colours outside the chart too, or the
  // pyramids pull the black background into the border texels.
  auto fill_background = [&](ImageF& image) -> long {
    if (options.dilate_texels < 0) return push_pull_fill(image, chart);
    if (options.dilate_texels > 0) {
      std::vector<char> known = chart;
      return dilate_rings(image, known, options.dilate_texels);
    }
    return 0;
  };

  ImageF final_texture;
  if (options.multiresolution_spline) {
    if (!report(progress, "spline", 0)) return cancelled("spline");
    if (options.keep_unblended) {
      ImageF shown = blended;
      fill_background(shown);
      out.unblended = linear_to_srgb(shown);
    }
    ImageF().pixels.swap(blended.pixels);  // not needed any more: give its memory back
    std::vector<TriangleCase> cases;
    std::vector<int> tri_region;
    classify_triangles(mesh, binding, cases, tri_region);
    if (options.label_regions && np >= 2) {
      s = label_regions(mesh, binding, *used_photos, cases, options.labeling, tri_region, rep.labeling);
      if (!s) return with_context(s, "region labelling");
      rep.labeled = true;
      for (size_t j = 0; j < raster.triangle.size(); ++j)
        if (raster.triangle[j] >= 0) out.region[j] = tri_region[raster.triangle[j]];
    }
    SplineBlender blender;
    s = blender.begin(size, size, 3, options.spline_levels);
    if (!s) return s;
    rep.spline_levels = blender.levels();
    ImageF complement = ImageF::make(size, size, 1, 1.f);
    ImageF mask = ImageF::make(size, size, 1, 0.f);
    ImageF photo_image;
    std::vector<char> seen;
    for (int i = 0; i < np; ++i) {
      std::vector<char> keep;
      if (rep.labeled) {
        keep.resize(tri_region.size());
        for (size_t f = 0; f < keep.size(); ++f) keep[f] = tri_region[f] == i;
      } else {
        keep = shrunk_region_triangles(mesh, tri_region, i);
      }
      long in_mask = 0;
      for (size_t j = 0; j < raster.triangle.size(); ++j) {
        const int f = raster.triangle[j];
        const bool m = f >= 0 && keep[f];
        mask.pixels[j] = m ? 1.f : 0.f;
        if (m) {
          complement.pixels[j] = 0.f;
          ++in_mask;
        }
      }
      // Photo i alone where it sees the surface, continued smoothly from its
      // own colours elsewhere: an image without seams of its own, so only
      // the masks decide where its light ends (Burt & Adelson's premise).
      if (photo_image.empty()) photo_image = ImageF::make(size, size, 3, 0.f);
      rep.photos[i].texels_seen = resample_single_photo(mesh, uv, binding, *used_photos, i, raster, photo_image, &seen);
      if (in_mask == 0) continue;  // its shrunk region is empty: nothing of its own to add
      push_pull_fill(photo_image, seen);
      s = blender.add(photo_image, mask);
      if (!s) return s;
      if (!report(progress, "spline", (i + 1.0) / (np + 1.0))) return cancelled("spline");
    }
    ImageF().pixels.swap(photo_image.pixels);
    out.source.assign(raster.triangle.size(), kRegionBackground);
    for (size_t j = 0; j < raster.triangle.size(); ++j) {
      const int f = raster.triangle[j];
      if (f < 0) continue;
      if (complement.pixels[j] == 0.f) {
        out.source[j] = tri_region[f];
        continue;
      }
      const Tri& t = mesh.triangles[f];
      const std::uint64_t any = binding.valid[t[0]] | binding.valid[t[1]] | binding.valid[t[2]];
      const bool several = (any & (any - 1)) != 0;
      out.source[j] = several ? kRegionBlended : kRegionFilled;
      rep.texels_blended += several;
    }
    // The complement image: the seam-free (feathered) resampling, filled
    // past the chart so the pyramids see no black border. Made last, so at
    // most one full-size image besides the blender's pyramids is alive.
    ImageF complement_image;
    s = resample_feathered(mesh, uv, binding, *used_photos, raster, vertex_colors, complement_image);
    if (!s) return s;
    push_pull_fill(complement_image, chart);
    s = blender.add(complement_image, complement);
    if (s) s = blender.finish(final_texture);
    if (!s) return s;
    if (!report(progress, "spline", 1)) return cancelled("spline");
  } else {
    final_texture = std::move(blended);
  }

  // 5. The unused texture space.
  if (!report(progress, "dilate", 0)) return cancelled("dilate");
  if (options.multiresolution_spline)
    for (size_t j = 0; j < chart.size(); ++j)
      if (!chart[j]) std::fill_n(final_texture.pixels.begin() + j * 3, 3, 0.f);
  rep.background_filled = fill_background(final_texture);
  out.skin = linear_to_srgb(final_texture);
  if (!options.multiresolution_spline && options.keep_unblended) out.unblended = out.skin;
  if (!report(progress, "dilate", 1)) return cancelled("dilate");
  return Status::success();
}

}  // namespace lk
