// The shape the generic head is cast from (generic_head_builder.h, step 1):
// a smooth signed distance function, negative inside, built from blended
// ellipsoids and mirror-symmetric (it only sees |x|). Metres, +y up, +z the
// face's look. The builder places the control mesh on it; the skin detail
// (skin_detail.h) measures how far the smooth levels lie from it.
#pragma once
#include "mesh/tri_mesh.h"

namespace lk {

struct HeadShape {
  // Left eyeball centre (the right one is mirrored) and the sphere the lids
  // follow; the lid sphere is larger than the eyeball so lids cover it.
  Vec3 eye_center{0.032, 0.025, 0.068};
  double lid_radius = 0.0140;
  double slit_y = -0.0530;  // height of the closed lip line

  double distance(const Vec3& p) const;
  // Central differences of distance (not unit length off the surface).
  Vec3 gradient(const Vec3& p) const;
  // Where the ray from an inside origin leaves the head for the last time,
  // i.e. the surface seen from outside along the ray. (The first exit would
  // miss overhangs such as the nose's tip, which rays reach after leaving
  // the face below it.)
  Vec3 cast(const Vec3& origin, const Vec3& dir) const;
  // Newton steps onto the zero level set.
  Vec3 project(Vec3 p) const;
};

}  // namespace lk
