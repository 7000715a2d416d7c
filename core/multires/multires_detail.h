// Internal to the multires module: the kernels and checks shared by
// evaluation (multires.cpp), displacement measurement (displacement.cpp) and
// fold limiting (fold_limit.cpp). Not part of the module's interface.
#pragma once
#include "common/status.h"
#include "multires/multires.h"

#include <vector>

namespace lk::multires_detail {

// Unnormalised face normal, length = 2 area (area-weighted sums). The ONLY
// face normal kernel: evaluate() and local updates must agree bit for bit.
inline Vec3 face_normal(const std::vector<Tri>& tris, const std::vector<Vec3>& P, int f) {
  const Tri& t = tris[f];
  const Vec3& a = P[t[0]];
  return (P[t[1]] - a).cross(P[t[2]] - a);
}

// The displaced position: the ONLY displacement kernel (same reason).
inline Vec3 displace(const Vec3& p, double d, const Vec3& n) { return p + d * n; }

// Normals and displaced positions of level l from its base positions.
void evaluate_level(MultiresMesh& m, int l);
// The same after the base positions of moved_base changed (repeats
// allowed): recomputes the face normals around them and the normals of
// their normal_reach with the kernels of evaluate_level, and every displaced
// position (cheap, and displacements may have changed anywhere, even back
// to an earlier value). The level ends bit-identical to a full
// evaluate_level provided its face normals and normals were current for
// the other base positions.
void update_level(MultiresMesh& m, int l, const std::vector<int>& moved_base);
// Level l+1's base positions refined again where they read the displaced
// level-l positions of `moved` (refine_reach; l < L), bit-identical to a
// full apply provided the rest was current.
void update_refinement(MultiresMesh& m, int l, const std::vector<int>& moved);
// Sizes the state arrays for the mesh's levels.
void resize_state(MultiresMesh& m);
// Sizes update_control_vertices' marks for the mesh's levels (cleared only
// when the levels changed) and reserves its work lists.
void size_scratch(MultiresMesh& m);
// InvalidInput unless the displacement and link arrays match the levels.
Status check_sizes(const MultiresMesh& m);
// Mean edge length of the triangles at positions P.
double mean_edge(const std::vector<Vec3>& P, const std::vector<Tri>& tris);

}  // namespace lk::multires_detail
