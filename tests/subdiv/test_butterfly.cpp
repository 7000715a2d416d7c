#include "subdiv/butterfly.h"

#include "io/io.h"
#include "mesh/topology.h"
#include "shapes.h"
#include "test_data.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <map>
#include <random>
#include <set>

using namespace lk;
using namespace lk::test;

namespace {

std::vector<Vec3> refine_positions(const std::vector<ButterflyLevel>& levels, const std::vector<Vec3>& control,
                                   int upto) {
  std::vector<Vec3> p = control, f;
  for (int l = 0; l < upto; ++l) {
    REQUIRE(apply(levels[l], p, f).ok());
    p.swap(f);
  }
  return p;
}

// Rotates and shifts the grid into a tilted plane, jittering the vertices
// inside the plane so no edge is axis-aligned or equally long.
TriMesh tilted_jittered(TriMesh m, Vec3& plane_normal, Vec3& plane_point) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-0.2, 0.2);
  for (Vec3& p : m.positions) p += Vec3(jitter(rng), jitter(rng), 0);
  const Mat3 R = (Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized())).toRotationMatrix();
  const Vec3 t(0.3, -2.0, 5.0);
  for (Vec3& p : m.positions) p = R * p + t;
  plane_normal = R * Vec3::UnitZ();
  plane_point = t;
  return m;
}

}  // namespace

TEST_CASE("butterfly: fine topology is the 1-to-4 split", "[subdiv]") {
  for (const TriMesh& m : {icosahedron(), mirrored_irregular_grid(3, 4), planar_fan(5)}) {
    std::vector<ButterflyLevel> levels;
    REQUIRE(build_butterfly_levels(m, 3, levels).ok());
    REQUIRE(levels.size() == 3);
    MeshTopology coarse_topo;
    REQUIRE(build_topology(m, coarse_topo).ok());
    int nv = m.num_vertices(), nf = m.num_triangles();
    for (const ButterflyLevel& L : levels) {
      CHECK(L.num_coarse_vertices == nv);
      CHECK(static_cast<int>(L.fine_triangles.size()) == 4 * nf);
      TriMesh fine;
      fine.positions.assign(L.num_fine_vertices, Vec3::Zero());
      fine.triangles = L.fine_triangles;
      MeshTopology t;
      REQUIRE(build_topology(fine, t).ok());  // still an oriented manifold
      CHECK(euler_characteristic(t, fine.num_triangles()) ==
            euler_characteristic(coarse_topo, m.num_triangles()));
      CHECK(t.boundary_loops.size() == coarse_topo.boundary_loops.size());
      // Every new vertex has valence 6 inside and 4 on the boundary.
      for (int v = nv; v < L.num_fine_vertices; ++v) CHECK(t.valence(v) == (t.is_boundary(v) ? 4 : 6));
      nv = L.num_fine_vertices;
      nf *= 4;
    }
  }
}

TEST_CASE("butterfly: stencils are affine and the regular one has 8 points", "[subdiv]") {
  for (const TriMesh& m : {icosahedron(), icosphere(1), mirrored_irregular_grid(3, 4), planar_fan(3),
                           planar_fan(4), planar_fan(9), octahedron()}) {
    std::vector<ButterflyLevel> levels;
    REQUIRE(build_butterfly_levels(m, 2, levels).ok());
    for (const ButterflyLevel& L : levels) {
      for (int k = 0; k < L.num_new_vertices(); ++k) {
        double sum = 0;
        for (int i = L.stencil_offsets[k]; i < L.stencil_offsets[k + 1]; ++i) {
          sum += L.stencil_weights[i];
          CHECK(L.stencil_indices[i] >= 0);
          CHECK(L.stencil_indices[i] < L.num_coarse_vertices);
        }
        CHECK(std::abs(sum - 1.0) < 1e-14);
      }
    }
  }
  // On a regular lattice, an edge far from the border uses 1/2, 1/8, -1/16.
  TriMesh g = regular_grid(6, 6);
  std::vector<ButterflyLevel> levels;
  REQUIRE(build_butterfly_levels(g, 1, levels).ok());
  const ButterflyLevel& L = levels[0];
  const int centre = 3 * 7 + 3, right = centre + 1;
  int found = 0;
  for (int k = 0; k < L.num_new_vertices(); ++k) {
    if (L.edge_endpoints[k] != std::array<int, 2>{centre, right}) continue;
    ++found;
    std::map<int, double> w;
    for (int i = L.stencil_offsets[k]; i < L.stencil_offsets[k + 1]; ++i) w[L.stencil_indices[i]] = L.stencil_weights[i];
    REQUIRE(w.size() == 8);
    CHECK(w[centre] == 0.5);
    CHECK(w[right] == 0.5);
    // apexes: (4,4) above-right and (3,2) below-left of the diagonal lattice
    CHECK(w[4 * 7 + 4] == 0.125);
    CHECK(w[2 * 7 + 3] == 0.125);
    for (int v : {4 * 7 + 3, 4 * 7 + 5, 2 * 7 + 2, 2 * 7 + 4}) CHECK(w[v] == -1.0 / 16);
  }
  CHECK(found == 1);
}

TEST_CASE("butterfly: coarse vertices are interpolated exactly at every level", "[subdiv]") {
  for (const TriMesh& m : {icosphere(1), mirrored_irregular_grid(3, 3)}) {
    std::vector<ButterflyLevel> levels;
    REQUIRE(build_butterfly_levels(m, 3, levels).ok());
    std::vector<Vec3> p = m.positions, f;
    for (const ButterflyLevel& L : levels) {
      REQUIRE(apply(L, p, f).ok());
      for (int v = 0; v < L.num_coarse_vertices; ++v) CHECK(f[v] == p[v]);
      // control vertices survive unchanged down to the finest level
      for (int v = 0; v < m.num_vertices(); ++v) CHECK(f[v] == m.positions[v]);
      p.swap(f);
    }
  }
}

TEST_CASE("butterfly: a plane with boundary and irregular valences stays planar", "[subdiv]") {
  Vec3 n, o;
  TriMesh m = tilted_jittered(mirrored_irregular_grid(4, 5), n, o);
  MeshTopology topo;
  REQUIRE(build_topology(m, topo).ok());
  std::set<int> valences;
  for (int v = 0; v < m.num_vertices(); ++v)
    if (!topo.is_boundary(v)) valences.insert(topo.valence(v));
  CHECK(valences.size() >= 4);  // the test covers extraordinary rules
  std::vector<ButterflyLevel> levels;
  REQUIRE(build_butterfly_levels(m, 3, levels).ok());
  for (int l = 1; l <= 3; ++l) {
    const auto p = refine_positions(levels, m.positions, l);
    double worst = 0;
    for (const Vec3& q : p) worst = std::max(worst, std::abs(n.dot(q - o)));
    INFO("level " << l);
    CHECK(worst < 1e-12);
  }
}

TEST_CASE("butterfly: regular lattice reproduces cubic height fields", "[subdiv]") {
  // The 8-point butterfly has cubic precision on the regular lattice: away
  // from the border (where reflected wings and the 4-point rule take over)
  // a new vertex lands exactly on the cubic. A wrong wing or apex breaks it.
  TriMesh g = regular_grid(8, 8);
  auto f = [](double x, double y) { return 0.1 * x * x * x - 0.2 * x * y * y + 0.3 * x * y - 0.05 * y * y + x - 2; };
  for (Vec3& p : g.positions) p.z() = f(p.x(), p.y());
  std::vector<ButterflyLevel> levels;
  REQUIRE(build_butterfly_levels(g, 1, levels).ok());
  const ButterflyLevel& L = levels[0];
  std::vector<Vec3> fine;
  REQUIRE(apply(L, g.positions, fine).ok());
  int checked = 0;
  for (int k = 0; k < L.num_new_vertices(); ++k) {
    const Vec3 q = fine[L.num_coarse_vertices + k];
    const auto [a, b] = L.edge_endpoints[k];
    const Vec3 mid = 0.5 * (g.positions[a] + g.positions[b]);
    const bool far_from_border = mid.x() > 2 && mid.x() < 6 && mid.y() > 2 && mid.y() < 6;
    if (!far_from_border) continue;
    ++checked;
    CHECK(q.x() == Approx(mid.x()).margin(1e-12));
    CHECK(q.y() == Approx(mid.y()).margin(1e-12));
    CHECK(q.z() == Approx(f(mid.x(), mid.y())).margin(1e-10));
  }
  CHECK(checked > 20);
}

TEST_CASE("butterfly: extraordinary rules put spoke points at the midpoint of a regular fan", "[subdiv]") {
  // For a planar regular K-gon around an interior vertex, sum_j s_j cos(2 pi j/K) = 1/2,
  // so the new vertex on each spoke is its midpoint; a wrong weight or ring
  // order moves it off.
  for (int K = 3; K <= 10; ++K) {
    TriMesh m = planar_fan(K);
    std::vector<ButterflyLevel> levels;
    REQUIRE(build_butterfly_levels(m, 1, levels).ok());
    std::vector<Vec3> fine;
    REQUIRE(apply(levels[0], m.positions, fine).ok());
    for (int k = 0; k < levels[0].num_new_vertices(); ++k) {
      const auto [a, b] = levels[0].edge_endpoints[k];
      if (a != 0) continue;  // spokes only
      INFO("K = " << K << " spoke to " << b);
      CHECK((fine[m.num_vertices() + k] - 0.5 * m.positions[b]).norm() < 1e-14);
    }
  }
}

TEST_CASE("butterfly: icospheres converge to the sphere with the expected trend", "[subdiv]") {
  // An interpolating scheme converges to its limit surface, not to the sphere
  // the control vertices sample: along the levels the radial error settles
  // on a plateau (its changes shrink geometrically), and the plateau drops
  // with the control mesh's edge length h. Measured (mean |r - 1| at level 4):
  // 2.5e-2, 3.7e-3, 7.4e-4, 1.5e-4 for h, h/2, h/4, h/8, i.e. ~h^2.5.
  double previous_plateau = 1e9;
  for (int k = 0; k <= 3; ++k) {
    TriMesh m = icosphere(k);
    std::vector<ButterflyLevel> levels;
    REQUIRE(build_butterfly_levels(m, 4, levels).ok());
    std::vector<std::vector<Vec3>> P;
    REQUIRE(apply_all(levels, m.positions, P).ok());
    std::vector<double> mean_err;
    for (const auto& p : P) {
      double sum = 0;
      for (const Vec3& q : p) sum += std::abs(q.norm() - 1.0);
      mean_err.push_back(sum / p.size());
    }
    INFO("control icosphere(" << k << ") mean radial error by level: " << mean_err[1] << " " << mean_err[2] << " "
                              << mean_err[3] << " " << mean_err[4]);
    CHECK(mean_err[0] < 1e-15);  // control vertices lie on the sphere
    for (int l = 2; l < 4; ++l)
      CHECK(std::abs(mean_err[l + 1] - mean_err[l]) < 0.5 * std::abs(mean_err[l] - mean_err[l - 1]));
    // Halving h cuts the error at least 4x (second order or better).
    CHECK(mean_err[4] < 0.25 * previous_plateau);
    previous_plateau = mean_err[4];
  }
  CHECK(previous_plateau < 3e-4);
}

TEST_CASE("butterfly: a mirror-symmetric mesh stays symmetric", "[subdiv]") {
  TriMesh m = mirrored_irregular_grid(3, 4);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> h(-0.3, 0.3);
  // Symmetric bumps: the same height for x and -x.
  std::map<std::pair<int, int>, double> heights;
  for (Vec3& p : m.positions) {
    auto key = std::make_pair(static_cast<int>(std::lround(std::abs(p.x()))), static_cast<int>(std::lround(p.y())));
    if (!heights.count(key)) heights[key] = h(rng);
    p.z() = heights[key];
  }
  // Mirror map of the control vertices.
  std::vector<int> mirror(m.num_vertices(), -1);
  for (int a = 0; a < m.num_vertices(); ++a)
    for (int b = 0; b < m.num_vertices(); ++b)
      if (m.positions[b] == Vec3(-m.positions[a].x(), m.positions[a].y(), m.positions[a].z())) mirror[a] = b;
  for (int v : mirror) REQUIRE(v >= 0);

  std::vector<ButterflyLevel> levels;
  REQUIRE(build_butterfly_levels(m, 3, levels).ok());
  std::vector<Vec3> p = m.positions, f;
  for (const ButterflyLevel& L : levels) {
    REQUIRE(apply(L, p, f).ok());
    std::map<std::pair<int, int>, int> by_edge;
    for (int k = 0; k < L.num_new_vertices(); ++k) by_edge[{L.edge_endpoints[k][0], L.edge_endpoints[k][1]}] = k;
    std::vector<int> fine_mirror(L.num_fine_vertices, -1);
    for (int v = 0; v < L.num_coarse_vertices; ++v) fine_mirror[v] = mirror[v];
    double worst = 0;
    for (int k = 0; k < L.num_new_vertices(); ++k) {
      int a = mirror[L.edge_endpoints[k][0]], b = mirror[L.edge_endpoints[k][1]];
      auto it = by_edge.find({std::min(a, b), std::max(a, b)});
      REQUIRE(it != by_edge.end());
      const int nc = L.num_coarse_vertices;
      fine_mirror[nc + k] = nc + it->second;
      const Vec3 q = f[nc + k], r = f[nc + it->second];
      worst = std::max(worst, (Vec3(-q.x(), q.y(), q.z()) - r).norm());
    }
    CHECK(worst < 1e-12);
    mirror = fine_mirror;
    p.swap(f);
  }
}

TEST_CASE("butterfly: apply works on any per-vertex data and matches positions bit for bit", "[subdiv]") {
  TriMesh m = icosphere(1);
  std::vector<ButterflyLevel> levels;
  REQUIRE(build_butterfly_levels(m, 2, levels).ok());
  std::vector<double> xs;
  std::vector<Vec2> uv;
  for (const Vec3& p : m.positions) {
    xs.push_back(p.x());
    uv.push_back(Vec2(p.y(), p.z()));
  }
  std::vector<std::vector<Vec3>> P;
  std::vector<std::vector<double>> X;
  std::vector<std::vector<Vec2>> UV;
  REQUIRE(apply_all(levels, m.positions, P).ok());
  REQUIRE(apply_all(levels, xs, X).ok());
  REQUIRE(apply_all(levels, uv, UV).ok());
  REQUIRE(P.size() == 3);
  for (size_t v = 0; v < P[2].size(); ++v) {
    CHECK(X[2][v] == P[2][v].x());
    CHECK(UV[2][v].x() == P[2][v].y());
    CHECK(UV[2][v].y() == P[2][v].z());
  }
}

TEST_CASE("butterfly: bad input gives clear errors", "[subdiv]") {
  std::vector<ButterflyLevel> levels;
  CHECK(build_butterfly_levels(TriMesh{}, 2, levels).code == ErrorCode::Empty);
  CHECK(build_butterfly_levels(icosahedron(), -1, levels).code == ErrorCode::InvalidInput);
  CHECK(build_butterfly_levels(icosahedron(), 12, levels).code == ErrorCode::TooLarge);

  TriMesh bad = icosahedron();
  bad.triangles.push_back({0, 11, 5});  // duplicate triangle: edge used twice in one direction
  Status s = build_butterfly_levels(bad, 1, levels);
  CHECK(s.code == ErrorCode::InvalidInput);
  CHECK(s.message.find("butterfly level 0") != std::string::npos);
  CHECK(levels.empty());

  TriMesh out_of_range = icosahedron();
  out_of_range.triangles[0][1] = 99;
  CHECK(build_butterfly_levels(out_of_range, 1, levels).code == ErrorCode::InvalidInput);

  REQUIRE(build_butterfly_levels(icosahedron(), 1, levels).ok());
  std::vector<Vec3> wrong(5, Vec3::Zero()), fine;
  Status a = apply(levels[0], wrong, fine);
  CHECK(a.code == ErrorCode::InvalidInput);
  CHECK(fine.empty());

  // Zero levels: nothing to do, not an error.
  CHECK(build_butterfly_levels(icosahedron(), 0, levels).ok());
  CHECK(levels.empty());
}

TEST_CASE("butterfly: finer levels derived from the coarse connectivity match a fresh build", "[subdiv]") {
  // Levels >= 1 derive their connectivity from the coarser level without
  // hashing; a level built from scratch on the same triangles (through
  // MeshTopology) must give the same stencils edge by edge.
  for (const TriMesh& m : {mirrored_irregular_grid(3, 4), icosphere(1), planar_fan(5)}) {
    std::vector<ButterflyLevel> derived;
    REQUIRE(build_butterfly_levels(m, 3, derived).ok());
    for (int l = 1; l < 3; ++l) {
      TriMesh level_mesh;
      level_mesh.positions.assign(derived[l].num_coarse_vertices, Vec3::Zero());
      level_mesh.triangles = derived[l].coarse_triangles;
      std::vector<ButterflyLevel> fresh;
      REQUIRE(build_butterfly_levels(level_mesh, 1, fresh).ok());
      const ButterflyLevel& a = derived[l];
      const ButterflyLevel& b = fresh[0];
      REQUIRE(a.num_fine_vertices == b.num_fine_vertices);
      std::map<std::array<int, 2>, std::map<int, double>> rows;
      for (int k = 0; k < b.num_new_vertices(); ++k)
        for (int i = b.stencil_offsets[k]; i < b.stencil_offsets[k + 1]; ++i)
          rows[b.edge_endpoints[k]][b.stencil_indices[i]] = b.stencil_weights[i];
      REQUIRE(static_cast<int>(rows.size()) == a.num_new_vertices());
      int mismatches = 0;
      for (int k = 0; k < a.num_new_vertices(); ++k) {
        const auto it = rows.find(a.edge_endpoints[k]);
        REQUIRE(it != rows.end());
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
      CHECK(mismatches == 0);
    }
  }
}

TEST_CASE("butterfly: real Cyberware scan (fran_cut) refines into a valid interpolating mesh", "[subdiv][shared]") {
  LK_REQUIRE_SHARED("head_scans/fran_cyberware/fran_cut.vtk");
  TriMesh fran;
  REQUIRE(load_mesh_file(shared_data_dir() + "/head_scans/fran_cyberware/fran_cut.vtk", fran).ok());
  std::vector<ButterflyLevel> levels;
  REQUIRE(build_butterfly_levels(fran, 2, levels).ok());
  std::vector<std::vector<Vec3>> P;
  REQUIRE(apply_all(levels, fran.positions, P).ok());
  for (int v = 0; v < fran.num_vertices(); ++v) CHECK(P[2][v] == fran.positions[v]);
  TriMesh fine;
  fine.positions = P[2];
  fine.triangles = levels[1].fine_triangles;
  MeshTopology t;
  REQUIRE(build_topology(fine, t).ok());
  for (const Vec3& p : P[2]) REQUIRE(p.allFinite());
  // A smooth interpolant of a smooth scan stays close to its triangles: new
  // vertices move off the edge midpoints by a small fraction of the edge length.
  const ButterflyLevel& L0 = levels[0];
  double worst = 0;
  for (int k = 0; k < L0.num_new_vertices(); ++k) {
    const auto [a, b] = L0.edge_endpoints[k];
    const double len = (fran.positions[a] - fran.positions[b]).norm();
    const Vec3 mid = 0.5 * (fran.positions[a] + fran.positions[b]);
    worst = std::max(worst, (P[1][L0.num_coarse_vertices + k] - mid).norm() / len);
  }
  INFO("largest offset from the edge midpoint: " << worst << " edge lengths");
  CHECK(worst < 0.5);
}
