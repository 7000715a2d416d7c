#include "project/project.h"

namespace lk {

std::vector<Vec3> HeadFrame::to_scan(const std::vector<Vec3>& points) const {
  std::vector<Vec3> out(points.size());
  for (size_t i = 0; i < out.size(); ++i) out[i] = to_scan(points[i]);
  return out;
}

TriMesh HeadFrame::to_scan(const TriMesh& mesh) const {
  TriMesh out = mesh;
  out.positions = to_scan(mesh.positions);
  out.normals.clear();
  return out;
}

}  // namespace lk
