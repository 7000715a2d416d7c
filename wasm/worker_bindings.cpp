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
// Jobs: parse_geometry (a dropped scan), check_image (a dropped photo).
#include "common/progress.h"
#include "io/io.h"
#include "mesh/geometry.h"

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

  val r = val::object();
  r.set("ok", true);
  r.set("code", std::string("Ok"));
  r.set("message", std::string());
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
  if (data == 0 && size != 0)
    return error_result(lk::Status::error(lk::ErrorCode::Internal, name + ": no input buffer"));
  lk::Image image;
  lk::Status status = lk::read_image(reinterpret_cast<const std::uint8_t*>(data), size, image);
  if (!status.ok()) return error_result(lk::with_context(status, name));
  val r = val::object();
  r.set("ok", true);
  r.set("code", std::string("Ok"));
  r.set("message", std::string());
  r.set("name", name);
  r.set("width", image.width);
  r.set("height", image.height);
  r.set("channels", image.channels);
  return r;
}

}  // namespace

EMSCRIPTEN_BINDINGS(likeness_worker) {
  emscripten::function("parse_geometry", &parse_geometry);
  emscripten::function("check_image", &check_image);
}
