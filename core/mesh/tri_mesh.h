// Triangle meshes and point clouds: plain data, no algorithms.
#pragma once
#include "common/types.h"

#include <string>

namespace lk {

// A triangle mesh. Attribute arrays are either empty or have one entry per
// vertex (#V); uvs may instead be per corner (3 * #F) when uv_per_corner is
// set, for charts with seams.
struct TriMesh {
  std::vector<Vec3> positions;  // #V
  std::vector<Tri> triangles;   // #F, counter-clockwise seen from outside
  std::vector<Vec3> normals;    // #V or empty
  std::vector<Vec3> colors;     // #V or empty, linear RGB in [0,1]
  std::vector<Vec2> uvs;        // #V (or 3*#F if uv_per_corner) or empty
  bool uv_per_corner = false;
  std::string texture_name;     // material's diffuse map, when read from / written to OBJ

  int num_vertices() const { return static_cast<int>(positions.size()); }
  int num_triangles() const { return static_cast<int>(triangles.size()); }
};

// An unstructured point cloud (a range scan). Optional arrays are empty or #P.
struct PointCloud {
  std::vector<Vec3> positions;  // #P
  std::vector<Vec3> normals;    // #P or empty
  std::vector<Vec3> colors;     // #P or empty, RGB in [0,1]
  // The scan's own triangles when it came as a mesh (indices into
  // positions), or empty: a raw cloud. Only the displacements read them
  // (multires/surface_samples.h).
  std::vector<Tri> faces;

  int size() const { return static_cast<int>(positions.size()); }
};

}  // namespace lk
