#include "anim/bake.h"

#include <algorithm>

namespace lk {

Status bake_face_shapes(const FaceRig& rig, MultiresMesh* mesh, int level, const std::vector<std::string>& names,
                        std::vector<BakedShape>& out) {
  const std::vector<std::string>& list = names.empty() ? face_shape_names() : names;
  if (mesh && mesh->control.size() != rig.rest.size())
    return Status::error(ErrorCode::InvalidInput, "the head's control mesh is not the rig's");
  if (mesh) {
    level = std::clamp(level, 0, mesh->num_levels());
    if (Status s = ensure_current(*mesh); !s.ok()) return s;
  }
  std::vector<BakedShape> baked;
  const std::vector<Vec3> rest_level = mesh ? mesh->state.displaced[static_cast<std::size_t>(level)] : std::vector<Vec3>{};
  for (const std::string& name : list) {
    BakedShape b;
    b.name = name;
    if (Status s = face_shape(name, b.controls); !s.ok()) return s;
    const std::vector<Vec3> posed = pose_face(rig, b.controls);
    b.control.resize(posed.size());
    for (std::size_t i = 0; i < posed.size(); ++i) b.control[i] = posed[i] - rig.rest[i];
    if (mesh) {
      if (Status s = pose_multires(*mesh, rig, b.controls, level); !s.ok()) return s;
      const std::vector<Vec3>& moved = mesh->state.displaced[static_cast<std::size_t>(level)];
      b.level.resize(moved.size());
      for (std::size_t i = 0; i < moved.size(); ++i) b.level[i] = moved[i] - rest_level[i];
      if (Status s = pose_multires(*mesh, rig, FaceControls{}, level); !s.ok()) return s;
    }
    baked.push_back(std::move(b));
  }
  if (mesh)
    if (Status s = ensure_current(*mesh); !s.ok()) return s;
  out = std::move(baked);
  return Status::success();
}

}  // namespace lk
