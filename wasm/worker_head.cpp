// The worker's head-project jobs (core/project): fit, animation, checks,
// exports; the project is kept here between calls.
#include "worker_common.h"

#include "project/export.h"
#include "project/fit_job.h"
#include "project/parts.h"
#include "project/pose.h"
#include "project/quality_job.h"

#include <algorithm>

namespace lk_worker {

std::unique_ptr<lk::HeadProject>& kept_project() {
  static std::unique_ptr<lk::HeadProject> kept;
  return kept;
}

const lk::GenericHead* generic_head(lk::Status& status) {
  static lk::GenericHead generic;  // parsed once per worker
  static bool have_generic = false;
  status = lk::Status::success();
  if (!have_generic) {
    status = lk::load_generic_head(generic);
    if (!status.ok()) return nullptr;
    have_generic = true;
  }
  return &generic;
}

namespace {

// {positions, indices, vertexCount, triangleCount} of a head-frame mesh, in
// the scan frame. Normals are left to the viewer (area-weighted on upload).
val mesh_arrays(const lk::HeadFrame& frame, const std::vector<lk::Vec3>& positions, const std::vector<lk::Tri>& tris) {
  val m = val::object();
  m.set("positions", float32_array(frame.to_scan(positions)));
  m.set("indices", uint32_array(tris));
  m.set("vertexCount", static_cast<double>(positions.size()));
  m.set("triangleCount", static_cast<double>(tris.size()));
  return m;
}


// A component mesh {positions, indices, uvs?, colors?}: uvs when textured,
// else one linear RGB colour for every vertex.
val component_arrays(const lk::HeadFrame& frame, const lk::TriMesh& m, const lk::Vec3* color) {
  val o = mesh_arrays(frame, m.positions, m.triangles);
  if (m.uvs.size() == m.positions.size() && !color) o.set("uvs", float32_array(m.uvs));
  if (color) o.set("colors", float32_array(std::vector<lk::Vec3>(m.positions.size(), *color)));
  return o;
}

// The generic teeth texture, made once per worker; empty if that ever
// fails. made_ms: the time it took (0 after the first call).
const lk::Image& generic_teeth_texture(double& made_ms) {
  made_ms = 0;
  static const lk::Image texture = [&made_ms] {
    const double t0 = now_ms();
    lk::Image t;
    if (!lk::generic_teeth_texture(teeth_composite(), t).ok()) t = lk::Image{};
    made_ms = now_ms() - t0;
    return t;
  }();
  return texture;
}

// The generic eyeballs, teeth and tongue placed in the fitted head
// (tarini2002 Sec. 4), scan frame, at rest; the lower teeth and the tongue
// follow the jaw through animate_frame's jawMatrix. Null when they cannot
// be placed.
val components_object(const lk::HeadProject& p, const lk::GenericHead& generic) {
  lk::HeadParts parts;
  if (!lk::place_head_parts(p.fit.control, generic, parts).ok()) return val::null();
  val o = val::object();
  val eyes = val::array();
  for (const lk::TriMesh& eye : parts.placed.eye) eyes.call<void>("push", component_arrays(p.frame, eye, nullptr));
  o.set("eyes", eyes);
  const lk::Vec3 ivory(0.80, 0.74, 0.60), tongue_pink(0.55, 0.16, 0.16);  // linear RGB
  // Textured teeth when the generic teeth texture exists, ivory otherwise;
  // voids are transparent (alpha 0): the renderer alpha-tests.
  double teeth_ms = 0;
  const lk::Image& teeth_tex = generic_teeth_texture(teeth_ms);
  const lk::Vec3* teeth_color = teeth_tex.empty() ? &ivory : nullptr;
  o.set("teeth", component_arrays(p.frame, parts.upper_teeth, teeth_color));
  o.set("lowerTeeth", component_arrays(p.frame, parts.lower_teeth, teeth_color));
  if (!teeth_tex.empty()) o.set("teethTexture", image_object(teeth_tex));
  o.set("teethTextureMs", teeth_ms);
  o.set("tongue", component_arrays(p.frame, parts.placed.tongue, &tongue_pink));
  lk::Image eye_texture;
  lk::EyeballTextureOptions eto;
  eto.size = 256;  // as the generic eyes
  if (lk::generic_eyeball_texture(eto, eye_texture).ok()) o.set("eyeTexture", image_object(eye_texture));
  return o;
}

// Runs the whole fit (jeong2002 Sec. 4-5) on a dropped scan's bytes.
// options: {levels, up:[x,y,z], facing:[x,y,z]} (all optional).
// progress(stage, fraction) with stage one of initial_alignment,
// local_fitting, global_fitting, subdivision; returning false cancels.
// The result carries untangle {pairsBefore, pairsEroded, pairsAfter,
// restoreSteps} (pipeline/untangle.h), headFacing and headUp (the head's +z
// and +y in the scan's frame: the page's view looks at the face with them),
// the texture landmarks and the placed components.
val fit_cloud(const std::string& name, lk::PointCloud cloud, double parse_ms, val options, val progress);

val fit_head_job(const std::string& name, std::uintptr_t data, std::size_t size, val options, val progress) {
  if (data == 0 && size != 0) return error_result(lk::ErrorCode::Internal, name + ": no input buffer");
  const double t_parse = now_ms();
  lk::TriMesh mesh;
  lk::PointCloud cloud;
  lk::GeometryKind kind = lk::GeometryKind::PointCloud;
  lk::Status status = lk::read_geometry(name, reinterpret_cast<const std::uint8_t*>(data), size, mesh, cloud, kind);
  if (!status.ok()) return error_result(lk::with_context(status, name));
  // A mesh scan is fitted through its vertices; its triangles (in `cloud`
  // too) are sampled for the displacements, as in the CLI.
  mesh = lk::TriMesh{};
  return fit_cloud(name, std::move(cloud), now_ms() - t_parse, options, progress);
}

// The same on the scan web/worker.js has pushed in slices (scan_stream()):
// the mesh's arrays move into the cloud, so the vertices are held once.
val fit_head_stream_job(val options, val progress) {
  if (!scan_stream()) return error_result(lk::ErrorCode::Internal, "no scan is being read");
  std::unique_ptr<lk::ScanStreamReader> reader = std::move(scan_stream());
  const std::string name = has(options, "name") ? options["name"].as<std::string>() : std::string("scan");
  const double t_parse = now_ms();
  lk::TriMesh mesh;
  lk::GeometryKind kind = lk::GeometryKind::PointCloud;
  const lk::Status status = reader->finish(mesh, kind);
  reader.reset();
  if (!status.ok()) return error_result(lk::with_context(status, name));
  lk::PointCloud cloud;
  cloud.positions = std::move(mesh.positions);
  if (mesh.normals.size() == cloud.positions.size()) cloud.normals = std::move(mesh.normals);
  if (mesh.colors.size() == cloud.positions.size()) cloud.colors = std::move(mesh.colors);
  cloud.faces = std::move(mesh.triangles);
  mesh = lk::TriMesh{};
  return fit_cloud(name, std::move(cloud), now_ms() - t_parse, options, progress);
}

// Runs fit (a fit_project or refit_project call making the new project)
// with the page's stage reporting; on success the new project is kept and
// returned as head_result with name, parseMs, fitMs and the stages.
template <class Fit>
val run_fit(const std::string& name, double parse_ms, val progress, Fit fit) {
  const lk::ProgressFn report = js_progress(progress);
  lk::Status generic_status;
  const lk::GenericHead* generic = generic_head(generic_status);
  if (!generic) return error_result(lk::with_context(generic_status, "generic head"));

  // Stage timing and stats through the observer; progress fractions from the
  // stages' own ProgressFn are attributed to the stage the observer opened.
  val stages = val::array();
  std::string current;
  double t_stage = 0;
  val stage_ms = val::object();
  lk::FitStageObserver observer;
  observer.started = [&](const std::string& stage) {
    current = stage;
    lk::report(report, stage.c_str(), 0.0);
    t_stage = now_ms();
  };
  observer.finished = [&](const std::string& stage, const lk::TriMesh&) {
    stage_ms.set(stage, now_ms() - t_stage);
    lk::report(report, stage.c_str(), 1.0);
  };
  // A stage measured again (global_fitting, when the guard moved the control
  // mesh after it) replaces its first figures.
  observer.measured = [&](const lk::FitStageReport& r) {
    val o = stats_object(r.distance);
    o.set("name", r.name);
    o.set("ms", stage_ms[r.name]);
    const int n = stages["length"].as<int>();
    for (int i = 0; i < n; ++i)
      if (stages[i]["name"].as<std::string>() == r.name) {
        stages.set(i, o);
        return;
      }
    stages.call<void>("push", o);
  };
  const lk::ProgressFn inner = [&](const char*, double fraction) {
    if (current.empty()) return true;
    return lk::report(report, current.c_str(), std::min(0.99, std::max(0.0, fraction)));
  };

  auto project = std::make_unique<lk::HeadProject>();
  const double t_fit = now_ms();
  const lk::Status status = fit(*generic, *project, observer, inner);
  const double fit_ms = now_ms() - t_fit;
  if (!status.ok()) return error_result(lk::with_context(status, name));
  val r = head_result(*project, *generic);
  r.set("name", name);
  r.set("parseMs", parse_ms);
  r.set("fitMs", fit_ms);
  r.set("stages", stages);
  kept_project() = std::move(project);
  return r;
}

// options[key], when given, as three numbers into out: false when it is not
// three numbers making a direction.
bool vec3_option(const val& options, const char* key, lk::Vec3& out) {
  if (!has(options, key) || options[key].isNull()) return true;
  const val v = options[key];
  if (v["length"].as<int>() != 3) return false;
  lk::Vec3 read;
  for (int k = 0; k < 3; ++k) read[k] = v[k].as<double>();
  if (!read.allFinite() || !(read.norm() > 0)) return false;
  out = read;
  return true;
}

val fit_cloud(const std::string& name, lk::PointCloud cloud, double parse_ms, val options, val progress) {
  lk::FitHeadOptions opt;
  if (has(options, "levels")) opt.levels = options["levels"].as<int>();
  // A dense cloud on cell averages (FitHeadOptions::thin_cells_per_edge, off
  // by default): the page's ?thin=X.
  if (has(options, "thinCells")) opt.thin_cells_per_edge = options["thinCells"].as<double>();
  if (!(opt.thin_cells_per_edge >= 0 && opt.thin_cells_per_edge <= 64))
    return error_result(lk::ErrorCode::InvalidInput, "thinCells must be 0..64");
  if (!vec3_option(options, "up", opt.up) || !vec3_option(options, "facing", opt.facing))
    return error_result(lk::ErrorCode::InvalidInput, "up and facing take three numbers");
  if (opt.levels < 1 || opt.levels > 4) return error_result(lk::ErrorCode::InvalidInput, "levels must be 1..4");
  return run_fit(name, parse_ms, progress,
                 [&](const lk::GenericHead& generic, lk::HeadProject& project, const lk::FitStageObserver& observer,
                     const lk::ProgressFn& inner) {
                   return lk::fit_project(std::move(cloud), generic, opt, project, observer, inner);
                 });
}

// Fits the kept head's scan again (a head opened from a project file keeps
// its scan's points, not the file) with the options it was fitted with.
// options: {levels (1..4), up, facing (three numbers each)}, each optional:
// else the kept head's. Returns what fit_head_job does; on an error the
// kept head stays.
val refit_kept_scan_job(val options, val progress) {
  if (!kept_project()) return error_result(lk::ErrorCode::InvalidInput, "no fitted head to fit again");
  const lk::HeadProject& kept = *kept_project();
  lk::RefitChanges changes;
  changes.levels = has(options, "levels") ? options["levels"].as<int>() : 0;
  if (changes.levels < 0 || changes.levels > 4) return error_result(lk::ErrorCode::InvalidInput, "levels must be 1..4");
  lk::Vec3 up = kept.options.up, facing = kept.options.facing;
  if (!vec3_option(options, "up", up) || !vec3_option(options, "facing", facing))
    return error_result(lk::ErrorCode::InvalidInput, "up and facing take three numbers");
  changes.up = up;
  changes.facing = facing;
  const std::string name = has(options, "name") ? options["name"].as<std::string>() : std::string("the kept scan");
  return run_fit(name, 0, progress,
                 [&](const lk::GenericHead& generic, lk::HeadProject& project, const lk::FitStageObserver& observer,
                     const lk::ProgressFn& inner) {
                   return lk::refit_project(kept, generic, changes, project, observer, inner);
                 });
}

// A small fit whose only purpose is to run the fit's code once, in a
// throw-away worker (web/worker.js ?warmup=1), so V8's optimizing tier has
// compiled it before the user's fit (docs/journal.md). The input is the generic
// head itself (its vertices and triangle centroids as a point cloud); the
// result is discarded and the kept project untouched.
// Returns {ok, code, message, points, fitMs}.
val warm_up_job(int levels) {
  lk::Status status;
  const lk::GenericHead* generic = generic_head(status);
  if (!generic) return error_result(lk::with_context(status, "generic head"));
  lk::PointCloud cloud;
  const std::vector<lk::Vec3>& P = generic->mesh.positions;
  cloud.positions = P;
  for (const lk::Tri& t : generic->mesh.triangles) cloud.positions.push_back((P[t[0]] + P[t[1]] + P[t[2]]) / 3.0);
  lk::FitHeadOptions opt;
  opt.levels = std::min(4, std::max(1, levels));
  lk::FitHeadResult discarded;
  const double t0 = now_ms();
  status = lk::fit_head(cloud, *generic, opt, discarded);
  if (!status.ok()) return error_result(lk::with_context(status, "warm-up"));
  val r = ok_result();
  r.set("points", static_cast<double>(cloud.positions.size()));
  r.set("fitMs", now_ms() - t0);
  return r;
}

// The jaw's motion as a column-major 4x4 Float32Array (scan frame).
val jaw_matrix(const lk::HeadProject& p, double amount) {
  const lk::Mat4 m = lk::jaw_motion(p, amount);
  std::vector<float> flat(16);
  for (int col = 0; col < 4; ++col)
    for (int row = 0; row < 4; ++row) flat[4 * col + row] = static_cast<float>(m(row, col));
  return typed_array("Float32Array", flat);
}

// One animation frame on the kept head: brows up and jaw open by `amount`
// in [0, 1] (core/project/pose.h), updated only up to the level shown: an
// animation drawn at level 1 does not pay for level 3.
// Returns {ok, level, positions (scan frame), updateMs, changed, vertexCount, jawMatrix}.
val animate_frame(double amount, int level) {
  if (!kept_project()) return error_result(lk::ErrorCode::InvalidInput, "no fitted head to animate");
  lk::HeadProject& p = *kept_project();
  const lk::MultiresMesh& mr = p.fit.multires;
  if (level < 0 || level > mr.num_levels())
    return error_result(lk::ErrorCode::InvalidInput, "no level " + std::to_string(level));
  amount = lk::clamp_pose_amount(amount);
  const double t0 = now_ms();
  lk::UpdateFootprint footprint;
  const lk::Status st = lk::pose_project(p, amount, level, &footprint);
  const double update_ms = now_ms() - t0;
  if (!st.ok()) return error_result(st);
  val r = ok_result();
  r.set("level", level);
  r.set("positions", float32_array(p.frame.to_scan(mr.state.displaced[level])));
  r.set("updateMs", update_ms);
  r.set("changed", footprint.displaced_changed.empty() ? 0 : footprint.displaced_changed[level]);
  r.set("vertexCount", mr.num_vertices(level));
  r.set("jawMatrix", jaw_matrix(p, amount));
  return r;
}

// {total, lips, ears, eyeSockets, rest} of a CrossingCounts.
val crossings_object(const lk::CrossingCounts& c) {
  val o = val::object();
  o.set("total", c.total);
  o.set("lips", c.lips);
  o.set("ears", c.ears);
  o.set("eyeSockets", c.eye_sockets);
  o.set("rest", c.rest);
  return o;
}

// The checks `likeness fit` prints after Table 1 (core/project/quality_job.h),
// separate from the fit so the page shows the fit first; measured on the
// first call, later calls return the same numbers.
// Returns {ok, level, triangles, flipped, degenerate, crossings, smoothCrossings
// ({total, lips, ears, eyeSockets, rest}), controlCrossings, checkMs}, and
// faceToScan {to: "triangles"|"points", vertices, meanMm, p99Mm, maxMm,
// colors (#V_L * 3 linear RGB)} where it could be measured.
val fit_quality_job() {
  static double check_ms = 0;
  if (!kept_project()) return error_result(lk::ErrorCode::InvalidInput, "no fitted head to check");
  lk::HeadProject& p = *kept_project();
  if (!p.quality.measured) {
    const double t0 = now_ms();
    lk::Status generic_status;
    const lk::GenericHead* generic = generic_head(generic_status);
    if (!generic) return error_result(lk::with_context(generic_status, "generic head"));
    if (lk::Status st = lk::measure_project_quality(p, *generic); !st.ok()) return error_result(st);
    check_ms = now_ms() - t0;
  }
  const lk::ProjectQuality& pq = p.quality;
  if (!pq.status.ok()) return error_result(pq.status);
  const lk::FitQuality& q = pq.fit;
  val r = ok_result();
  r.set("level", q.level);
  r.set("triangles", q.triangles);
  r.set("flipped", q.flipped);
  r.set("degenerate", q.degenerate);
  r.set("crossings", crossings_object(q.crossings));
  r.set("smoothCrossings", crossings_object(q.smooth_crossings));
  r.set("controlCrossings", q.control_crossings);
  if (pq.to_scan_status.ok()) {
    val d = val::object();
    d.set("to", std::string(pq.to_scan.to_points ? "points" : "triangles"));
    d.set("vertices", pq.to_scan.vertices);
    d.set("meanMm", 1e3 * pq.to_scan.mean);
    d.set("p99Mm", 1e3 * pq.to_scan.p99);
    d.set("maxMm", 1e3 * pq.to_scan.max);
    d.set("colors", float32_array(pq.to_scan_colors));
    r.set("faceToScan", d);
  }
  r.set("checkMs", check_ms);
  return r;
}

// The kept head as a file, scan frame: level `level` (0 = control mesh) of
// the current pose as "obj" text or binary "ply"; "map": the checks'
// distance map as a coloured binary PLY (the finest level at rest, as
// likeness fit's face_to_scan.ply). Returns {ok, bytes}.
val export_head(int level, const std::string& format) {
  if (!kept_project()) return error_result(lk::ErrorCode::InvalidInput, "no fitted head to export");
  lk::LevelFormat f = lk::LevelFormat::Obj;
  if (format == "ply") f = lk::LevelFormat::Ply;
  else if (format == "map") f = lk::LevelFormat::DistanceMap;
  else if (format != "obj") {
    if (level < 0 || level > kept_project()->fit.multires.num_levels())
      return error_result(lk::ErrorCode::InvalidInput, "no level " + std::to_string(level));
    return error_result(lk::ErrorCode::InvalidInput, "unknown format " + format);
  }
  lk::Bytes bytes;
  if (lk::Status st = lk::export_level(*kept_project(), level, f, lk::ExportFrame::Scan, bytes); !st.ok())
    return error_result(st);
  val r = ok_result();
  r.set("bytes", bytes_array(bytes.data(), bytes.size()));
  return r;
}

// The textured head as three files: level `level` with the texture's uvs
// (OBJ, "mtllib <base>.mtl"), the material (map_Kd <base>.png) and the skin
// PNG. Current pose, scan frame. Returns {ok, obj, mtl, png} (Uint8Arrays).
val export_textured(int level, const std::string& base) {
  if (!kept_project()) return error_result(lk::ErrorCode::InvalidInput, "no fitted head to export");
  lk::TexturedFiles files;
  if (lk::Status st = lk::export_textured(*kept_project(), level, base, lk::ExportFrame::Scan, files); !st.ok())
    return error_result(st);
  val r = ok_result();
  r.set("obj", bytes_array(files.obj));
  r.set("mtl", bytes_array(files.mtl));
  r.set("png", bytes_array(files.png.data(), files.png.size()));
  return r;
}

}  // namespace

val stats_object(const lk::DistanceStats& d) {
  val o = val::object();
  o.set("meanPct", d.mean_pct);
  o.set("maxPct", d.max_pct);
  o.set("rmsPct", d.mean != 0 ? d.rms / d.mean * d.mean_pct : 0.0);
  o.set("points", d.count);
  return o;
}

// What the page shows of a head project, for a fit and an opened project
// alike: {points, fittedPoints, thinnedTo, unitToMetres, notes, headFacing, headUp,
// untangle, meshes {aligned, local, control, levels}, animatedVertices,
// landmarks, components}.
val head_result(const lk::HeadProject& p, const lk::GenericHead& generic) {
  const lk::FitHeadResult& fit = p.fit;
  val r = ok_result();
  r.set("points", fit.points);
  r.set("fittedPoints", fit.fitted_points);
  // A dense cloud fitted on cell averages (FitHeadOptions::thin_cells_per_edge):
  // how many; 0 when every point was fitted. The notes say it in words.
  r.set("thinnedTo", fit.thinning.thinned ? fit.thinning.kept : 0);
  r.set("unitToMetres", fit.unit_to_metres);
  // What the fit decided on its own (the scan turned to face +z, a face-only
  // capture, a unit guessed): `likeness fit` prints these as "note:" lines.
  val notes = val::array();
  for (const std::string& note : fit.notes) notes.call<void>("push", note);
  r.set("notes", notes);
  r.set("headFacing", vec3_array(p.frame.head_to_scan * lk::Vec3(0, 0, 1)));
  r.set("headUp", vec3_array(p.frame.head_to_scan * lk::Vec3(0, 1, 0)));
  val untangle = val::object();
  untangle.set("pairsBefore", fit.untangle.pairs_before);
  untangle.set("pairsEroded", fit.untangle.pairs_eroded);
  untangle.set("pairsAfter", fit.untangle.pairs_after);
  untangle.set("restoreSteps", fit.untangle.restore_steps);
  r.set("untangle", untangle);
  val meshes = val::object();
  meshes.set("aligned", mesh_arrays(p.frame, fit.aligned.positions, fit.aligned.triangles));
  meshes.set("local", mesh_arrays(p.frame, fit.local.positions, fit.local.triangles));
  meshes.set("control", mesh_arrays(p.frame, fit.control.positions, fit.control.triangles));
  val levels = val::array();
  for (const lk::TriMesh& m : fit.level_meshes) levels.call<void>("push", mesh_arrays(p.frame, m.positions, m.triangles));
  meshes.set("levels", levels);
  r.set("meshes", meshes);
  r.set("animatedVertices", static_cast<double>(p.rig.moved.size()));
  // Texture landmarks where they are on the fitted surface (finest level,
  // rest pose, scan frame): control vertices keep their index on every level.
  val landmarks = val::array();
  const std::vector<lk::Vec3>& finest = fit.level_meshes.back().positions;
  for (const lk::TextureLandmark& l : lk::texture_landmarks(generic)) {
    if (l.vertex >= static_cast<int>(finest.size())) continue;
    val o = val::object();
    o.set("id", std::string(l.id));
    o.set("label", std::string(l.label));
    o.set("vertex", l.vertex);
    o.set("position", vec3_array(p.frame.to_scan(finest[l.vertex])));
    landmarks.call<void>("push", o);
  }
  r.set("landmarks", landmarks);
  r.set("components", components_object(p, generic));
  return r;
}

}  // namespace lk_worker

EMSCRIPTEN_BINDINGS(likeness_worker_head) {
  using namespace lk_worker;
  emscripten::function("fit_head_job", &fit_head_job);
  emscripten::function("fit_head_stream_job", &fit_head_stream_job);
  emscripten::function("refit_kept_scan_job", &refit_kept_scan_job);
  emscripten::function("warm_up_job", &warm_up_job);
  emscripten::function("animate_frame", &animate_frame);
  emscripten::function("fit_quality_job", &fit_quality_job);
  emscripten::function("export_head", &export_head);
  emscripten::function("export_textured", &export_textured);
}
