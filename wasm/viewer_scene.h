// What the web viewer shows: one model at a time (the generic head at start,
// then whatever the user loads), drawn with lk::Renderer and looked at through
// an lk::OrbitCamera. No SDL or Emscripten here; viewer_main.cpp feeds it
// input and a GL context.
//
// Array shapes of the flat arrays coming from JS (worker results):
//   positions #V*3 floats, normals #V*3 or 0, colors #V*3 or 0 (in [0,1]),
//   indices #F*3 (unsigned, < #V), uvs #V*2 (in [0,1]), texture pixels
//   width*height*channels bytes (sRGB).
#pragma once
#include "common/status.h"
#include "render/camera.h"
#include "render/renderer.h"

#include <cstdint>
#include <string>
#include <vector>

namespace lk::web {

// Builds a TriMesh / PointCloud from flat arrays, checking lengths, index
// ranges and finiteness (the arrays come from JS: never trust them).
Status mesh_from_arrays(const std::vector<float>& positions, const std::vector<float>& normals,
                        const std::vector<float>& colors, const std::vector<std::uint32_t>& indices,
                        TriMesh& out);
Status cloud_from_arrays(const std::vector<float>& positions, const std::vector<float>& normals,
                         const std::vector<float>& colors, PointCloud& out);

// The head shown before anything is loaded: the generic head of jeong2002
// (core/head, embedded in the module).
Status start_head(TriMesh& out);

class ViewerScene {
 public:
  // Needs a current GL context.
  Status init();

  // Replace the shown model; the camera is reframed on it unless keep_view
  // (switching between a fit's stages and levels keeps the user's view). On
  // failure the previous model stays.
  Status show_mesh(const TriMesh& mesh, bool keep_view = false);
  Status show_points(const PointCloud& cloud);
  // Animation: new positions (#V, same topology) for the shown mesh; normals
  // are recomputed. Fails when no mesh is shown or the count differs.
  Status update_positions(const std::vector<Vec3>& positions);
  // The same from #V by 3 floats (the worker's Float32Array, copied into the
  // heap): only the vertices that moved are renormalized and re-sent (see
  // Renderer::update_mesh_positions). `stats` is optional.
  Status update_positions(const float* positions_xyz, size_t vertex_count, MeshUpdateStats* stats = nullptr);

  // Morph targets on the shown mesh (Renderer::set_morph_targets): shape i
  // moves counts[i] vertices, its run of `indices` (concatenated over the
  // shapes) by 3 floats each of `offsets`. Gone when the model is replaced
  // (model_serial() changes). set_morph_weights: one weight per shape (a
  // uniform update, nothing re-sent).
  Status set_morph_targets(const std::uint32_t* counts, size_t shape_count, const std::uint32_t* indices,
                           size_t index_count, const float* offsets, size_t offset_count);
  Status set_morph_weights(const float* weights, size_t count);
  int morph_target_count() const;
  // set_morph_targets spread over calls, so the page never stalls on it:
  // begin (the checks, the shapes copied, the mesh's rest state kept: the
  // mesh may be posed on the CPU meanwhile), then each continue prepares
  // shapes for about budget_ms (at least one), or sorts their entries (a
  // call of its own), or writes and uploads bands of the texture for about
  // budget_ms, or sets the attributes and checks for GL errors (a call of
  // its own: in a browser it waits for the GPU process); done after that. Fails (and drops the job)
  // when another model was shown since begin.
  Status begin_morph_targets(const std::uint32_t* counts, size_t shape_count, const std::uint32_t* indices,
                             size_t index_count, const float* offsets, size_t offset_count);
  Status continue_morph_targets(double budget_ms, bool& done);
  bool morph_job_pending() const { return morph_job_ != nullptr; }
  // Where the last set_morph_targets (or job) spent its time (ms, a steady
  // clock): the shapes copied out of the flat arrays, the renderer's
  // prepare (normal offsets; a job: its steps' sum, their number and the
  // longest), the packing (at once: into texels; a job: the entries sorted
  // by vertex), the upload (the GL calls; a job: its bands of texels
  // written and sent, their number and the longest); entries and the data
  // texture's bytes.
  struct MorphUploadTimes {
    double split_ms = 0, prepare_ms = 0, pack_ms = 0, upload_ms = 0;
    double sync_ms = 0;  // a job's last call: the attributes and the GL error check (it waits for the GPU process)
    int steps = 0, bands = 0;
    double longest_step_ms = 0, longest_band_ms = 0;
    std::size_t entries = 0, texture_bytes = 0;
  };
  const MorphUploadTimes& last_morph_upload() const { return morph_times_; }
  // Bumped whenever another model is shown (its morph targets are gone).
  int model_serial() const { return model_serial_; }

  // The skin texture of a textured head: the shown mesh must carry uvs
  // (show_mesh with TriMesh::uvs). Replaced with the model.
  Status set_texture(const Image& image);

  // Extra meshes drawn with the model (the fitted head's eyeballs, teeth and
  // tongue), each optionally textured (the mesh then carries uvs). Kept when
  // the model changes; cleared or hidden by the page.
  Status add_component(const TriMesh& mesh, const Image* texture);
  void clear_components();
  void set_components_visible(bool on);
  // Moves component `index` (in the order added) rigidly: object -> world.
  Status set_component_matrix(size_t index, const glm::mat4& model);
  // Moves component `index`'s vertices (#V as added, in its own frame:
  // before its matrix); the normals follow. For a part that bends (the
  // tongue out), where a matrix cannot carry it.
  Status set_component_positions(size_t index, const float* positions_xyz, size_t vertex_count);
  // Morph targets on component `index` (its vertices as added, its own
  // frame, before its matrix), blended in the vertex shader as the model's
  // are: the tongue's own push (tongueOut), so a frame sends weights only.
  // The flat arrays as set_morph_targets takes them; an empty list removes
  // them. set_component_morph_weights: one weight per shape.
  Status set_component_morph_targets(size_t index, const std::uint32_t* counts, size_t shape_count,
                                     const std::uint32_t* indices, size_t index_count, const float* offsets,
                                     size_t offset_count);
  Status set_component_morph_weights(size_t index, const float* weights, size_t count);
  int component_morph_target_count(size_t index) const;

  // A few big points drawn over everything else (the landmark the page asks
  // the user to click); an empty cloud clears them.
  Status set_markers(const PointCloud& cloud);

  // Points drawn together with the model (the scan under a fitted head).
  // Kept until replaced or cleared; hidden/shown without re-uploading.
  Status set_overlay_points(const PointCloud& cloud);
  void clear_overlay();
  void set_overlay_visible(bool on);

  void set_point_size(float pixels);
  // Triangle edges over the surface (meshes; kept across model changes).
  void set_wireframe(bool on);
  // Frames the model from the default view: three-quarter, in the head's own
  // frame while one is set (set_head_frame), else in the world's.
  void reset_view();
  // The shown head's +z (facing) and +y (up) in world coordinates: a fit is
  // shown over its scan in the scan's orientation, which need not face +z.
  // Reframes the view. Cleared when a model is shown without keep_view (a
  // new scan, the generic head).
  void set_head_frame(const Vec3& facing, const Vec3& up);
  // Unit vector from the camera's target to its eye (tests, scripts).
  Vec3 view_direction() const;
  void resize(int width_px, int height_px);

  // Pointer deltas in framebuffer pixels.
  void orbit(float dx, float dy);
  void pan(float dx, float dy);
  void zoom(float amount_px);

  // Draws if anything changed since the last draw. Returns true when it drew.
  bool draw_if_needed(Status& status);
  void invalidate() { dirty_ = true; }

 private:
  Status replace(DrawableHandle fresh, bool keep_view);

  Renderer renderer_;
  OrbitCamera camera_;
  DrawableHandle model_ = kNoHandle;
  int model_serial_ = 0;
  MorphUploadTimes morph_times_;
  Renderer::MorphJobPtr morph_job_;
  int morph_job_serial_ = 0;       // model_serial_ at begin
  int morph_job_phase_ = 0;        // 0 the shapes, 1 the packing, 2 the bands, 3 the attributes and error check
  Renderer::MorphData morph_job_data_;
  // The flat arrays cut into shapes (set_morph_targets, begin_morph_targets).
  Status split_shapes(const std::uint32_t* counts, size_t shape_count, const std::uint32_t* indices, size_t index_count,
                      const float* offsets, size_t offset_count, std::vector<Renderer::MorphShape>& shapes) const;
  static Status split_flat_shapes(const std::uint32_t* counts, size_t shape_count, const std::uint32_t* indices,
                                  size_t index_count, const float* offsets, size_t offset_count,
                                  std::vector<Renderer::MorphShape>& shapes);
  bool model_is_points_ = false;
  size_t model_vertices_ = 0;
  TextureHandle texture_ = kNoHandle;
  // Success when component `index` exists, else "no component N".
  Status check_component(size_t index) const;
  std::vector<DrawableHandle> components_;
  std::vector<TextureHandle> component_textures_;
  bool components_visible_ = true;
  DrawableHandle markers_ = kNoHandle;
  DrawableHandle overlay_ = kNoHandle;
  bool overlay_visible_ = true;
  BBox bounds_;
  bool has_head_frame_ = false;
  Vec3 head_facing_ = Vec3(0, 0, 1), head_up_ = Vec3(0, 1, 0);
  float point_size_ = 3.0f;
  bool wireframe_ = false;
  int width_ = 1, height_ = 1;
  bool dirty_ = true;
};

}  // namespace lk::web
