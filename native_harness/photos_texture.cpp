#include "photos_texture.h"

#include "io/io.h"
#include "project/texture_job.h"
#include "texture/texture.h"

namespace lk::cli {

Status write_photos_texture(const TriMesh& control, const std::vector<ButterflyLevel>& levels,
                            const std::vector<Vec3>& fine_positions, const std::vector<std::string>& image_paths,
                            const std::vector<std::string>& names, const std::vector<Camera>& cameras, int size,
                            const std::string& out_dir, std::vector<Vec2>* uvs, Image* skin,
                            std::vector<Image>* images) {
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
  TexturedHead head;
  s = name_photos(texture_head(mesh, photos, options, head), names);
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
