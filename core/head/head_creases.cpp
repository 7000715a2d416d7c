#include "head/head_creases.h"

#include <algorithm>

namespace lk {

ButterflyCreases head_creases(const TriMesh& mesh, const HeadAnnotations& annotations) {
  ButterflyCreases creases;
  for (const CreaseCurve& c : annotations.creases) add_crease_polyline(c.vertices, c.closed, creases);
  const int nv = mesh.num_vertices();
  for (const EyeSocket* eye : {&annotations.eye_left, &annotations.eye_right}) {
    int lo = -1, hi = -1;
    for (int v : eye->rim) {
      if (v < 0 || v >= nv) continue;
      if (lo < 0 || mesh.positions[v].x() < mesh.positions[lo].x()) lo = v;
      if (hi < 0 || mesh.positions[v].x() > mesh.positions[hi].x()) hi = v;
    }
    if (lo < 0 || lo == hi) continue;
    creases.corners.push_back(lo);
    creases.corners.push_back(hi);
  }
  std::sort(creases.corners.begin(), creases.corners.end());
  creases.corners.erase(std::unique(creases.corners.begin(), creases.corners.end()), creases.corners.end());
  return creases;
}

}  // namespace lk
