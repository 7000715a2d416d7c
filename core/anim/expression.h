// set_expression: a head posed by weights per shape name (face_shapes.h),
// the weighted recipes summed into channel values, the control mesh posed
// by the muscle layer and the multiresolution head following by the local
// update (face_pose.h).
#pragma once
#include "anim/face_pose.h"

#include <map>
#include <string>

namespace lk {

// InvalidInput on an unknown name (nothing is changed then) or a mesh that
// is not the rig's; levels up to max_level (-1: all) are updated.
Status set_expression(MultiresMesh& mesh, const FaceRig& rig, const std::map<std::string, double>& weights,
                      int max_level = -1, UpdateFootprint* footprint = nullptr);

}  // namespace lk
