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
// Sizes the state arrays for the mesh's levels.
void resize_state(MultiresMesh& m);
// InvalidInput unless the displacement and link arrays match the levels.
Status check_sizes(const MultiresMesh& m);
// Mean edge length of the triangles at positions P.
double mean_edge(const std::vector<Vec3>& P, const std::vector<Tri>& tris);

}  // namespace lk::multires_detail
