// likeness_viewer.wasm: the 3D view of the web app. An SDL2 window on the
// page's <canvas id="canvas"> with a GLES 3.0 (WebGL2) context, an orbit
// camera on mouse, touch and keyboard, and embind calls for web/js/viewer.js:
//
//   show_mesh(positions, normals, colors, indices) -> "" or an error message
//   show_points(positions, normals, colors)        -> "" or an error message
//   show_generic_head()                            -> "" or an error message
//   show_mesh_keep_view(...)  as show_mesh, the camera stays (stage/level switch)
//   update_positions(positions) -> "" or error: animation frame, same #V
//     (Float32Array #V*3; only moved vertices are renormalized and re-sent);
//     last_update() -> {moved, renormalized, uploaded} vertex counts of it
//   set_morph_targets(counts, indices, offsets) -> "" or error: morph
//     targets blended in the vertex shader on the shown mesh (counts
//     Uint32Array #shapes, indices Uint32Array and offsets Float32Array
//     (3 per index) concatenated over the shapes); set_morph_weights(w)
//     (Float32Array, one per shape) -> "" or error: a frame of animation;
//     begin_morph_targets(counts, indices, offsets) -> "" or error and
//     continue_morph_targets(budgetMs) -> {done, error}: the same spread
//     over frames (the page's way: no stall); morph_target_count(),
//     last_morph_upload() -> {copyMs, splitMs, prepareMs, packMs, uploadMs,
//     steps, longestStepMs, bands, longestBandMs, syncMs, entries, textureBytes} (where the last one
//     spent its time), model_serial() (changes with every model shown),
//     pose_serial() (changes with every update_positions)
//   show_textured_mesh(positions, indices, uvs, width, height, channels, pixels)
//     -> "" or error: a head with its skin texture (camera kept)
//   set_markers(positions, colors) -> "": big points over the model (the
//     landmark asked for); empty positions clear them
//   add_component(positions, indices, colors, uvs, width, height, channels, pixels)
//     -> "" or error: an extra mesh (eyeball, teeth, tongue) drawn with the
//     model; clear_components(), set_components_visible(on),
//     set_component_matrix(index, m16) (column-major object -> world),
//     set_component_positions(index, positions),
//     set_component_morph_targets(index, counts, indices, offsets) and
//     set_component_morph_weights(index, w) -> "" or error (the tongue's
//     push on the GPU), component_morph_target_count(index)
//   set_overlay_points(positions, normals, colors) -> "": the scan under a fit
//     (empty positions clear it); set_overlay_visible(on)
//   set_point_size(pixels), set_wireframe(on), reset_view()
//   set_head_frame(fx, fy, fz, ux, uy, uz): the shown head's facing (+z) and
//     up (+y) in the scan's frame; reframes the view on its face (kept by
//     reset_view until a new scan or the generic head is shown)
//   view_direction() -> [x, y, z]: unit vector from the view's target to the eye
//   orbit(dx, dy), pan(dx, dy), zoom(amount): camera steps in pixels, as if
//     dragged (the page's keyboard control)
//   frames_drawn() -> number of frames drawn so far (0 until the head is up)
//   set_profiling(on), last_draw_ms(): glFinish after each draw and its ms
//   startup_error() -> "" or why the viewer could not start
//   startup_times() -> [[step, ms], ...]: main()'s steps (SDL, WebGL context,
//     renderer, generic head)
// Arrays are JS typed arrays (Float32Array / Uint32Array), shapes as in
// viewer_scene.h. Nothing throws: failures come back as messages.
//
// Input: left drag orbits, right/middle or shift+left drag pans, the wheel
// zooms; one finger orbits and a pinch zooms on touch screens. Keys are
// web/js/viewer.js's (arrows orbit, shift+arrows pan, +/- zoom, R resets).
// The canvas is redrawn only when something changed, so an idle page costs
// no CPU (WebGL2 runs on the CPU under SwiftShader).
#include "viewer_scene.h"

#include <GLES3/gl3.h>
#include <SDL.h>
#include <emscripten.h>
#include <emscripten/bind.h>
#include <emscripten/html5.h>
#include <emscripten/val.h>

#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

namespace {

using emscripten::val;

// The one viewer of the page. A global because the browser's frame callback
// and the embind functions have no other way to reach it.
struct Viewer {
  SDL_Window* window = nullptr;
  SDL_GLContext context = nullptr;
  lk::web::ViewerScene scene;
  int frames_drawn = 0;
  // Profiling (the page's ?profile=1): glFinish after each draw so the time
  // spent rasterizing (SwiftShader: on the CPU, in the GPU process) is
  // measured here instead of showing up later as a slow frame.
  bool profiling = false;
  // Drawing-buffer pixels per CSS pixel, times devicePixelRatio (the page
  // lowers it while animating: SwiftShader's cost grows with the pixels).
  double render_scale = 1.0;
  double last_draw_ms = 0;
  std::string startup_error;
  // main()'s steps, ms each (startup_times()): where the viewer's start goes.
  std::vector<std::pair<const char*, double>> startup_ms;
  bool panning = false, orbiting = false;
  // Animation: the last frame's positions (reused, #V*3) and what its
  // update did.
  std::vector<float> animation_positions;
  std::vector<float> morph_weights;  // the last set_morph_weights (reused)
  std::vector<float> component_weights;  // the last set_component_morph_weights (reused)
  double morph_copy_ms = 0;          // the last set_morph_targets' copy into the heap
  int pose_serial = 0;               // update_positions calls so far
  lk::MeshUpdateStats last_update;
};
Viewer* g_viewer = nullptr;

constexpr const char* kCanvas = "#canvas";

// Keeps the drawing buffer at the canvas' CSS size times the device pixel
// ratio, so the page's layout decides the size and the image stays sharp.
void fit_canvas(Viewer& v) {
  double css_w = 0, css_h = 0;
  emscripten_get_element_css_size(kCanvas, &css_w, &css_h);
  const double dpr = emscripten_get_device_pixel_ratio() * v.render_scale;
  const int want_w = std::max(1, int(std::lround(css_w * dpr)));
  const int want_h = std::max(1, int(std::lround(css_h * dpr)));
  int w = 0, h = 0;
  emscripten_get_canvas_element_size(kCanvas, &w, &h);
  if (w != want_w || h != want_h) emscripten_set_canvas_element_size(kCanvas, want_w, want_h);
  v.scene.resize(want_w, want_h);
}

// SDL reports mouse motion in its window's units; the camera wants
// framebuffer pixels.
float pixels_per_sdl_unit(const Viewer& v) {
  int sdl_w = 0, sdl_h = 0, w = 0, h = 0;
  SDL_GetWindowSize(v.window, &sdl_w, &sdl_h);
  emscripten_get_canvas_element_size(kCanvas, &w, &h);
  return sdl_w > 0 ? float(w) / float(sdl_w) : 1.0f;
}

void handle_event(Viewer& v, const SDL_Event& e) {
  switch (e.type) {
    case SDL_MOUSEBUTTONDOWN: {
      const bool shift = (SDL_GetModState() & KMOD_SHIFT) != 0;
      if (e.button.button == SDL_BUTTON_LEFT && !shift) v.orbiting = true;
      else v.panning = true;
      break;
    }
    case SDL_MOUSEBUTTONUP:
      v.orbiting = v.panning = false;
      break;
    case SDL_MOUSEMOTION: {
      if (!v.orbiting && !v.panning) break;
      const float k = pixels_per_sdl_unit(v);
      if (v.orbiting) v.scene.orbit(e.motion.xrel * k, e.motion.yrel * k);
      else v.scene.pan(e.motion.xrel * k, e.motion.yrel * k);
      break;
    }
    case SDL_MOUSEWHEEL:
      // SDL scales DOM pixel deltas down by 100 (one notch ~ 1); give the
      // camera pixels back. Positive y is "wheel away": zoom in.
      v.scene.zoom(e.wheel.preciseY * 100.0f);
      break;
    case SDL_MULTIGESTURE: {
      // dDist is the change in finger spread, normalised to the touch device.
      int w = 0, h = 0;
      emscripten_get_canvas_element_size(kCanvas, &w, &h);
      v.scene.zoom(e.mgesture.dDist * float(h) * 2.0f);
      break;
    }
    default:
      break;
  }
}

void frame() {
  Viewer& v = *g_viewer;
  SDL_Event e;
  while (SDL_PollEvent(&e)) handle_event(v, e);
  fit_canvas(v);
  lk::Status status;
  const double t0 = emscripten_get_now();
  if (v.scene.draw_if_needed(status)) {
    if (v.profiling) {
      // glFinish does not wait in Chromium's WebGL; reading a pixel does.
      unsigned char pixel[4];
      glReadPixels(0, 0, 1, 1, GL_RGBA, GL_UNSIGNED_BYTE, pixel);
      v.last_draw_ms = emscripten_get_now() - t0;
    }
    if (status.ok()) ++v.frames_drawn;
    else std::fprintf(stderr, "likeness viewer: draw failed: %s\n", status.message.c_str());
  }
}

std::string show_start_head() {
  lk::TriMesh head;
  lk::Status s = lk::web::start_head(head);
  if (s.ok()) s = g_viewer->scene.show_mesh(head);
  return s.ok() ? std::string() : s.message;
}

// ---- embind -----------------------------------------------------------------

template <typename T>
std::vector<T> from_js(const val& array) {
  if (array.isUndefined() || array.isNull()) return {};
  return emscripten::convertJSArrayToNumberVector<T>(array);
}

std::string js_show_mesh(val positions, val normals, val colors, val indices) {
  if (!g_viewer || !g_viewer->startup_error.empty()) return "the viewer is not running";
  lk::TriMesh mesh;
  lk::Status s = lk::web::mesh_from_arrays(from_js<float>(positions), from_js<float>(normals),
                                           from_js<float>(colors), from_js<std::uint32_t>(indices), mesh);
  if (s.ok()) s = g_viewer->scene.show_mesh(mesh);
  return s.ok() ? std::string() : s.message;
}

// Same as show_mesh but keeps the camera where the user left it.
std::string js_show_mesh_keep_view(val positions, val normals, val colors, val indices) {
  if (!g_viewer || !g_viewer->startup_error.empty()) return "the viewer is not running";
  lk::TriMesh mesh;
  lk::Status s = lk::web::mesh_from_arrays(from_js<float>(positions), from_js<float>(normals),
                                           from_js<float>(colors), from_js<std::uint32_t>(indices), mesh);
  if (s.ok()) s = g_viewer->scene.show_mesh(mesh, true);
  return s.ok() ? std::string() : s.message;
}

// An animation frame: new positions for the shown mesh (same vertex count),
// a Float32Array of #V*3. Copied once into a buffer kept between frames (no
// allocation per frame); the renderer re-sends only what moved.
std::string js_update_positions(val positions) {
  if (!g_viewer || !g_viewer->startup_error.empty()) return "the viewer is not running";
  if (positions.isUndefined() || positions.isNull()) return "no positions";
  const size_t n = positions["length"].as<size_t>();
  if (n == 0 || n % 3 != 0) return "positions: length " + std::to_string(n) + " is not a positive multiple of 3";
  std::vector<float>& staging = g_viewer->animation_positions;
  if (staging.size() != n) staging.resize(n);
  // Float32Array.set into a view of the heap: one memcpy for a typed array
  // (a plain JS array is converted element by element).
  val(emscripten::typed_memory_view(n, staging.data())).call<void>("set", positions);
  lk::MeshUpdateStats stats;
  const lk::Status s = g_viewer->scene.update_positions(staging.data(), n / 3, &stats);
  if (!s.ok()) return s.message;
  g_viewer->last_update = stats;
  ++g_viewer->pose_serial;
  return std::string();
}

// A typed array copied into a vector through a view of the heap (one memcpy).
template <typename T>
void copy_typed(const val& array, std::vector<T>& out) {
  const size_t n = array["length"].as<size_t>();
  out.resize(n);
  if (n) val(emscripten::typed_memory_view(n, out.data())).call<void>("set", array);
}

// The morph targets' three typed arrays copied out of JS (what: the call,
// for its message); "" or why not.
struct MorphArrays {
  std::vector<std::uint32_t> counts, indices;
  std::vector<float> offsets;
};
std::string copy_morph_arrays(const char* what, val counts, val indices, val offsets, MorphArrays& out) {
  if (!g_viewer || !g_viewer->startup_error.empty()) return "the viewer is not running";
  for (const val* a : {&counts, &indices, &offsets})
    if (a->isUndefined() || a->isNull()) return std::string(what) + " needs counts, indices and offsets";
  const double t0 = emscripten_get_now();
  copy_typed(counts, out.counts);
  copy_typed(indices, out.indices);
  copy_typed(offsets, out.offsets);
  g_viewer->morph_copy_ms = emscripten_get_now() - t0;
  return std::string();
}

std::string js_set_morph_targets(val counts, val indices, val offsets) {
  MorphArrays m;
  if (std::string e = copy_morph_arrays("set_morph_targets", counts, indices, offsets, m); !e.empty()) return e;
  const lk::Status s = g_viewer->scene.set_morph_targets(m.counts.data(), m.counts.size(), m.indices.data(), m.indices.size(),
                                                         m.offsets.data(), m.offsets.size());
  return s.ok() ? std::string() : s.message;
}

// set_morph_targets over several frames (ViewerScene::begin_morph_targets):
// begin with the same arrays, then continue_morph_targets(budgetMs) once a
// frame -> {done, error} until done (uploaded) or an error.
std::string js_begin_morph_targets(val counts, val indices, val offsets) {
  MorphArrays m;
  if (std::string e = copy_morph_arrays("begin_morph_targets", counts, indices, offsets, m); !e.empty()) return e;
  const lk::Status s = g_viewer->scene.begin_morph_targets(m.counts.data(), m.counts.size(), m.indices.data(),
                                                           m.indices.size(), m.offsets.data(), m.offsets.size());
  return s.ok() ? std::string() : s.message;
}

val js_continue_morph_targets(double budget_ms) {
  val r = val::object();
  bool done = false;
  lk::Status s = g_viewer && g_viewer->startup_error.empty()
                     ? g_viewer->scene.continue_morph_targets(std::isfinite(budget_ms) ? budget_ms : 0.0, done)
                     : lk::Status::error(lk::ErrorCode::InvalidInput, "the viewer is not running");
  r.set("done", done);
  r.set("error", s.ok() ? std::string() : s.message);
  return r;
}

// Where the last set_morph_targets or job spent its time: {copyMs (the
// typed arrays into the heap), splitMs, prepareMs, packMs, uploadMs, steps,
// longestStepMs, bands, longestBandMs, syncMs (ViewerScene's MorphUploadTimes),
// entries, textureBytes}.
val js_last_morph_upload() {
  val r = val::object();
  if (!g_viewer) return r;
  const lk::web::ViewerScene::MorphUploadTimes& t = g_viewer->scene.last_morph_upload();
  r.set("copyMs", g_viewer->morph_copy_ms);
  r.set("splitMs", t.split_ms);
  r.set("prepareMs", t.prepare_ms);
  r.set("packMs", t.pack_ms);
  r.set("uploadMs", t.upload_ms);
  r.set("steps", t.steps);
  r.set("longestStepMs", t.longest_step_ms);
  r.set("bands", t.bands);
  r.set("syncMs", t.sync_ms);
  r.set("longestBandMs", t.longest_band_ms);
  r.set("entries", double(t.entries));
  r.set("textureBytes", double(t.texture_bytes));
  return r;
}

// An animation frame on the GPU: the weights only (a uniform update).
std::string js_set_morph_weights(val weights) {
  if (!g_viewer || !g_viewer->startup_error.empty()) return "the viewer is not running";
  if (weights.isUndefined() || weights.isNull()) return "no weights";
  std::vector<float>& w = g_viewer->morph_weights;
  copy_typed(weights, w);
  const lk::Status s = g_viewer->scene.set_morph_weights(w.data(), w.size());
  return s.ok() ? std::string() : s.message;
}

int js_morph_target_count() { return g_viewer ? g_viewer->scene.morph_target_count() : 0; }
int js_model_serial() { return g_viewer ? g_viewer->scene.model_serial() : 0; }
int js_pose_serial() { return g_viewer ? g_viewer->pose_serial : 0; }

// A head with its skin texture: the mesh as show_mesh_keep_view plus uvs
// (#V*2) and the texture (width*height*channels sRGB bytes, 3 or 4 channels).
std::string js_show_textured_mesh(val positions, val indices, val uvs, int width, int height, int channels,
                                  val pixels) {
  if (!g_viewer || !g_viewer->startup_error.empty()) return "the viewer is not running";
  lk::TriMesh mesh;
  lk::Status s = lk::web::mesh_from_arrays(from_js<float>(positions), {}, {}, from_js<std::uint32_t>(indices), mesh);
  if (!s.ok()) return s.message;
  const std::vector<float> uv = from_js<float>(uvs);
  if (uv.size() != 2 * mesh.positions.size())
    return "uvs: " + std::to_string(uv.size()) + " values for " + std::to_string(mesh.positions.size()) +
           " vertices (need 2 per vertex)";
  mesh.uvs.resize(mesh.positions.size());
  for (size_t i = 0; i < mesh.uvs.size(); ++i) {
    if (!std::isfinite(uv[2 * i]) || !std::isfinite(uv[2 * i + 1])) return "uvs: NaN or infinite values";
    mesh.uvs[i] = lk::Vec2(uv[2 * i], uv[2 * i + 1]);
  }
  if (width <= 0 || height <= 0 || (channels != 3 && channels != 4)) return "texture: bad size or channel count";
  lk::Image image;
  image.width = width;
  image.height = height;
  image.channels = channels;
  image.pixels = from_js<std::uint8_t>(pixels);
  if (image.pixels.size() != static_cast<size_t>(width) * height * channels)
    return "texture: " + std::to_string(image.pixels.size()) + " bytes for " + std::to_string(width) + "x" +
           std::to_string(height) + "x" + std::to_string(channels);
  s = g_viewer->scene.show_mesh(mesh, true);
  if (s.ok()) s = g_viewer->scene.set_texture(image);
  return s.ok() ? std::string() : s.message;
}

// One extra mesh drawn with the model (eyeball, teeth, tongue): colors #V*3
// linear RGB or empty; uvs #V*2 with a texture (width*height*channels bytes)
// or empty.
std::string js_add_component(val positions, val indices, val colors, val uvs, int width, int height, int channels,
                             val pixels) {
  if (!g_viewer || !g_viewer->startup_error.empty()) return "the viewer is not running";
  lk::TriMesh mesh;
  lk::Status s = lk::web::mesh_from_arrays(from_js<float>(positions), {}, from_js<float>(colors),
                                           from_js<std::uint32_t>(indices), mesh);
  if (!s.ok()) return s.message;
  const std::vector<float> uv = from_js<float>(uvs);
  if (uv.empty()) {
    s = g_viewer->scene.add_component(mesh, nullptr);
    return s.ok() ? std::string() : s.message;
  }
  if (uv.size() != 2 * mesh.positions.size()) return "uvs: need 2 per vertex";
  mesh.uvs.resize(mesh.positions.size());
  for (size_t i = 0; i < mesh.uvs.size(); ++i) mesh.uvs[i] = lk::Vec2(uv[2 * i], uv[2 * i + 1]);
  lk::Image image;
  image.width = width;
  image.height = height;
  image.channels = channels;
  image.pixels = from_js<std::uint8_t>(pixels);
  if (width <= 0 || height <= 0 || (channels != 3 && channels != 4) ||
      image.pixels.size() != static_cast<size_t>(width) * height * channels)
    return "texture: size and bytes disagree";
  s = g_viewer->scene.add_component(mesh, &image);
  return s.ok() ? std::string() : s.message;
}

// Rigid motion of component `index` (order of add_component): 16 floats,
// column-major (the jaw's motion for the lower teeth and the tongue).
std::string js_set_component_matrix(int index, val matrix) {
  if (!g_viewer || !g_viewer->startup_error.empty()) return "the viewer is not running";
  const std::vector<float> m = from_js<float>(matrix);
  if (m.size() != 16) return "a 4x4 matrix needs 16 numbers";
  glm::mat4 model(1.0f);
  for (int i = 0; i < 16; ++i) {
    if (!std::isfinite(m[i])) return "matrix: NaN or infinite values";
    model[i / 4][i % 4] = m[i];
  }
  if (index < 0) return "no component " + std::to_string(index);
  lk::Status s = g_viewer->scene.set_component_matrix(static_cast<size_t>(index), model);
  return s.ok() ? std::string() : s.message;
}

// Component index's vertices (#V * 3 floats, its own frame): a tongue out.
std::string js_set_component_positions(int index, val positions) {
  if (!g_viewer || !g_viewer->startup_error.empty()) return "the viewer is not running";
  const std::vector<float> p = from_js<float>(positions);
  if (index < 0) return "no component " + std::to_string(index);
  if (p.size() % 3) return "positions: need 3 numbers per vertex";
  lk::Status s = g_viewer->scene.set_component_positions(static_cast<size_t>(index), p.data(), p.size() / 3);
  return s.ok() ? std::string() : s.message;
}

// The tongue's push as morph targets on component index (the same flat
// arrays as set_morph_targets, the component's own vertices), and a frame's
// weights for them (Float32Array, one per shape): no vertex upload.
std::string js_set_component_morph_targets(int index, val counts, val indices, val offsets) {
  if (index < 0) return "no component " + std::to_string(index);
  MorphArrays m;
  if (std::string e = copy_morph_arrays("set_component_morph_targets", counts, indices, offsets, m); !e.empty()) return e;
  const lk::Status s = g_viewer->scene.set_component_morph_targets(static_cast<size_t>(index), m.counts.data(), m.counts.size(),
                                                                   m.indices.data(), m.indices.size(), m.offsets.data(),
                                                                   m.offsets.size());
  return s.ok() ? std::string() : s.message;
}

std::string js_set_component_morph_weights(int index, val weights) {
  if (!g_viewer || !g_viewer->startup_error.empty()) return "the viewer is not running";
  if (index < 0) return "no component " + std::to_string(index);
  if (weights.isUndefined() || weights.isNull()) return "no weights";
  std::vector<float>& w = g_viewer->component_weights;
  copy_typed(weights, w);
  const lk::Status s = g_viewer->scene.set_component_morph_weights(static_cast<size_t>(index), w.data(), w.size());
  return s.ok() ? std::string() : s.message;
}

int js_component_morph_target_count(int index) {
  return g_viewer && index >= 0 ? g_viewer->scene.component_morph_target_count(static_cast<size_t>(index)) : 0;
}

void js_clear_components() {
  if (g_viewer) g_viewer->scene.clear_components();
}
void js_set_components_visible(bool on) {
  if (g_viewer) g_viewer->scene.set_components_visible(on);
}

// Big marker points (positions #N*3, colors #N*3 sRGB); empty clears them.
std::string js_set_markers(val positions, val colors) {
  if (!g_viewer || !g_viewer->startup_error.empty()) return "the viewer is not running";
  std::vector<float> flat = from_js<float>(positions);
  lk::PointCloud cloud;
  if (!flat.empty()) {
    lk::Status s = lk::web::cloud_from_arrays(flat, {}, from_js<float>(colors), cloud);
    if (!s.ok()) return s.message;
  }
  lk::Status s = g_viewer->scene.set_markers(cloud);
  return s.ok() ? std::string() : s.message;
}

// The scan's points drawn under a fitted head; empty positions clear them.
std::string js_set_overlay_points(val positions, val normals, val colors) {
  if (!g_viewer || !g_viewer->startup_error.empty()) return "the viewer is not running";
  std::vector<float> flat = from_js<float>(positions);
  if (flat.empty()) {
    g_viewer->scene.clear_overlay();
    return std::string();
  }
  lk::PointCloud cloud;
  lk::Status s = lk::web::cloud_from_arrays(flat, from_js<float>(normals), from_js<float>(colors), cloud);
  if (s.ok()) s = g_viewer->scene.set_overlay_points(cloud);
  return s.ok() ? std::string() : s.message;
}

void js_set_overlay_visible(bool on) {
  if (g_viewer) g_viewer->scene.set_overlay_visible(on);
}

std::string js_show_points(val positions, val normals, val colors) {
  if (!g_viewer || !g_viewer->startup_error.empty()) return "the viewer is not running";
  lk::PointCloud cloud;
  lk::Status s = lk::web::cloud_from_arrays(from_js<float>(positions), from_js<float>(normals),
                                            from_js<float>(colors), cloud);
  if (s.ok()) s = g_viewer->scene.show_points(cloud);
  return s.ok() ? std::string() : s.message;
}

std::string js_show_generic_head() {
  if (!g_viewer || !g_viewer->startup_error.empty()) return "the viewer is not running";
  return show_start_head();
}

void js_set_point_size(float pixels) {
  if (g_viewer && std::isfinite(pixels)) g_viewer->scene.set_point_size(std::min(64.0f, std::max(1.0f, pixels)));
}

void js_set_wireframe(bool on) {
  if (g_viewer) g_viewer->scene.set_wireframe(on);
}

void js_reset_view() {
  if (g_viewer) g_viewer->scene.reset_view();
}

void js_set_head_frame(double fx, double fy, double fz, double ux, double uy, double uz) {
  const lk::Vec3 facing(fx, fy, fz), up(ux, uy, uz);
  if (g_viewer && facing.allFinite() && up.allFinite()) g_viewer->scene.set_head_frame(facing, up);
}

val js_view_direction() {
  val a = val::array();
  if (!g_viewer) return a;
  const lk::Vec3 d = g_viewer->scene.view_direction();
  for (int k = 0; k < 3; ++k) a.call<void>("push", d[k]);
  return a;
}

// Camera steps for keyboard (and scripted) control, in framebuffer pixels as
// if dragged; zoom > 0 moves closer.
void js_orbit(float dx, float dy) {
  if (g_viewer && std::isfinite(dx) && std::isfinite(dy)) g_viewer->scene.orbit(dx, dy);
}
void js_pan(float dx, float dy) {
  if (g_viewer && std::isfinite(dx) && std::isfinite(dy)) g_viewer->scene.pan(dx, dy);
}
void js_zoom(float amount) {
  if (g_viewer && std::isfinite(amount)) g_viewer->scene.zoom(amount);
}

void js_set_render_scale(double scale) {
  if (g_viewer && std::isfinite(scale)) g_viewer->render_scale = std::min(2.0, std::max(0.25, scale));
}

void js_set_profiling(bool on) {
  if (g_viewer) g_viewer->profiling = on;
}
double js_last_draw_ms() { return g_viewer ? g_viewer->last_draw_ms : 0; }
// What the last update_positions did: {moved, renormalized, uploaded} vertices.
val js_last_update() {
  val o = val::object();
  const lk::MeshUpdateStats s = g_viewer ? g_viewer->last_update : lk::MeshUpdateStats{};
  o.set("moved", s.moved_vertices);
  o.set("renormalized", s.renormalized);
  o.set("uploaded", s.uploaded_vertices);
  return o;
}

int js_frames_drawn() { return g_viewer ? g_viewer->frames_drawn : 0; }
// main()'s steps so far: [[name, ms], ...].
val js_startup_times() {
  val r = val::array();
  if (g_viewer)
    for (const auto& [name, ms] : g_viewer->startup_ms) {
      val step = val::array();
      step.call<void>("push", std::string(name));
      step.call<void>("push", ms);
      r.call<void>("push", step);
    }
  return r;
}

std::string js_startup_error() { return g_viewer ? g_viewer->startup_error : std::string("not started"); }

}  // namespace

EMSCRIPTEN_BINDINGS(likeness_viewer) {
  emscripten::function("show_mesh", &js_show_mesh);
  emscripten::function("show_points", &js_show_points);
  emscripten::function("show_mesh_keep_view", &js_show_mesh_keep_view);
  emscripten::function("update_positions", &js_update_positions);
  emscripten::function("set_morph_targets", &js_set_morph_targets);
  emscripten::function("set_morph_weights", &js_set_morph_weights);
  emscripten::function("morph_target_count", &js_morph_target_count);
  emscripten::function("last_morph_upload", &js_last_morph_upload);
  emscripten::function("begin_morph_targets", &js_begin_morph_targets);
  emscripten::function("continue_morph_targets", &js_continue_morph_targets);
  emscripten::function("model_serial", &js_model_serial);
  emscripten::function("pose_serial", &js_pose_serial);
  emscripten::function("set_overlay_points", &js_set_overlay_points);
  emscripten::function("show_textured_mesh", &js_show_textured_mesh);
  emscripten::function("set_markers", &js_set_markers);
  emscripten::function("add_component", &js_add_component);
  emscripten::function("clear_components", &js_clear_components);
  emscripten::function("set_component_matrix", &js_set_component_matrix);
  emscripten::function("set_component_positions", &js_set_component_positions);
  emscripten::function("set_component_morph_targets", &js_set_component_morph_targets);
  emscripten::function("set_component_morph_weights", &js_set_component_morph_weights);
  emscripten::function("component_morph_target_count", &js_component_morph_target_count);
  emscripten::function("set_components_visible", &js_set_components_visible);
  emscripten::function("set_overlay_visible", &js_set_overlay_visible);
  emscripten::function("show_generic_head", &js_show_generic_head);
  emscripten::function("set_point_size", &js_set_point_size);
  emscripten::function("set_wireframe", &js_set_wireframe);
  emscripten::function("reset_view", &js_reset_view);
  emscripten::function("set_head_frame", &js_set_head_frame);
  emscripten::function("view_direction", &js_view_direction);
  emscripten::function("orbit", &js_orbit);
  emscripten::function("pan", &js_pan);
  emscripten::function("zoom", &js_zoom);
  emscripten::function("frames_drawn", &js_frames_drawn);
  emscripten::function("set_profiling", &js_set_profiling);
  emscripten::function("set_render_scale", &js_set_render_scale);
  emscripten::function("last_draw_ms", &js_last_draw_ms);
  emscripten::function("last_update", &js_last_update);
  emscripten::function("startup_error", &js_startup_error);
  emscripten::function("startup_times", &js_startup_times);
}

int main(int argc, char** argv) {
  g_viewer = new Viewer();
  Viewer& v = *g_viewer;
  double step_start = emscripten_get_now();
  const auto step_done = [&](const char* name) {
    const double now = emscripten_get_now();
    v.startup_ms.emplace_back(name, now - step_start);
    step_start = now;
  };
  // Arguments from the page (Module.arguments): --msaa N (samples, 0 = off).
  int msaa = 4;
  for (int i = 1; i + 1 < argc; ++i)
    if (std::string(argv[i]) == "--msaa") msaa = std::max(0, std::min(8, std::atoi(argv[i + 1])));
  // SDL listens for keys on the canvas (default: the whole window, where it
  // would swallow Tab and the arrows for the rest of the page); see below.
  SDL_SetHint(SDL_HINT_EMSCRIPTEN_KEYBOARD_ELEMENT, kCanvas);
  if (SDL_Init(SDL_INIT_VIDEO) != 0) {
    v.startup_error = std::string("SDL_Init failed: ") + SDL_GetError();
    return 0;
  }
  step_done("SDL_Init");
  SDL_GL_SetAttribute(SDL_GL_CONTEXT_PROFILE_MASK, SDL_GL_CONTEXT_PROFILE_ES);
  SDL_GL_SetAttribute(SDL_GL_CONTEXT_MAJOR_VERSION, 3);
  SDL_GL_SetAttribute(SDL_GL_CONTEXT_MINOR_VERSION, 0);
  SDL_GL_SetAttribute(SDL_GL_DEPTH_SIZE, 24);
  SDL_GL_SetAttribute(SDL_GL_MULTISAMPLEBUFFERS, msaa > 0 ? 1 : 0);  // WebGL antialias
  SDL_GL_SetAttribute(SDL_GL_MULTISAMPLESAMPLES, msaa);
  v.window = SDL_CreateWindow("Likeness", SDL_WINDOWPOS_UNDEFINED, SDL_WINDOWPOS_UNDEFINED, 960, 720,
                              SDL_WINDOW_OPENGL);
  if (!v.window) {
    v.startup_error = std::string("could not create the window: ") + SDL_GetError();
    return 0;
  }
  step_done("window");
  // SDL's key handlers call preventDefault on keys, Tab included, which
  // would trap keyboard users in the canvas. Unregister them: web/js/viewer.js
  // handles the view keys (through orbit/pan/zoom below) and lets the rest
  // through.
  emscripten_set_keydown_callback(kCanvas, nullptr, 0, nullptr);
  emscripten_set_keyup_callback(kCanvas, nullptr, 0, nullptr);
  emscripten_set_keypress_callback(kCanvas, nullptr, 0, nullptr);
  v.context = SDL_GL_CreateContext(v.window);
  if (!v.context) {
    v.startup_error = std::string("WebGL 2 is not available: ") + SDL_GetError();
    return 0;
  }
  step_done("WebGL context");
  if (lk::Status s = v.scene.init(); !s.ok()) {
    v.startup_error = "the renderer could not start: " + s.message;
    return 0;
  }
  step_done("renderer (shaders)");
  fit_canvas(v);
  if (std::string err = show_start_head(); !err.empty()) {
    v.startup_error = "could not show the head: " + err;
    return 0;
  }
  step_done("generic head shown");
  emscripten_set_main_loop(frame, 0, 0);
  return 0;
}
