// Embind surface of likeness_worker.wasm: the core's long-running jobs, run
// inside a Web Worker (web/worker.js) so the page stays responsive.
//
// Calling convention (kept the same for every job so later stages follow it):
//   - input bytes are copied by JS into this module's heap (_malloc) and passed
//     as (pointer, size); the job never keeps them after it returns;
//   - a job returns a plain JS object {ok, code, message, ...}; errors are
//     values (lk::Status), nothing is thrown across the boundary;
//   - long jobs take a JS progress function (stage, fraction) -> bool|undefined;
//     returning false cancels (lk::ProgressFn semantics, core/common/progress.h).
//
// Arrays handed back are fresh JS typed arrays (copies), so JS may transfer
// them to the main thread while this heap is reused:
//   positions Float32Array  #V*3      normals Float32Array #V*3 (or length 0)
//   colors    Float32Array  #V*3 or 0 indices Uint32Array  #F*3 (0 for points)
//
// Jobs: parse_geometry (a dropped scan), check_image (a dropped photo),
// parse_points (a photo's points file), fit_head_job (scan -> fitted
// multiresolution head, jeong2002 Sec. 4-5, with the texture landmarks'
// places), then, on the fitted head kept in this worker: fit_quality_job
// (the finest level's checks, as `likeness fit` prints them), animate_frame
// (Sec. 6 local update), export_head (OBJ/PLY bytes), texture_job (photos +
// correspondences -> cameras, chart, skin texture; tarini2002 Sec. 3) and
// export_textured (OBJ + MTL + PNG); eye_photo_job and smile_photo_job
// (tarini2002 Sec. 4: iris and teeth textures from the user's photos).
#include "common/helper_thread.h"
#include "common/parallel.h"
#include "common/progress.h"
#include "components/components.h"
#include "head/generic_head.h"
#include "iris/iris.h"
#include "io/io.h"
#include "mesh/geometry.h"
#include "pipeline/fit_head.h"
#include "pipeline/fit_quality.h"
#include "teeth/synthetic_smile.h"
#include "teeth/teeth.h"
#include "texture/correspondences.h"
#include "texture/refine_uv.h"
#include "texture/texture.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>

#include <emscripten/bind.h>
#include <emscripten/val.h>

#include <cstdint>
#include <string>
#include <vector>

namespace {

using emscripten::val;

val float32_array(const std::vector<lk::Vec3>& v) {
  std::vector<float> flat(v.size() * 3);
  for (size_t i = 0; i < v.size(); ++i)
    for (int k = 0; k < 3; ++k) flat[3 * i + k] = static_cast<float>(v[i][k]);
  // new Float32Array(view) copies out of the wasm heap.
  return val::global("Float32Array").new_(emscripten::typed_memory_view(flat.size(), flat.data()));
}

val uint32_array(const std::vector<lk::Tri>& tris) {
  std::vector<std::uint32_t> flat(tris.size() * 3);
  for (size_t i = 0; i < tris.size(); ++i)
    for (int k = 0; k < 3; ++k) flat[3 * i + k] = static_cast<std::uint32_t>(tris[i][k]);
  return val::global("Uint32Array").new_(emscripten::typed_memory_view(flat.size(), flat.data()));
}

val vec3_array(const lk::Vec3& p) {
  val a = val::array();
  for (int k = 0; k < 3; ++k) a.call<void>("push", p[k]);
  return a;
}

val error_result(const lk::Status& s) {
  val r = val::object();
  r.set("ok", false);
  r.set("code", std::string(lk::to_string(s.code)));
  r.set("message", s.message);
  return r;
}

// The success object every job returns, to be filled with its results.
val ok_result() {
  val r = val::object();
  r.set("ok", true);
  r.set("code", std::string("Ok"));
  r.set("message", std::string());
  return r;
}

// Decodes an image the page handed over as bytes in the heap; errors name
// the file.
lk::Status decode_image(const std::string& name, std::uintptr_t data, std::size_t size, lk::Image& image,
                        int channels = 0) {
  if (data == 0 && size != 0) return lk::Status::error(lk::ErrorCode::Internal, name + ": no input buffer");
  const lk::Status status = lk::read_image(reinterpret_cast<const std::uint8_t*>(data), size, image, channels);
  return status.ok() ? status : lk::with_context(status, name);
}

// Wraps a JS function (stage, fraction) -> bool|undefined as an lk::ProgressFn.
// Only an explicit `false` cancels, so a callback that returns nothing is fine.
lk::ProgressFn js_progress(val fn) {
  if (fn.isUndefined() || fn.isNull()) return {};
  return [fn](const char* stage, double fraction) {
    val answer = fn(std::string(stage), fraction);
    return !(answer.isFalse());
  };
}

// Parses a dropped PLY / OBJ / XYZ file (reader chosen by lk::read_geometry from
// the name's extension or the first bytes). Meshes without normals get
// area-weighted vertex normals so the viewer can shade them; point clouds keep
// whatever normals the file had (possibly none).
val parse_geometry(const std::string& name, std::uintptr_t data, std::size_t size, val progress) {
  const lk::ProgressFn report = js_progress(progress);
  if (!lk::report(report, "load", 0.0))
    return error_result(lk::Status::error(lk::ErrorCode::Cancelled, name + ": cancelled"));
  if (data == 0 && size != 0)
    return error_result(lk::Status::error(lk::ErrorCode::Internal, name + ": no input buffer"));

  lk::TriMesh mesh;
  lk::PointCloud cloud;
  lk::GeometryKind kind = lk::GeometryKind::PointCloud;
  const auto* bytes = reinterpret_cast<const std::uint8_t*>(data);
  lk::Status status = lk::read_geometry(name, bytes, size, mesh, cloud, kind);
  if (!status.ok()) return error_result(lk::with_context(status, name));
  if (!lk::report(report, "load", 0.8))
    return error_result(lk::Status::error(lk::ErrorCode::Cancelled, name + ": cancelled"));

  const bool is_mesh = kind == lk::GeometryKind::Mesh;
  const std::vector<lk::Vec3>& positions = is_mesh ? mesh.positions : cloud.positions;
  if (positions.empty())
    return error_result(lk::Status::error(lk::ErrorCode::Empty, name + ": no vertices"));
  if (is_mesh && mesh.normals.size() != mesh.positions.size()) mesh.normals = lk::vertex_normals(mesh);
  const std::vector<lk::Vec3>& normals = is_mesh ? mesh.normals : cloud.normals;
  const std::vector<lk::Vec3>& colors = is_mesh ? mesh.colors : cloud.colors;
  const lk::BBox box = lk::bounding_box(positions);

  val r = ok_result();
  r.set("name", name);
  r.set("kind", std::string(is_mesh ? "mesh" : "points"));
  r.set("vertexCount", static_cast<double>(positions.size()));
  r.set("triangleCount", static_cast<double>(is_mesh ? mesh.triangles.size() : 0));
  r.set("positions", float32_array(positions));
  r.set("normals", normals.size() == positions.size() ? float32_array(normals) : float32_array({}));
  r.set("colors", colors.size() == positions.size() ? float32_array(colors) : float32_array({}));
  r.set("indices", is_mesh ? uint32_array(mesh.triangles) : uint32_array({}));
  r.set("bboxMin", vec3_array(box.min));
  r.set("bboxMax", vec3_array(box.max));
  lk::report(report, "load", 1.0);
  return r;
}

// Decodes a dropped photo (PNG/JPEG/...) to check it is a whole, usable image
// and reports its size; the texturing stage decodes it again when it runs, so
// the pixels are not kept here.
val check_image(const std::string& name, std::uintptr_t data, std::size_t size) {
  lk::Image image;
  lk::Status status = decode_image(name, data, size, image);
  if (!status.ok()) return error_result(status);
  val r = ok_result();
  r.set("name", name);
  r.set("width", image.width);
  r.set("height", image.height);
  r.set("channels", image.channels);
  return r;
}

// ---- the fitted head ---------------------------------------------------------
// Core has no clocks; the binding times stages with the worker's
// performance.now() from the FitStageObserver callbacks.
double now_ms() { return val::global("performance").call<double>("now"); }

// The last fit, kept in the worker for animation and export (the page holds
// only what it displays). Meshes handed to the page are in the SCAN's frame
// (its units and orientation) so they lie over the scan points it shows.
struct FitSession {
  lk::FitHeadResult fit;
  lk::Mat3 head_to_scan = lk::Mat3::Identity();  // inverse of fit.scan_to_head.A
  lk::Vec3 head_offset = lk::Vec3::Zero();       // fit.scan_to_head.t
  // Animation: control vertices moved, their rest positions (head frame) and
  // how each moves: 0 = brow (raised), 1 = jaw (rotated open).
  std::vector<int> moved;
  std::vector<lk::Vec3> rest;
  std::vector<int> kind;
  std::vector<double> weight;  // brow falloff in [0, 1]; 1 for the jaw
  lk::Vec3 jaw_pivot = lk::Vec3::Zero();
  double head_size = 0.25;  // metres, sets the brow lift
  // The last texture (texture_job): the chart on the finest level (a
  // coarser level's uvs are its prefix, see refine_uv.h) and the skin image.
  std::vector<lk::Vec2> uvs;
  lk::Image skin;
  bool posed = false;  // the last animation frame left the head off its rest pose
  // The finest level's checks (fit_quality_job), measured once on the rest pose.
  bool have_quality = false;
  lk::FitQuality quality;
  double quality_ms = 0;
  // The scan's points, and its triangles when it came as a mesh (scan
  // frame), kept for the check of the other direction (face to scan).
  lk::PointCloud scan;
  bool have_to_scan = false;
  lk::CoveredDistances to_scan;
  std::vector<lk::Vec3> to_scan_colors;  // the finest level's distance map (fit_quality.h, distance_colors)
};
std::unique_ptr<FitSession> g_session;

std::vector<lk::Vec3> to_scan_frame(const FitSession& s, const std::vector<lk::Vec3>& head_positions) {
  std::vector<lk::Vec3> out(head_positions.size());
  for (size_t i = 0; i < out.size(); ++i) out[i] = s.head_to_scan * (head_positions[i] - s.head_offset);
  return out;
}

// {positions, indices} of a head-frame mesh, in the scan frame. Normals are
// left to the viewer (area-weighted on upload), which matches the surface.
val mesh_arrays(const FitSession& s, const std::vector<lk::Vec3>& positions, const std::vector<lk::Tri>& tris) {
  val m = val::object();
  m.set("positions", float32_array(to_scan_frame(s, positions)));
  m.set("indices", uint32_array(tris));
  m.set("vertexCount", static_cast<double>(positions.size()));
  m.set("triangleCount", static_cast<double>(tris.size()));
  return m;
}

val stats_object(const lk::DistanceStats& d) {
  val o = val::object();
  o.set("meanPct", d.mean_pct);
  o.set("maxPct", d.max_pct);
  o.set("rmsPct", d.mean != 0 ? d.rms / d.mean * d.mean_pct : 0.0);
  o.set("points", d.count);
  return o;
}

// Picks the animated control vertices from the generic head's regions (the
// generic head and the control mesh share vertex indices):
//  - brows: the "brow" region is lifted fully and the skin around it follows
//    with a smooth falloff (to zero at 3 % of the head's size), so the
//    forehead stretches instead of tearing at the region's edge;
//  - jaw: "lower_lip", "chin" and "jaw" rotate down rigidly about a hinge at
//    the jaw region's top back (the temporomandibular joint's place).
void prepare_animation(FitSession& s, const lk::HeadAnnotations& ann) {
  s.moved.clear();
  s.rest.clear();
  s.kind.clear();
  s.weight.clear();
  const std::vector<lk::Vec3>& P = s.fit.control.positions;
  const lk::BBox box = lk::bounding_box(P);
  s.head_size = (box.max - box.min).norm();
  std::vector<char> taken(P.size(), 0);
  auto region = [&](const char* name) {
    auto it = ann.regions.find(name);
    return it == ann.regions.end() ? std::vector<int>{} : it->second;
  };
  for (const char* name : {"lower_lip", "chin", "jaw"})
    for (int v : region(name)) {
      if (v < 0 || v >= static_cast<int>(P.size()) || taken[v]) continue;
      taken[v] = 1;
      s.moved.push_back(v);
      s.rest.push_back(P[v]);
      s.kind.push_back(1);
      s.weight.push_back(1.0);
    }
  const std::vector<int> brow = region("brow");
  const double falloff = 0.03 * s.head_size;
  for (size_t v = 0; v < P.size(); ++v) {
    if (taken[v] || brow.empty()) continue;
    double nearest = 1e300;
    for (int b : brow)
      if (b >= 0 && b < static_cast<int>(P.size())) nearest = std::min(nearest, (P[v] - P[b]).norm());
    if (nearest >= falloff) continue;
    const double x = 1.0 - nearest / falloff;  // 1 on the brow, 0 at the falloff radius
    s.moved.push_back(static_cast<int>(v));
    s.rest.push_back(P[v]);
    s.kind.push_back(0);
    s.weight.push_back(x * x * (3.0 - 2.0 * x));  // smoothstep
  }
  lk::Vec3 top_back(0, -1e9, 1e9);
  for (size_t i = 0; i < s.moved.size(); ++i)
    if (s.kind[i] == 1) {
      top_back.y() = std::max(top_back.y(), s.rest[i].y());
      top_back.z() = std::min(top_back.z(), s.rest[i].z());
    }
  s.jaw_pivot = lk::Vec3(0.5 * (box.min.x() + box.max.x()), top_back.y(), top_back.z());
}

// Named points a user clicks in each photo to calibrate it (tarini2002
// Sec. 3: "about 12-15 corresponding feature points"). Each is a control
// vertex of the generic head picked from its annotations (extremes of the
// eye rims, lips, ears, nose, chin, brow), so the fitted head (same vertex
// indices) knows where it is. "right"/"left" are the person's own sides:
// +x is the head's left. Order = the order the page asks for them in.
struct Landmark {
  const char* id;
  const char* label;
  int vertex;
};

std::vector<Landmark> texture_landmarks(const lk::GenericHead& g) {
  const lk::HeadAnnotations& ann = g.annotations;
  const std::vector<lk::Vec3>& P = g.mesh.positions;
  auto region = [&](const char* name) {
    auto it = ann.regions.find(name);
    return it == ann.regions.end() ? std::vector<int>{} : it->second;
  };
  // The region's vertex that maximizes score (or -1 for an empty region).
  auto best = [&](const std::vector<int>& set, auto score) {
    int pick = -1;
    double top = -1e300;
    for (int v : set)
      if (v >= 0 && v < static_cast<int>(P.size()) && score(P[v]) > top) {
        top = score(P[v]);
        pick = v;
      }
    return pick;
  };
  std::vector<int> corners;  // the two mouth corners: in "lips" but in neither lip
  {
    const std::vector<int> up = region("upper_lip"), low = region("lower_lip");
    for (int v : region("lips"))
      if (std::find(up.begin(), up.end(), v) == up.end() && std::find(low.begin(), low.end(), v) == low.end() &&
          v >= 0 && v < static_cast<int>(P.size()))
        corners.push_back(v);
    // The mouth bag is in "lips" too: keep the frontmost candidates.
    std::sort(corners.begin(), corners.end(), [&](int a, int b) { return P[a].z() > P[b].z(); });
  }
  const double front_z = [&] {
    double z = -1e300;
    for (const lk::Vec3& p : P) z = std::max(z, p.z());
    return z;
  }();
  auto frontal = [&](const lk::Vec3& p) { return p.z() - front_z; };
  std::vector<Landmark> out = {
      {"eye_right_outer", "Right eye, outer corner", best(ann.eye_right.rim, [](const lk::Vec3& p) { return -p.x(); })},
      {"eye_right_inner", "Right eye, inner corner", best(ann.eye_right.rim, [](const lk::Vec3& p) { return p.x(); })},
      {"eye_left_inner", "Left eye, inner corner", best(ann.eye_left.rim, [](const lk::Vec3& p) { return -p.x(); })},
      {"eye_left_outer", "Left eye, outer corner", best(ann.eye_left.rim, [](const lk::Vec3& p) { return p.x(); })},
      {"brow_middle", "Between the brows", best(region("brow"), [&](const lk::Vec3& p) { return frontal(p) - 4 * std::abs(p.x()); })},
      {"nose_tip", "Tip of the nose", best(region("nose"), [](const lk::Vec3& p) { return p.z(); })},
      {"mouth_right", "Right mouth corner", best(corners, [&](const lk::Vec3& p) { return -p.x() + 0.1 * frontal(p); })},
      {"mouth_left", "Left mouth corner", best(corners, [&](const lk::Vec3& p) { return p.x() + 0.1 * frontal(p); })},
      {"upper_lip", "Middle of the upper lip", best(region("upper_lip"), [](const lk::Vec3& p) { return p.z() - 4 * std::abs(p.x()); })},
      {"chin", "Tip of the chin", best(region("chin"), [](const lk::Vec3& p) { return p.z() - p.y() - 4 * std::abs(p.x()); })},
      {"ear_right_lobe", "Right ear lobe (bottom)", best(region("ear_right"), [](const lk::Vec3& p) { return -p.y(); })},
      {"ear_right_top", "Right ear, top", best(region("ear_right"), [](const lk::Vec3& p) { return p.y(); })},
      {"ear_left_lobe", "Left ear lobe (bottom)", best(region("ear_left"), [](const lk::Vec3& p) { return -p.y(); })},
      {"ear_left_top", "Left ear, top", best(region("ear_left"), [](const lk::Vec3& p) { return p.y(); })},
  };
  out.erase(std::remove_if(out.begin(), out.end(), [](const Landmark& l) { return l.vertex < 0; }), out.end());
  return out;
}

// Poses the kept head: brows up and jaw open by amount in [0, 1] (0 = rest),
// through the multires local update (jeong2002 Sec. 6), up to level
// max_level (-1: all; the levels above are brought up to date when read).
lk::Status set_pose(FitSession& s, double amount, lk::UpdateFootprint* footprint, int max_level = -1) {
  const double brow_lift = 0.02 * s.head_size * amount;  // ~7 mm on a head
  const double jaw_angle = 0.14 * amount;                 // ~8 degrees
  const double c = std::cos(jaw_angle), sn = std::sin(jaw_angle);
  std::vector<lk::Vec3> target(s.moved.size());
  for (size_t i = 0; i < s.moved.size(); ++i) {
    const lk::Vec3& p = s.rest[i];
    if (s.kind[i] == 0) {
      target[i] = p + lk::Vec3(0, brow_lift * s.weight[i], 0);
    } else {
      // Rotation about the x axis through the hinge: the chin swings down.
      const lk::Vec3 d = p - s.jaw_pivot;
      target[i] = s.jaw_pivot + lk::Vec3(d.x(), c * d.y() - sn * d.z(), sn * d.y() + c * d.z());
    }
  }
  return lk::update_control_vertices(s.fit.multires, s.moved, target, footprint, max_level);
}

// Puts the kept head back at rest, the pose its checks and distance map
// are of, when an animation frame left it posed.
lk::Status to_rest_pose(FitSession& s) {
  if (!s.posed) return lk::Status::success();
  const lk::Status st = set_pose(s, 0.0, nullptr);
  if (st.ok()) s.posed = false;
  return st;
}

const lk::GenericHead* generic_head(lk::Status& status) {
  static lk::GenericHead generic;  // parsed once per worker
  static bool have_generic = false;
  if (!have_generic) {
    status = lk::load_generic_head(generic);
    if (!status.ok()) return nullptr;
    have_generic = true;
  }
  status = lk::Status::success();
  return &generic;
}

// A generic iris for the eyeballs while no eye photo is given (tarini2002
// Sec. 4.1 synthesizes one from a photo; this stands in for it): a brown
// iris with radial streaks, darker towards the limbus, as a polar image.
lk::PolarIris generic_polar_iris() {
  lk::PolarIris iris;
  iris.angles = 96;
  iris.radii = 24;
  iris.rgb.resize(static_cast<size_t>(iris.angles) * iris.radii * 3);
  iris.valid.assign(static_cast<size_t>(iris.angles) * iris.radii, 1);
  for (int a = 0; a < iris.angles; ++a)
    for (int r = 0; r < iris.radii; ++r) {
      const double t = r / double(iris.radii - 1);  // 0 at the pupil, 1 at the limbus
      const double streak = 0.85 + 0.15 * std::sin(a * 1.7) * std::sin(a * 0.37 + r * 0.5);
      const double shade = streak * (1.0 - 0.45 * t * t);
      float* px = iris.at(a, r);
      px[0] = static_cast<float>(0.42 * shade);
      px[1] = static_cast<float>(0.27 * shade);
      px[2] = static_cast<float>(0.14 * shade);
    }
  return iris;
}

// {positions, indices, uvs?, colors?} of a head-frame component mesh, in the
// scan frame. colors: one linear RGB for every vertex (none when textured).
val component_arrays(const FitSession& s, const lk::TriMesh& m, const lk::Vec3* color) {
  val o = mesh_arrays(s, m.positions, m.triangles);
  if (m.uvs.size() == m.positions.size() && !color) {
    std::vector<float> uv(2 * m.uvs.size());
    for (size_t i = 0; i < m.uvs.size(); ++i) {
      uv[2 * i] = static_cast<float>(m.uvs[i].x());
      uv[2 * i + 1] = static_cast<float>(m.uvs[i].y());
    }
    o.set("uvs", val::global("Float32Array").new_(emscripten::typed_memory_view(uv.size(), uv.data())));
  }
  if (color) o.set("colors", float32_array(std::vector<lk::Vec3>(m.positions.size(), *color)));
  return o;
}

// Splits a mesh by its triangles' centroids: below height y (head frame)
// or not; each part keeps only its own vertices (and their uvs).
void split_below(const lk::TriMesh& m, double y, lk::TriMesh& above, lk::TriMesh& below) {
  std::vector<int> map_above(m.positions.size(), -1), map_below(m.positions.size(), -1);
  for (const lk::Tri& t : m.triangles) {
    const double cy = (m.positions[t[0]].y() + m.positions[t[1]].y() + m.positions[t[2]].y()) / 3.0;
    lk::TriMesh& part = cy < y ? below : above;
    std::vector<int>& map = cy < y ? map_below : map_above;
    lk::Tri out;
    for (int k = 0; k < 3; ++k) {
      if (map[t[k]] < 0) {
        map[t[k]] = static_cast<int>(part.positions.size());
        part.positions.push_back(m.positions[t[k]]);
        if (m.uvs.size() == m.positions.size()) part.uvs.push_back(m.uvs[t[k]]);
      }
      out[k] = map[t[k]];
    }
    part.triangles.push_back(out);
  }
}

// The jaw's rigid motion for `amount` (the rotation set_pose gives the jaw
// vertices), as a column-major 4x4 matrix in the scan frame: p_scan' =
// A^-1 (c + R (A p_scan + t - c) - t) with the scan -> head map (A, t).
val jaw_matrix(const FitSession& s, double amount) {
  const double angle = 0.14 * amount, c = std::cos(angle), sn = std::sin(angle);
  lk::Mat3 R;
  R << 1, 0, 0, 0, c, -sn, 0, sn, c;
  const lk::Mat3 A = s.head_to_scan.inverse();
  const lk::Mat3 M = s.head_to_scan * R * A;
  const lk::Vec3 t = s.head_to_scan * (s.jaw_pivot + R * (s.head_offset - s.jaw_pivot) - s.head_offset);
  std::vector<float> m(16, 0.0f);
  for (int col = 0; col < 3; ++col)
    for (int row = 0; row < 3; ++row) m[4 * col + row] = static_cast<float>(M(row, col));
  for (int row = 0; row < 3; ++row) m[12 + row] = static_cast<float>(t[row]);
  m[15] = 1.0f;
  return val::global("Float32Array").new_(emscripten::typed_memory_view(m.size(), m.data()));
}

// {width, height, channels, pixels} of an image (a copy out of the heap).
val image_object(const lk::Image& image) {
  val t = val::object();
  t.set("width", image.width);
  t.set("height", image.height);
  t.set("channels", image.channels);
  t.set("pixels", val::global("Uint8Array").new_(emscripten::typed_memory_view(image.pixels.size(), image.pixels.data())));
  return t;
}

// Teeth photo -> the composite texture in make_teeth_model's uv layout
// (tarini2002 Sec. 4.2): classification, voids transparent, equalization,
// hidden parts, then the generic side teeth around it.
lk::Status teeth_texture(const lk::Image& photo, lk::Image& texture) {
  const lk::TeethOptions options;
  lk::TeethResult teeth;
  if (lk::Status s = lk::teeth_texture_from_photo(photo, options, teeth); !s.ok()) return s;
  lk::TeethCompositeOptions composite;
  composite.width = 512;  // half the CLI's size: the teeth cover few pixels on screen
  composite.height = 256;
  return lk::teeth_composite_generic(teeth, options, composite, texture);
}

// The generic teeth texture when no smile photo is given, made by our own
// tools (a synthetic smile whose lips hide parts of two teeth, as the CLI's
// --synthetic-smile) once per worker; empty if that ever fails. made_ms:
// the time it took (0 after the first call).
const lk::Image& generic_teeth_texture(double& made_ms) {
  made_ms = 0;
  static const lk::Image texture = [&made_ms] {
    const double t0 = now_ms();
    lk::SyntheticSmileOptions so;
    so.upper_dip = 40;
    so.lower_rise = 34;
    lk::Image t;
    if (!teeth_texture(lk::make_synthetic_smile(so).image, t).ok()) t = lk::Image{};
    made_ms = now_ms() - t0;
    return t;
  }();
  return texture;
}

// The generic eyeballs (with the generic iris texture), teeth and tongue of
// tarini2002 Sec. 4, placed from the fitted control mesh's eye rims and lips
// (core/components), in the scan frame, at rest; the lower teeth and the
// tongue follow the jaw through animate_frame's jawMatrix.
val components_object(const FitSession& s, const lk::GenericHead& generic) {
  lk::GenericHead fitted;
  fitted.mesh.positions = s.fit.control.positions;
  fitted.mesh.triangles = s.fit.control.triangles;
  fitted.annotations = generic.annotations;
  lk::ComponentPlacement placement;
  if (!lk::place_components(fitted, generic, placement).ok()) return val::null();
  const lk::PlacedComponents parts = lk::build_placed_components(placement);
  val o = val::object();
  val eyes = val::array();
  for (const lk::TriMesh& eye : parts.eye) eyes.call<void>("push", component_arrays(s, eye, nullptr));
  o.set("eyes", eyes);
  const lk::Vec3 ivory(0.80, 0.74, 0.60), tongue_pink(0.55, 0.16, 0.16);  // linear RGB
  // The lower arch (below the bite plane, which sits at the mouth centre)
  // and the tongue ride on the jaw: animate_frame returns its motion.
  lk::TriMesh upper, lower;
  split_below(parts.teeth, placement.mouth_center.y(), upper, lower);
  // Textured teeth (uvs passed) when the generic teeth texture exists;
  // ivory otherwise. Voids are transparent (alpha 0): the renderer alpha-tests.
  double teeth_ms = 0;
  const lk::Image& teeth_tex = generic_teeth_texture(teeth_ms);
  const lk::Vec3* teeth_color = teeth_tex.empty() ? &ivory : nullptr;
  o.set("teeth", component_arrays(s, upper, teeth_color));
  o.set("lowerTeeth", component_arrays(s, lower, teeth_color));
  if (!teeth_tex.empty()) o.set("teethTexture", image_object(teeth_tex));
  o.set("teethTextureMs", teeth_ms);
  o.set("tongue", component_arrays(s, parts.tongue, &tongue_pink));
  lk::Image eye_texture;
  lk::EyeballTextureOptions eto;
  eto.size = 256;
  if (lk::eyeball_texture(generic_polar_iris(), 0.35, eto, eye_texture).ok()) o.set("eyeTexture", image_object(eye_texture));
  return o;
}

// Runs the whole fit (jeong2002 Sec. 4-5) on a dropped scan's bytes.
// options: {levels, up:[x,y,z], facing:[x,y,z]} (all optional).
// progress(stage, fraction) with stage one of initial_alignment,
// local_fitting, global_fitting, subdivision; returning false cancels.
// The result carries untangle {pairsBefore, pairsEroded, pairsAfter,
// restoreSteps}: the smooth surface's new crossing pairs the untangling
// found, left after its erosion and at its end (pipeline/untangle.h), and
// headFacing, headUp: the head's +z and +y in the scan's frame (the page's
// view looks at the face with them).
val fit_head_job(const std::string& name, std::uintptr_t data, std::size_t size, val options, val progress) {
  const lk::ProgressFn report = js_progress(progress);
  if (data == 0 && size != 0)
    return error_result(lk::Status::error(lk::ErrorCode::Internal, name + ": no input buffer"));
  const double t_parse = now_ms();
  lk::TriMesh mesh;
  lk::PointCloud cloud;
  lk::GeometryKind kind = lk::GeometryKind::PointCloud;
  lk::Status status = lk::read_geometry(name, reinterpret_cast<const std::uint8_t*>(data), size, mesh, cloud, kind);
  if (!status.ok()) return error_result(lk::with_context(status, name));
  // A mesh scan is fitted through its vertices; its triangles (in `cloud`
  // too) are sampled for the displacements, as in the CLI.
  mesh = lk::TriMesh{};
  const double parse_ms = now_ms() - t_parse;

  lk::FitHeadOptions opt;
  auto vec3_option = [&](const char* key, lk::Vec3& out) {
    const val v = options[key];
    if (v.isUndefined() || v.isNull()) return true;
    if (v["length"].as<int>() != 3) return false;
    for (int k = 0; k < 3; ++k) out[k] = v[k].as<double>();
    return true;
  };
  if (!options.isUndefined() && !options.isNull()) {
    if (!options["levels"].isUndefined()) opt.levels = options["levels"].as<int>();
    if (!vec3_option("up", opt.up) || !vec3_option("facing", opt.facing))
      return error_result(lk::Status::error(lk::ErrorCode::InvalidInput, "up and facing take three numbers"));
  }
  if (opt.levels < 1 || opt.levels > 4)
    return error_result(lk::Status::error(lk::ErrorCode::InvalidInput, "levels must be 1..4"));

  lk::Status generic_status;
  const lk::GenericHead* generic_ptr = generic_head(generic_status);
  if (!generic_ptr) return error_result(lk::with_context(generic_status, "generic head"));
  const lk::GenericHead& generic = *generic_ptr;

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
  observer.measured = [&](const lk::FitStageReport& r) {
    val o = stats_object(r.distance);
    o.set("name", r.name);
    o.set("ms", stage_ms[r.name]);
    stages.call<void>("push", o);
  };
  const lk::ProgressFn inner = [&](const char*, double fraction) {
    if (current.empty()) return true;
    return lk::report(report, current.c_str(), std::min(0.99, std::max(0.0, fraction)));
  };

  auto session = std::make_unique<FitSession>();
  const double t_fit = now_ms();
  status = lk::fit_head(cloud, generic, opt, session->fit, observer, inner);
  const double fit_ms = now_ms() - t_fit;
  if (!status.ok()) return error_result(lk::with_context(status, name));

  FitSession& s = *session;
  s.scan.positions = std::move(cloud.positions);
  s.scan.faces = std::move(cloud.faces);
  s.head_to_scan = s.fit.scan_to_head.A.inverse();
  s.head_offset = s.fit.scan_to_head.t;
  prepare_animation(s, generic.annotations);

  val r = ok_result();
  r.set("name", name);
  r.set("points", s.fit.points);
  r.set("fittedPoints", s.fit.fitted_points);
  r.set("unitToMetres", s.fit.unit_to_metres);
  r.set("parseMs", parse_ms);
  r.set("fitMs", fit_ms);
  r.set("stages", stages);
  // What the fit decided on its own (the scan turned to face +z, a face-only
  // capture, a unit guessed): `likeness fit` prints these as "note:" lines.
  val notes = val::array();
  for (const std::string& note : s.fit.notes) notes.call<void>("push", note);
  r.set("notes", notes);
  r.set("headFacing", vec3_array(s.head_to_scan * lk::Vec3(0, 0, 1)));
  r.set("headUp", vec3_array(s.head_to_scan * lk::Vec3(0, 1, 0)));
  val untangle = val::object();
  untangle.set("pairsBefore", s.fit.untangle.pairs_before);
  untangle.set("pairsEroded", s.fit.untangle.pairs_eroded);
  untangle.set("pairsAfter", s.fit.untangle.pairs_after);
  untangle.set("restoreSteps", s.fit.untangle.restore_steps);
  r.set("untangle", untangle);
  val meshes = val::object();
  meshes.set("aligned", mesh_arrays(s, s.fit.aligned.positions, s.fit.aligned.triangles));
  meshes.set("local", mesh_arrays(s, s.fit.local.positions, s.fit.local.triangles));
  meshes.set("control", mesh_arrays(s, s.fit.control.positions, s.fit.control.triangles));
  val levels = val::array();
  for (const lk::TriMesh& m : s.fit.level_meshes) levels.call<void>("push", mesh_arrays(s, m.positions, m.triangles));
  meshes.set("levels", levels);
  r.set("meshes", meshes);
  r.set("animatedVertices", static_cast<double>(s.moved.size()));
  // Texture landmarks where they are on the fitted surface (finest level,
  // rest pose, scan frame): control vertices keep their index on every level.
  val landmarks = val::array();
  const std::vector<lk::Vec3>& finest = s.fit.multires.state.displaced[s.fit.multires.num_levels()];
  for (const Landmark& l : texture_landmarks(generic)) {
    if (l.vertex >= static_cast<int>(finest.size())) continue;
    val o = val::object();
    o.set("id", std::string(l.id));
    o.set("label", std::string(l.label));
    o.set("vertex", l.vertex);
    o.set("position", vec3_array(s.head_to_scan * (finest[l.vertex] - s.head_offset)));
    landmarks.call<void>("push", o);
  }
  r.set("landmarks", landmarks);
  r.set("components", components_object(s, generic));
  g_session = std::move(session);
  return r;
}

// A small fit whose only purpose is to run the fit's code once, in a
// throw-away worker (web/worker.js ?warmup=1) started beside the one that
// fits the user's scan. V8 compiles a wasm function with its optimizing tier
// only after it has run for a while, so the first fit in a page ran its hot
// loops on the baseline tier (+0.6-1.5 s, mostly in the alignment:
// docs/web.md); the compiled code belongs to the module's bytes and is shared
// by every worker of the page that instantiates them. The input is the
// generic head itself (its vertices and triangle centroids as a point cloud):
// nothing is shipped for it. The fitted head is discarded; the kept fit
// (g_session) is untouched. Returns {ok, code, message, points, fitMs}.
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

// One animation frame on the kept fit: brows up and jaw open by `amount` in
// [0, 1], applied to the rest pose through the multires local update
// (jeong2002 Sec. 6: only the moved vertices' support is recomputed).
// Returns {ok, positions (level `level`, scan frame), updateMs, changed}.
val animate_frame(double amount, int level) {
  if (!g_session) return error_result(lk::Status::error(lk::ErrorCode::InvalidInput, "no fitted head to animate"));
  FitSession& s = *g_session;
  lk::MultiresMesh& mr = s.fit.multires;
  if (level < 0 || level > mr.num_levels())
    return error_result(lk::Status::error(lk::ErrorCode::InvalidInput, "no level " + std::to_string(level)));
  if (!std::isfinite(amount)) amount = 0;
  amount = std::min(1.0, std::max(0.0, amount));
  const double t0 = now_ms();
  lk::UpdateFootprint footprint;
  // Only up to the level shown: an animation drawn at level 1 (adaptive
  // detail) does not pay for level 3.
  lk::Status st = set_pose(s, amount, &footprint, level);
  const double update_ms = now_ms() - t0;
  if (!st.ok()) return error_result(st);
  s.posed = amount != 0;
  val r = ok_result();
  r.set("level", level);
  r.set("positions", float32_array(to_scan_frame(s, mr.state.displaced[level])));
  r.set("updateMs", update_ms);
  r.set("changed", footprint.displaced_changed.empty() ? 0 : footprint.displaced_changed[level]);
  r.set("vertexCount", mr.num_vertices(level));
  r.set("jawMatrix", jaw_matrix(s, amount));
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

// The checks `likeness fit` prints after Table 1 (core/pipeline/fit_quality.h),
// on the kept fit's finest level at rest: triangles turned over by a
// displacement, degenerate ones, self-intersecting pairs by region of the
// displaced and of the smooth level, and the control mesh's own pairs.
// Separate from fit_head_job so the page shows the fit first and the checks
// when they are done (they cost about as much as a tenth of the fit); the
// first call measures, later calls return the same numbers.
// Returns {ok, level, triangles, flipped, degenerate, crossings, smoothCrossings
// ({total, lips, ears, eyeSockets, rest}), controlCrossings, checkMs}, and
// faceToScan {to: "triangles"|"points", vertices, meanMm, p99Mm, maxMm,
// colors}: level L's face to the scan where scanned (fit_quality.h), and
// its map as #V_L * 3 linear RGB (distance_colors) for the viewer.
val fit_quality_job() {
  if (!g_session) return error_result(lk::Status::error(lk::ErrorCode::InvalidInput, "no fitted head to check"));
  FitSession& s = *g_session;
  if (!s.have_quality) {
    const double t0 = now_ms();
    // The checks are of the fitted head, not of an animation pose.
    if (lk::Status st = to_rest_pose(s); !st.ok()) return error_result(st);
    if (lk::Status st = lk::ensure_current(s.fit.multires); !st.ok()) return error_result(st);
    lk::Status generic_status;
    const lk::GenericHead* generic = generic_head(generic_status);
    if (!generic) return error_result(lk::with_context(generic_status, "generic head"));
    if (lk::Status st = lk::measure_fit_quality(s.fit, generic->annotations, s.quality); !st.ok()) return error_result(st);
    // The other direction (likeness fit prints it too): to the scan's
    // triangles, or to its points' local patches.
    std::vector<double> per_vertex;
    s.have_to_scan = lk::measure_fit_to_scan(s.fit, s.scan, *generic, s.to_scan, "face", &per_vertex).ok();
    if (s.have_to_scan) s.to_scan_colors = lk::distance_colors(per_vertex);
    s.quality_ms = now_ms() - t0;
    s.have_quality = true;
  }
  const lk::FitQuality& q = s.quality;
  val r = ok_result();
  r.set("level", q.level);
  r.set("triangles", q.triangles);
  r.set("flipped", q.flipped);
  r.set("degenerate", q.degenerate);
  r.set("crossings", crossings_object(q.crossings));
  r.set("smoothCrossings", crossings_object(q.smooth_crossings));
  r.set("controlCrossings", q.control_crossings);
  if (s.have_to_scan) {
    val d = val::object();
    d.set("to", std::string(s.to_scan.to_points ? "points" : "triangles"));
    d.set("vertices", s.to_scan.vertices);
    d.set("meanMm", 1e3 * s.to_scan.mean);
    d.set("p99Mm", 1e3 * s.to_scan.p99);
    d.set("maxMm", 1e3 * s.to_scan.max);
    d.set("colors", float32_array(s.to_scan_colors));
    r.set("faceToScan", d);
  }
  r.set("checkMs", s.quality_ms);
  return r;
}

// The kept head as a file: level `level` (0 = control mesh) in the scan's
// frame, as OBJ text or binary PLY. The current animation pose is exported.
// format "map": the checks' distance map (fit_quality_job) as a binary PLY
// with vertex colours, as likeness fit's face_to_scan.ply: the finest level
// (whatever `level` says) at rest, the pose the distances were measured on.
val export_head(int level, const std::string& format) {
  if (!g_session) return error_result(lk::Status::error(lk::ErrorCode::InvalidInput, "no fitted head to export"));
  FitSession& s = *g_session;
  lk::MultiresMesh& mr = s.fit.multires;
  const bool map = format == "map";
  if (map) {
    if (!s.have_quality || !s.have_to_scan)
      return error_result(lk::Status::error(lk::ErrorCode::InvalidInput,
                                            "no distance map yet: it comes with the checks of the fitted head"));
    level = mr.num_levels();
    if (lk::Status st = to_rest_pose(s); !st.ok()) return error_result(st);
  }
  if (level < 0 || level > mr.num_levels())
    return error_result(lk::Status::error(lk::ErrorCode::InvalidInput, "no level " + std::to_string(level)));
  const lk::Status current = lk::ensure_current(mr);  // an animation may have updated only coarser levels
  if (!current.ok()) return error_result(current);
  lk::TriMesh m;
  m.positions = to_scan_frame(s, mr.state.displaced[level]);
  m.triangles = mr.triangles(level);
  val r = ok_result();
  if (map) {
    if (s.to_scan_colors.size() != m.positions.size())
      return error_result(lk::Status::error(lk::ErrorCode::Internal, "the distance map does not match the finest level"));
    m.colors = s.to_scan_colors;
  }
  if (format == "obj") {
    const std::string text = lk::write_obj(m);
    r.set("bytes", val::global("Uint8Array").new_(emscripten::typed_memory_view(text.size(),
                                                   reinterpret_cast<const std::uint8_t*>(text.data()))));
  } else if (format == "ply" || map) {
    const lk::Bytes bytes = lk::write_ply(m);
    r.set("bytes", val::global("Uint8Array").new_(emscripten::typed_memory_view(bytes.size(), bytes.data())));
  } else {
    return error_result(lk::Status::error(lk::ErrorCode::InvalidInput, "unknown format " + format));
  }
  return r;
}


// ---- texturing (tarini2002 Sec. 3) ------------------------------------------
// The steps the Texture job reports, in order: progress(stage, fraction) gets
// stage "texture:<step>" and the job's overall fraction; each step's name
// goes in the result's steps[] with its ms.
// "chart" is the control mesh's stretch-minimizing chart refined to the
// level; texture_head's own "parameterize" then only measures its stretch.
const char* const kTextureSteps[] = {"decode", "calibrate", "chart", "parameterize", "bind", "fill holes",
                                     "resample", "spline", "dilate"};
constexpr int kNumTextureSteps = 9;

int texture_step_index(const std::string& name) {
  for (int i = 0; i < kNumTextureSteps; ++i)
    if (name == kTextureSteps[i]) return i;
  return -1;
}

val calib_object(const lk::CalibResult& c) {
  val o = val::object();
  o.set("ok", true);
  o.set("rms", c.rms);
  o.set("inliers", c.num_inliers);
  o.set("focal", c.camera.fx);
  val errors = val::array(), outlier = val::array();
  for (size_t k = 0; k < c.errors.size(); ++k) {
    errors.call<void>("push", std::isfinite(c.errors[k]) ? c.errors[k] : -1.0);  // -1: behind the camera
    outlier.call<void>("push", k < c.outlier.size() && c.outlier[k] != 0);
  }
  o.set("errors", errors);
  o.set("outlier", outlier);
  return o;
}

// Textures the kept head from photos: photos is an array of
// {name, ptr, size, points} with the photo file's bytes at (ptr, size) and
// points a Float64Array of u v X Y Z per correspondence (pixels, top-left
// origin; the point on the head in the scan's frame, as the fit result's
// landmarks and exported meshes). options: {level (default finest), size
// (texture texels, default 1024)}. Each photo is calibrated on its own
// (core/calib), the control mesh gets the stretch-minimizing chart and the
// level its refinement (refine_uv.h), then lk::texture_head.
// Returns {ok, code, message, calib: [per photo {ok, rms, inliers, focal,
// errors[], outlier[]} or {ok:false, message}], uvs Float32Array #V*2,
// skin {width, height, channels, pixels Uint8Array}, steps [{name, ms}],
// level, vertexCount, textureMs}. On a calibration failure calib still holds
// every photo's outcome (the page marks the bad points).
val texture_job(val photos, val options, val progress) {
  const lk::ProgressFn report = js_progress(progress);
  if (!g_session) return error_result(lk::Status::error(lk::ErrorCode::InvalidInput, "fit a head first: there is no head to texture"));
  FitSession& s = *g_session;
  lk::MultiresMesh& mr = s.fit.multires;
  int level = mr.num_levels();
  int size = 1024;
  if (!options.isUndefined() && !options.isNull()) {
    if (!options["level"].isUndefined()) level = options["level"].as<int>();
    if (!options["size"].isUndefined()) size = options["size"].as<int>();
  }
  if (level < 0 || level > mr.num_levels())
    return error_result(lk::Status::error(lk::ErrorCode::InvalidInput, "no level " + std::to_string(level)));
  if (size < 16 || size > 4096)
    return error_result(lk::Status::error(lk::ErrorCode::InvalidInput, "texture size must be 16..4096 texels"));
  const int count = photos.isArray() ? photos["length"].as<int>() : 0;
  if (count == 0) return error_result(lk::Status::error(lk::ErrorCode::InvalidInput, "no photo to texture from"));
  if (count > lk::kMaxTexturePhotos)
    return error_result(lk::Status::error(lk::ErrorCode::InvalidInput, std::to_string(count) + " photos; at most " +
                                                                         std::to_string(lk::kMaxTexturePhotos) + " are used"));

  val steps = val::array();
  int step = -1;
  double t_step = 0;
  auto begin_step = [&](const std::string& name) {
    step = texture_step_index(name);
    t_step = now_ms();
    return lk::report(report, ("texture:" + name).c_str(), std::max(0, step) / double(kNumTextureSteps));
  };
  auto end_step = [&](const std::string& name) {
    val o = val::object();
    o.set("name", name);
    o.set("ms", now_ms() - t_step);
    steps.call<void>("push", o);
  };
  auto cancelled = [](const std::string& where) {
    return error_result(lk::Status::error(lk::ErrorCode::Cancelled, "texturing cancelled at " + where));
  };
  const double t_job = now_ms();

  // 1. Decode the photos and read their correspondences.
  if (!begin_step("decode")) return cancelled("decode");
  std::vector<std::string> names(count);
  std::vector<lk::TexturePhoto> tex_photos(count);
  std::vector<std::vector<lk::Correspondence>> points(count);
  for (int i = 0; i < count; ++i) {
    const val p = photos[i];
    names[i] = p["name"].isString() ? p["name"].as<std::string>() : "photo " + std::to_string(i + 1);
    const std::uintptr_t ptr = p["ptr"].as<std::uintptr_t>();
    const std::size_t bytes = p["size"].as<std::size_t>();
    if (ptr == 0) return error_result(lk::Status::error(lk::ErrorCode::Internal, names[i] + ": no input buffer"));
    const lk::Status st = decode_image(names[i], ptr, bytes, tex_photos[i].image, 3);
    if (!st.ok()) return error_result(st);
    const std::vector<double> flat = emscripten::convertJSArrayToNumberVector<double>(p["points"]);
    if (flat.size() % 5 != 0)
      return error_result(lk::Status::error(lk::ErrorCode::InvalidInput, names[i] + ": points need 5 numbers each (u v X Y Z)"));
    for (size_t k = 0; k + 4 < flat.size(); k += 5) {
      lk::Correspondence c;
      c.pixel = lk::Vec2(flat[k], flat[k + 1]);
      c.point = lk::Vec3(flat[k + 2], flat[k + 3], flat[k + 4]);
      points[i].push_back(c);
    }
    if (points[i].size() < 6)
      return error_result(lk::Status::error(lk::ErrorCode::InvalidInput,
                                            names[i] + ": " + std::to_string(points[i].size()) +
                                                " points; calibrating a photo needs at least 6 (12-15 are best)"));
    if (!lk::report(report, "texture:decode", (i + 1.0) / count / kNumTextureSteps)) return cancelled("decode");
  }
  end_step("decode");

  // 2. One camera per photo (each alone first, so every photo's outcome is known).
  if (!begin_step("calibrate")) return cancelled("calibrate");
  lk::CalibOptions calib_options;
  std::vector<lk::CalibResult> calib(count);
  val calib_out = val::array();
  std::string calib_failure;
  lk::ErrorCode calib_code = lk::ErrorCode::Ok;
  for (int i = 0; i < count; ++i) {
    const lk::Image& im = tex_photos[i].image;
    lk::Status st = lk::calibrate_camera(points[i], im.width, im.height, calib_options, calib[i]);
    if (st.ok()) {
      calib_out.call<void>("push", calib_object(calib[i]));
      tex_photos[i].camera = calib[i].camera;
    } else {
      val o = val::object();
      o.set("ok", false);
      o.set("message", st.message);
      calib_out.call<void>("push", o);
      if (calib_failure.empty()) {
        calib_failure = names[i] + ": calibration failed: " + st.message;
        calib_code = st.code;
      }
    }
  }
  if (!calib_failure.empty()) {
    end_step("calibrate");
    val r = error_result(lk::Status::error(calib_code, calib_failure));
    r.set("calib", calib_out);
    return r;
  }
  // Photos of one size most likely come from one camera: refine them jointly
  // with one focal length (much steadier than a focal per photo from 12-15
  // clicks). The per-photo results above stay if the joint fit fails.
  std::vector<std::array<int, 2>> sizes;
  for (const auto& p : tex_photos) sizes.push_back({p.image.width, p.image.height});
  if (lk::photos_look_like_one_camera(sizes)) {
    std::vector<lk::CalibResult> shared;
    if (lk::calibrate_photos(points, sizes, calib_options, shared, /*same_camera=*/true).ok()) {
      calib = shared;
      calib_out = val::array();
      for (int i = 0; i < count; ++i) {
        calib_out.call<void>("push", calib_object(calib[i]));
        tex_photos[i].camera = calib[i].camera;
      }
    }
  }
  end_step("calibrate");

  // 3. The chart on the control mesh (head frame: the view weight assumes
  // the head looks along +z), refined to the level.
  if (!begin_step("chart")) return cancelled("chart");
  lk::Status st = set_pose(s, 0.0, nullptr);  // texture the rest pose
  if (!st.ok()) return error_result(st);
  s.posed = false;
  lk::TriMesh control;
  control.positions = s.fit.control.positions;
  control.triangles = s.fit.control.triangles;
  std::vector<lk::Vec2> control_uv;
  lk::UvStats uv_stats;
  st = lk::parameterize_stretch(control, lk::UvOptions{}, control_uv, uv_stats);
  if (!st.ok()) return error_result(lk::with_context(st, "parameterization of the control mesh"));
  std::vector<lk::Vec2> finest_uv = control_uv;
  if (mr.num_levels() > 0) {
    st = lk::refine_chart_uvs(mr.levels, control_uv, finest_uv);
    if (!st.ok()) return error_result(st);
  }
  end_step("chart");

  lk::TriMesh mesh;
  mesh.positions = to_scan_frame(s, mr.state.displaced[level]);
  mesh.triangles = mr.triangles(level);
  mesh.uvs.assign(finest_uv.begin(), finest_uv.begin() + mesh.positions.size());
  lk::TextureOptions topt;
  topt.size = size;
  lk::TexturedHead out;
  std::string current;
  const lk::ProgressFn inner = [&](const char* name, double fraction) {
    const int index = texture_step_index(name);
    if (index < 0) return lk::report(report, ("texture:" + std::string(name)).c_str(), std::max(0, step) / double(kNumTextureSteps));
    if (fraction <= 0 && current != name) {
      if (!current.empty()) end_step(current);
      current = name;
      step = index;
      t_step = now_ms();
    }
    const double overall = (index + std::min(1.0, std::max(0.0, fraction))) / kNumTextureSteps;
    return lk::report(report, ("texture:" + std::string(name)).c_str(), std::min(0.999, overall));
  };
  st = lk::texture_head(mesh, tex_photos, topt, out, inner);
  if (!current.empty()) end_step(current);
  if (!st.ok()) {
    // texture_head names photos by index ("photo 1 ..."): use the file names.
    for (int i = 0; i < count; ++i) {
      const std::string tag = "photo " + std::to_string(i) + " ";
      if (st.message.rfind(tag, 0) == 0) st.message = names[i] + st.message.substr(tag.size() - 1);
    }
    val r = error_result(st);
    r.set("calib", calib_out);
    return r;
  }
  s.uvs = finest_uv;
  s.skin = out.skin;
  lk::report(report, "texture:done", 1.0);

  val r = ok_result();
  r.set("calib", calib_out);
  std::vector<float> uv_flat(2 * finest_uv.size());
  for (size_t i = 0; i < finest_uv.size(); ++i) {
    uv_flat[2 * i] = static_cast<float>(finest_uv[i].x());
    uv_flat[2 * i + 1] = static_cast<float>(finest_uv[i].y());
  }
  r.set("uvs", val::global("Float32Array").new_(emscripten::typed_memory_view(uv_flat.size(), uv_flat.data())));
  val skin = val::object();
  skin.set("width", out.skin.width);
  skin.set("height", out.skin.height);
  skin.set("channels", out.skin.channels);
  skin.set("pixels", val::global("Uint8Array").new_(emscripten::typed_memory_view(out.skin.pixels.size(), out.skin.pixels.data())));
  r.set("skin", skin);
  r.set("steps", steps);
  r.set("level", level);
  r.set("vertexCount", static_cast<double>(mesh.positions.size()));
  r.set("chartL2", uv_stats.l2_stretch);
  r.set("textureMs", now_ms() - t_job);
  return r;
}

// The textured head as three files: level `level` with the texture's uvs
// (OBJ, "mtllib <base>.mtl"), the material (map_Kd <base>.png) and the skin
// PNG. Current pose, scan frame, like export_head.
val export_textured(int level, const std::string& base) {
  if (!g_session) return error_result(lk::Status::error(lk::ErrorCode::InvalidInput, "no fitted head to export"));
  FitSession& s = *g_session;
  if (s.skin.empty() || s.uvs.empty())
    return error_result(lk::Status::error(lk::ErrorCode::InvalidInput, "the head is not textured yet"));
  lk::MultiresMesh& mr = s.fit.multires;
  if (level < 0 || level > mr.num_levels())
    return error_result(lk::Status::error(lk::ErrorCode::InvalidInput, "no level " + std::to_string(level)));
  const lk::Status current = lk::ensure_current(mr);  // an animation may have updated only coarser levels
  if (!current.ok()) return error_result(current);
  lk::TriMesh m;
  m.positions = to_scan_frame(s, mr.state.displaced[level]);
  m.triangles = mr.triangles(level);
  if (m.positions.size() > s.uvs.size())
    return error_result(lk::Status::error(lk::ErrorCode::Internal, "the texture chart is smaller than the level"));
  m.uvs.assign(s.uvs.begin(), s.uvs.begin() + m.positions.size());
  const std::string obj = lk::write_obj(m, base + ".mtl");
  const std::string mtl = lk::write_mtl(base + ".png");
  const lk::Bytes png = lk::write_png(s.skin);
  if (png.empty()) return error_result(lk::Status::error(lk::ErrorCode::Internal, "could not encode the skin PNG"));
  auto bytes = [](const std::uint8_t* data, size_t n) {
    return val::global("Uint8Array").new_(emscripten::typed_memory_view(n, data));
  };
  val r = ok_result();
  r.set("obj", bytes(reinterpret_cast<const std::uint8_t*>(obj.data()), obj.size()));
  r.set("mtl", bytes(reinterpret_cast<const std::uint8_t*>(mtl.data()), mtl.size()));
  r.set("png", bytes(png.data(), png.size()));
  return r;
}

// Points files as `likeness texture --points` reads them ("u v X Y Z" per
// line): the text -> {ok, points Float64Array 5*N} or the parser's message.
val parse_points(const std::string& text) {
  std::vector<lk::Correspondence> pts;
  lk::Status st = lk::parse_correspondences(text, pts);
  if (!st.ok()) return error_result(st);
  std::vector<double> flat;
  for (const lk::Correspondence& c : pts)
    flat.insert(flat.end(), {c.pixel.x(), c.pixel.y(), c.point.x(), c.point.y(), c.point.z()});
  val r = ok_result();
  r.set("points", val::global("Float64Array").new_(emscripten::typed_memory_view(flat.size(), flat.data())));
  return r;
}

// An eye photo (role "Eye (iris)") -> the eyeball texture (tarini2002 Sec.
// 4.1): the iris found from the darkest blob near the centre (or from
// guess [x, y] in pixels, optional), its valid part resynthesized around the
// whole circle. {ok, texture, circle: {x, y, radius, pupilRadius}, usedTwoD,
// sectorDeg, ms} or the core's error (no dark blob, the circle never stops).
val eye_photo_job(const std::string& name, std::uintptr_t data, std::size_t size, val guess) {
  const double t0 = now_ms();
  lk::Image photo;
  lk::Status status = decode_image(name, data, size, photo);
  if (!status.ok()) return error_result(status);
  lk::Vec2 guess_px;
  const bool have_guess = !guess.isUndefined() && !guess.isNull() && guess["length"].as<int>() == 2;
  if (have_guess) guess_px = lk::Vec2(guess[0].as<double>(), guess[1].as<double>());
  lk::IrisResult iris;
  lk::EyeballTextureOptions eto;
  eto.size = 256;  // as the generic eyes
  status = lk::iris_texture_from_photo(photo, have_guess ? &guess_px : nullptr, iris, eto);
  if (!status.ok()) return error_result(lk::with_context(status, name + ": no iris found"));
  val r = ok_result();
  r.set("texture", image_object(iris.texture));
  val c = val::object();
  c.set("x", iris.circle.center.x());
  c.set("y", iris.circle.center.y());
  c.set("radius", iris.circle.radius);
  c.set("pupilRadius", iris.circle.pupil_radius);
  r.set("circle", c);
  r.set("usedTwoD", iris.report.used_2d);
  r.set("sectorDeg", iris.report.sector_deg);
  r.set("ms", now_ms() - t0);
  return r;
}

// A smile photo (role "Smile (teeth)") -> the teeth texture in the teeth
// model's uv layout (tarini2002 Sec. 4.2). {ok, texture (RGBA), ms} or the
// core's error (e.g. no teeth found).
val smile_photo_job(const std::string& name, std::uintptr_t data, std::size_t size) {
  const double t0 = now_ms();
  lk::Image photo;
  lk::Status status = decode_image(name, data, size, photo);
  if (!status.ok()) return error_result(status);
  lk::Image texture;
  status = teeth_texture(photo, texture);
  if (!status.ok()) return error_result(lk::with_context(status, name));
  val r = ok_result();
  r.set("texture", image_object(texture));
  r.set("ms", now_ms() - t0);
  return r;
}

// Micro-benchmark of what a parallel_for costs beyond its items
// (tests/browser/parallel_overhead_node.mjs): `loops` loops of `items` small
// items (a few hundred flops each, grain 64) on parallel_for, or as plain
// loops when parallel is false. Wall ms of the whole run.
double parallel_loops_ms(int loops, int items, bool parallel) {
  items = std::max(1, items);
  std::vector<double> out(items);
  const auto item = [&out](int i) {
    double x = i * 1e-3;
    for (int k = 0; k < 32; ++k) x = std::sin(x) + 0.5 * x;
    out[i] = x;
  };
  const double t0 = now_ms();
  for (int l = 0; l < loops; ++l) {
    if (parallel) {
      lk::parallel_for(0, items, 64, [&item](int i, int) { item(i); });
    } else {
      for (int i = 0; i < items; ++i) item(i);
    }
  }
  const double ms = now_ms() - t0;
  volatile double keep = out[items / 2];  // (the items' results are used)
  (void)keep;
  return ms;
}

double parallel_loops_run() { return static_cast<double>(lk::parallel_loops_run().load()); }

// `jobs` jobs in a row, each `items` small items split in two halves: on a
// HelperThread (threaded) or both halves on this thread. What waking the
// parked helper and waiting for it cost per job (the alignment makes ~760
// such jobs of ~0.4 ms each). A measurement for parallel_overhead_node.mjs.
double helper_jobs_ms(int jobs, int items, bool threaded) {
  items = std::max(2, items);
  std::vector<double> out(items);
  const std::function<void(int)> half = [&out, items](int part) {
    const int begin = part == 0 ? 0 : items / 2, end = part == 0 ? items / 2 : items;
    for (int i = begin; i < end; ++i) {
      double x = i * 1e-3;
      for (int k = 0; k < 32; ++k) x = std::sin(x) + 0.5 * x;
      out[i] = x;
    }
  };
  const double t0 = now_ms();
  if (threaded) {
    lk::HelperThread helper;
    for (int j = 0; j < jobs; ++j) helper.run(half);
  } else {
    for (int j = 0; j < jobs; ++j) half(0), half(1);
  }
  const double ms = now_ms() - t0;
  volatile double keep = out[items / 2];
  (void)keep;
  return ms;
}

}  // namespace

EMSCRIPTEN_BINDINGS(likeness_worker) {
  emscripten::function("fit_head_job", &fit_head_job);
  // Threads the core's parallel loops use here (1 in the single-threaded build).
  emscripten::function("parallel_workers", &lk::parallel_workers);
  emscripten::function("parallel_loops_ms", &parallel_loops_ms);
  // parallel_for loops that could use more than one thread so far
  // (fit_timing.mjs reads it around a fit: each loop starts the threads once).
  emscripten::function("parallel_loops_run", &parallel_loops_run);
  emscripten::function("helper_jobs_ms", &helper_jobs_ms);
  emscripten::function("animate_frame", &animate_frame);
  emscripten::function("fit_quality_job", &fit_quality_job);
  emscripten::function("warm_up_job", &warm_up_job);
  emscripten::function("export_head", &export_head);
  emscripten::function("parse_geometry", &parse_geometry);
  emscripten::function("check_image", &check_image);
  emscripten::function("texture_job", &texture_job);
  emscripten::function("export_textured", &export_textured);
  emscripten::function("parse_points", &parse_points);
  emscripten::function("eye_photo_job", &eye_photo_job);
  emscripten::function("smile_photo_job", &smile_photo_job);
}
