// Shared by the worker's binding files: conversions between JS values and
// core types, the worker's clock and the head project kept between calls.
#pragma once
#include "calib/camera.h"
#include "head/generic_head.h"
#include "io/io.h"
#include "io/scan_stream.h"
#include "project/project.h"
#include "teeth/teeth.h"

#include <emscripten/bind.h>
#include <emscripten/val.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace lk_worker {

using emscripten::val;

// The scan web/worker.js is reading in slices (scan_stream_begin, then
// scan_stream_push per slice); parse_scan_stream or fit_head_stream_job
// finishes it. One at a time: jobs run in order.
std::unique_ptr<lk::ScanStreamReader>& scan_stream();

template <class T>
inline val typed_array(const char* type, const std::vector<T>& flat) {
  // new <Type>Array(view) copies out of the wasm heap.
  return val::global(type).new_(emscripten::typed_memory_view(flat.size(), flat.data()));
}

inline val float32_array(const std::vector<lk::Vec3>& v) {
  std::vector<float> flat(v.size() * 3);
  for (size_t i = 0; i < v.size(); ++i)
    for (int k = 0; k < 3; ++k) flat[3 * i + k] = static_cast<float>(v[i][k]);
  return typed_array("Float32Array", flat);
}

inline val float32_array(const std::vector<lk::Vec2>& v) {
  std::vector<float> flat(v.size() * 2);
  for (size_t i = 0; i < v.size(); ++i)
    for (int k = 0; k < 2; ++k) flat[2 * i + k] = static_cast<float>(v[i][k]);
  return typed_array("Float32Array", flat);
}

inline val uint32_array(const std::vector<lk::Tri>& tris) {
  std::vector<std::uint32_t> flat(tris.size() * 3);
  for (size_t i = 0; i < tris.size(); ++i)
    for (int k = 0; k < 3; ++k) flat[3 * i + k] = static_cast<std::uint32_t>(tris[i][k]);
  return typed_array("Uint32Array", flat);
}

inline val bytes_array(const std::uint8_t* data, size_t size) {
  return val::global("Uint8Array").new_(emscripten::typed_memory_view(size, data));
}
inline val bytes_array(const std::string& text) {
  return bytes_array(reinterpret_cast<const std::uint8_t*>(text.data()), text.size());
}

inline val vec3_array(const lk::Vec3& p) {
  val a = val::array();
  for (int k = 0; k < 3; ++k) a.call<void>("push", p[k]);
  return a;
}

inline val error_result(const lk::Status& s) {
  val r = val::object();
  r.set("ok", false);
  r.set("code", std::string(lk::to_string(s.code)));
  r.set("message", s.message);
  return r;
}

inline val error_result(lk::ErrorCode code, const std::string& message) {
  return error_result(lk::Status::error(code, message));
}

// The success object every job returns, to be filled with its results.
inline val ok_result() {
  val r = val::object();
  r.set("ok", true);
  r.set("code", std::string("Ok"));
  r.set("message", std::string());
  return r;
}

// {width, height, channels, pixels} of an image (a copy out of the heap).
inline val image_object(const lk::Image& image) {
  val t = val::object();
  t.set("width", image.width);
  t.set("height", image.height);
  t.set("channels", image.channels);
  t.set("pixels", bytes_array(image.pixels.data(), image.pixels.size()));
  return t;
}

// An image object as image_object makes it (the eye and smile photo jobs'
// textures, handed back by the page) -> out; a malformed one is refused.
inline lk::Status image_from_object(const val& o, lk::Image& out) {
  if (o.isUndefined() || o.isNull() || o["pixels"].isUndefined())
    return lk::Status::error(lk::ErrorCode::InvalidInput, "not an image");
  const int w = o["width"].as<int>(), h = o["height"].as<int>(), c = o["channels"].as<int>();
  if (w <= 0 || h <= 0 || w > 8192 || h > 8192 || c < 1 || c > 4)
    return lk::Status::error(lk::ErrorCode::InvalidInput, "image of " + std::to_string(w) + "x" + std::to_string(h) + "x" +
                                                           std::to_string(c) + " is out of range");
  std::vector<std::uint8_t> pixels = emscripten::convertJSArrayToNumberVector<std::uint8_t>(o["pixels"]);
  if (pixels.size() != static_cast<std::size_t>(w) * h * c)
    return lk::Status::error(lk::ErrorCode::InvalidInput, "image pixels do not match its size");
  out.width = w;
  out.height = h;
  out.channels = c;
  out.pixels = std::move(pixels);
  return lk::Status::success();
}

// Whether an options object gives key (undefined and null objects give none).
inline bool has(const val& object, const char* key) {
  return !object.isUndefined() && !object.isNull() && !object[key].isUndefined();
}

// A photo the page handed over in the heap: RGBA pixels the browser decoded
// (decoded = {width, height}; worker.js ran inspect_image on the file first),
// or, with decoded null, the file's bytes for read_image (stb behind our
// checks: the fallback where the browser's decoders are missing). Channels
// as read_image gives them (0: RGB, or RGBA when any pixel is not opaque).
// Errors name the file.
inline lk::Status decode_image(const std::string& name, std::uintptr_t data, std::size_t size, const val& decoded,
                               lk::Image& image, int channels = 0) {
  if (data == 0 && size != 0) return lk::Status::error(lk::ErrorCode::Internal, name + ": no input buffer");
  if (has(decoded, "width") && decoded["width"].as<int>() > 0) {
    const int w = decoded["width"].as<int>(), h = has(decoded, "height") ? decoded["height"].as<int>() : 0;
    if (h <= 0 || channels < 0 || channels > 4 || size != static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * 4)
      return lk::Status::error(lk::ErrorCode::Internal, name + ": the decoded pixels do not match their size");
    const std::uint8_t* p = reinterpret_cast<const std::uint8_t*>(data);
    const std::size_t n = static_cast<std::size_t>(w) * h;
    bool opaque = true;
    for (std::size_t i = 0; i < n && opaque; ++i) opaque = p[4 * i + 3] == 255;
    const int c = channels != 0 ? channels : (opaque ? 3 : 4);
    image = lk::Image::make(w, h, c);
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint8_t* s = p + 4 * i;
      std::uint8_t* d = &image.pixels[i * c];
      if (c >= 3) {
        d[0] = s[0]; d[1] = s[1]; d[2] = s[2];
        if (c == 4) d[3] = s[3];
      } else {  // stb's luminance
        d[0] = static_cast<std::uint8_t>((s[0] * 77 + s[1] * 150 + s[2] * 29) >> 8);
        if (c == 2) d[1] = s[3];
      }
    }
    return lk::Status::success();
  }
  const lk::Status status = lk::read_image(reinterpret_cast<const std::uint8_t*>(data), size, image, channels);
  return status.ok() ? status : lk::with_context(status, name);
}

// Wraps a JS function (stage, fraction) -> bool|undefined as an lk::ProgressFn.
// Only an explicit `false` cancels, so a callback that returns nothing is fine.
inline lk::ProgressFn js_progress(val fn) {
  if (fn.isUndefined() || fn.isNull()) return {};
  return [fn](const char* stage, double fraction) {
    val answer = fn(std::string(stage), fraction);
    return !(answer.isFalse());
  };
}

// Core has no clocks: the bindings time jobs with the worker's performance.now().
inline double now_ms() { return val::global("performance").call<double>("now"); }

// The teeth textures' size: half the CLI's, the teeth cover few pixels on screen.
inline lk::TeethCompositeOptions teeth_composite() {
  lk::TeethCompositeOptions o;
  o.width = 512;
  o.height = 256;
  return o;
}

// The last fit (worker_head.cpp); null before the first.
std::unique_ptr<lk::HeadProject>& kept_project();

// The cameras of the photos the kept head was made from (worker_photos.cpp),
// by photo name: what the texture job uses for a head from photos. They
// belong to `project` only (another head kept since: not its cameras).
struct PhotoCameras {
  const lk::HeadProject* project = nullptr;
  std::vector<std::string> names;
  std::vector<lk::Camera> cameras;
  const lk::Camera* find(const lk::HeadProject* of, const std::string& name) const;
};
PhotoCameras& kept_photo_cameras();

// The generic head, parsed once per worker; null (and status) on an error.
const lk::GenericHead* generic_head(lk::Status& status);

// {meanPct, maxPct, rmsPct, points} of a stage's distances.
val stats_object(const lk::DistanceStats& d);

// What the page shows of a head project, fitted or opened (worker_head.cpp).
val head_result(const lk::HeadProject& p, const lk::GenericHead& generic);

}  // namespace lk_worker
