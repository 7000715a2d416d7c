#include "viewer_scene.h"

#include "head/generic_head.h"

#include <algorithm>
#include <chrono>
#include <cmath>

namespace lk::web {

namespace {

bool all_finite(const std::vector<float>& v) {
  for (float x : v)
    if (!std::isfinite(x)) return false;
  return true;
}

std::vector<Vec3> to_vec3(const std::vector<float>& flat) {
  std::vector<Vec3> out(flat.size() / 3);
  for (size_t i = 0; i < out.size(); ++i) out[i] = Vec3(flat[3 * i], flat[3 * i + 1], flat[3 * i + 2]);
  return out;
}

// Optional per-vertex arrays must be empty or exactly #V*3.
Status check_attribute(const char* what, const std::vector<float>& a, size_t vertex_count) {
  if (!a.empty() && a.size() != vertex_count * 3)
    return Status::error(ErrorCode::InvalidInput, std::string(what) + ": " + std::to_string(a.size()) +
                                                      " values for " + std::to_string(vertex_count) +
                                                      " vertices (need 3 per vertex)");
  if (!all_finite(a)) return Status::error(ErrorCode::InvalidInput, std::string(what) + ": NaN or infinite values");
  return Status::success();
}

Status check_positions(const std::vector<float>& positions) {
  if (positions.empty()) return Status::error(ErrorCode::Empty, "no vertices");
  if (positions.size() % 3 != 0)
    return Status::error(ErrorCode::InvalidInput, "positions: length " + std::to_string(positions.size()) +
                                                      " is not a multiple of 3");
  if (!all_finite(positions)) return Status::error(ErrorCode::InvalidInput, "positions: NaN or infinite values");
  return Status::success();
}

}  // namespace

Status mesh_from_arrays(const std::vector<float>& positions, const std::vector<float>& normals,
                        const std::vector<float>& colors, const std::vector<std::uint32_t>& indices,
                        TriMesh& out) {
  if (Status s = check_positions(positions); !s.ok()) return s;
  const size_t nv = positions.size() / 3;
  if (Status s = check_attribute("normals", normals, nv); !s.ok()) return s;
  if (Status s = check_attribute("colors", colors, nv); !s.ok()) return s;
  if (indices.empty()) return Status::error(ErrorCode::Empty, "a mesh needs triangles");
  if (indices.size() % 3 != 0)
    return Status::error(ErrorCode::InvalidInput, "indices: length " + std::to_string(indices.size()) +
                                                      " is not a multiple of 3");
  for (std::uint32_t i : indices)
    if (i >= nv)
      return Status::error(ErrorCode::InvalidInput, "indices: vertex " + std::to_string(i) + " of " +
                                                        std::to_string(nv));
  out = TriMesh{};
  out.positions = to_vec3(positions);
  out.normals = to_vec3(normals);
  out.colors = to_vec3(colors);
  out.triangles.resize(indices.size() / 3);
  for (size_t f = 0; f < out.triangles.size(); ++f)
    out.triangles[f] = {int(indices[3 * f]), int(indices[3 * f + 1]), int(indices[3 * f + 2])};
  return Status::success();
}

Status cloud_from_arrays(const std::vector<float>& positions, const std::vector<float>& normals,
                         const std::vector<float>& colors, PointCloud& out) {
  if (Status s = check_positions(positions); !s.ok()) return s;
  const size_t nv = positions.size() / 3;
  if (Status s = check_attribute("normals", normals, nv); !s.ok()) return s;
  if (Status s = check_attribute("colors", colors, nv); !s.ok()) return s;
  out = PointCloud{};
  out.positions = to_vec3(positions);
  out.normals = to_vec3(normals);
  out.colors = to_vec3(colors);
  return Status::success();
}

Status start_head(TriMesh& out) {
  GenericHead head;
  if (Status s = load_generic_head(head); !s.ok()) return s;
  out = std::move(head.mesh);
  return Status::success();
}

Status ViewerScene::init() {
  RendererOptions options;
  // glGetError per frame would make the page wait for each draw to finish
  // in the GPU process (see RendererOptions); uploads still check.
  options.check_errors_every_frame = false;
  return renderer_.init(options);
}

Status ViewerScene::replace(DrawableHandle fresh, bool keep_view) {
  BBox box;
  if (Status s = renderer_.bounds(fresh, box); !s.ok()) {
    renderer_.remove(fresh);
    return s;
  }
  if (model_ != kNoHandle) renderer_.remove(model_);
  if (texture_ != kNoHandle) renderer_.remove_texture(texture_);
  texture_ = kNoHandle;
  model_ = fresh;
  ++model_serial_;
  bounds_ = box;
  if (model_is_points_) renderer_.set_point_size(model_, point_size_);
  else renderer_.set_wireframe(model_, wireframe_);
  if (keep_view) {
    dirty_ = true;
  } else {
    has_head_frame_ = false;
    reset_view();
  }
  return Status::success();
}

Status ViewerScene::show_mesh(const TriMesh& mesh, bool keep_view) {
  DrawableHandle fresh = kNoHandle;
  if (Status s = renderer_.upload_mesh(mesh, fresh); !s.ok()) return s;
  model_is_points_ = false;
  model_vertices_ = mesh.positions.size();
  return replace(fresh, keep_view);
}

Status ViewerScene::show_points(const PointCloud& cloud) {
  DrawableHandle fresh = kNoHandle;
  if (Status s = renderer_.upload_points(cloud, fresh); !s.ok()) return s;
  model_is_points_ = true;
  model_vertices_ = cloud.positions.size();
  return replace(fresh, false);
}

Status ViewerScene::update_positions(const std::vector<Vec3>& positions) {
  if (model_ == kNoHandle || model_is_points_)
    return Status::error(ErrorCode::InvalidInput, "no mesh is shown to update");
  if (positions.size() != model_vertices_)
    return Status::error(ErrorCode::InvalidInput, std::to_string(positions.size()) + " positions for a mesh of " +
                                                      std::to_string(model_vertices_) + " vertices");
  if (Status s = renderer_.update_mesh(model_, positions); !s.ok()) return s;
  dirty_ = true;
  return Status::success();
}

Status ViewerScene::update_positions(const float* positions_xyz, size_t vertex_count, MeshUpdateStats* stats) {
  if (model_ == kNoHandle || model_is_points_)
    return Status::error(ErrorCode::InvalidInput, "no mesh is shown to update");
  if (vertex_count != model_vertices_)
    return Status::error(ErrorCode::InvalidInput, std::to_string(vertex_count) + " positions for a mesh of " +
                                                      std::to_string(model_vertices_) + " vertices");
  if (Status s = renderer_.update_mesh_positions(model_, positions_xyz, vertex_count, stats); !s.ok()) return s;
  dirty_ = true;
  return Status::success();
}

Status ViewerScene::split_shapes(const std::uint32_t* counts, size_t shape_count, const std::uint32_t* indices,
                                 size_t index_count, const float* offsets, size_t offset_count,
                                 std::vector<Renderer::MorphShape>& shapes) const {
  if (model_ == kNoHandle || model_is_points_)
    return Status::error(ErrorCode::InvalidInput, "no mesh is shown to morph");
  return split_flat_shapes(counts, shape_count, indices, index_count, offsets, offset_count, shapes);
}

Status ViewerScene::split_flat_shapes(const std::uint32_t* counts, size_t shape_count, const std::uint32_t* indices,
                                      size_t index_count, const float* offsets, size_t offset_count,
                                      std::vector<Renderer::MorphShape>& shapes) {
  if (offset_count != 3 * index_count)
    return Status::error(ErrorCode::InvalidInput, std::to_string(offset_count) + " offset values for " +
                                                      std::to_string(index_count) + " vertices (need 3 per vertex)");
  shapes.assign(shape_count, {});
  size_t at = 0;
  for (size_t i = 0; i < shape_count; ++i) {
    if (counts[i] > index_count - at)
      return Status::error(ErrorCode::InvalidInput, "the shapes' vertex counts add up to more than the " +
                                                        std::to_string(index_count) + " indices given");
    shapes[i].vertices.assign(indices + at, indices + at + counts[i]);
    shapes[i].offsets.assign(offsets + 3 * at, offsets + 3 * (at + counts[i]));
    at += counts[i];
  }
  if (at != index_count)
    return Status::error(ErrorCode::InvalidInput, "the shapes' vertex counts add up to " + std::to_string(at) + ", not the " +
                                                      std::to_string(index_count) + " indices given");
  return Status::success();
}

namespace {
using Clock = std::chrono::steady_clock;
double ms_between(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double, std::milli>(b - a).count(); }
}  // namespace

Status ViewerScene::set_morph_targets(const std::uint32_t* counts, size_t shape_count, const std::uint32_t* indices,
                                      size_t index_count, const float* offsets, size_t offset_count) {
  morph_job_.reset();
  const Clock::time_point t0 = Clock::now();
  std::vector<Renderer::MorphShape> shapes;
  if (Status s = split_shapes(counts, shape_count, indices, index_count, offsets, offset_count, shapes); !s.ok()) return s;
  const Clock::time_point t1 = Clock::now();
  Renderer::MorphData data;
  if (Status s = renderer_.prepare_morph_targets(model_, shapes, data); !s.ok()) return s;
  const Clock::time_point t2 = Clock::now();
  if (Status s = renderer_.upload_morph_targets(model_, data); !s.ok()) return s;
  const Clock::time_point t3 = Clock::now();
  morph_times_ = {};
  morph_times_.split_ms = ms_between(t0, t1);
  morph_times_.prepare_ms = ms_between(t1, t2);  // the packing included
  morph_times_.upload_ms = ms_between(t2, t3);
  morph_times_.steps = 1;
  morph_times_.longest_step_ms = morph_times_.prepare_ms;
  morph_times_.entries = data.entries;
  morph_times_.texture_bytes = data.texels.size() * sizeof(float);
  dirty_ = true;
  return Status::success();
}

Status ViewerScene::begin_morph_targets(const std::uint32_t* counts, size_t shape_count, const std::uint32_t* indices,
                                        size_t index_count, const float* offsets, size_t offset_count) {
  morph_job_.reset();
  const Clock::time_point t0 = Clock::now();
  std::vector<Renderer::MorphShape> shapes;
  if (Status s = split_shapes(counts, shape_count, indices, index_count, offsets, offset_count, shapes); !s.ok()) return s;
  if (Status s = renderer_.begin_morph_targets(model_, std::move(shapes), morph_job_); !s.ok()) return s;
  morph_job_serial_ = model_serial_;
  morph_job_phase_ = 0;
  morph_job_data_ = {};
  morph_times_ = {};
  morph_times_.split_ms = ms_between(t0, Clock::now());
  return Status::success();
}

Status ViewerScene::continue_morph_targets(double budget_ms, bool& done) {
  done = false;
  if (!morph_job_) return Status::error(ErrorCode::InvalidInput, "no morph targets are being prepared");
  if (morph_job_serial_ != model_serial_) {
    morph_job_.reset();
    return Status::error(ErrorCode::InvalidInput, "another model was shown while its morph targets were prepared");
  }
  const Clock::time_point t0 = Clock::now();
  Status s;
  if (morph_job_phase_ == 0) {  // the shapes, one at a time, for about budget_ms
    bool shapes_done = false;
    do {
      const Clock::time_point a = Clock::now();
      s = renderer_.step_morph_targets(*morph_job_, 1, shapes_done);
      const double step = ms_between(a, Clock::now());
      morph_times_.prepare_ms += step;
      morph_times_.longest_step_ms = std::max(morph_times_.longest_step_ms, step);
      ++morph_times_.steps;
    } while (s.ok() && !shapes_done && ms_between(t0, Clock::now()) < budget_ms);
    if (shapes_done) morph_job_phase_ = 1;
  } else if (morph_job_phase_ == 1) {  // the entries sorted by vertex, a call of its own
    s = renderer_.finish_morph_targets(*morph_job_, morph_job_data_, false);
    morph_times_.pack_ms = ms_between(t0, Clock::now());
    morph_job_phase_ = 2;
  } else if (morph_job_phase_ == 3) {  // the attributes and the one GL error check, a call of its own
    s = renderer_.finish_morph_upload(model_, *morph_job_, morph_job_data_);
    morph_times_.sync_ms = ms_between(t0, Clock::now());
    if (s.ok()) {
      morph_times_.entries = morph_job_data_.entries;
      morph_times_.texture_bytes = size_t(morph_job_data_.width) * size_t(morph_job_data_.rows) * 4 * sizeof(float);
      morph_job_.reset();
      morph_job_data_ = {};
      done = true;
      dirty_ = true;
    }
  } else {  // the texels written and sent in bands of 32 rows (2 MB), for about budget_ms
    bool uploaded = false;
    do {
      const Clock::time_point a = Clock::now();
      s = renderer_.upload_morph_band(model_, *morph_job_, morph_job_data_, 32, uploaded);
      const double step = ms_between(a, Clock::now());
      morph_times_.upload_ms += step;
      morph_times_.longest_band_ms = std::max(morph_times_.longest_band_ms, step);
      ++morph_times_.bands;
    } while (s.ok() && !uploaded && ms_between(t0, Clock::now()) < budget_ms);
    if (s.ok() && uploaded) morph_job_phase_ = 3;
  }
  if (!s.ok()) morph_job_.reset();
  return s;
}

Status ViewerScene::set_morph_weights(const float* weights, size_t count) {
  if (model_ == kNoHandle || model_is_points_)
    return Status::error(ErrorCode::InvalidInput, "no mesh is shown to morph");
  if (Status s = renderer_.set_morph_weights(model_, weights, count); !s.ok()) return s;
  dirty_ = true;
  return Status::success();
}

int ViewerScene::morph_target_count() const {
  return model_ == kNoHandle || model_is_points_ ? 0 : renderer_.morph_target_count(model_);
}

Status ViewerScene::set_texture(const Image& image) {
  if (model_ == kNoHandle || model_is_points_)
    return Status::error(ErrorCode::InvalidInput, "no mesh is shown to texture");
  TextureHandle fresh = kNoHandle;
  if (Status s = renderer_.upload_texture(image, fresh); !s.ok()) return s;
  if (Status s = renderer_.attach_texture(model_, fresh); !s.ok()) {
    renderer_.remove_texture(fresh);
    return s;
  }
  if (texture_ != kNoHandle) renderer_.remove_texture(texture_);
  texture_ = fresh;
  // Skin from photos already carries its shading's colour: a little less
  // specular than the bare skin-tone default.
  if (DrawStyle* style = renderer_.style(model_)) style->specular = 0.15f;
  dirty_ = true;
  return Status::success();
}

Status ViewerScene::add_component(const TriMesh& mesh, const Image* texture) {
  DrawableHandle fresh = kNoHandle;
  if (Status s = renderer_.upload_mesh(mesh, fresh); !s.ok()) return s;
  if (texture) {
    TextureHandle t = kNoHandle;
    Status s = renderer_.upload_texture(*texture, t);
    if (s.ok()) s = renderer_.attach_texture(fresh, t);
    if (!s.ok()) {
      if (t != kNoHandle) renderer_.remove_texture(t);
      renderer_.remove(fresh);
      return s;
    }
    component_textures_.push_back(t);
  }
  renderer_.set_visible(fresh, components_visible_);
  if (DrawStyle* style = renderer_.style(fresh)) style->specular = 0.6f;  // wet eyes and teeth
  components_.push_back(fresh);
  dirty_ = true;
  return Status::success();
}

void ViewerScene::clear_components() {
  for (DrawableHandle h : components_) renderer_.remove(h);
  for (TextureHandle t : component_textures_) renderer_.remove_texture(t);
  components_.clear();
  component_textures_.clear();
  dirty_ = true;
}

Status ViewerScene::check_component(size_t index) const {
  if (index >= components_.size())
    return Status::error(ErrorCode::InvalidInput, "no component " + std::to_string(index));
  return Status::success();
}

Status ViewerScene::set_component_matrix(size_t index, const glm::mat4& model) {
  if (Status s = check_component(index); !s.ok()) return s;
  dirty_ = true;
  return renderer_.set_model_matrix(components_[index], model);
}

Status ViewerScene::set_component_positions(size_t index, const float* positions_xyz, size_t vertex_count) {
  if (Status s = check_component(index); !s.ok()) return s;
  dirty_ = true;
  return renderer_.update_mesh_positions(components_[index], positions_xyz, vertex_count);
}

Status ViewerScene::set_component_morph_targets(size_t index, const std::uint32_t* counts, size_t shape_count,
                                                const std::uint32_t* indices, size_t index_count, const float* offsets,
                                                size_t offset_count) {
  if (Status s = check_component(index); !s.ok()) return s;
  std::vector<Renderer::MorphShape> shapes;
  if (Status s = split_flat_shapes(counts, shape_count, indices, index_count, offsets, offset_count, shapes); !s.ok())
    return s;
  dirty_ = true;
  return renderer_.set_morph_targets(components_[index], shapes);
}

Status ViewerScene::set_component_morph_weights(size_t index, const float* weights, size_t count) {
  if (Status s = check_component(index); !s.ok()) return s;
  dirty_ = true;
  return renderer_.set_morph_weights(components_[index], weights, count);
}

int ViewerScene::component_morph_target_count(size_t index) const {
  return index < components_.size() ? renderer_.morph_target_count(components_[index]) : 0;
}

void ViewerScene::set_components_visible(bool on) {
  components_visible_ = on;
  for (DrawableHandle h : components_) renderer_.set_visible(h, on);
  dirty_ = true;
}

Status ViewerScene::set_markers(const PointCloud& cloud) {
  if (markers_ != kNoHandle) renderer_.remove(markers_);
  markers_ = kNoHandle;
  dirty_ = true;
  if (cloud.positions.empty()) return Status::success();
  if (Status s = renderer_.upload_points(cloud, markers_); !s.ok()) return s;
  renderer_.set_point_size(markers_, 16.0f);
  return Status::success();
}

Status ViewerScene::set_overlay_points(const PointCloud& cloud) {
  DrawableHandle fresh = kNoHandle;
  if (Status s = renderer_.upload_points(cloud, fresh); !s.ok()) return s;
  clear_overlay();
  overlay_ = fresh;
  renderer_.set_point_size(overlay_, std::max(1.0f, point_size_ - 1.0f));
  renderer_.set_visible(overlay_, overlay_visible_);
  dirty_ = true;
  return Status::success();
}

void ViewerScene::clear_overlay() {
  if (overlay_ != kNoHandle) renderer_.remove(overlay_);
  overlay_ = kNoHandle;
  dirty_ = true;
}

void ViewerScene::set_overlay_visible(bool on) {
  overlay_visible_ = on;
  if (overlay_ != kNoHandle) renderer_.set_visible(overlay_, on);
  dirty_ = true;
}

void ViewerScene::set_point_size(float pixels) {
  point_size_ = pixels;
  if (model_ != kNoHandle && model_is_points_) renderer_.set_point_size(model_, pixels);
  if (overlay_ != kNoHandle) renderer_.set_point_size(overlay_, std::max(1.0f, pixels - 1.0f));
  dirty_ = true;
}

void ViewerScene::set_wireframe(bool on) {
  wireframe_ = on;
  if (model_ != kNoHandle && !model_is_points_) renderer_.set_wireframe(model_, on);
  dirty_ = true;
}

void ViewerScene::reset_view() {
  const float aspect = float(width_) / float(height_);
  if (bounds_.valid())
    camera_ = has_head_frame_ ? canonical_view(CanonicalView::ThreeQuarter, bounds_, aspect, head_facing_, head_up_)
                              : canonical_view(CanonicalView::ThreeQuarter, bounds_, aspect);
  dirty_ = true;
}

Vec3 ViewerScene::view_direction() const {
  const glm::vec3 d = camera_.eye() - camera_.target;
  return Vec3(d.x, d.y, d.z).normalized();
}

void ViewerScene::set_head_frame(const Vec3& facing, const Vec3& up) {
  has_head_frame_ = true;
  head_facing_ = facing;
  head_up_ = up;
  reset_view();
}

void ViewerScene::resize(int width_px, int height_px) {
  if (width_px == width_ && height_px == height_) return;
  width_ = std::max(1, width_px);
  height_ = std::max(1, height_px);
  dirty_ = true;
}

void ViewerScene::orbit(float dx, float dy) {
  camera_.orbit(dx, dy, float(height_));
  dirty_ = true;
}

void ViewerScene::pan(float dx, float dy) {
  camera_.pan(dx, dy, float(height_));
  dirty_ = true;
}

void ViewerScene::zoom(float amount_px) {
  camera_.zoom(amount_px);
  dirty_ = true;
}

bool ViewerScene::draw_if_needed(Status& status) {
  if (!dirty_) return false;
  dirty_ = false;
  Viewport viewport;
  viewport.width = width_;
  viewport.height = height_;
  status = renderer_.draw(camera_.matrices(float(width_) / float(height_)), viewport);
  return true;
}

}  // namespace lk::web
