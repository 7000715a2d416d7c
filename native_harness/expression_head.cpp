#include "expression_head.h"

#include "anim/face_pose.h"
#include "head/generic_head.h"
#include "io/io.h"
#include "head/head_creases.h"
#include "project/pose.h"
#include "project/project_file.h"

#include <algorithm>

namespace lk::cli {

Status load_expression_head(const std::string& project_path, const std::string& mesh_path, int levels,
                            ExpressionHead& out, const LidSeal& seal) {
  if (Status s = load_generic_head(out.generic); !s.ok()) return s;
  TriMesh control;
  if (!project_path.empty()) {
    Bytes bytes;
    HeadProject p;
    if (Status s = read_file(project_path, bytes); !s.ok()) return s;
    if (Status s = load_project(bytes.data(), bytes.size(), p); !s.ok()) return with_context(s, project_path);
    if (Status s = rest_pose(p); !s.ok()) return with_context(s, project_path);
    control = p.fit.control;
    out.multires = p.fit.multires;
    if (!p.texture.empty()) {
      out.skin = p.texture.skin;
      out.uvs = p.texture.uvs;
    }
    out.eye_texture = p.parts.eye_texture;
    out.description = project_path;
  } else {
    if (!mesh_path.empty()) {
      if (Status s = load_mesh_file(mesh_path, control); !s.ok()) return s;
      out.description = mesh_path;
    } else {
      control = out.generic.mesh;
      out.description = "the generic head";
    }
    if (control.num_vertices() != out.generic.mesh.num_vertices())
      return Status::error(ErrorCode::InvalidInput, out.description + " does not have the generic head's " +
                                                        std::to_string(out.generic.mesh.num_vertices()) + " vertices");
    control.triangles = out.generic.mesh.triangles;
    if (Status s = build_multires(control, head_creases(out.generic.mesh, out.generic.annotations), levels, out.multires); !s.ok())
      return s;
  }
  if (Status s = make_face_rig(control, out.generic, out.rig, seal); !s.ok()) return with_context(s, out.description);
  out.have_parts = place_head_parts(control, out.generic, out.parts).ok();
  return Status::success();
}

Status pose_expression_head(ExpressionHead& h, const FaceControls& controls, int level, PosedHead& out) {
  level = std::clamp(level, 0, h.multires.num_levels());
  if (Status s = pose_multires(h.multires, h.rig, controls, level); !s.ok()) return s;
  out.head = level_mesh(h.multires, level);
  if (!h.uvs.empty() && h.uvs.size() >= out.head.positions.size())
    out.head.uvs.assign(h.uvs.begin(), h.uvs.begin() + static_cast<std::ptrdiff_t>(out.head.positions.size()));
  out.parts.clear();
  out.part_colors.clear();
  if (!h.have_parts) return Status::success();
  out.part_textures.clear();
  Image iris = h.eye_texture;
  EyeballTextureOptions eye_options;
  eye_options.size = 256;
  if (iris.empty() && !generic_eyeball_texture(eye_options, iris).ok()) iris = Image{};
  auto add = [&](const TriMesh& m, std::vector<Vec3> positions, const Vec3& color, const Image& texture = Image{}) {
    TriMesh posed = m;
    posed.positions = std::move(positions);
    posed.normals.clear();
    if (texture.empty()) posed.uvs.clear();
    out.parts.push_back(std::move(posed));
    out.part_colors.push_back(color);
    out.part_textures.push_back(texture);
  };
  for (int e = 0; e < 2; ++e)
    add(h.parts.placed.eye[e], pose_eye(h.rig, h.parts.placed.eye[e].positions, controls, e), Vec3(0.92, 0.92, 0.9), iris);
  add(h.parts.upper_teeth, h.parts.upper_teeth.positions, Vec3(0.9, 0.87, 0.78));
  add(h.parts.lower_teeth, pose_lower_teeth(h.rig, h.parts.lower_teeth.positions, controls), Vec3(0.9, 0.87, 0.78));
  add(h.parts.placed.tongue, pose_tongue(h.rig, h.parts.placed.tongue.positions, controls), Vec3(0.62, 0.25, 0.25));
  return Status::success();
}

}  // namespace lk::cli
