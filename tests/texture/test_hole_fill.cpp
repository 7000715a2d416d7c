// Hole filling (tarini2002 Sec. 3.2): 80/60/40/20 % passes, then any
// coloured neighbour; every vertex ends coloured.
#include "fixtures.h"
#include "mesh/topology.h"
#include "texture/hole_fill.h"

#include <catch2/catch.hpp>

using namespace lk;
using namespace lk::test;

TEST_CASE("hole filling respects the threshold order") {
  // 9 x 9 vertex grid: interior vertices have 6 neighbours.
  const int n = 8;
  const TriMesh m = plane_grid(n, 0, 1, 0, 1, 0);
  MeshTopology topo;
  REQUIRE(build_topology(m, topo).ok());
  auto id = [n](int i, int j) { return j * (n + 1) + i; };
  const int nv = m.num_vertices();
  // Colour = x (a linear field): an interior vertex filled from its full
  // ring gets exactly its own x (the ring is symmetric).
  std::vector<Vec3> colors(nv, Vec3::Zero());
  std::vector<char> colored(nv, 0);
  auto set = [&](int v) {
    colors[v] = Vec3::Constant(m.positions[v].x());
    colored[v] = 1;
  };
  // Region A: everything with i <= 3 coloured except vertex a = (2, 4),
  // which then has 6/6 coloured neighbours (> 80 %).
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= 3; ++i) set(id(i, j));
  const int a = id(2, 4);
  colored[a] = 0;
  colors[a] = Vec3::Zero();
  // Vertex b = (6, 4): a lonely coloured neighbour c = (7, 4) on its right
  // and nothing else nearby: 1/6 < 20 %, so only the last pass (or neighbours
  // filled before) can colour it.
  const int b = id(6, 4), c = id(7, 4);
  set(c);
  HoleFillReport rep;
  std::vector<int> pass;
  REQUIRE(fill_vertex_colors(topo, colors, colored, HoleFillOptions(), rep, &pass).ok());
  for (int v = 0; v < nv; ++v) REQUIRE(colored[v]);
  CHECK(rep.uncolorable == 0);
  CHECK(pass[a] == 0);
  CHECK(colors[a].x() == Approx(m.positions[a].x()).margin(1e-12));
  CHECK(pass[c] == -1);
  CHECK(pass[b] > pass[a]);
  CHECK(pass[b] >= 1);
  REQUIRE(rep.filled_per_pass.size() == 5);
  int total = 0;
  for (int k : rep.filled_per_pass) total += k;
  CHECK(total == nv - 4 * (n + 1));  // every vertex not coloured on input
  // Averages of neighbours stay inside the range of the input colours.
  for (int v = 0; v < nv; ++v) {
    CHECK(colors[v].x() >= -1e-12);
    CHECK(colors[v].x() <= 1 + 1e-12);
  }
}

TEST_CASE("hole filling: a vertex needing 20 % waits for the 20 % pass") {
  // A fan: centre vertex with 5 neighbours on a circle, one coloured (20 %).
  // Neighbours see centre + 2 rim vertices: the coloured rim vertex makes
  // 1/3 (33 %) for its two rim neighbours, so they fill in the 20 % pass
  // too, in the paper's sweep order; the centre itself qualifies only at 20 %.
  TriMesh m;
  m.positions.push_back(Vec3::Zero());
  for (int k = 0; k < 5; ++k) m.positions.emplace_back(std::cos(k * 1.2566), std::sin(k * 1.2566), 0);
  for (int k = 0; k < 5; ++k) m.triangles.push_back({0, 1 + k, 1 + (k + 1) % 5});
  MeshTopology topo;
  REQUIRE(build_topology(m, topo).ok());
  std::vector<Vec3> colors(6, Vec3::Zero());
  std::vector<char> colored(6, 0);
  colors[1] = Vec3(1, 0.5, 0.25);
  colored[1] = 1;
  HoleFillReport rep;
  std::vector<int> pass;
  REQUIRE(fill_vertex_colors(topo, colors, colored, HoleFillOptions(), rep, &pass).ok());
  CHECK(pass[0] == 3);  // 1/5 = 20 %: the 20 % pass (index 3), not earlier
  CHECK(rep.filled_per_pass[0] == 0);
  CHECK(rep.filled_per_pass[1] == 0);
  CHECK(rep.filled_per_pass[2] == 0);
  for (int v = 0; v < 6; ++v) CHECK(colors[v].isApprox(Vec3(1, 0.5, 0.25)));
}

TEST_CASE("hole filling: isolated components get the fallback, and bad input is an error") {
  TriMesh m = plane_grid(2, 0, 1, 0, 1, 0);
  append_mesh(m, plane_grid(2, 2, 3, 0, 1, 0));
  MeshTopology topo;
  REQUIRE(build_topology(m, topo).ok());
  std::vector<Vec3> colors(m.num_vertices(), Vec3::Zero());
  std::vector<char> colored(m.num_vertices(), 0);
  colors[0] = Vec3(1, 0, 0);
  colored[0] = 1;
  HoleFillReport rep;
  REQUIRE(fill_vertex_colors(topo, colors, colored, HoleFillOptions(), rep).ok());
  CHECK(rep.uncolorable == 9);
  CHECK(colors[m.num_vertices() - 1].isApprox(HoleFillOptions().fallback_color));
  std::vector<char> short_flags(3, 0);
  CHECK(fill_vertex_colors(topo, colors, short_flags, HoleFillOptions(), rep).code == ErrorCode::InvalidInput);
  HoleFillOptions bad;
  bad.thresholds = {0.8, 1.5};
  CHECK(fill_vertex_colors(topo, colors, colored, bad, rep).code == ErrorCode::InvalidInput);
}
