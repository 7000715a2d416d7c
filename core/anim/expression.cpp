#include "anim/expression.h"

#include "anim/face_shapes.h"

namespace lk {

Status set_expression(MultiresMesh& mesh, const FaceRig& rig, const std::map<std::string, double>& weights,
                      int max_level, UpdateFootprint* footprint) {
  FaceControls controls;
  if (Status s = face_controls_from_weights(weights, controls); !s.ok()) return s;
  return pose_multires(mesh, rig, controls, max_level, footprint);
}

}  // namespace lk
