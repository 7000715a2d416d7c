// Two parallel sheets with a step in one of them, for the global fit's
// smooth-surface guard and fold relief tests: the control sheets do not
// cross, but one sheet's Butterfly surface dips through the other at the
// foot of its step (the stencils' -1/16 wings undershoot where the control
// sheet bends sharply).
#pragma once
#include "fit/global_fit.h"
#include "mesh/primitives.h"
#include "mesh/topology.h"
#include "mesh/tri_mesh.h"
#include "raycast/self_intersection.h"
#include "subdiv/butterfly.h"

#include <catch2/catch.hpp>

#include <array>
#include <random>
#include <vector>

namespace lk::test {

// Two 20 x 20 sheets over the unit square: A at z = 0 and B above it. B
// starts stepped, at z = high for x < 0.5 and at low_z (just above A) from
// x = 0.5 on, and its data follow that shape; A's data lie on A. The
// reference (GlobalFitTerms::fold_reference, what the fits take as the
// template) is the two sheets flat, B at `high`: their surfaces do not
// cross, so every crossing of the fitted sheets' surface is new.
// (Until 22 Nov the sheets started flat and B's low data, closer to A,
// never pulled B down: the crossings the tests counted there were rounding
// noise of flat sheets, see raycast/self_intersection.h.)
struct StepSheets {
  TriMesh start;
  std::vector<Vec3> flat;  // the reference positions
  MeshTopology topo;
  std::vector<Vec3> points, b_points;  // all data; B's data alone
  int b_first_vertex = 0;

  TriMesh flat_mesh() const {
    TriMesh m = start;
    m.positions = flat;
    return m;
  }
  GlobalFitTerms terms() const {
    GlobalFitTerms t;
    t.fold_reference = flat;
    return t;
  }
};

inline StepSheets make_step_sheets(double low_z = 0.005, double high = 0.2) {
  StepSheets c;
  const int n = 20;
  const TriMesh grid = make_regular_grid(n, n);
  for (const Vec3& p : grid.positions) c.start.positions.push_back(Vec3(p.x() / n, p.y() / n, 0));
  for (const Tri& t : grid.triangles) c.start.triangles.push_back(t);
  c.b_first_vertex = grid.num_vertices();
  for (const Vec3& p : grid.positions) c.start.positions.push_back(Vec3(p.x() / n, p.y() / n, p.x() < n / 2 ? high : low_z));
  for (const Tri& t : grid.triangles)
    c.start.triangles.push_back({{t[0] + c.b_first_vertex, t[1] + c.b_first_vertex, t[2] + c.b_first_vertex}});
  c.flat = c.start.positions;
  for (int v = c.b_first_vertex; v < c.start.num_vertices(); ++v) c.flat[v].z() = high;
  REQUIRE(build_topology(c.start, c.topo).ok());
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(0, 1);
  for (int i = 0; i < 8000; ++i) c.points.push_back(Vec3(U(rng), U(rng), 0));
  for (int i = 0; i < 8000; ++i) {
    const double x = U(rng);
    c.b_points.push_back(Vec3(x, U(rng), x < 0.5 ? high : low_z));
  }
  c.points.insert(c.points.end(), c.b_points.begin(), c.b_points.end());
  return c;
}

// m refined `levels` times by plain Butterfly (no creases), as a mesh;
// level triangle f lies in control face f >> (2 levels).
inline TriMesh butterfly_level(const TriMesh& m, int levels) {
  std::vector<ButterflyLevel> lv;
  REQUIRE(build_butterfly_levels(m, levels, lv).ok());
  std::vector<std::vector<Vec3>> refined;
  REQUIRE(apply_all(lv, m.positions, refined).ok());
  TriMesh fine;
  fine.positions = refined.back();
  fine.triangles = lv.back().fine_triangles;
  return fine;
}

// The crossing pairs of butterfly_level(m, levels), sorted.
inline std::vector<std::array<int, 2>> smooth_level_pairs(const TriMesh& m, int levels) {
  const TriMesh fine = butterfly_level(m, levels);
  std::vector<std::array<int, 2>> pairs;
  REQUIRE(find_self_intersections(fine, pairs).ok());
  return pairs;
}

}  // namespace lk::test
