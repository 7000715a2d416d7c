// Samples on a mesh scan's own triangles (core/multires/surface_samples.h):
// where they lie, how many, which triangles are left out. What they do for
// a fit: tests/pipeline/test_mesh_scan.cpp.
#include "multires/surface_samples.h"

#include "../subdiv/shapes.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <set>
#include <tuple>

using namespace lk;
using namespace lk::test;

namespace {

std::vector<char> all(int n) { return std::vector<char>(n, 1); }

// The unit square [0,1]^2 in z = 0 as two triangles.
TriMesh unit_square() {
  TriMesh m;
  m.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(0, 1, 0)};
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  return m;
}

PointCloud samples_of(const TriMesh& m, double spacing, SurfaceSampleStats& stats, double max_edge_ratio = 4.0) {
  PointCloud out;
  REQUIRE(sample_scan_surface(m.positions, {}, m.triangles, all(m.num_vertices()), spacing, max_edge_ratio, 1000000,
                              out, stats)
              .ok());
  return out;
}

}  // namespace

TEST_CASE("surface samples: a flat square is covered evenly, on the plane, without duplicates",
          "[multires][surface_samples]") {
  SurfaceSampleStats stats;
  // Longest edge sqrt(2): n = ceil(1.414 / 0.1) = 15 cuts, 225 per triangle.
  const PointCloud s = samples_of(unit_square(), 0.1, stats);
  REQUIRE(stats.triangles_sampled == 2);
  REQUIRE(stats.samples == 2 * 15 * 15);
  REQUIRE(s.size() == stats.samples);
  CHECK(s.normals.empty());  // the scan had none
  std::set<std::tuple<long, long>> seen;
  int cells[4][4] = {};
  for (const Vec3& p : s.positions) {
    // A plane's Phong tessellation is the plane itself.
    CHECK(std::abs(p.z()) < 1e-15);
    CHECK(p.x() > 0);
    CHECK(p.x() < 1);
    CHECK(p.y() > 0);
    CHECK(p.y() < 1);
    // None on the shared diagonal (each triangle keeps to its side), none twice.
    CHECK(std::abs(p.x() - p.y()) > 1e-9);
    CHECK(seen.insert({std::lround(p.x() * 1e9), std::lround(p.y() * 1e9)}).second);
    ++cells[std::min(3, int(p.x() * 4))][std::min(3, int(p.y() * 4))];
  }
  // Uniform density: each quarter-by-quarter cell holds 1/16 of the samples
  // (28.1), give or take the cell boundaries' rounding.
  for (auto& row : cells)
    for (int c : row) {
      CHECK(c >= 22);
      CHECK(c <= 34);
    }
}

TEST_CASE("surface samples: a coarse sphere's samples lie on the sphere, not on its facets, whatever the winding",
          "[multires][surface_samples]") {
  const TriMesh sphere = icosphere(2);  // 162 vertices on the unit sphere, edges ~0.3
  SurfaceSampleStats stats;
  const PointCloud s = samples_of(sphere, 0.05, stats);
  REQUIRE(stats.samples > 5000);
  // The facets' depth below the sphere: their centroids' mean.
  double facet_depth = 0;
  for (const Tri& t : sphere.triangles)
    facet_depth += 1.0 - ((sphere.positions[t[0]] + sphere.positions[t[1]] + sphere.positions[t[2]]) / 3).norm();
  facet_depth /= sphere.num_triangles();
  double off = 0;
  for (const Vec3& p : s.positions) off += std::abs(p.norm() - 1.0);
  off /= s.size();
  INFO("centroid depth of the facets " << facet_depth << ", mean |r - 1| of the samples " << off);
  // Flat samples would lie 0.45-0.5 of the centroid depth below on average
  // (a quadratic bubble); on the Phong tessellation with alpha 1/2 the
  // second-order error cancels (alpha 3/4 left 0.35 of it, above).
  CHECK(off < 0.1 * facet_depth);

  // The same sphere with every other triangle wound the other way: the
  // tangent planes do not depend on the normals' signs, and a triangle's
  // sub-triangle centroids do not depend on its corners' order.
  TriMesh mixed = sphere;
  for (size_t f = 0; f < mixed.triangles.size(); f += 2) std::swap(mixed.triangles[f][1], mixed.triangles[f][2]);
  SurfaceSampleStats mixed_stats;
  const PointCloud m = samples_of(mixed, 0.05, mixed_stats);
  REQUIRE(m.size() == s.size());
  std::vector<double> ra, rb;
  for (int i = 0; i < s.size(); ++i) ra.push_back(s.positions[i].norm()), rb.push_back(m.positions[i].norm());
  std::sort(ra.begin(), ra.end());
  std::sort(rb.begin(), rb.end());
  double largest = 0;
  for (size_t i = 0; i < ra.size(); ++i) largest = std::max(largest, std::abs(ra[i] - rb[i]));
  CHECK(largest < 1e-12);
}

TEST_CASE("surface samples: left-out corners, hole-bridging triangles and dense triangles get none",
          "[multires][surface_samples]") {
  // A strip of 10 unit squares along x, plus one long sliver joining its
  // ends (a triangle across a hole).
  TriMesh strip;
  for (int i = 0; i <= 10; ++i) {
    strip.positions.push_back(Vec3(i, 0, 0));
    strip.positions.push_back(Vec3(i, 1, 0));
  }
  for (int i = 0; i < 10; ++i) {
    strip.triangles.push_back({2 * i, 2 * i + 2, 2 * i + 3});
    strip.triangles.push_back({2 * i, 2 * i + 3, 2 * i + 1});
  }
  strip.triangles.push_back({0, 20, 21});
  SurfaceSampleStats stats;
  PointCloud out;
  std::vector<char> keep = all(strip.num_vertices());
  keep[1] = 0;  // the first square's top-left corner is not measured (a pocket)
  REQUIRE(sample_scan_surface(strip.positions, {}, strip.triangles, keep, 0.5, 4.0, 100000, out, stats).ok());
  CHECK(stats.triangles_skipped_long == 1);  // the sliver: 10 against a median edge of 1
  CHECK(stats.triangles_sampled == 19);      // the first square lost one of its two triangles
  for (const Vec3& p : out.positions) CHECK_FALSE((p.x() < 1 && p.x() < p.y()));
  // A spacing above the longest edge: the corners are dense enough.
  SurfaceSampleStats dense;
  PointCloud none;
  REQUIRE(sample_scan_surface(strip.positions, {}, strip.triangles, all(strip.num_vertices()), 2.0, 4.0, 100000, none,
                              dense)
              .ok());
  CHECK(none.size() == 0);
  CHECK(dense.triangles_dense == 20);
}

TEST_CASE("surface samples: normals are interpolated when the scan has them", "[multires][surface_samples]") {
  const TriMesh sq = unit_square();
  const std::vector<Vec3> normals(4, Vec3(0, 0, 1));
  PointCloud out;
  out.positions = {Vec3(5, 5, 5)};
  out.normals = {Vec3(1, 0, 0)};
  SurfaceSampleStats stats;
  REQUIRE(sample_scan_surface(sq.positions, normals, sq.triangles, all(4), 0.5, 4.0, 1000, out, stats).ok());
  REQUIRE(out.normals.size() == out.positions.size());
  CHECK(out.positions.size() == 1 + 2 * 9);
  for (int i = 1; i < out.size(); ++i) CHECK(out.normals[i].isApprox(Vec3(0, 0, 1)));
}

TEST_CASE("surface samples: bad input is refused and a limit is kept", "[multires][surface_samples]") {
  const TriMesh sq = unit_square();
  PointCloud out;
  SurfaceSampleStats stats;
  CHECK(sample_scan_surface(sq.positions, {}, {{0, 1, 7}}, all(4), 0.1, 4.0, 1000, out, stats).code ==
        ErrorCode::InvalidInput);
  CHECK(sample_scan_surface(sq.positions, {}, sq.triangles, all(4), 0.0, 4.0, 1000, out, stats).code ==
        ErrorCode::InvalidInput);
  CHECK(sample_scan_surface(sq.positions, {}, sq.triangles, all(4), std::nan(""), 4.0, 1000, out, stats).code ==
        ErrorCode::InvalidInput);
  CHECK(sample_scan_surface(sq.positions, {}, sq.triangles, all(3), 0.1, 4.0, 1000, out, stats).code ==
        ErrorCode::InvalidInput);
  // 450 samples against a limit of 100: nothing appended.
  CHECK(sample_scan_surface(sq.positions, {}, sq.triangles, all(4), 0.1, 4.0, 100, out, stats).code ==
        ErrorCode::TooLarge);
  CHECK(out.size() == 0);
}
