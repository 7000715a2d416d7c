// Cameras for the renderer (not from the papers): an orbit camera driven by
// pixel deltas (mouse, touch) and the canonical views used in docs and tests.
//
// Head conventions (head_model.h): the head looks along +z, up is +y, +x is
// the head's LEFT (the viewer's right in a frontal view). So "left" looks at
// the head's left cheek from +x, "right" from -x, "top" looks down from +y
// with the face towards the bottom of the image, and "three-quarter" sits
// between front and left, slightly above eye level.
#pragma once
#include "common/status.h"
#include "common/types.h"
#include "render/renderer.h"

#include <glm/glm.hpp>

#include <string>
#include <vector>

namespace lk {

enum class CanonicalView { Front, Left, Right, Back, Top, ThreeQuarter };

// "front" | "left" | "right" | "back" | "top" | "three-quarter" (also
// "three_quarter"). InvalidInput names the accepted values otherwise.
Status parse_canonical_view(const std::string& name, CanonicalView& out);
const char* to_string(CanonicalView view);

// A camera orbiting a target point. yaw turns around +y (0 = on +z looking
// at the face, +90 degrees = on +x, the head's left); pitch raises the camera
// (limited to just under +-90 degrees so "up" stays defined).
struct OrbitCamera {
  glm::vec3 target = {0.0f, 0.0f, 0.0f};
  float distance = 1.0f;     // target to eye, world units
  float yaw_deg = 0.0f;
  float pitch_deg = 0.0f;
  float fov_y_deg = 30.0f;   // vertical field of view
  float scene_radius = 0.5f; // size of what is looked at: sets near/far planes
  // The frame yaw and pitch are taken in (columns: its x, up and z axes in
  // world coordinates); the identity but for a head shown in a scan's own
  // orientation, whose up the view keeps (canonical_view with facing, up).
  glm::mat3 frame = glm::mat3(1.0f);

  glm::vec3 eye() const;
  glm::mat4 view() const;
  glm::mat4 projection(float aspect) const;  // aspect = width / height
  CameraMatrices matrices(float aspect) const;

  // Pointer interaction; deltas in pixels, viewport_height in pixels (so the
  // feel does not depend on the canvas size). Dragging the full viewport
  // height turns the camera by 180 degrees; pan keeps the point under the
  // cursor under the cursor (at the target's depth); zoom > 0 moves closer
  // (wheel: pass -deltaY).
  void orbit(float dx_px, float dy_px, float viewport_height_px);
  void pan(float dx_px, float dy_px, float viewport_height_px);
  void zoom(float amount_px);
};

// A camera that frames bbox from the named direction, filling the image of
// the given aspect (width / height) with a small margin.
OrbitCamera canonical_view(CanonicalView view, const BBox& bbox, float aspect);
Status canonical_view(const std::string& name, const BBox& bbox, float aspect, OrbitCamera& out);
// The same for a head whose own frame is not the world's: `facing` and `up`
// are the head's +z and +y in world coordinates (a fitted head shown over its
// scan in the scan's orientation, which need not face +z). The view's
// direction is taken in the head's frame, so "three-quarter" shows the face
// from its left front whatever way the scan faced, and the head's up is the
// view's (the camera's frame is the head's: a scan with +z up is seen
// upright, and orbits about its own up). Facing and up need not be unit or
// exactly orthogonal (up is made orthogonal to facing); degenerate ones give
// the plain canonical view.
OrbitCamera canonical_view(CanonicalView view, const BBox& bbox, float aspect, const Vec3& facing, const Vec3& up);
// Tighter: frames the points themselves (e.g. mesh vertices), not their box,
// whose corners stick out beyond a round head in perspective. Aimed at the
// box centre. Empty points give a default camera.
OrbitCamera canonical_view(CanonicalView view, const std::vector<Vec3>& points, float aspect);

// Distance at which a camera looking along `forward` (unit, from eye to
// target) with the given up vector sees all of bbox centred on its centre.
float framing_distance(const BBox& bbox, const glm::vec3& forward, const glm::vec3& up,
                       float fov_y_deg, float aspect, float margin = 1.08f);
float framing_distance(const std::vector<Vec3>& points, const Vec3& center, const glm::vec3& forward,
                       const glm::vec3& up, float fov_y_deg, float aspect, float margin = 1.08f);

}  // namespace lk
