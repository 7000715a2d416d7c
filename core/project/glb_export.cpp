#include "project/glb_export.h"

#include "anim/bake.h"
#include "mesh/geometry.h"
#include "project/export.h"
#include "project/gltf_scene.h"
#include "project/parts.h"
#include "project/pose.h"

#include "multires/multires.h"

#include <algorithm>
#include <cmath>
#include <functional>

namespace lk {

namespace {

// The mesh moved by -origin (its node sits at origin), with normals.
TriMesh about(const TriMesh& m, const Vec3& origin) {
  TriMesh out = m;
  if (out.normals.size() != out.positions.size()) out.normals = vertex_normals(out);
  for (Vec3& p : out.positions) p -= origin;
  return out;
}

int textured_material(GltfBuilder& w, const std::string& name, const Image& texture, const std::vector<double>& rgba,
                      bool mask) {
  int tex = -1;
  if (!texture.empty()) {
    const Bytes png = write_png(texture);
    if (!png.empty()) tex = w.png_texture(w.view(png.data(), png.size()), name);
  }
  const int m = w.material(name, tex, rgba, 0.5);
  if (mask && tex >= 0) {
    w.model.materials[m].alphaMode = "MASK";
    w.model.materials[m].alphaCutoff = 0.5;
  }
  return m;
}

void add_child(tinygltf::Model& model, int parent, int child) { model.nodes[parent].children.push_back(child); }

// The offsets of a part's vertices (head frame) under each baked shape, as
// morph targets: only the shapes that move the part (by 10 micrometres or
// more), so each part carries the names that concern it.
std::vector<MorphTarget> part_targets(const std::vector<BakedShape>& shapes, const std::vector<Vec3>& rest,
                                      const std::function<std::vector<Vec3>(const FaceControls&)>& pose) {
  std::vector<MorphTarget> out;
  for (const BakedShape& b : shapes) {
    MorphTarget t;
    t.name = b.name;
    t.delta = pose(b.controls);
    double largest = 0;
    for (std::size_t i = 0; i < rest.size(); ++i) {
      t.delta[i] -= rest[i];
      largest = std::max(largest, t.delta[i].cwiseAbs().maxCoeff());
    }
    if (largest >= 1e-5) out.push_back(std::move(t));
  }
  return out;
}

}  // namespace

void use_generic_part_textures(GlbExportOptions& options) {
  EyeballTextureOptions eye;
  eye.size = 256;
  TeethCompositeOptions teeth;
  teeth.width = 512;
  teeth.height = 256;
  if (!generic_eyeball_texture(eye, options.eye_texture).ok()) options.eye_texture = Image{};
  if (!generic_teeth_texture(teeth, options.teeth_texture).ok()) options.teeth_texture = Image{};
}

Status export_glb(HeadProject& project, const GenericHead& generic, const GlbExportOptions& options, Bytes& out,
                  GlbExportReport* report) {
  if (project.fit.multires.num_levels() == 0) return Status::error(ErrorCode::InvalidInput, "no fitted head to export");
  const int level = std::clamp(options.level, 0, project.fit.multires.num_levels());
  if (Status s = rest_pose(project); !s.ok()) return s;
  TriMesh head;
  if (Status s = project_level_mesh(project, level, ExportFrame::Head, head); !s.ok()) return s;
  if (head.normals.size() != head.positions.size()) head.normals = vertex_normals(head);

  tinygltf::Model model;
  model.asset.version = "2.0";
  model.asset.generator = "Likeness";
  GltfBuilder w(model);

  // The head, textured when the project is (a coarser level's uvs are the
  // finest level's prefix).
  const bool textured = !project.texture.empty() && project.texture.uvs.size() >= head.positions.size();
  std::vector<Vec2> uvs;
  if (textured) uvs.assign(project.texture.uvs.begin(), project.texture.uvs.begin() + static_cast<std::ptrdiff_t>(head.positions.size()));
  const int skin = textured_material(w, "skin", textured ? project.texture.skin : Image{}, {0.8, 0.62, 0.52, 1.0}, false);
  // Morph targets: every expression, ARKit shape and viseme of the muscle
  // layer (core/anim), baked on this level by the local update.
  FaceRig face;
  if (Status s = make_face_rig(project.fit.control, generic, face); !s.ok()) return s;
  std::vector<BakedShape> shapes;
  {
    MultiresMesh work = project.fit.multires;  // at rest, current
    if (Status s = bake_face_shapes(face, &work, level, {}, shapes); !s.ok()) return s;
  }
  std::vector<MorphTarget> head_targets;
  for (const BakedShape& b : shapes) head_targets.push_back({b.name, b.level});
  const int neck = w.node("Neck");
  const int head_node = w.node("Head", w.mesh("head", head.positions, head.normals, uvs, head.triangles, skin, head_targets));
  add_child(model, neck, head_node);

  HeadParts parts;
  if (place_head_parts(project.fit.control, generic, parts).ok()) {
    const int eye_mat = textured_material(w, "eye", options.eye_texture, {0.92, 0.92, 0.9, 1.0}, false);
    const char* eye_names[2] = {"LeftEye", "RightEye"};  // 0 = the head's left (+x)
    for (int e = 0; e < 2; ++e) {
      const Vec3 c = parts.placement.eye_center[e];
      const TriMesh eye = about(parts.placed.eye[e], c);
      const std::vector<MorphTarget> turns = part_targets(shapes, parts.placed.eye[e].positions, [&](const FaceControls& fc) {
        return pose_eye(face, parts.placed.eye[e].positions, fc, e);
      });
      add_child(model, head_node,
                w.node(eye_names[e], w.mesh(eye_names[e], eye.positions, eye.normals, eye.uvs, eye.triangles, eye_mat, turns), c));
    }
    const int teeth_mat = textured_material(w, "teeth", options.teeth_texture, {0.80, 0.74, 0.60, 1.0}, true);
    const int tongue_mat = w.material("tongue", -1, {0.55, 0.16, 0.16, 1.0}, 0.5);
    auto uv_if = [](const TriMesh& m, bool want) { return want && m.uvs.size() == m.positions.size() ? m.uvs : std::vector<Vec2>{}; };
    const bool teeth_tex = !options.teeth_texture.empty();
    const TriMesh upper = about(parts.upper_teeth, Vec3::Zero());
    add_child(model, head_node, w.node("UpperTeeth", w.mesh("UpperTeeth", upper.positions, upper.normals, uv_if(upper, teeth_tex), upper.triangles, teeth_mat)));
    const Vec3 hinge = project.rig.jaw_pivot;
    const int jaw = w.node("Jaw", -1, hinge);
    add_child(model, head_node, jaw);
    const TriMesh lower = about(parts.lower_teeth, hinge), tongue = about(parts.placed.tongue, hinge);
    // They move with the jaw (and the tongue out) under the head's target
    // names (the Jaw node also turns them, for tools that drive bones).
    const std::vector<MorphTarget> lower_targets = part_targets(shapes, parts.lower_teeth.positions, [&](const FaceControls& fc) {
      return pose_lower_teeth(face, parts.lower_teeth.positions, fc);
    });
    const std::vector<MorphTarget> tongue_targets = part_targets(shapes, parts.placed.tongue.positions, [&](const FaceControls& fc) {
      return pose_tongue(face, parts.placed.tongue.positions, fc);
    });
    add_child(model, jaw, w.node("LowerTeeth", w.mesh("LowerTeeth", lower.positions, lower.normals, uv_if(lower, teeth_tex),
                                                      lower.triangles, teeth_mat, lower_targets)));
    add_child(model, jaw, w.node("Tongue", w.mesh("Tongue", tongue.positions, tongue.normals, {}, tongue.triangles, tongue_mat,
                                                  tongue_targets)));
  }

  tinygltf::Scene scene;
  scene.name = "Likeness head";
  scene.nodes.push_back(neck);
  model.scenes.push_back(scene);
  model.defaultScene = 0;
  if (report) {
    report->level = level;
    report->head_vertices = head.num_vertices();
    report->head_triangles = head.num_triangles();
    report->head_targets = static_cast<int>(head_targets.size());
    report->nodes.clear();
    for (const tinygltf::Node& n : model.nodes) report->nodes.push_back(n.name);
  }
  return write_glb(model, out);
}

}  // namespace lk
