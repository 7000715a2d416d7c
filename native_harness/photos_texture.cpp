#include "photos_texture.h"

#include "io/io.h"
#include "project/texture_job.h"
#include "texture/texture.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>

namespace lk::cli {

void print_blend_figures(const TextureReport& t, const char* indent) {
  std::printf("%schart texels whose fine detail blends >= 2 photos: %ld of %ld (%.1f%%)\n", indent, t.texels_blended,
              t.chart_texels, 100.0 * t.texels_blended / std::max(1L, t.chart_texels));
  if (t.labeled)
    std::printf("%sregion labelling: energy %.1f -> %.1f, boundary edges %d -> %d, %d triangles relabelled, %d passes\n",
                indent, t.labeling.energy_before, t.labeling.energy_after, t.labeling.boundary_edges_before,
                t.labeling.boundary_edges_after, t.labeling.triangles_changed, t.labeling.passes);
}

Status write_photos_texture(const TriMesh& control, const std::vector<ButterflyLevel>& levels,
                            const std::vector<Vec3>& fine_positions, const std::vector<std::string>& image_paths,
                            const std::vector<std::string>& names, const std::vector<Camera>& cameras, int size,
                            const std::string& out_dir, std::vector<Vec2>* uvs, Image* skin,
                            std::vector<Image>* images, bool register_photos, bool label_regions) {
  if (levels.empty() || image_paths.size() != cameras.size() || names.size() != cameras.size())
    return Status::error(ErrorCode::InvalidInput, "texture: no level, or photos and cameras differ in number");
  TriMesh mesh;
  mesh.positions = fine_positions;
  mesh.triangles = levels.back().fine_triangles;
  UvStats chart;
  Status s = level_chart(control, levels, UvOptions{}, mesh.uvs, chart);
  if (!s) return with_context(s, "texture chart");
  std::vector<TexturePhoto> photos(cameras.size());
  for (size_t i = 0; i < cameras.size(); ++i) {
    s = load_image_file(image_paths[i], photos[i].image, 3);
    if (!s) return s;  // names the file
    photos[i].camera = cameras[i];
  }
  TextureOptions options;
  options.size = size;
  options.register_photos = register_photos;
  options.label_regions = label_regions;
  TexturedHead head;
  std::chrono::steady_clock::time_point start;
  double register_ms = 0;
  s = name_photos(texture_head(mesh, photos, options, head,
                               [&](const char* step, double f) {
                                 if (std::string(step) != "register") return true;
                                 if (f == 0) start = std::chrono::steady_clock::now();
                                 else register_ms = std::chrono::duration<double, std::milli>(
                                                        std::chrono::steady_clock::now() - start).count();
                                 return true;
                               }),
                  names);
  if (s && head.report.registered) {
    const RegisterReport& g = head.report.registration;
    std::printf("texture registration: %.0f ms (wall), reference %s, %d vertices, luminance rms %.4f -> %.4f\n",
                register_ms, names[g.reference].c_str(), g.vertices, g.rms_before, g.rms_after);
    for (size_t i = 0; i < g.photos.size(); ++i)
      std::printf("  %s: rms %.4f -> %.4f, turned %.3f deg, moved %.1f mm, field <= %.2f px, gain %.3f\n",
                  names[i].c_str(), g.photos[i].rms_before, g.photos[i].rms_after, g.photos[i].rotation_deg,
                  g.photos[i].translation_mm, g.photos[i].field_max_px, g.photos[i].gain);
  }
  if (s) print_blend_figures(head.report, "texture: ");
  if (s && !head.source.empty()) {
    static const unsigned char kPalette[6][3] = {{230, 60, 60}, {60, 170, 60}, {60, 90, 230}, {230, 200, 40}, {200, 60, 220}, {40, 200, 220}};
    Image map = Image::make(size, size, 3, 0);
    for (size_t j = 0; j < head.source.size(); ++j) {
      const int r = head.source[j];
      unsigned char* px = &map.pixels[j * 3];
      if (r >= 0) std::copy_n(kPalette[r % 6], 3, px);
      else if (r == kRegionBlended) std::fill_n(px, 3, 255);
      else if (r == kRegionFilled) std::fill_n(px, 3, 128);
    }
    s = save_png_file(out_dir + "/sources.png", map);
  }
  if (s) s = write_file(out_dir + "/textured.obj", write_obj(head.mesh, "textured.mtl"));
  if (s) s = write_file(out_dir + "/textured.mtl", write_mtl("skin.png"));
  if (s) s = save_png_file(out_dir + "/skin.png", head.skin);
  if (s && uvs) *uvs = mesh.uvs;
  if (s && skin) *skin = head.skin;
  if (s && images)
    for (TexturePhoto& p : photos) images->push_back(std::move(p.image));
  return s;
}

}  // namespace lk::cli
