// Generic eyes, teeth arch and tongue (Tarini et al. 2002, Sec. 4 and
// Fig. 7/8), placed and scaled into a (fitted) head from its annotations.
//
// Model frames: +z forward (out of the face), +y up, +x the head's left.
// make_eyeball: unit sphere, per-vertex uvs in the eyeball texture layout of
//   iris/iris.h (azimuthal equidistant, frontal hemisphere; the back
//   hemisphere maps onto the rim, i.e. sclera).
// make_teeth_arch: upper and lower arches around a parabola, width 1 (x in
//   [-0.5, 0.5]), each a closed band; its uvs put the upper front teeth in the
//   texture's upper half and the lower ones in the lower half.
//   NOT YET as in the paper: no separate billboard / 3-D side teeth shapes.
// make_tongue: a flattened half-ellipsoid of length 1 along -z.
#pragma once
#include "common/status.h"
#include "head/head_model.h"
#include "mesh/tri_mesh.h"

namespace lk {

TriMesh make_eyeball(int rings = 16, int segments = 24);
TriMesh make_teeth_arch(int segments = 24);
TriMesh make_tongue(int rings = 8, int segments = 16);

struct ComponentPlacement {
  Vec3 eye_center[2] = {Vec3::Zero(), Vec3::Zero()};  // 0 = left (+x), 1 = right
  double eye_radius[2] = {0, 0};
  Vec3 mouth_center = Vec3::Zero();
  double mouth_width = 0;
};

// Placement from the fitted head's annotated vertices (eye rim loops, lip
// vertices), so it follows the fitted geometry: each component keeps its
// offset from the centroid of its vertex set in the generic head, scaled by
// the ratio of the set's size (mean distance to its centroid) fitted/generic.
// Both heads must share the generic head's topology and be in the head frame.
Status place_components(const GenericHead& fitted, const GenericHead& generic, ComponentPlacement& out);

// The three meshes moved into the head: eyes (2), teeth, tongue.
struct PlacedComponents {
  TriMesh eye[2], teeth, tongue;
};
PlacedComponents build_placed_components(const ComponentPlacement& placement);

}  // namespace lk
