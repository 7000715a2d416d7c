#include "project/glb_export.h"

#include "anim/bake.h"
#include "anim/clips.h"
#include "anim/face_pose.h"
#include "anim/face_shapes.h"
#include "mesh/geometry.h"
#include "mesh/topology.h"
#include "project/export.h"
#include "project/gltf_scene.h"
#include "project/parts.h"
#include "project/pose.h"

#include "multires/multires.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <cmath>
#include <functional>
#include <map>

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

// The skeleton's joints, in the skin's order.
enum Joint { kNeck = 0, kHead, kLeftEye, kRightEye, kJaw, kJointCount };

// Each level-`level` head vertex's share of the Neck, Head and Jaw joints
// (they sum to 1). On the control mesh: the jaw's share is the muscle
// layer's (anim: the jaw's rigid motion, so turning the Jaw bone opens the
// mouth as jawOpen's rotation does); the neck region's vertices go from the
// Head at the head joint's height to the Neck at the neck's bottom
// (smoothstep; neck_y: the bottom ring's top), so turning the head bends
// the neck instead of swinging its cut; the rest is the Head's. Finer levels take the mean of their edge's
// two ends (linear, so the shares stay in [0, 1]).
std::vector<std::array<double, 3>> head_skin_weights(const MultiresMesh& mr, int level, const FaceRig& face,
                                                     const HeadAnnotations& annotations, double neck_y, double head_y) {
  const std::vector<Vec3>& control = mr.control;
  std::vector<std::array<double, 3>> w(control.size(), {0.0, 1.0, 0.0});  // neck, head, jaw
  for (std::size_t i = 0; i < face.jaw.index.size(); ++i) w[face.jaw.index[i]][2] = std::clamp(face.jaw.weight[i], 0.0, 1.0);
  const auto neck = annotations.regions.find("neck");
  if (neck != annotations.regions.end() && head_y > neck_y)
    for (int v : neck->second) {
      const double t = std::clamp((head_y - control[v].y()) / (head_y - neck_y), 0.0, 1.0);
      w[v][0] = std::min(t * t * (3 - 2 * t), 1.0 - w[v][2]);
    }
  for (auto& x : w) x[1] = 1.0 - x[0] - x[2];
  for (int l = 0; l < level && l < mr.num_levels(); ++l) {
    const ButterflyLevel& lv = mr.levels[l];
    w.resize(lv.num_fine_vertices);
    for (int k = 0; k < lv.num_new_vertices(); ++k)
      for (int j = 0; j < 3; ++j)
        w[lv.num_coarse_vertices + k][j] = 0.5 * (w[lv.edge_endpoints[k][0]][j] + w[lv.edge_endpoints[k][1]][j]);
  }
  return w;
}

// The control mesh's open neck: the centre of its boundary loops' vertices
// (the origin when it has none), and their highest y, below which the
// neck is all the Neck joint's.
struct NeckBottom {
  Vec3 center = Vec3::Zero();
  double top = 0;
};
NeckBottom neck_bottom(const TriMesh& control) {
  MeshTopology topo;
  NeckBottom out;
  Vec3 sum = Vec3::Zero();
  int n = 0;
  if (build_topology(control, topo).ok())
    for (const auto& loop : topo.boundary_loops)
      for (int v : loop) {
        sum += control.positions[v];
        out.top = n++ ? std::max(out.top, control.positions[v].y()) : control.positions[v].y();
      }
  if (n) out.center = sum / n;
  return out;
}

// A column-major 4x4 translation by -t: the inverse bind matrix of a joint
// at t whose ancestors only translate.
void inverse_bind(const Vec3& t, std::vector<float>& out) {
  const float m[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, float(-t.x()), float(-t.y()), float(-t.z()), 1};
  out.insert(out.end(), m, m + 16);
}

// A mesh node with morph targets, by their names.
struct MorphedNode {
  int node = -1;
  std::vector<std::string> targets;
};

// A joint the face's controls turn about its own origin (an eye's: the
// eyeball's centre), and how.
struct TurnedNode {
  int node = -1;
  std::function<Mat3(const FaceControls&)> turn;
};

// The clip's controls at time t (its shapes' weights summed into channels).
FaceControls clip_controls(const WeightClip& clip, double t) {
  const std::vector<double> weights = clip_weights(clip, t);
  std::map<std::string, double> named;
  for (std::size_t s = 0; s < clip.shapes.size(); ++s) named[clip.shapes[s]] += weights[s];
  FaceControls c;
  if (!face_controls_from_weights(named, c).ok()) c = FaceControls{};
  return c;
}

// Key times every 1/60 s over the clip (its own keys, at multiples of
// 0.1 s, among them): rotations between them are slerped (LINEAR), which
// follows the clip's smoothstep turns to about 0.06 degrees (at 30 keys a
// second: 0.23).
constexpr double kTurnRate = 60.0;

// Key times as an animation's input accessor (with the min and max glTF wants).
int time_input(GltfBuilder& w, const std::vector<float>& times) {
  const int input = w.accessor(times.data(), times.size() * 4, static_cast<int>(times.size()), TINYGLTF_COMPONENT_TYPE_FLOAT,
                               TINYGLTF_TYPE_SCALAR, 0);
  w.model.accessors.back().minValues = {double(times.front())};
  w.model.accessors.back().maxValues = {double(times.back())};
  return input;
}

// A channel of anim on node's path, its own sampler reading input and output.
void add_channel(tinygltf::Animation& anim, int input, int output, const char* interpolation, int node, const char* path) {
  tinygltf::AnimationSampler sampler;
  sampler.input = input;
  sampler.interpolation = interpolation;
  sampler.output = output;
  anim.samplers.push_back(sampler);
  tinygltf::AnimationChannel channel;
  channel.sampler = static_cast<int>(anim.samplers.size()) - 1;
  channel.target_node = node;
  channel.target_path = path;
  anim.channels.push_back(channel);
}

// The joints the clip turns, as `rotation` channels (LINEAR quaternions
// sampled at kTurnRate); their ids, into turned_out.
void add_turn_channels(GltfBuilder& w, const WeightClip& clip, const std::vector<TurnedNode>& turned,
                       tinygltf::Animation& anim, std::vector<int>& turned_out) {
  const int keys = static_cast<int>(std::lround(clip.duration() * kTurnRate)) + 1;
  if (keys < 2) return;
  std::vector<float> times(static_cast<std::size_t>(keys));
  std::vector<FaceControls> controls(times.size());
  for (std::size_t k = 0; k < times.size(); ++k) {
    const double t = std::min(static_cast<double>(k) / kTurnRate, clip.duration());
    times[k] = static_cast<float>(t);
    controls[k] = clip_controls(clip, t);
  }
  int input = -1;
  for (const TurnedNode& n : turned) {
    std::vector<float> q;
    bool moves = false;
    Eigen::Quaterniond prev = Eigen::Quaterniond::Identity();
    for (const FaceControls& c : controls) {
      Eigen::Quaterniond r(n.turn(c));
      r.normalize();
      if (r.dot(prev) < 0) r.coeffs() = -r.coeffs();  // the short way from the previous key
      prev = r;
      moves = moves || r.vec().norm() > 1e-6;
      q.insert(q.end(), {float(r.x()), float(r.y()), float(r.z()), float(r.w())});
    }
    if (!moves) continue;
    if (input < 0) input = time_input(w, times);
    const int output = w.accessor(q.data(), q.size() * 4, keys, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC4, 0);
    add_channel(anim, input, output, "LINEAR", n.node, "rotation");
    turned_out.push_back(n.node);
  }
}

// The clip as one glTF animation: the joints it turns (an eye's, in Gaze)
// as rotation channels, so tools that read the gaze from the bones see it;
// per other node whose targets include some of the clip's shapes, a
// `weights` channel (CUBICSPLINE: each key's in tangents, values and out
// tangents over all the mesh's targets; zero for the targets the clip does
// not drive), the key times shared. A turned node's own targets (the
// eyeball's eyeLook shapes, for tools that set single weights) are not
// also animated: the eye would turn twice. False when the clip moves nothing.
bool add_clip_animation(GltfBuilder& w, const WeightClip& clip, const std::vector<MorphedNode>& nodes,
                        const std::vector<TurnedNode>& turned) {
  tinygltf::Animation anim;
  anim.name = clip.name;
  std::vector<int> turned_nodes;
  add_turn_channels(w, clip, turned, anim, turned_nodes);
  int input = -1;
  const std::size_t keys = clip.times.size();
  for (const MorphedNode& n : nodes) {
    if (std::find(turned_nodes.begin(), turned_nodes.end(), n.node) != turned_nodes.end()) continue;
    std::vector<int> column(n.targets.size(), -1);  // target -> the clip's shape
    bool any = false;
    for (std::size_t t = 0; t < n.targets.size(); ++t)
      for (std::size_t s = 0; s < clip.shapes.size(); ++s)
        if (n.targets[t] == clip.shapes[s]) {
          column[t] = static_cast<int>(s);
          any = true;
        }
    if (!any || keys < 2) continue;
    if (input < 0) input = time_input(w, std::vector<float>(clip.times.begin(), clip.times.end()));
    const std::size_t m = n.targets.size();
    std::vector<float> out(3 * keys * m, 0.0f);
    for (std::size_t k = 0; k < keys; ++k)
      for (std::size_t t = 0; t < m; ++t) {
        if (column[t] < 0) continue;
        const std::size_t s = static_cast<std::size_t>(column[t]);
        out[(3 * k + 0) * m + t] = static_cast<float>(clip.slope[k][s]);  // in tangent
        out[(3 * k + 1) * m + t] = static_cast<float>(clip.value[k][s]);
        out[(3 * k + 2) * m + t] = static_cast<float>(clip.slope[k][s]);  // out tangent
      }
    const int output = w.accessor(out.data(), out.size() * 4, static_cast<int>(out.size()), TINYGLTF_COMPONENT_TYPE_FLOAT,
                                  TINYGLTF_TYPE_SCALAR, 0);
    add_channel(anim, input, output, "CUBICSPLINE", n.node, "weights");
  }
  if (anim.channels.empty()) return false;
  w.model.animations.push_back(anim);
  return true;
}

std::vector<std::string> names_of(const std::vector<MorphTarget>& targets) {
  std::vector<std::string> out;
  for (const MorphTarget& t : targets) out.push_back(t.name);
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
  const int head_mesh = w.mesh("HeadMesh", head.positions, head.normals, uvs, head.triangles, skin, head_targets);

  // The skeleton: Neck (at the neck's bottom) > Head (above it, at the jaw
  // hinge's height: where the skull turns on the spine) > LeftEye, RightEye,
  // Jaw; the head mesh is skinned to Neck, Head and Jaw and sits at the
  // root, as glTF wants of skinned meshes. Every node only translates; each
  // part mesh is in its node's frame.
  const Vec3 hinge = project.rig.jaw_pivot;
  const NeckBottom bottom = neck_bottom(project.fit.control);
  const Vec3 neck_at = bottom.center;
  const Vec3 head_at(neck_at.x(), hinge.y(), neck_at.z());
  HeadParts parts;
  const bool have_parts = place_head_parts(project.fit.control, generic, parts).ok();
  const Vec3 eye_at[2] = {have_parts ? parts.placement.eye_center[0] : head_at, have_parts ? parts.placement.eye_center[1] : head_at};
  const int neck = w.node("Neck", -1, neck_at);
  const int head_node = w.node("Head", -1, head_at - neck_at);
  add_child(model, neck, head_node);
  const char* eye_names[2] = {"LeftEye", "RightEye"};  // 0 = the head's left (+x)
  int eye_node[2];
  for (int e = 0; e < 2; ++e) {
    eye_node[e] = w.node(eye_names[e], -1, eye_at[e] - head_at);
    add_child(model, head_node, eye_node[e]);
  }
  const int jaw = w.node("Jaw", -1, hinge - head_at);
  add_child(model, head_node, jaw);
  {
    const Vec3 joint_at[kJointCount] = {neck_at, head_at, eye_at[0], eye_at[1], hinge};
    std::vector<float> ibm;
    for (const Vec3& t : joint_at) inverse_bind(t, ibm);
    tinygltf::Skin sk;
    sk.name = "HeadSkeleton";
    sk.joints = {neck, head_node, eye_node[0], eye_node[1], jaw};
    sk.skeleton = neck;
    sk.inverseBindMatrices = w.accessor(ibm.data(), ibm.size() * 4, kJointCount, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_MAT4, 0);
    // Four joint slots per vertex: the joints with a share, largest first,
    // then unused slots of joint 0 and weight 0 (as the validator wants);
    // the shares sum to 1.
    const auto share = head_skin_weights(project.fit.multires, level, face, generic.annotations, bottom.top, head_at.y());
    const int n = head.num_vertices();
    std::vector<std::uint8_t> joints(4 * static_cast<std::size_t>(n), 0);
    std::vector<float> weights(4 * static_cast<std::size_t>(n), 0.0f);
    for (int v = 0; v < n; ++v) {
      const float neck_w = static_cast<float>(share[v][0]);
      float jaw_w = static_cast<float>(share[v][2]);
      float head_w = 1.0f - neck_w - jaw_w;
      if (head_w < 0) {  // rounding: the jaw takes what the neck leaves
        head_w = 0;
        jaw_w = 1.0f - neck_w;
      }
      std::array<std::pair<float, std::uint8_t>, 3> slots = {{{neck_w, kNeck}, {head_w, kHead}, {jaw_w, kJaw}}};
      std::stable_sort(slots.begin(), slots.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
      for (int k = 0; k < 3 && slots[k].first > 0; ++k) {
        joints[4 * v + k] = slots[k].second;
        weights[4 * v + k] = slots[k].first;
      }
    }
    tinygltf::Primitive& prim = model.meshes[head_mesh].primitives[0];
    prim.attributes["JOINTS_0"] = w.accessor(joints.data(), joints.size(), n, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE,
                                             TINYGLTF_TYPE_VEC4, TINYGLTF_TARGET_ARRAY_BUFFER);
    prim.attributes["WEIGHTS_0"] = w.accessor(weights.data(), weights.size() * 4, n, TINYGLTF_COMPONENT_TYPE_FLOAT,
                                              TINYGLTF_TYPE_VEC4, TINYGLTF_TARGET_ARRAY_BUFFER);
    model.skins.push_back(sk);
  }
  const int head_mesh_node = w.node("HeadMesh", head_mesh);
  model.nodes[head_mesh_node].skin = 0;
  std::vector<MorphedNode> morphed = {{head_mesh_node, names_of(head_targets)}};
  std::vector<TurnedNode> turned;

  if (have_parts) {
    const int eye_mat = textured_material(w, "eye", options.eye_texture, {0.92, 0.92, 0.9, 1.0}, false);
    for (int e = 0; e < 2; ++e) {
      const TriMesh eye = about(parts.placed.eye[e], eye_at[e]);
      const std::vector<MorphTarget> turns = part_targets(shapes, parts.placed.eye[e].positions, [&](const FaceControls& fc) {
        return pose_eye(face, parts.placed.eye[e].positions, fc, e);
      });
      model.nodes[eye_node[e]].mesh = w.mesh(eye_names[e], eye.positions, eye.normals, eye.uvs, eye.triangles, eye_mat, turns);
      if (!turns.empty()) morphed.push_back({eye_node[e], names_of(turns)});
      // The joint turns about the eyeball's centre, its origin, as pose_eye does.
      turned.push_back({eye_node[e], [e](const FaceControls& c) { return eye_rotation(c, e); }});
    }
    const int teeth_mat = textured_material(w, "teeth", options.teeth_texture, {0.80, 0.74, 0.60, 1.0}, true);
    const int tongue_mat = w.material("tongue", -1, {0.55, 0.16, 0.16, 1.0}, 0.5);
    auto uv_if = [](const TriMesh& m, bool want) { return want && m.uvs.size() == m.positions.size() ? m.uvs : std::vector<Vec2>{}; };
    const bool teeth_tex = !options.teeth_texture.empty();
    const TriMesh upper = about(parts.upper_teeth, head_at);
    add_child(model, head_node, w.node("UpperTeeth", w.mesh("UpperTeeth", upper.positions, upper.normals, uv_if(upper, teeth_tex), upper.triangles, teeth_mat)));
    const TriMesh lower = about(parts.lower_teeth, hinge), tongue = about(parts.placed.tongue, hinge);
    // They move with the jaw (and the tongue out) under the head's target
    // names (the Jaw node also turns them, for tools that drive bones).
    const std::vector<MorphTarget> lower_targets = part_targets(shapes, parts.lower_teeth.positions, [&](const FaceControls& fc) {
      return pose_lower_teeth(face, parts.lower_teeth.positions, fc);
    });
    const std::vector<MorphTarget> tongue_targets = part_targets(shapes, parts.placed.tongue.positions, [&](const FaceControls& fc) {
      return pose_tongue(face, parts.placed.tongue.positions, fc);
    });
    const int lower_node = w.node("LowerTeeth", w.mesh("LowerTeeth", lower.positions, lower.normals, uv_if(lower, teeth_tex),
                                                       lower.triangles, teeth_mat, lower_targets));
    const int tongue_node = w.node("Tongue", w.mesh("Tongue", tongue.positions, tongue.normals, {}, tongue.triangles, tongue_mat,
                                                    tongue_targets));
    add_child(model, jaw, lower_node);
    add_child(model, jaw, tongue_node);
    if (!lower_targets.empty()) morphed.push_back({lower_node, names_of(lower_targets)});
    if (!tongue_targets.empty()) morphed.push_back({tongue_node, names_of(tongue_targets)});
  }

  std::vector<WeightClip> clips;
  if (options.animations) clips = weight_clips();
  if (!options.say.visemes.empty()) {
    WeightClip said;
    if (Status s = speech_clip(options.say, said); !s.ok()) return with_context(s, "the words to say");
    clips.push_back(std::move(said));
  }
  std::vector<std::string> animations;
  for (const WeightClip& clip : clips)
    if (add_clip_animation(w, clip, morphed, turned)) animations.push_back(clip.name);

  tinygltf::Scene scene;
  scene.name = "Likeness head";
  scene.nodes.push_back(neck);
  scene.nodes.push_back(head_mesh_node);
  model.scenes.push_back(scene);
  model.defaultScene = 0;
  if (report) {
    report->level = level;
    report->head_vertices = head.num_vertices();
    report->head_triangles = head.num_triangles();
    report->head_targets = static_cast<int>(head_targets.size());
    report->animations = animations;
    report->nodes.clear();
    for (const tinygltf::Node& n : model.nodes) report->nodes.push_back(n.name);
  }
  return write_glb(model, out);
}

}  // namespace lk
