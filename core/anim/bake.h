// The named shapes (face_shapes.h) baked for one head: each shape alone at
// full weight as vertex offsets from the rest pose, on the control mesh and
// on one level of the multiresolution head (what a GLB morph target holds).
#pragma once
#include "anim/face_pose.h"
#include "anim/face_shapes.h"

namespace lk {

struct BakedShape {
  std::string name;
  FaceControls controls;
  std::vector<Vec3> control;  // #V_0 offsets
  std::vector<Vec3> level;    // #V_level offsets (empty without a multires head)
};

// Bakes `names` (face_shape_names() when empty). With mesh (at rest, its
// control mesh the rig's), each shape is posed by the local update up to
// `level` (clamped to the levels there are), read, and put back to rest;
// the mesh is left at rest and current. InvalidInput on an unknown name or
// a mesh that is not the rig's.
Status bake_face_shapes(const FaceRig& rig, MultiresMesh* mesh, int level, const std::vector<std::string>& names,
                        std::vector<BakedShape>& out);

}  // namespace lk
