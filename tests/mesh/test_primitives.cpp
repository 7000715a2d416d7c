#include "mesh/geometry.h"
#include "mesh/primitives.h"
#include "mesh/topology.h"

#include <catch2/catch.hpp>

#include <cmath>

using namespace lk;

TEST_CASE("primitives: icospheres are closed unit spheres with the known counts", "[mesh]") {
  for (int splits = 0; splits <= 3; ++splits) {
    const TriMesh m = make_icosphere(splits);
    const int expected_v = 10 * (1 << (2 * splits)) + 2;
    CHECK(m.num_vertices() == expected_v);
    CHECK(m.num_triangles() == 20 * (1 << (2 * splits)));
    MeshTopology topo;
    REQUIRE(build_topology(m, topo).ok());
    CHECK(topo.boundary_loops.empty());
    CHECK(m.num_vertices() - static_cast<int>(topo.edges.size()) + m.num_triangles() == 2);  // sphere: chi = 2
    for (const Vec3& p : m.positions) CHECK(std::abs(p.norm() - 1.0) < 1e-12);
    // Counter-clockwise seen from outside: every face normal points away from the centre.
    for (int f = 0; f < m.num_triangles(); ++f) {
      const Tri& t = m.triangles[f];
      const Vec3 c = (m.positions[t[0]] + m.positions[t[1]] + m.positions[t[2]]) / 3.0;
      CHECK(face_normal_area(m, f).dot(c) > 0);
    }
  }
}

TEST_CASE("primitives: the regular grid is a flat disk with valence 6 inside", "[mesh]") {
  const TriMesh g = make_regular_grid(4, 3);
  CHECK(g.num_vertices() == 20);
  CHECK(g.num_triangles() == 24);
  MeshTopology topo;
  REQUIRE(build_topology(g, topo).ok());
  REQUIRE(topo.boundary_loops.size() == 1);
  for (int f = 0; f < g.num_triangles(); ++f) CHECK(face_normal_area(g, f).z() > 0);
  const int interior = 1 * 5 + 1;  // vertex (1, 1)
  CHECK(topo.valence(interior) == 6);
}
