// Embind surface of likeness_worker.wasm: the core's long-running jobs, run
// inside a Web Worker (web/worker.js) so the page stays responsive. Each
// function converts JS values to core types, calls one job of the head
// project (core/project) and converts the result back; the project itself
// (the last fit, its pose, texture and checks) lives here between calls.
//
// Calling convention (the same for every job):
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
// Meshes handed to the page are in the SCAN's frame, over the scan it shows.
#include "worker_common.h"

#include "common/helper_thread.h"
#include "common/parallel.h"
#include "io/exif.h"
#include "mesh/geometry.h"
#include "texture/correspondences.h"

#include <emscripten/heap.h>

#include <algorithm>
#include <cmath>
#include <functional>

namespace lk_worker {

std::unique_ptr<lk::ScanStreamReader>& scan_stream() {
  static std::unique_ptr<lk::ScanStreamReader> reader;
  return reader;
}

namespace {

// ---- loading ------------------------------------------------------------------

// The page's arrays for a parsed scan. Meshes without normals get
// area-weighted vertex normals so the viewer can shade them; point clouds
// keep whatever normals the file had (possibly none).
val geometry_result(const std::string& name, lk::TriMesh& mesh, lk::GeometryKind kind,
                    const lk::ProgressFn& report) {
  const bool is_mesh = kind == lk::GeometryKind::Mesh;
  if (mesh.positions.empty()) return error_result(lk::ErrorCode::Empty, name + ": no vertices");
  if (is_mesh && mesh.normals.size() != mesh.positions.size()) mesh.normals = lk::vertex_normals(mesh);
  const std::vector<lk::Vec3>& positions = mesh.positions;
  const lk::BBox box = lk::bounding_box(positions);

  val r = ok_result();
  r.set("name", name);
  r.set("kind", std::string(is_mesh ? "mesh" : "points"));
  r.set("vertexCount", static_cast<double>(positions.size()));
  r.set("triangleCount", static_cast<double>(is_mesh ? mesh.triangles.size() : 0));
  r.set("positions", float32_array(positions));
  r.set("normals", float32_array(mesh.normals.size() == positions.size() ? mesh.normals : std::vector<lk::Vec3>{}));
  r.set("colors", float32_array(mesh.colors.size() == positions.size() ? mesh.colors : std::vector<lk::Vec3>{}));
  r.set("indices", uint32_array(is_mesh ? mesh.triangles : std::vector<lk::Tri>{}));
  r.set("bboxMin", vec3_array(box.min));
  r.set("bboxMax", vec3_array(box.max));
  lk::report(report, "load", 1.0);
  return r;
}

// Parses a dropped PLY / OBJ / XYZ / VTK file's bytes (reader chosen by
// lk::read_geometry from the name's extension or the first bytes).
val parse_geometry(const std::string& name, std::uintptr_t data, std::size_t size, val progress) {
  const lk::ProgressFn report = js_progress(progress);
  if (!lk::report(report, "load", 0.0)) return error_result(lk::ErrorCode::Cancelled, name + ": cancelled");
  if (data == 0 && size != 0) return error_result(lk::ErrorCode::Internal, name + ": no input buffer");

  lk::TriMesh mesh;
  lk::PointCloud cloud;
  lk::GeometryKind kind = lk::GeometryKind::PointCloud;
  const auto* bytes = reinterpret_cast<const std::uint8_t*>(data);
  lk::Status status = lk::read_geometry(name, bytes, size, mesh, cloud, kind);
  if (!status.ok()) return error_result(lk::with_context(status, name));
  cloud = lk::PointCloud();  // the mesh holds the same vertices
  if (!lk::report(report, "load", 0.8)) return error_result(lk::ErrorCode::Cancelled, name + ": cancelled");
  return geometry_result(name, mesh, kind, report);
}

// ---- a scan read in slices (io/scan_stream.h) ------------------------------------

std::string& scan_stream_name() {
  static std::string name;
  return name;
}

// Starts reading a scan of `size` bytes (a File's size: a double from JS).
val scan_stream_begin(const std::string& name, double size) {
  scan_stream().reset();
  if (!(size >= 0) || size > static_cast<double>(lk::kMaxGeometryBytes))
    return error_result(lk::ErrorCode::TooLarge, name + ": too large: " + std::to_string(static_cast<long long>(size)) +
                                                     " bytes, the limit is " + std::to_string(lk::kMaxGeometryBytes));
  scan_stream() = std::make_unique<lk::ScanStreamReader>(name, static_cast<std::uint64_t>(size));
  scan_stream_name() = name;
  return ok_result();
}

// The next slice, at (data, size) in the heap; the reader keeps only what it
// has not finished parsing. {ok, vertices: the count the file declares once
// known (PLY header, .pts count line), verticesRead: the OBJ or XYZ vertices
// parsed so far}.
val scan_stream_push(std::uintptr_t data, std::size_t size) {
  if (!scan_stream()) return error_result(lk::ErrorCode::Internal, "no scan is being read");
  if (data == 0 && size != 0) return error_result(lk::ErrorCode::Internal, "no input buffer");
  const lk::Status status = scan_stream()->push(reinterpret_cast<const std::uint8_t*>(data), size);
  if (!status.ok()) {
    scan_stream().reset();
    return error_result(lk::with_context(status, scan_stream_name()));
  }
  val r = ok_result();
  r.set("vertices", static_cast<double>(scan_stream()->declared_vertices()));
  r.set("verticesRead", static_cast<double>(scan_stream()->vertices_read()));
  r.set("streaming", scan_stream()->streaming());
  return r;
}

// Ends the scan being read: parse_geometry's result.
val parse_scan_stream(val progress) {
  const lk::ProgressFn report = js_progress(progress);
  if (!scan_stream()) return error_result(lk::ErrorCode::Internal, "no scan is being read");
  std::unique_ptr<lk::ScanStreamReader> reader = std::move(scan_stream());
  const std::string name = scan_stream_name();
  lk::TriMesh mesh;
  lk::GeometryKind kind = lk::GeometryKind::PointCloud;
  const lk::Status status = reader->finish(mesh, kind);
  reader.reset();
  if (!status.ok()) return error_result(lk::with_context(status, name));
  if (!lk::report(report, "load", 0.8)) return error_result(lk::ErrorCode::Cancelled, name + ": cancelled");
  return geometry_result(name, mesh, kind, report);
}

// The most the wasm heap may grow to (ALLOW_MEMORY_GROWTH's maximum).
double heap_max_bytes() { return static_cast<double>(emscripten_get_heap_max()); }

// inspect_image on a dropped photo's bytes (io.h): JPEG or PNG, whole, within
// the limits, no decompression bomb; {ok, format, width, height (as shown),
// orientation} or the refusal, naming the file. worker.js runs it before the
// browser decodes the bytes.
val inspect_image(const std::string& name, std::uintptr_t data, std::size_t size) {
  if (data == 0 && size != 0) return error_result(lk::ErrorCode::Internal, name + ": no input buffer");
  lk::ImageInfo info;
  const lk::Status status = lk::inspect_image(reinterpret_cast<const std::uint8_t*>(data), size, info);
  if (!status.ok()) return error_result(lk::with_context(status, name));
  val r = ok_result();
  r.set("format", std::string(info.format));
  r.set("width", info.width);
  r.set("height", info.height);
  r.set("orientation", info.orientation);
  return r;
}

// jpeg_truncation_probe (io.h): {ok, probe: Uint8Array} (empty for a PNG);
// worker.js decodes both with the browser and refuses the photo when their
// pixels differ (image data cut short and filled by the decoder).
val jpeg_truncation_probe(const std::string& name, std::uintptr_t data, std::size_t size) {
  if (data == 0 && size != 0) return error_result(lk::ErrorCode::Internal, name + ": no input buffer");
  lk::Bytes probe;
  const lk::Status status = lk::jpeg_truncation_probe(reinterpret_cast<const std::uint8_t*>(data), size, probe);
  if (!status.ok()) return error_result(lk::with_context(status, name));
  val r = ok_result();
  r.set("probe", bytes_array(probe.data(), probe.size()));
  return r;
}

// Decodes a dropped photo (decoded: see decode_image) to check it is a
// whole, usable image and reports its size; the texture job decodes it
// again, so the pixels are not kept here.
val check_image(const std::string& name, std::uintptr_t data, std::size_t size, val decoded) {
  lk::Image image;
  lk::Status status = decode_image(name, data, size, decoded, image);
  if (!status.ok()) return error_result(status);
  val r = ok_result();
  r.set("name", name);
  r.set("width", image.width);
  r.set("height", image.height);
  r.set("channels", image.channels);
  return r;
}

// The focal in pixels a photo file's EXIF gives for its width x height
// (io/exif.h): {focalPx (0: none: not a JPEG, no EXIF, no focal tag, or
// broken EXIF), source (the rule used)}. The prior of a head from photos,
// as `likeness photos` takes it.
val photo_focal(std::uintptr_t data, std::size_t size, int width, int height) {
  lk::ExifInfo exif;
  std::string source;
  double focal = 0;
  if (lk::read_jpeg_exif(reinterpret_cast<const std::uint8_t*>(data), size, exif).ok() && exif.present)
    focal = lk::exif_focal_pixels(exif, width, height, 0, &source);
  val r = val::object();
  r.set("focalPx", focal);
  r.set("source", source);
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
  r.set("points", typed_array("Float64Array", flat));
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
}  // namespace lk_worker

// The jobs of worker_head.cpp and worker_texture.cpp register in their files.
EMSCRIPTEN_BINDINGS(likeness_worker_load) {
  using namespace lk_worker;
  // Threads the core's parallel loops use here (1 in the single-threaded build).
  emscripten::function("parallel_workers", &lk::parallel_workers);
  emscripten::function("parallel_loops_ms", &parallel_loops_ms);
  // parallel_for loops that could use more than one thread so far
  // (fit_timing.mjs reads it around a fit: each loop starts the threads once).
  emscripten::function("parallel_loops_run", &parallel_loops_run);
  emscripten::function("helper_jobs_ms", &helper_jobs_ms);
  emscripten::function("parse_geometry", &parse_geometry);
  emscripten::function("scan_stream_begin", &scan_stream_begin);
  emscripten::function("scan_stream_push", &scan_stream_push);
  emscripten::function("parse_scan_stream", &parse_scan_stream);
  emscripten::function("heap_max_bytes", &heap_max_bytes);
  emscripten::function("check_image", &check_image);
  emscripten::function("photo_focal", &photo_focal);
  emscripten::function("inspect_image", &inspect_image);
  emscripten::function("jpeg_truncation_probe", &jpeg_truncation_probe);
  emscripten::function("parse_points", &parse_points);
}
