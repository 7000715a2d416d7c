// Crease curves in the Modified Butterfly (subdiv/butterfly.h): tagged
// edges refine by the 4-point rule along their polyline, and the mesh is
// refined as if cut along them.
#include "subdiv/butterfly.h"

#include "mesh/topology.h"
#include "shapes.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <set>

using namespace lk;
using namespace lk::test;

namespace {

// Vertex id of mirrored_irregular_grid(n, m) at column i (x = i - n), row j.
int grid_id(int n, int i, int j) { return j * (2 * n + 1) + i; }

// The column x = 0 of mirrored_irregular_grid(n, m), bottom to top: it runs
// from boundary to boundary and has irregular valences along it.
std::vector<int> middle_column(int n, int m) {
  std::vector<int> c;
  for (int j = 0; j <= m; ++j) c.push_back(grid_id(n, n, j));
  return c;
}

// A closed rectangle of grid edges around the cells i0..i1-1, j0..j1-1.
std::vector<int> rectangle_loop(int n, int i0, int i1, int j0, int j1) {
  std::vector<int> loop;
  for (int i = i0; i < i1; ++i) loop.push_back(grid_id(n, i, j0));
  for (int j = j0; j < j1; ++j) loop.push_back(grid_id(n, i1, j));
  for (int i = i1; i > i0; --i) loop.push_back(grid_id(n, i, j1));
  for (int j = j1; j > j0; --j) loop.push_back(grid_id(n, i0, j));
  return loop;
}

std::vector<Vec3> refine(const std::vector<ButterflyLevel>& levels, const std::vector<Vec3>& control, int upto) {
  std::vector<Vec3> p = control, f;
  for (int l = 0; l < upto; ++l) {
    REQUIRE(apply(levels[l], p, f).ok());
    p.swap(f);
  }
  return p;
}

// The new vertex on edge {a, b} of a level (-1 if there is no such edge).
int new_vertex_on(const ButterflyLevel& level, int a, int b) {
  for (int k = 0; k < level.num_new_vertices(); ++k) {
    const auto& e = level.edge_endpoints[k];
    if ((e[0] == a && e[1] == b) || (e[0] == b && e[1] == a)) return level.num_coarse_vertices + k;
  }
  return -1;
}

// Dyn-Levin-Gregory 4-point scheme on a polyline alone; an open polyline's
// missing outer points are reflections (2 p_0 - p_1), as in butterfly.h.
std::vector<Vec3> four_point(const std::vector<Vec3>& p, bool closed) {
  const int n = static_cast<int>(p.size());
  auto at = [&](int i, int from) -> Vec3 {
    if (closed) return p[((i % n) + n) % n];
    if (i < 0) return 2 * p[0] - p[from];
    if (i >= n) return 2 * p[n - 1] - p[from];
    return p[i];
  };
  std::vector<Vec3> out;
  const int segments = closed ? n : n - 1;
  for (int i = 0; i < segments; ++i) {
    out.push_back(p[i]);
    const Vec3 a = p[i], b = at(i + 1, i), before = at(i - 1, i + 1), after = at(i + 2, i);
    out.push_back(9.0 / 16 * (a + b) - 1.0 / 16 * (before + after));
  }
  if (!closed) out.push_back(p[n - 1]);
  return out;
}

// Random heights: a non-planar surface whose crease polylines are 3-D curves.
TriMesh crumpled_grid(int n, int m, unsigned seed) {
  TriMesh g = mirrored_irregular_grid(n, m);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> h(-0.5, 0.5);
  for (Vec3& p : g.positions) p.z() = h(rng);
  return g;
}

}  // namespace

TEST_CASE("butterfly creases: no creases, or tags on boundary edges only, change nothing", "[subdiv][crease]") {
  for (const TriMesh& m : {crumpled_grid(3, 4, 1), icosphere(1)}) {
    std::vector<ButterflyLevel> plain, tagged;
    REQUIRE(build_butterfly_levels(m, 3, plain).ok());
    ButterflyCreases creases;
    MeshTopology topo;
    REQUIRE(build_topology(m, topo).ok());
    for (const Edge& e : topo.edges)
      if (e.boundary()) creases.edges.push_back({e.v1, e.v0});
    REQUIRE(build_butterfly_levels(m, creases, 3, tagged).ok());
    for (int l = 0; l < 3; ++l) {
      CHECK(tagged[l].stencil_offsets == plain[l].stencil_offsets);
      CHECK(tagged[l].stencil_indices == plain[l].stencil_indices);
      CHECK(tagged[l].stencil_weights == plain[l].stencil_weights);  // bit for bit
      CHECK(tagged[l].fine_triangles == plain[l].fine_triangles);
      CHECK(std::count(tagged[l].crease_edges.begin(), tagged[l].crease_edges.end(), 1) == 0);
    }
  }
}

TEST_CASE("butterfly creases: a crease edge's stencil is the 4-point rule, reflected at an open end", "[subdiv][crease]") {
  const int n = 3, m = 4;
  TriMesh g = mirrored_irregular_grid(n, m);
  ButterflyCreases creases;
  add_crease_polyline(middle_column(n, m), false, creases);
  std::vector<ButterflyLevel> levels;
  REQUIRE(build_butterfly_levels(g, creases, 1, levels).ok());
  const ButterflyLevel& L = levels[0];
  auto row = [&](int a, int b) {
    std::map<int, double> w;
    const int k = new_vertex_on(L, a, b) - L.num_coarse_vertices;
    REQUIRE(k >= 0);
    CHECK(L.crease_edges[k] == 1);
    for (int i = L.stencil_offsets[k]; i < L.stencil_offsets[k + 1]; ++i) w[L.stencil_indices[i]] = L.stencil_weights[i];
    return w;
  };
  const auto c = middle_column(n, m);
  // Inside the polyline: -1/16, 9/16, 9/16, -1/16 on four crease vertices.
  const std::map<int, double> inner = {{c[0], -1.0 / 16}, {c[1], 9.0 / 16}, {c[2], 9.0 / 16}, {c[3], -1.0 / 16}};
  CHECK(row(c[1], c[2]) == inner);
  // At the open end c[0] (a corner): the outer point is 2 c0 - c1.
  const std::map<int, double> end = {{c[0], 7.0 / 16}, {c[1], 10.0 / 16}, {c[2], -1.0 / 16}};
  CHECK(row(c[0], c[1]) == end);
  int tagged = 0;
  for (char t : L.crease_edges) tagged += t;
  CHECK(tagged == m);
}

TEST_CASE("butterfly creases: a plane with crease lines and loops stays planar", "[subdiv][crease]") {
  // Every stencil, cut or not, is affine, so a plane is reproduced exactly
  // whatever the tags (irregular valences on and beside the creases included).
  const int n = 4, m = 6;
  TriMesh g = mirrored_irregular_grid(n, m);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> jitter(-0.2, 0.2);
  for (Vec3& p : g.positions) p += Vec3(jitter(rng), jitter(rng), 0);
  const Mat3 R = Eigen::AngleAxisd(0.9, Vec3(2, -1, 3).normalized()).toRotationMatrix();
  const Vec3 t(1.0, 2.0, -3.0);
  for (Vec3& p : g.positions) p = R * p + t;
  const Vec3 normal = R * Vec3::UnitZ();
  ButterflyCreases creases;
  add_crease_polyline(middle_column(n, m), false, creases);
  add_crease_polyline(rectangle_loop(n, 1, 3, 1, 4), true, creases);
  std::vector<ButterflyLevel> levels;
  REQUIRE(build_butterfly_levels(g, creases, 3, levels).ok());
  const auto p = refine(levels, g.positions, 3);
  double worst = 0;
  for (const Vec3& q : p) worst = std::max(worst, std::abs(normal.dot(q - t)));
  CHECK(worst < 1e-12);
  // The curved version is not planar (else the check above proves nothing).
  TriMesh bent = g;
  for (Vec3& q : bent.positions) q += 0.3 * std::sin(q.x() + q.y()) * normal;
  const auto pb = refine(levels, bent.positions, 3);
  double bulge = 0;
  for (const Vec3& q : pb) bulge = std::max(bulge, std::abs(normal.dot(q - t)));
  CHECK(bulge > 0.1);
}

TEST_CASE("butterfly creases: a crease polyline refines exactly as the 4-point scheme on the curve alone", "[subdiv][crease]") {
  const int n = 4, m = 6;
  for (bool closed : {false, true}) {
    TriMesh g = crumpled_grid(n, m, closed ? 11 : 12);
    const std::vector<int> curve = closed ? rectangle_loop(n, 1, 6, 1, 5) : middle_column(n, m);
    ButterflyCreases creases;
    add_crease_polyline(curve, closed, creases);
    const int L = 3;
    std::vector<ButterflyLevel> levels;
    REQUIRE(build_butterfly_levels(g, creases, L, levels).ok());
    std::vector<Vec3> mesh_p = g.positions, fine;
    std::vector<int> ids = curve;
    std::vector<Vec3> curve_p;
    for (int v : curve) curve_p.push_back(g.positions[v]);
    for (int l = 0; l < L; ++l) {
      REQUIRE(apply(levels[l], mesh_p, fine).ok());
      mesh_p.swap(fine);
      curve_p = four_point(curve_p, closed);
      std::vector<int> next;
      const size_t segments = closed ? ids.size() : ids.size() - 1;
      for (size_t i = 0; i < segments; ++i) {
        next.push_back(ids[i]);
        const int v = new_vertex_on(levels[l], ids[i], ids[(i + 1) % ids.size()]);
        REQUIRE(v >= 0);
        CHECK(levels[l].crease_edges[v - levels[l].num_coarse_vertices] == 1);
        next.push_back(v);
      }
      if (!closed) next.push_back(ids.back());
      ids = next;
      REQUIRE(ids.size() == curve_p.size());
      double worst = 0;
      for (size_t i = 0; i < ids.size(); ++i) worst = std::max(worst, (mesh_p[ids[i]] - curve_p[i]).norm());
      INFO((closed ? "closed" : "open") << " curve, level " << l + 1);
      CHECK(worst < 1e-14);
    }
    // The same curve without the tag is not refined as a curve: the surface
    // around it pulls it (so the check above can fail).
    std::vector<ButterflyLevel> plain;
    REQUIRE(build_butterfly_levels(g, 1, plain).ok());
    std::vector<Vec3> p1;
    REQUIRE(apply(plain[0], g.positions, p1).ok());
    std::vector<Vec3> c0;
    for (int v : curve) c0.push_back(g.positions[v]);
    const auto c1 = four_point(c0, closed);
    double differs = 0;
    for (size_t i = 0; i + 1 < curve.size(); ++i)
      differs = std::max(differs, (p1[new_vertex_on(plain[0], curve[i], curve[i + 1])] - c1[2 * i + 1]).norm());
    CHECK(differs > 1e-3);
  }
}

TEST_CASE("butterfly creases: the two sides of a crease do not influence each other", "[subdiv][crease]") {
  // The crease column x = 0 splits the grid into x < 0 and x > 0. Moving a
  // vertex on one side must leave every level-3 vertex of the other side and
  // of the crease curve where it was.
  const int n = 4, m = 6, L = 3;
  TriMesh g = crumpled_grid(n, m, 5);
  ButterflyCreases creases;
  add_crease_polyline(middle_column(n, m), false, creases);
  std::vector<ButterflyLevel> levels;
  REQUIRE(build_butterfly_levels(g, creases, L, levels).ok());
  // Side of every vertex on every level: -1, +1, 0 on the crease.
  std::vector<int> side(g.num_vertices());
  for (int v = 0; v < g.num_vertices(); ++v) side[v] = g.positions[v].x() < 0 ? -1 : g.positions[v].x() > 0 ? 1 : 0;
  for (const ButterflyLevel& lv : levels) {
    std::vector<int> next(side);
    next.resize(lv.num_fine_vertices);
    for (int k = 0; k < lv.num_new_vertices(); ++k) {
      const int a = side[lv.edge_endpoints[k][0]], b = side[lv.edge_endpoints[k][1]];
      next[lv.num_coarse_vertices + k] = lv.crease_edges[k] ? 0 : a != 0 ? a : b;
      if (!lv.crease_edges[k]) REQUIRE(a * b >= 0);  // no edge jumps the crease
    }
    side = next;
  }
  const auto before = refine(levels, g.positions, L);
  std::vector<ButterflyLevel> plain;
  REQUIRE(build_butterfly_levels(g, L, plain).ok());
  const auto plain_before = refine(plain, g.positions, L);
  for (int moving_side : {-1, 1}) {
    for (int v = 0; v < g.num_vertices(); ++v) {
      if (side[v] != moving_side) continue;
      TriMesh moved = g;
      moved.positions[v] += Vec3(0.3, -0.2, 0.7);
      const auto after = refine(levels, moved.positions, L);
      int crossed = 0, same_side = 0;
      for (size_t i = 0; i < after.size(); ++i) {
        if (after[i] == before[i]) continue;
        if (side[i] == moving_side) ++same_side;
        else ++crossed;
      }
      INFO("moved vertex " << v << " on side " << moving_side);
      CHECK(crossed == 0);
      CHECK(same_side > 0);
    }
  }
  // Without the crease, a vertex next to the column does move the other side.
  TriMesh moved = g;
  const int beside = grid_id(n, n - 1, m / 2);
  moved.positions[beside] += Vec3(0.3, -0.2, 0.7);
  const auto after = refine(plain, moved.positions, L);
  int crossed = 0;
  for (size_t i = 0; i < after.size(); ++i) crossed += after[i] != plain_before[i] && side[i] >= 0;
  CHECK(crossed > 0);
}

TEST_CASE("butterfly creases: finer levels derived with creases match a fresh build with the child creases", "[subdiv][crease]") {
  const int n = 4, m = 6;
  TriMesh g = mirrored_irregular_grid(n, m);
  ButterflyCreases creases;
  add_crease_polyline(middle_column(n, m), false, creases);
  add_crease_polyline(rectangle_loop(n, 1, 3, 1, 4), true, creases);
  std::vector<ButterflyLevel> derived;
  REQUIRE(build_butterfly_levels(g, creases, 3, derived).ok());
  std::set<int> corners(creases.corners.begin(), creases.corners.end());
  for (int l = 1; l < 3; ++l) {
    TriMesh level_mesh;
    level_mesh.positions.assign(derived[l].num_coarse_vertices, Vec3::Zero());
    level_mesh.triangles = derived[l].coarse_triangles;
    ButterflyCreases child;  // halves of the tagged edges of the level above
    const ButterflyLevel& up = derived[l - 1];
    for (int k = 0; k < up.num_new_vertices(); ++k)
      if (up.crease_edges[k])
        for (int end : up.edge_endpoints[k]) child.edges.push_back({end, up.num_coarse_vertices + k});
    child.corners = creases.corners;
    std::vector<ButterflyLevel> fresh;
    REQUIRE(build_butterfly_levels(level_mesh, child, 1, fresh).ok());
    const ButterflyLevel& a = derived[l];
    const ButterflyLevel& b = fresh[0];
    std::map<std::array<int, 2>, std::map<int, double>> rows;
    std::map<std::array<int, 2>, char> tags;
    for (int k = 0; k < b.num_new_vertices(); ++k) {
      tags[b.edge_endpoints[k]] = b.crease_edges[k];
      for (int i = b.stencil_offsets[k]; i < b.stencil_offsets[k + 1]; ++i)
        rows[b.edge_endpoints[k]][b.stencil_indices[i]] = b.stencil_weights[i];
    }
    int mismatches = 0, tagged = 0;
    for (int k = 0; k < a.num_new_vertices(); ++k) {
      const auto it = rows.find(a.edge_endpoints[k]);
      REQUIRE(it != rows.end());
      tagged += a.crease_edges[k];
      if (tags[a.edge_endpoints[k]] != a.crease_edges[k]) ++mismatches;
      if (static_cast<int>(it->second.size()) != a.stencil_offsets[k + 1] - a.stencil_offsets[k]) {
        ++mismatches;
        continue;
      }
      for (int i = a.stencil_offsets[k]; i < a.stencil_offsets[k + 1]; ++i) {
        const auto w = it->second.find(a.stencil_indices[i]);
        if (w == it->second.end() || std::abs(w->second - a.stencil_weights[i]) > 1e-15) ++mismatches;
      }
    }
    INFO("level " << l);
    CHECK(tagged == static_cast<int>(child.edges.size()));
    CHECK(mismatches == 0);
  }
}

TEST_CASE("butterfly creases: bad creases give clear errors", "[subdiv][crease]") {
  TriMesh g = mirrored_irregular_grid(2, 2);
  std::vector<ButterflyLevel> levels;
  ButterflyCreases not_an_edge;
  not_an_edge.edges.push_back({grid_id(2, 0, 0), grid_id(2, 4, 2)});
  Status s = build_butterfly_levels(g, not_an_edge, 2, levels);
  CHECK(s.code == ErrorCode::InvalidInput);
  CHECK(s.message.find("not an edge") != std::string::npos);
  CHECK(levels.empty());
  ButterflyCreases out_of_range;
  out_of_range.edges.push_back({0, g.num_vertices()});
  s = build_butterfly_levels(g, out_of_range, 2, levels);
  CHECK(s.code == ErrorCode::InvalidInput);
  CHECK(s.message.find("out of range") != std::string::npos);
  ButterflyCreases self_loop;
  self_loop.edges.push_back({3, 3});
  CHECK(build_butterfly_levels(g, self_loop, 1, levels).code == ErrorCode::InvalidInput);
  ButterflyCreases bad_corner;
  bad_corner.corners.push_back(-1);
  s = build_butterfly_levels(g, bad_corner, 1, levels);
  CHECK(s.code == ErrorCode::InvalidInput);
  CHECK(s.message.find("corner") != std::string::npos);
}
