// A small mesh with every attribute, shared by the PLY reader's tests and the
// stream reader's: a quad split in two and an extra triangle, colors on the
// 1/255 grid so uchar storage is exact.
#pragma once
#include "mesh/tri_mesh.h"

inline lk::TriMesh sample_mesh() {
  lk::TriMesh m;
  m.positions = {{0, 0, 0}, {1.5, 0, 0}, {1.5, 2.25, 0}, {0, 2.25, -0.125}, {0.75, 1, 3}};
  m.triangles = {{0, 1, 2}, {0, 2, 3}, {1, 4, 2}};
  m.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0.6, 0.8}, {0, -0.6, 0.8}, {1, 0, 0}};
  m.colors = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {10 / 255.0, 20 / 255.0, 30 / 255.0}, {1, 1, 1}};
  m.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}, {0.5, 0.5}};
  return m;
}
