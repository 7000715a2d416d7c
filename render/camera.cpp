// Orbit camera and canonical views (see camera.h).
#include "render/camera.h"

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>

namespace lk {
namespace {

constexpr float kMaxPitchDeg = 89.5f;  // keeps lookAt's up vector well defined

glm::vec3 direction_from_angles(float yaw_deg, float pitch_deg) {
  const float yaw = glm::radians(yaw_deg), pitch = glm::radians(pitch_deg);
  return {std::cos(pitch) * std::sin(yaw), std::sin(pitch), std::cos(pitch) * std::cos(yaw)};
}

struct ViewAngles {
  float yaw_deg, pitch_deg;
};

ViewAngles angles_of(CanonicalView v) {
  switch (v) {
    case CanonicalView::Front: return {0.0f, 0.0f};
    case CanonicalView::Left: return {90.0f, 0.0f};
    case CanonicalView::Right: return {-90.0f, 0.0f};
    case CanonicalView::Back: return {180.0f, 0.0f};
    case CanonicalView::Top: return {0.0f, kMaxPitchDeg};
    case CanonicalView::ThreeQuarter: return {35.0f, 8.0f};
  }
  return {0.0f, 0.0f};
}

}  // namespace

Status parse_canonical_view(const std::string& name, CanonicalView& out) {
  if (name == "front") out = CanonicalView::Front;
  else if (name == "left") out = CanonicalView::Left;
  else if (name == "right") out = CanonicalView::Right;
  else if (name == "back") out = CanonicalView::Back;
  else if (name == "top") out = CanonicalView::Top;
  else if (name == "three-quarter" || name == "three_quarter") out = CanonicalView::ThreeQuarter;
  else
    return Status::error(ErrorCode::InvalidInput,
                         "unknown view '" + name + "' (use front|left|right|back|top|three-quarter)");
  return Status::success();
}

const char* to_string(CanonicalView view) {
  switch (view) {
    case CanonicalView::Front: return "front";
    case CanonicalView::Left: return "left";
    case CanonicalView::Right: return "right";
    case CanonicalView::Back: return "back";
    case CanonicalView::Top: return "top";
    case CanonicalView::ThreeQuarter: return "three-quarter";
  }
  return "?";
}

glm::vec3 OrbitCamera::eye() const {
  return target + distance * (frame * direction_from_angles(yaw_deg, pitch_deg));
}

glm::mat4 OrbitCamera::view() const {
  return glm::lookAt(eye(), target, frame[1]);
}

glm::mat4 OrbitCamera::projection(float aspect) const {
  // Near/far hug the scene so depth precision stays good at any zoom.
  const float r = std::max(scene_radius, 1e-6f);
  const float near_plane = std::max(distance - 2.0f * r, distance * 0.01f);
  const float far_plane = distance + 2.0f * r;
  return glm::perspective(glm::radians(fov_y_deg), std::max(aspect, 1e-6f), near_plane, far_plane);
}

CameraMatrices OrbitCamera::matrices(float aspect) const { return {view(), projection(aspect)}; }

void OrbitCamera::orbit(float dx_px, float dy_px, float viewport_height_px) {
  const float deg_per_px = 180.0f / std::max(viewport_height_px, 1.0f);
  // Dragging right turns the object right, i.e. moves the camera left.
  yaw_deg -= dx_px * deg_per_px;
  yaw_deg = std::fmod(yaw_deg, 360.0f);
  pitch_deg = std::clamp(pitch_deg + dy_px * deg_per_px, -kMaxPitchDeg, kMaxPitchDeg);
}

void OrbitCamera::pan(float dx_px, float dy_px, float viewport_height_px) {
  // World size of one pixel at the target's depth.
  const float world_per_px =
      2.0f * distance * std::tan(glm::radians(fov_y_deg) * 0.5f) / std::max(viewport_height_px, 1.0f);
  const glm::mat4 v = view();
  const glm::vec3 right(v[0][0], v[1][0], v[2][0]);
  const glm::vec3 up(v[0][1], v[1][1], v[2][1]);
  // Screen y grows downwards: dragging down moves the scene down.
  target += (-dx_px * right + dy_px * up) * world_per_px;
}

void OrbitCamera::zoom(float amount_px) {
  distance *= std::exp(-amount_px * 0.002f);
  distance = std::clamp(distance, scene_radius * 0.05f, scene_radius * 50.0f);
}

float framing_distance(const std::vector<Vec3>& points, const Vec3& center, const glm::vec3& forward,
                       const glm::vec3& up, float fov_y_deg, float aspect, float margin) {
  if (points.empty()) return 1.0f;
  const glm::vec3 f = glm::normalize(forward);
  const glm::vec3 r = glm::normalize(glm::cross(f, up));
  const glm::vec3 u = glm::cross(r, f);
  const float tan_y = std::tan(glm::radians(fov_y_deg) * 0.5f) / margin;
  const float tan_x = tan_y * aspect;
  float d = 0.0f;
  for (const Vec3& q : points) {
    const glm::vec3 p(static_cast<float>(q.x() - center.x()), static_cast<float>(q.y() - center.y()),
                      static_cast<float>(q.z() - center.z()));
    // A point nearer the camera than the target needs more room: its distance
    // to the eye is shorter by its depth towards the camera.
    const float toward = -glm::dot(p, f);
    d = std::max(d, toward + std::abs(glm::dot(p, r)) / tan_x);
    d = std::max(d, toward + std::abs(glm::dot(p, u)) / tan_y);
  }
  return std::max(d, 1e-6f);
}

float framing_distance(const BBox& bbox, const glm::vec3& forward, const glm::vec3& up,
                       float fov_y_deg, float aspect, float margin) {
  if (!bbox.valid()) return 1.0f;
  std::vector<Vec3> corners;
  for (int i = 0; i < 8; ++i)
    corners.emplace_back((i & 1) ? bbox.max.x() : bbox.min.x(), (i & 2) ? bbox.max.y() : bbox.min.y(),
                         (i & 4) ? bbox.max.z() : bbox.min.z());
  return framing_distance(corners, bbox.center(), forward, up, fov_y_deg, aspect, margin);
}

namespace {

OrbitCamera aimed_at(CanonicalView view, const BBox& bbox) {
  OrbitCamera cam;
  const ViewAngles a = angles_of(view);
  cam.yaw_deg = a.yaw_deg;
  cam.pitch_deg = a.pitch_deg;
  if (!bbox.valid()) return cam;
  const Vec3 c = bbox.center();
  cam.target = glm::vec3(static_cast<float>(c.x()), static_cast<float>(c.y()), static_cast<float>(c.z()));
  cam.scene_radius = std::max(static_cast<float>(0.5 * bbox.diagonal()), 1e-6f);
  return cam;
}

glm::vec3 forward_of(const OrbitCamera& cam) { return -direction_from_angles(cam.yaw_deg, cam.pitch_deg); }

}  // namespace

OrbitCamera canonical_view(CanonicalView view, const std::vector<Vec3>& points, float aspect) {
  BBox bbox;
  for (const Vec3& p : points) bbox.extend(p);
  OrbitCamera cam = aimed_at(view, bbox);
  if (!bbox.valid()) return cam;
  cam.distance = framing_distance(points, bbox.center(), forward_of(cam), glm::vec3(0, 1, 0),
                                  cam.fov_y_deg, aspect);
  return cam;
}

OrbitCamera canonical_view(CanonicalView view, const BBox& bbox, float aspect) {
  OrbitCamera cam = aimed_at(view, bbox);
  if (!bbox.valid()) return cam;
  cam.distance = framing_distance(bbox, forward_of(cam), glm::vec3(0, 1, 0), cam.fov_y_deg, aspect);
  return cam;
}

OrbitCamera canonical_view(CanonicalView view, const BBox& bbox, float aspect, const Vec3& facing, const Vec3& up) {
  const Vec3 z = facing.normalized();
  const Vec3 y = (up - up.dot(z) * z).normalized();
  if (!z.allFinite() || !y.allFinite() || facing.norm() == 0 || (up - up.dot(z) * z).norm() < 1e-6 * up.norm())
    return canonical_view(view, bbox, aspect);
  const Vec3 x = y.cross(z);  // the head's left (head_model.h)
  OrbitCamera cam = aimed_at(view, bbox);  // yaw and pitch in the head's frame
  auto column = [](const Vec3& v) { return glm::vec3(float(v.x()), float(v.y()), float(v.z())); };
  cam.frame = glm::mat3(column(x), column(y), column(z));
  if (!bbox.valid()) return cam;
  cam.distance = framing_distance(bbox, cam.frame * forward_of(cam), cam.frame[1], cam.fov_y_deg, aspect);
  return cam;
}

Status canonical_view(const std::string& name, const BBox& bbox, float aspect, OrbitCamera& out) {
  CanonicalView v = CanonicalView::Front;
  Status s = parse_canonical_view(name, v);
  if (!s) return s;
  if (!bbox.valid()) return Status::error(ErrorCode::Empty, "canonical_view: empty bounding box");
  out = canonical_view(v, bbox, aspect);
  return Status::success();
}

}  // namespace lk
