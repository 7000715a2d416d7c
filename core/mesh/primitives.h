// Closed and planar meshes with exactly known geometry: the icosahedron and
// the icosphere (1:4 midpoint splits projected onto the unit sphere) and the
// regular triangulated grid. Used wherever an analytic reference surface is
// needed (tests, benchmarks) so there is one definition of each.
// Shapes: positions #V by 3, triangles #F by 3, counter-clockwise seen from
// outside (sphere) or from +z (grid).
#pragma once
#include "mesh/tri_mesh.h"

namespace lk {

// Regular icosahedron on the unit sphere: 12 vertices of valence 5, 20 faces.
TriMesh make_icosahedron();

// The icosahedron refined `splits` times by 1:4 midpoint splitting, every new
// vertex projected onto the unit sphere: 10 * 4^splits + 2 vertices with
// valences 5 and 6. Vertex order: the coarse vertices first, then midpoints
// in the order the triangles of the previous level are visited.
TriMesh make_icosphere(int splits);

// (n+1) x (m+1) grid on [0,n] x [0,m] in the z = 0 plane, every cell split by
// the same diagonal, so interior vertices have valence 6 (a regular lattice).
TriMesh make_regular_grid(int n, int m);

}  // namespace lk
