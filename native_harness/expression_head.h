// The head that `likeness render --expression` draws and `likeness bench
// --only anim` times: a head project's fit (its multires levels, skin and
// uvs), a mesh with the generic head's vertices, or the generic head, with
// its face rig (core/anim) and its parts (eyes, teeth, tongue).
#pragma once
#include "anim/face_rig.h"
#include "head/head_model.h"
#include "image/image.h"
#include "multires/multires.h"
#include "project/parts.h"

#include <string>
#include <vector>

namespace lk::cli {

struct ExpressionHead {
  GenericHead generic;
  MultiresMesh multires;   // at rest, current
  FaceRig rig;
  Image skin;              // empty unless a textured project
  std::vector<Vec2> uvs;   // the finest level's, when textured
  Image eye_texture;       // the project's own iris (an eye photo's, or found in its photos); empty: the generic one
  HeadParts parts;
  bool have_parts = false;
  std::string description;
};

// project_path (a .likeness.glb project) or mesh_path (generic topology) or
// neither (the generic head, refined to `levels`).
// seal: how the closed lids meet (LidSeal, default: as the asset's rig).
Status load_expression_head(const std::string& project_path, const std::string& mesh_path, int levels,
                            ExpressionHead& out, const LidSeal& seal = {});

// The head at `level` posed by controls (the multires is posed and left so)
// and its parts posed with it: eyes, upper teeth, lower teeth, tongue.
struct PosedHead {
  TriMesh head;
  std::vector<TriMesh> parts;
  std::vector<Vec3> part_colors;  // sRGB
  std::vector<Image> part_textures;  // per part, empty: its colour (the eyes wear the generic iris)
};
Status pose_expression_head(ExpressionHead& head, const FaceControls& controls, int level, PosedHead& out);

}  // namespace lk::cli
