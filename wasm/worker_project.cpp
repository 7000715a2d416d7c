// The worker's project-file jobs (core/project/project_file.h): the kept
// head project saved as a .likeness.glb's bytes, and such bytes opened as
// the kept project without fitting; and the GLB for avatar tools
// (core/project/glb_export.h).
#include "worker_common.h"

#include "anim/bake.h"
#include "anim/clips.h"
#include "anim/speech.h"
#include "anim/expression.h"
#include "project/glb_export.h"
#include "project/parts.h"
#include "project/pose.h"
#include "project/project_file.h"

namespace lk_worker {
namespace {

// The kept head project as a file (core/project/project_file.h: a GLB whose
// scene is the head, the project in its extras), with the eyes' and
// teeth's textures the page shows: parts {eyeTexture, eyeSource,
// teethTexture, teethSource} (image_object's form; a missing texture: the
// generic one) become the project's parts; inputs {photos: [{name, role,
// bytes (Uint8Array: the file as dropped), points (likeness-landmarks JSON
// text or '')}], pageOptions (a JSON object's text)} become what the file
// keeps of the page (project file version 3). Returns {ok, bytes}.
val save_project_job(val parts, val inputs) {
  if (!kept_project()) return error_result(lk::ErrorCode::InvalidInput, "no fitted head to save");
  lk::ProjectParts kept;
  const std::pair<const char*, std::pair<lk::Image*, std::string*>> from[2] = {
      {"eye", {&kept.eye_texture, &kept.eye_source}}, {"teeth", {&kept.teeth_texture, &kept.teeth_source}}};
  for (const auto& [name, into] : from) {
    const std::string key = std::string(name) + "Texture", source = std::string(name) + "Source";
    if (!has(parts, key.c_str()) || parts[key].isNull()) continue;
    if (lk::Status st = image_from_object(parts[key], *into.first); !st.ok())
      return error_result(lk::with_context(st, std::string(name) + " texture"));
    if (has(parts, source.c_str()) && parts[source].isString()) *into.second = parts[source].as<std::string>();
  }
  lk::ProjectInputs in;
  if (has(inputs, "photos")) {
    const val photos = inputs["photos"];
    const int n = photos["length"].as<int>();
    for (int i = 0; i < n; ++i) {
      const val ph = photos[i];
      lk::ProjectPhoto photo;
      if (!ph["name"].isString() || ph["bytes"].isUndefined())
        return error_result(lk::ErrorCode::InvalidInput, "photo " + std::to_string(i + 1) + " has no name or bytes");
      photo.name = ph["name"].as<std::string>();
      if (ph["role"].isString()) photo.role = ph["role"].as<std::string>();
      photo.bytes = emscripten::convertJSArrayToNumberVector<std::uint8_t>(ph["bytes"]);
      if (ph["points"].isString()) photo.points = ph["points"].as<std::string>();
      in.photos.push_back(std::move(photo));
    }
  }
  if (has(inputs, "pageOptions") && inputs["pageOptions"].isString()) in.page_options = inputs["pageOptions"].as<std::string>();
  kept_project()->parts = std::move(kept);
  // Kept only for this file: the worker's project goes on without them.
  struct Inputs {
    lk::HeadProject& p;
    ~Inputs() { p.inputs = {}; }
  } hold{*kept_project()};
  kept_project()->inputs = std::move(in);
  lk::Bytes bytes;
  if (lk::Status st = lk::save_project(*kept_project(), bytes); !st.ok()) return error_result(st);
  val r = ok_result();
  r.set("bytes", bytes_array(bytes.data(), bytes.size()));
  return r;
}

// The kept head as a GLB at level (glb_export.h), with the generic eyes'
// and teeth's textures unless parts gives {eyeTexture, teethTexture} (as
// image_object makes them) and, with a speech document (anim/speech.h,
// from web/js/speech.js), its "Say" clip as one more animation; the
// project is put at rest. Returns {ok, bytes, level, vertices}.
val export_glb_job(int level, val parts, std::string speech) {
  if (!kept_project()) return error_result(lk::ErrorCode::InvalidInput, "no fitted head to export");
  lk::Status generic_status;
  const lk::GenericHead* generic = generic_head(generic_status);
  if (!generic) return error_result(lk::with_context(generic_status, "generic head"));
  lk::GlbExportOptions o;
  o.level = level;
  if (!speech.empty())
    if (lk::Status st = lk::parse_speech_json(speech, o.say); !st.ok()) return error_result(lk::with_context(st, "the words to say"));
  lk::use_generic_part_textures(o);
  // The iris and teeth textures made from the user's eye and smile photos
  // replace the generic ones.
  if (has(parts, "eyeTexture") && !parts["eyeTexture"].isNull())
    if (lk::Status st = image_from_object(parts["eyeTexture"], o.eye_texture); !st.ok()) return error_result(lk::with_context(st, "eye texture"));
  if (has(parts, "teethTexture") && !parts["teethTexture"].isNull())
    if (lk::Status st = image_from_object(parts["teethTexture"], o.teeth_texture); !st.ok()) return error_result(lk::with_context(st, "teeth texture"));
  lk::Bytes bytes;
  lk::GlbExportReport report;
  if (lk::Status st = lk::export_glb(*kept_project(), *generic, o, bytes, &report); !st.ok()) return error_result(st);
  val r = ok_result();
  r.set("bytes", bytes_array(bytes.data(), bytes.size()));
  r.set("level", report.level);
  r.set("vertices", report.head_vertices);
  return r;
}

// A clip for the page: {name, shapes, times, values, slopes} (values and
// slopes key-major: [k * shapes + s]).
val clip_value(const lk::WeightClip& c) {
  val o = val::object();
  o.set("name", c.name);
  val names = val::array();
  for (const std::string& n : c.shapes) names.call<void>("push", n);
  o.set("shapes", names);
  std::vector<double> values, slopes;
  for (std::size_t k = 0; k < c.times.size(); ++k) {
    values.insert(values.end(), c.value[k].begin(), c.value[k].end());
    slopes.insert(slopes.end(), c.slope[k].begin(), c.slope[k].end());
  }
  o.set("times", typed_array("Float64Array", c.times));
  o.set("values", typed_array("Float64Array", values));
  o.set("slopes", typed_array("Float64Array", slopes));
  return o;
}

// The muscle layer's shapes (core/anim: 10 expressions, ARKit's 52, 15
// visemes) baked on the kept head at level (put at rest first), for
// morph-target playback: each shape's moved vertices and their offsets in
// the scan frame, and for a shape that moves the jaw its rigid motion in the
// scan frame (for the lower teeth and tongue; blended as I + sum w (M - I),
// as the GLB's morph targets on the teeth blend). Returns {ok, level,
// vertexCount, shapes: [{name, indices (Uint32Array), offsets (Float32Array,
// 3 per index), jawMatrix? (Float32Array, 4x4 column-major), eyeMatrices?
// ([left, right], the same, for the gaze shapes), tongueOffsets?
// (Float32Array, 3 per vertex of the components' tongue, scan frame: its
// push out before the jaw's motion, for the shapes with tongue out)}],
// clips (anim/clips.h: [{name, shapes, times, values, slopes}], values and
// slopes key-major: [k * shapes + s]: what Talk plays), lids ([[upper,
// lower] vertex of each eye's middle rim column]), bakeMs}.
val face_shapes_job(int level) {
  if (!kept_project()) return error_result(lk::ErrorCode::InvalidInput, "no fitted head to animate");
  lk::HeadProject& p = *kept_project();
  if (level < 0 || level > p.fit.multires.num_levels())
    return error_result(lk::ErrorCode::InvalidInput, "no level " + std::to_string(level));
  lk::Status generic_status;
  const lk::GenericHead* generic = generic_head(generic_status);
  if (!generic) return error_result(lk::with_context(generic_status, "generic head"));
  const double t0 = now_ms();
  lk::FaceRig rig;
  std::vector<lk::BakedShape> baked;
  lk::Status st = lk::rest_pose(p);
  if (st.ok()) st = lk::make_face_rig(p.fit.control, *generic, rig);
  if (st.ok()) st = lk::bake_face_shapes(rig, &p.fit.multires, level, {}, baked);
  if (!st.ok()) return error_result(st);
  const double bake_ms = now_ms() - t0;
  // The tongue as the components job places it (scan frame there), for
  // its push out, which bends it: no matrix can carry it.
  lk::HeadParts parts;
  const bool have_tongue = lk::place_head_parts(p.fit.control, *generic, parts).ok();
  val shapes = val::array();
  for (const lk::BakedShape& b : baked) {
    std::vector<std::uint32_t> indices;
    std::vector<float> offsets;
    // Offsets under a micrometre (head frame, metres) are left out: a third
    // of the moved vertices at level 3 of our synthetic fit, no visible
    // motion (a pixel is some 300 micrometres on a head filling 1000), and
    // each costs the morph targets' prepare and texture (two texels).
    for (std::size_t i = 0; i < b.level.size(); ++i)
      if (b.level[i].squaredNorm() >= 1e-12) {
        const lk::Vec3 d = p.frame.head_to_scan * b.level[i];
        indices.push_back(static_cast<std::uint32_t>(i));
        offsets.insert(offsets.end(), {static_cast<float>(d.x()), static_cast<float>(d.y()), static_cast<float>(d.z())});
      }
    val shape = val::object();
    shape.set("name", b.name);
    shape.set("indices", typed_array("Uint32Array", indices));
    shape.set("offsets", typed_array("Float32Array", offsets));
    // Head frame p -> R (p - h) + h + t, seen in the scan frame, column-major.
    const auto in_scan = [&](const lk::Mat3& R, const lk::Vec3& h, const lk::Vec3& t) {
      const lk::Mat3& H = p.frame.head_to_scan;
      const lk::Vec3 o = p.frame.head_offset;
      lk::Mat4 m = lk::Mat4::Identity();
      m.topLeftCorner<3, 3>() = H * R * H.inverse();
      m.topRightCorner<3, 1>() = H * (R * (o - h) + h + t - o);
      std::vector<float> flat(16);
      for (int col = 0; col < 4; ++col)
        for (int row = 0; row < 4; ++row) flat[4 * col + row] = static_cast<float>(m(row, col));
      return typed_array("Float32Array", flat);
    };
    lk::Mat3 R;
    lk::Vec3 t;
    lk::jaw_motion(rig, b.controls, R, t);
    if (!R.isIdentity() || t != lk::Vec3::Zero()) shape.set("jawMatrix", in_scan(R, rig.jaw.hinge, t));
    // The gaze (eyeLook*): each eyeball turned about its centre, as the
    // GLB's eye targets (pose_eye); eye 0 the left, 1 the right.
    const lk::Mat3 left = lk::eye_rotation(b.controls, 0), right = lk::eye_rotation(b.controls, 1);
    if (!left.isIdentity() || !right.isIdentity()) {
      val eyes = val::array();
      eyes.call<void>("push", in_scan(left, rig.lids[0].center, lk::Vec3::Zero()));
      eyes.call<void>("push", in_scan(right, rig.lids[1].center, lk::Vec3::Zero()));
      shape.set("eyeMatrices", eyes);
    }
    if (have_tongue && b.controls[lk::kTongueOut] > 0) {
      lk::FaceControls out_only;
      out_only[lk::kTongueOut] = b.controls[lk::kTongueOut];
      const std::vector<lk::Vec3>& rest = parts.placed.tongue.positions;
      const std::vector<lk::Vec3> pushed = lk::pose_tongue(rig, rest, out_only);
      std::vector<float> flat;
      for (std::size_t i = 0; i < rest.size(); ++i) {
        const lk::Vec3 d = p.frame.head_to_scan * (pushed[i] - rest[i]);
        flat.insert(flat.end(), {static_cast<float>(d.x()), static_cast<float>(d.y()), static_cast<float>(d.z())});
      }
      shape.set("tongueOffsets", typed_array("Float32Array", flat));
    }
    shapes.call<void>("push", shape);
  }
  val clips = val::array();
  for (const lk::WeightClip& c : lk::weight_clips()) clips.call<void>("push", clip_value(c));
  // Each eye's middle rim column, upper and lower lid vertex (control
  // vertices, which every level keeps first): the page measures the lid
  // gap with them, as the core's semantic checks do.
  val lids = val::array();
  for (int e = 0; e < 2; ++e) {
    const std::vector<int>& up = rig.landmarks.upper_lid[static_cast<std::size_t>(e)];
    const std::vector<int>& lo = rig.landmarks.lower_lid[static_cast<std::size_t>(e)];
    if (up.empty() || up.size() != lo.size()) continue;
    val pair = val::array();
    pair.call<void>("push", up[up.size() / 2]);
    pair.call<void>("push", lo[up.size() / 2]);
    lids.call<void>("push", pair);
  }
  val r = ok_result();
  r.set("level", level);
  r.set("vertexCount", p.fit.multires.num_vertices(level));
  r.set("shapes", shapes);
  r.set("lids", lids);
  r.set("clips", clips);
  r.set("bakeMs", bake_ms);
  return r;
}

// The kept head's muscle rig, made once per head: the rig is a function of
// the control mesh at rest, so one whose rest positions are the head's is
// the head's.
const lk::FaceRig* kept_face_rig(lk::HeadProject& p, lk::Status& status) {
  static lk::FaceRig rig;
  static bool made = false;
  if (made && rig.rest == p.fit.control.positions) return &rig;
  made = false;
  lk::Status generic_status;
  const lk::GenericHead* generic = generic_head(generic_status);
  if (!generic) {
    status = lk::with_context(generic_status, "generic head");
    return nullptr;
  }
  status = lk::make_face_rig(p.fit.control, *generic, rig);
  made = status.ok();
  return made ? &rig : nullptr;
}

// One frame of the live muscle path (issue 38): weights {name: w} (the
// shape names of face_shapes_job) pose the kept head's control mesh by the
// muscle layer and the levels up to `level` follow by the local update
// (anim/expression.h); the positions are read and the head is put back at
// rest exactly, so every other job sees it at rest. Returns {ok, level,
// positions (scan frame), vertexCount, changed (level vertices recomputed),
// poseMs (pose + local update), restMs (the way back)}.
val expression_frame_job(val weights, int level) {
  if (!kept_project()) return error_result(lk::ErrorCode::InvalidInput, "no fitted head to animate");
  lk::HeadProject& p = *kept_project();
  lk::MultiresMesh& mr = p.fit.multires;
  if (level < 0 || level > mr.num_levels())
    return error_result(lk::ErrorCode::InvalidInput, "no level " + std::to_string(level));
  std::map<std::string, double> w;
  const val names = val::global("Object").call<val>("keys", weights);
  for (int i = 0, n = names["length"].as<int>(); i < n; ++i) {
    const std::string name = names[i].as<std::string>();
    w[name] = weights[name].as<double>();
  }
  lk::Status st = lk::rest_pose(p);
  const lk::FaceRig* rig = st.ok() ? kept_face_rig(p, st) : nullptr;
  if (!rig) return error_result(st);
  lk::UpdateFootprint footprint;
  const double t0 = now_ms();
  st = lk::set_expression(mr, *rig, w, level, &footprint);
  const double pose_ms = now_ms() - t0;
  if (!st.ok()) return error_result(st);
  val r = ok_result();
  r.set("level", level);
  r.set("positions", float32_array(p.frame.to_scan(mr.state.displaced[level])));
  r.set("vertexCount", mr.num_vertices(level));
  r.set("changed", footprint.displaced_changed.empty() ? 0 : footprint.displaced_changed[level]);
  r.set("poseMs", pose_ms);
  const double t1 = now_ms();
  st = lk::set_expression(mr, *rig, {}, level);
  r.set("restMs", now_ms() - t1);
  if (!st.ok()) return error_result(st);
  return r;
}

// A saved project's bytes -> the kept project (at rest), without fitting.
// Returns what fit_head_job does (stages: the saved figures, ms 0) and
// scan {positions (scan frame), vertexCount}, texture {uvs, skin, level}
// when textured, loadMs. A refused file leaves the kept project as it was.
val load_project_job(const std::string& name, std::uintptr_t data, std::size_t size) {
  if (data == 0 && size != 0) return error_result(lk::ErrorCode::Internal, name + ": no input buffer");
  const double t0 = now_ms();
  auto project = std::make_unique<lk::HeadProject>();
  lk::Status st = lk::load_project(reinterpret_cast<const std::uint8_t*>(data), size, *project);
  if (st.ok()) st = lk::rest_pose(*project);
  if (!st.ok()) return error_result(lk::with_context(st, name));
  lk::Status generic_status;
  const lk::GenericHead* generic = generic_head(generic_status);
  if (!generic) return error_result(lk::with_context(generic_status, "generic head"));
  const lk::HeadProject& p = *project;
  val r = head_result(p, *generic);
  r.set("name", name);
  val stages = val::array();
  for (const lk::FitStageReport& s : p.fit.stages) {
    val o = stats_object(s.distance);
    o.set("name", s.name);
    o.set("ms", 0);
    stages.call<void>("push", o);
  }
  r.set("stages", stages);
  val scan = val::object();
  scan.set("positions", float32_array(p.scan.positions));
  scan.set("vertexCount", static_cast<double>(p.scan.positions.size()));
  r.set("scan", scan);
  if (!p.texture.empty()) {
    val t = val::object();
    t.set("uvs", float32_array(p.texture.uvs));
    t.set("skin", image_object(p.texture.skin));
    t.set("level", p.fit.multires.num_levels());
    r.set("texture", t);
  }
  // The eyes' and teeth's textures made from photos, when it keeps them.
  val parts = val::object();
  if (!p.parts.eye_texture.empty()) {
    parts.set("eyeTexture", image_object(p.parts.eye_texture));
    parts.set("eyeSource", p.parts.eye_source);
  }
  if (!p.parts.teeth_texture.empty()) {
    parts.set("teethTexture", image_object(p.parts.teeth_texture));
    parts.set("teethSource", p.parts.teeth_source);
  }
  r.set("parts", parts);
  // The photos and the page's options it keeps (version 3), for the page to
  // put back; the worker's project keeps none of them.
  val in = val::object();
  val photos = val::array();
  for (const lk::ProjectPhoto& ph : p.inputs.photos) {
    val o = val::object();
    o.set("name", ph.name);
    o.set("role", ph.role);
    o.set("bytes", bytes_array(ph.bytes.data(), ph.bytes.size()));
    o.set("points", ph.points);
    photos.call<void>("push", o);
  }
  in.set("photos", photos);
  in.set("pageOptions", p.inputs.page_options);
  r.set("inputs", in);
  project->inputs = {};
  r.set("loadMs", now_ms() - t0);
  kept_project() = std::move(project);
  return r;
}

// Typed words, as the page's speech document (anim/speech.h), as a clip
// the page's Talk plays (anim/clips.h speech_clip): {ok, clip}, or the
// reason there is nothing to say.
val say_clip_job(std::string speech) {
  lk::Speech said;
  lk::WeightClip clip;
  lk::Status st = lk::parse_speech_json(speech, said);
  if (st) st = lk::speech_clip(said, clip);
  if (!st.ok()) return error_result(st);
  val r = ok_result();
  r.set("clip", clip_value(clip));
  return r;
}

}  // namespace
}  // namespace lk_worker

EMSCRIPTEN_BINDINGS(likeness_worker_project) {
  using namespace lk_worker;
  emscripten::function("save_project_job", &save_project_job);
  emscripten::function("load_project_job", &load_project_job);
  emscripten::function("export_glb_job", &export_glb_job);
  emscripten::function("face_shapes_job", &face_shapes_job);
  emscripten::function("say_clip_job", &say_clip_job);
  emscripten::function("expression_frame_job", &expression_frame_job);
}
