#include "mesh/geometry.h"
#include "mesh/primitives.h"
#include "mesh/topology.h"

#include <catch2/catch.hpp>

using namespace lk;

namespace {

// An icosahedron-like closed octahedron and a fan-shaped disk.
TriMesh octahedron() {
  TriMesh m;
  m.positions = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  m.triangles = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  return m;
}

}  // namespace

TEST_CASE("closed octahedron: edges, valence, no boundary", "[mesh]") {
  TriMesh m = octahedron();
  MeshTopology t;
  REQUIRE(build_topology(m, t).ok());
  CHECK(t.edges.size() == 12);
  CHECK(euler_characteristic(t, m.num_triangles()) == 2);
  CHECK(t.boundary_loops.empty());
  for (int v = 0; v < 6; ++v) {
    CHECK(t.valence(v) == 4);
    CHECK_FALSE(t.is_boundary(v));
    CHECK(t.ring_faces[v].size() == 4);
  }
  CHECK(t.find_edge(0, 2) >= 0);
  CHECK(t.find_edge(0, 1) == -1);
  // Rings are counter-clockwise seen from outside: for the top vertex 4
  // (normal +z) successive neighbours turn positively about +z.
  const auto& r = t.rings[4];
  for (size_t i = 0; i < r.size(); ++i) {
    const Vec3 a = m.positions[r[i]], b = m.positions[r[(i + 1) % r.size()]];
    CHECK(a.cross(b).z() > 0);
  }
  // Normals of a closed convex mesh point away from its centre.
  auto n = vertex_normals(m);
  for (int v = 0; v < 6; ++v) CHECK(n[v].dot(m.positions[v]) > 0.9);
}

TEST_CASE("ring distances on the octahedron", "[mesh]") {
  TriMesh m = octahedron();
  MeshTopology t;
  REQUIRE(build_topology(m, t).ok());
  // Vertex 0's opposite is 1; every other vertex is its neighbour.
  CHECK(ring_distances(t, {0}, 2) == std::vector<int>{0, 2, 1, 1, 1, 1});
  CHECK(ring_distances(t, {0}, 1) == std::vector<int>{0, -1, 1, 1, 1, 1});
  CHECK(ring_distances(t, {0, 1}, 0) == std::vector<int>{0, 0, -1, -1, -1, -1});
  CHECK(ring_distances(t, {}, 3) == std::vector<int>(6, -1));
}

TEST_CASE("grid disk: one boundary loop, ordered rings", "[mesh]") {
  TriMesh m = make_regular_grid(4, 4);
  MeshTopology t;
  REQUIRE(build_topology(m, t).ok());
  CHECK(euler_characteristic(t, m.num_triangles()) == 1);
  REQUIRE(t.boundary_loops.size() == 1);
  CHECK(t.boundary_loops[0].size() == 16);
  // Interior vertex (2,2): valence 6, closed ring.
  const int c = 2 * 5 + 2;
  CHECK(t.valence(c) == 6);
  CHECK_FALSE(t.is_boundary(c));
  // Corner vertex 0 is on the boundary; its ring starts and ends on boundary neighbours.
  CHECK(t.is_boundary(0));
  const auto& r0 = t.rings[0];
  CHECK(t.ring_faces[0].size() + 1 == r0.size());
  CHECK(t.edges[t.find_edge(0, r0.front())].boundary());
  CHECK(t.edges[t.find_edge(0, r0.back())].boundary());
  // Consecutive boundary loop vertices are joined by boundary edges.
  const auto& loop = t.boundary_loops[0];
  for (size_t i = 0; i < loop.size(); ++i) {
    const int e = t.find_edge(loop[i], loop[(i + 1) % loop.size()]);
    REQUIRE(e >= 0);
    CHECK(t.edges[e].boundary());
  }
  CHECK(surface_area(m) == Approx(16.0));
}

TEST_CASE("topology rejects broken connectivity", "[mesh]") {
  TriMesh m = octahedron();
  MeshTopology t;
  SECTION("index out of range") {
    m.triangles[0][1] = 17;
    auto s = build_topology(m, t);
    CHECK(s.code == ErrorCode::InvalidInput);
    CHECK(s.message.find("outside") != std::string::npos);
  }
  SECTION("repeated vertex") {
    m.triangles[0] = {0, 0, 4};
    CHECK_FALSE(build_topology(m, t).ok());
  }
  SECTION("flipped triangle") {
    std::swap(m.triangles[0][1], m.triangles[0][2]);
    CHECK_FALSE(build_topology(m, t).ok());
  }
  SECTION("edge shared by three triangles") {
    m.positions.push_back({0, 0, 2});
    m.triangles.push_back({0, 6, 2});  // shares edge 0-2 with two triangles... in a new direction
    m.triangles.push_back({2, 6, 0});
    CHECK_FALSE(build_topology(m, t).ok());
  }
  SECTION("bow-tie vertex") {
    TriMesh b;
    b.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {-1, 0, 0}, {-1, -1, 0}};
    b.triangles = {{0, 1, 2}, {0, 3, 4}};
    auto s = build_topology(b, t);
    CHECK_FALSE(s.ok());
    CHECK(s.message.find("non-manifold") != std::string::npos);
  }
}
