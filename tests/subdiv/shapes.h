// Small synthetic meshes with known geometry for the subdivision and
// multiresolution tests (shared by tests/subdiv and tests/multires).
#pragma once
#include "mesh/primitives.h"
#include "mesh/tri_mesh.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

namespace lk::test {

// Regular icosahedron on the unit sphere (every vertex has valence 5).
inline TriMesh icosahedron() { return make_icosahedron(); }

// Octahedron on the unit sphere (valence 4 everywhere), symmetric under x -> -x.
inline TriMesh octahedron() {
  TriMesh m;
  m.positions = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  m.triangles = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  return m;
}

// (n+1) x (m+1) grid on [0,n] x [0,m] in the z = 0 plane, every cell split by
// the same diagonal: interior vertices have valence 6 (a regular lattice).
inline TriMesh regular_grid(int n, int m) { return make_regular_grid(n, m); }

// A grid on [-n,n] x [0,m] whose diagonals mirror across x = 0 (so the mesh
// is symmetric under x -> -x) and alternate in a few cells, which creates
// interior vertices of valence 4, 5, 7 and 8 besides 6.
inline TriMesh mirrored_irregular_grid(int n, int m) {
  TriMesh g;
  const int w = 2 * n;
  for (int j = 0; j <= m; ++j)
    for (int i = 0; i <= w; ++i) g.positions.push_back(Vec3(i - n, j, 0));
  auto id = [w](int i, int j) { return j * (w + 1) + i; };
  for (int j = 0; j < m; ++j)
    for (int i = 0; i < w; ++i) {
      const bool right = i >= n;                 // cell x-range [i-n, i-n+1]
      const int mi = right ? i - n : n - 1 - i;  // mirrored cell column
      bool flip = right;                          // diagonal direction mirrors
      if ((mi + j) % 3 == 0) flip = !flip;        // irregular valences, symmetric
      if (!flip) {
        g.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
        g.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
      } else {
        g.triangles.push_back({id(i, j), id(i + 1, j), id(i, j + 1)});
        g.triangles.push_back({id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
      }
    }
  return g;
}

// A planar fan: one interior vertex of valence K at the origin and a
// regular K-gon of boundary vertices at unit distance.
inline TriMesh planar_fan(int K) {
  TriMesh m;
  m.positions.push_back(Vec3::Zero());
  const double pi = std::acos(-1.0);
  for (int j = 0; j < K; ++j) m.positions.push_back(Vec3(std::cos(2 * pi * j / K), std::sin(2 * pi * j / K), 0));
  for (int j = 0; j < K; ++j) m.triangles.push_back({0, 1 + j, 1 + (j + 1) % K});
  return m;
}

// Icosahedron refined by midpoint splitting and projected onto the unit
// sphere `times` times: a smooth closed control mesh with valences 5 and 6.
inline TriMesh icosphere(int times) { return make_icosphere(times); }

}  // namespace lk::test
