// likeness render: draws a mesh and/or point cloud headlessly (OSMesa) from a
// canonical view into a PNG, with the same renderer and shaders as the web app.
#include "command.h"
#include "expression_head.h"

#include <cstdio>

#include "anim/face_shapes.h"

#include "io/io.h"
#include "mesh/geometry.h"
#include "render/ambient_occlusion.h"
#include "render/camera.h"
#include "render/offscreen.h"

#include <nlohmann/json.hpp>

#include <map>

#include <cmath>
#include <fstream>
#include <iostream>
#include <sys/stat.h>

namespace lk::cli {
namespace {

const char* kName = "render";

bool file_exists(const std::string& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode);
}

// Bad options: message on stderr, exit code 2.
int usage_error(const std::string& message) {
  fail(kName, message);
  return 2;
}

std::string directory_of(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? "" : path.substr(0, slash + 1);
}

int run_render(const Args& args) {
  if (!only_known_options(kName, args,
                          {"mesh", "points", "texture", "wireframe", "edges-only", "view", "size", "out",
                           "point-size", "supersample", "no-ao", "flat", "yaw", "pitch", "camera-out", "expression",
                           "project", "level", "columns", "face", "lid-seal"}))
    return 2;
  // --expression NAME: a head with the generic head's vertices (--mesh, or
  // --project FILE, or the generic head) posed by the muscle layer and drawn
  // at --level L (default 2) with its eyes, teeth and tongue.
  // Several names (comma-separated) make a sheet of --columns tiles, each
  // --size pixels, in reading order; --face frames the face alone.
  const bool posing = args.has("expression") || args.has("project");
  const std::string expression = args.get("expression", "neutral");
  std::vector<std::string> names;
  for (std::size_t at = 0; at <= expression.size();) {
    const std::size_t comma = std::min(expression.find(',', at), expression.size());
    names.push_back(expression.substr(at, comma - at));
    at = comma + 1;
  }
  std::vector<FaceControls> faces(names.size());
  int columns = 0;
  if (!args.get_int("columns", static_cast<int>(names.size()), columns, 1, 64)) return 2;
  if (posing) {
    // A tile's names joined by '+' are posed together, each at full weight.
    for (std::size_t i = 0; i < names.size(); ++i) {
      std::map<std::string, double> weights;
      for (const std::string& name : split_list(names[i], '+')) weights[name] = 1.0;
      if (weights.empty()) return usage_error("--expression has an empty name (see docs/design/muscles.md)");
      if (Status st = face_controls_from_weights(weights, faces[i]); !st)
        return usage_error(st.message + " (see docs/design/muscles.md)");
    }
    if (args.has("points") || args.has("texture")) return usage_error("--expression draws a head alone: no --points or --texture");
    if (args.has("project") && args.has("mesh")) return usage_error("give --project or --mesh, not both");
  }
  int level = 2;
  if (!args.get_int("level", 2, level, 0, 4)) return 2;
  const std::string mesh_path = args.get("mesh"), points_path = args.get("points");
  const std::string out_path = args.get("out"), texture_path = args.get("texture");
  if (mesh_path.empty() && points_path.empty() && !posing)
    return usage_error("give --mesh FILE and/or --points FILE");
  if (out_path.empty()) return usage_error("--out PNG is required");
  if (args.has("texture") && texture_path.empty()) return usage_error("--texture needs a file");
  if (!texture_path.empty() && mesh_path.empty())
    return usage_error("--texture needs a --mesh with uvs to put it on");

  CanonicalView view = CanonicalView::Front;
  Status s = parse_canonical_view(args.get("view", "front"), view);
  if (!s) return usage_error(s.message);
  int size = 0, supersample = 0;
  double point_size = 0, yaw = 0, pitch = 0;
  if (!args.get_int("size", 1024, size, 16, 4096) || !args.get_int("supersample", 2, supersample, 1, 4) ||
      !args.get_double("point-size", 0.0, point_size, 0, 64) || !args.get_double("yaw", 0.0, yaw, -360, 360) ||
      !args.get_double("pitch", 0.0, pitch, -80, 80))
    return 2;
  const bool own_angles = args.has("yaw") || args.has("pitch");
  const std::string camera_out = args.get("camera-out");
  if (args.has("camera-out") && camera_out.empty()) return usage_error("--camera-out needs a file");

  TriMesh mesh;
  PointCloud cloud;
  Image texture;
  PosedHead posed;
  ExpressionHead head;
  if (posing) {
    LidSeal seal;  // --lid-seal RIM,CORNER: the closed lids' option (docs/design/muscles.md)
    if (args.has("lid-seal") && std::sscanf(args.get("lid-seal").c_str(), "%lf,%lf", &seal.rim, &seal.corner) != 2)
      return usage_error("--lid-seal needs RIM,CORNER (e.g. 0.995,0.6)");
    s = load_expression_head(args.get("project"), mesh_path, level, head, seal);
    if (s) s = pose_expression_head(head, FaceControls{}, level, posed);
    if (!s) return fail(kName, s.message);
    mesh = posed.head;
    texture = head.skin;
    if (texture.empty()) mesh.uvs.clear();
  } else if (!mesh_path.empty()) {
    s = load_mesh_file(mesh_path, mesh);
    if (!s) return fail(kName, s.message);
  }
  if (!points_path.empty()) {
    TriMesh as_mesh;
    GeometryKind kind = GeometryKind::PointCloud;
    s = load_geometry_file(points_path, as_mesh, cloud, kind);
    if (!s) return fail(kName, s.message);
    if (cloud.size() == 0) return fail(kName, points_path + ": no points");
    // A mesh shown as points: its vertex normals colour the sprites.
    if (kind == GeometryKind::Mesh && cloud.normals.empty() && as_mesh.num_triangles() > 0 &&
        as_mesh.num_vertices() == cloud.size())
      cloud.normals = vertex_normals(as_mesh);
  }
  // An OBJ's material names its texture; use it when no --texture is given.
  std::string tex_path = texture_path;
  if (tex_path.empty() && !mesh.texture_name.empty()) {
    // load_mesh_file already resolves map_Kd against the MTL's folder; a bare
    // name is tried beside the mesh too.
    const std::string beside = directory_of(mesh_path) + mesh.texture_name;
    if (file_exists(mesh.texture_name)) tex_path = mesh.texture_name;
    else if (file_exists(beside)) tex_path = beside;
  }
  if (!tex_path.empty() && !posing) {
    if (mesh.uvs.empty()) return fail(kName, mesh_path + ": the mesh has no uvs, so a texture cannot be applied");
    s = load_image_file(tex_path, texture);
    if (!s) return fail(kName, s.message);
  }

  // Baked occlusion shades cavities (eyes, nostrils, ears); skipped on
  // request or for meshes so large that baking would take long.
  std::vector<float> occlusion;
  if (!mesh.positions.empty() && !args.has("no-ao")) {
    s = vertex_ambient_occlusion(mesh, OcclusionOptions{}, occlusion);
    if (s.code == ErrorCode::TooLarge) std::cout << "note: " << s.message << "; rendering without it\n";
    else if (!s) return fail(kName, with_context(s, mesh_path).message);
  }

  const bool edges_only = args.has("edges-only");
  const bool wireframe = args.has("wireframe") || edges_only;
  // Dense clouds read best with small sprites, sparse ones with larger.
  if (point_size == 0)
    point_size = cloud.size() > 200000 ? 1.5 : cloud.size() > 20000 ? 2.5 : 4.0;
  point_size *= supersample;

  auto setup = [&](Renderer& r) -> Status {
    if (!mesh.positions.empty()) {
      DrawableHandle h;
      Status st = r.upload_mesh(mesh, h);
      if (!st) return with_context(st, mesh_path);
      if (!occlusion.empty()) st = r.set_occlusion(h, occlusion);
      if (!st) return st;
      DrawStyle& style = *r.style(h);
      style.wireframe = wireframe;
      style.surface = !edges_only;
      style.flat_shading = args.has("flat");
      // Lines keep their look at any supersampling.
      style.wire_width_px = 1.0f * supersample;
      if (!texture.empty()) {
        TextureHandle t;
        st = r.upload_texture(texture, t);
        if (st) st = r.attach_texture(h, t);
        if (!st) return with_context(st, tex_path);
      }
    }
    for (std::size_t i = 0; i < posed.parts.size(); ++i) {
      DrawableHandle h;
      Status st = r.upload_mesh(posed.parts[i], h);
      const Vec3& c = posed.part_colors[i];
      if (st) st = r.set_base_color(h, glm::vec3(float(c.x()), float(c.y()), float(c.z())));
      if (st && !posed.part_textures[i].empty()) {
        TextureHandle t;
        st = r.upload_texture(posed.part_textures[i], t);
        if (st) st = r.attach_texture(h, t);
      }
      if (!st) return st;
    }
    if (cloud.size() > 0) {
      DrawableHandle h;
      Status st = r.upload_points(cloud, h);
      if (st) st = r.set_point_size(h, static_cast<float>(point_size));
      if (!st) return with_context(st, points_path);
    }
    return Status::success();
  };
  // Frame what is drawn (vertices and points), not its box: tighter on round heads.
  std::vector<Vec3> framed = mesh.positions;
  framed.insert(framed.end(), cloud.positions.begin(), cloud.positions.end());
  if (posing && args.has("face")) {  // the rig's reach at rest: brows to chin
    framed.clear();
    for (int v : head.rig.moved) framed.push_back(head.rig.rest[static_cast<std::size_t>(v)]);
  }
  // --yaw/--pitch: a camera at those angles (degrees, OrbitCamera's) instead
  // of the named view's, framed the same way (e.g. known cameras for
  // detecting landmarks on the generic head, scripts/make-landmark-map).
  auto camera = [&](float aspect) {
    OrbitCamera cam = canonical_view(view, framed, aspect);
    if (own_angles && !framed.empty()) {
      cam.yaw_deg = static_cast<float>(yaw);
      cam.pitch_deg = static_cast<float>(pitch);
      BBox box;
      for (const Vec3& p : framed) box.extend(p);
      const glm::vec3 forward = glm::normalize(cam.target - cam.eye());
      cam.distance = framing_distance(framed, box.center(), forward, glm::vec3(0, 1, 0), cam.fov_y_deg, aspect);
    }
    return cam;
  };
  auto camera_for = [&](float aspect) { return camera(aspect).matrices(aspect); };

  OffscreenOptions options;
  options.width = options.height = size;
  options.supersample = supersample;
  Image image;
  if (posing) {
    // Each name posed and drawn (the occlusion of the rest pose kept), the
    // tiles laid out in rows.
    const int rows = (static_cast<int>(names.size()) + columns - 1) / columns;
    for (std::size_t i = 0; i < names.size(); ++i) {
      s = pose_expression_head(head, faces[i], level, posed);
      if (!s) return fail(kName, s.message);
      const std::vector<Vec2> uvs = mesh.uvs;
      mesh = posed.head;
      mesh.uvs = uvs;
      Image tile;
      s = render_offscreen(setup, camera_for, options, tile);
      if (!s) return fail(kName, s.message);
      if (image.empty()) image = Image::make(tile.width * std::min(columns, static_cast<int>(names.size())), tile.height * rows, tile.channels, 255);
      const int x0 = static_cast<int>(i) % columns * tile.width, y0 = static_cast<int>(i) / columns * tile.height;
      for (int y = 0; y < tile.height; ++y)
        std::copy(tile.at(0, y), tile.at(0, y) + static_cast<std::ptrdiff_t>(tile.width) * tile.channels, image.at(x0, y0 + y));
    }
  } else {
    s = render_offscreen(setup, camera_for, options, image);
  }
  if (!s) return fail(kName, s.message);
  s = save_png_file(out_path, image);
  if (!s) return fail(kName, s.message);
  if (!camera_out.empty()) {
    // The camera of the image: GL view and projection matrices (column-major,
    // as glm stores them), so a tool can project points into it or cast rays
    // from its pixels (pixel (u, v), origin top-left: ndc x = 2u/W - 1, y = 1 - 2v/H).
    const OrbitCamera cam = camera(1.0f);
    const CameraMatrices m = cam.matrices(1.0f);
    const glm::vec3 eye = cam.eye();
    nlohmann::json j = {{"format", "likeness-camera"}, {"version", 1}, {"width", size}, {"height", size},
                        {"fov_y_deg", cam.fov_y_deg}, {"yaw_deg", cam.yaw_deg}, {"pitch_deg", cam.pitch_deg},
                        {"eye", {eye.x, eye.y, eye.z}}, {"target", {cam.target.x, cam.target.y, cam.target.z}}};
    for (const auto& [name, mat] : {std::pair{"view", m.view}, std::pair{"projection", m.projection}}) {
      nlohmann::json a = nlohmann::json::array();
      for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) a.push_back(mat[c][r]);
      j[name] = a;
    }
    std::ofstream f(camera_out);
    f << j.dump(1) << "\n";
    if (!f) return fail(kName, camera_out + ": cannot write");
  }
  std::cout << "wrote " << out_path << " (" << image.width << "x" << image.height << ", ";
  if (own_angles) std::cout << "yaw " << yaw << ", pitch " << pitch << " degrees";
  else std::cout << to_string(view) << " view";
  if (!mesh.positions.empty()) std::cout << ", " << mesh.num_triangles() << " triangles";
  if (posing) std::cout << ", expression " << expression;
  if (cloud.size() > 0) std::cout << ", " << cloud.size() << " points";
  if (!texture.empty()) std::cout << ", textured by " << (posing ? std::string("the project's skin") : tex_path);
  std::cout << ")\n";
  return 0;
}

Registrar reg({"render",
               "likeness render --mesh FILE [--points FILE] [--texture PNG] [--wireframe | --edges-only] "
               "[--view front|left|right|back|top|three-quarter] [--size N] [--point-size PX] "
               "[--flat] [--supersample 1..4] [--no-ao] [--yaw DEG --pitch DEG] [--camera-out FILE.json] --out PNG | "
               "likeness render --expression NAME[+NAME...][,NAME...] [--columns C] [--face] [--project FILE | --mesh FILE] [--level L] [--lid-seal RIM,CORNER] [--view ...] --out PNG",
               "draws a mesh (with baked ambient occlusion) and/or point cloud from a canonical view into a PNG "
               "(OSMesa, same shaders as the web app); --yaw/--pitch turn the camera, --camera-out writes its matrices",
               run_render});

}  // namespace
}  // namespace lk::cli
