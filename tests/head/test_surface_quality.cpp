// head/surface_quality.h: the roughness and crossing figures of issue 35 must
// see a fold where there is one, in the region where it is, and nowhere else.
#include "head/generic_head.h"
#include "head/surface_quality.h"
#include "mesh/geometry.h"
#include "test_scan.h"

#include <catch2/catch.hpp>

#include <cmath>

using namespace lk;

namespace {

const RegionRoughness& region_named(const HeadSurfaceQuality& q, const std::string& name) {
  for (const RegionRoughness& r : q.regions)
    if (r.region == name) return r;
  FAIL("no region " << name);
  return q.regions.front();
}

}  // namespace

TEST_CASE("dihedral angles: 0 on a flat sheet, the hinge angle across a fold", "[head]") {
  // A 4 x 4 grid of unit squares in z = 0, each split in two; then the half
  // x > 2 turned about the line x = 2 by 30 degrees.
  TriMesh m;
  const int n = 4;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) m.positions.push_back(Vec3(i, j, 0));
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i, b = a + 1, c = a + n + 2, d = a + n + 1;
      m.triangles.push_back({a, b, c});
      m.triangles.push_back({a, c, d});
    }
  const std::vector<char> all(m.num_triangles(), 1);
  std::vector<double> flat = dihedral_angles(m, all);
  // Interior edges: 3 x 4 vertical + 4 x 3 horizontal + 16 diagonals.
  REQUIRE(flat.size() == 40u);
  CHECK(flat.back() < 1e-6);
  const double turn = 30 * M_PI / 180;
  for (Vec3& p : m.positions)
    if (p.x() > 2) p = Vec3(2 + (p.x() - 2) * std::cos(turn), p.y(), (p.x() - 2) * std::sin(turn));
  const std::vector<double> folded = dihedral_angles(m, all);
  REQUIRE(folded.size() == 40u);
  int at_hinge = 0;
  for (double a : folded) {
    if (a > 1e-6) {
      CHECK(a == Approx(30).margin(1e-9));
      ++at_hinge;
    }
  }
  CHECK(at_hinge == 4);  // the four edges on x = 2
  // Faces left out are not measured: only the folded half, which is flat.
  std::vector<char> right(m.num_triangles(), 0);
  for (int f = 0; f < m.num_triangles(); ++f) right[f] = (f / 2) % n >= 2;
  const std::vector<double> half = dihedral_angles(m, right);
  CHECK(half.size() == 18u);  // 8 diagonals, 4 on x = 3, 2 x 3 across the rows
  CHECK(half.back() < 1e-6);
}

TEST_CASE("head surface quality sees a lump on the cheek there and not elsewhere", "[head]") {
  const GenericHead& head = test::generic_head();
  HeadSurfaceQuality before;
  REQUIRE(measure_head_surface(head, 3, before).ok());
  REQUIRE(before.crossing_pairs.size() == 4u);
  CHECK(before.crossing_pairs[0] == 0);  // the control mesh is clean (test_generic_head)
  REQUIRE(before.regions.size() == 6u);
  for (const RegionRoughness& r : before.regions) {
    INFO(r.region);
    CHECK(r.edges > 300);
    CHECK(r.mean_deg > 0);
    CHECK(r.max_deg >= r.p99_deg);
    CHECK(r.p99_deg >= r.p95_deg);
    CHECK(r.p95_deg >= r.mean_deg);
  }
  // Push the cheek vertex nearest the cheek region's centroid 4 mm out
  // along its normal: a lump a person would see.
  GenericHead lumpy = head;
  const std::vector<int>& cheeks = head.annotations.regions.at("cheeks");
  Vec3 c = Vec3::Zero();
  for (int v : cheeks) c += head.mesh.positions[v];
  c /= double(cheeks.size());
  int at = cheeks.front();
  for (int v : cheeks)
    if ((head.mesh.positions[v] - c).norm() < (head.mesh.positions[at] - c).norm()) at = v;
  const std::vector<Vec3> normals = vertex_normals(head.mesh);
  lumpy.mesh.positions[at] += 0.004 * normals[at];
  HeadSurfaceQuality after;
  REQUIRE(measure_head_surface(lumpy, 3, after).ok());
  const RegionRoughness &b = region_named(before, "cheeks"), &a = region_named(after, "cheeks");
  INFO("cheeks max " << b.max_deg << " -> " << a.max_deg << " deg, p99 " << b.p99_deg << " -> " << a.p99_deg);
  CHECK(a.max_deg > b.max_deg + 5);
  CHECK(a.p99_deg > b.p99_deg);
  // The ears, far from it, measure exactly as before.
  CHECK(region_named(after, "ears").max_deg == region_named(before, "ears").max_deg);
  CHECK(region_named(after, "ears").mean_deg == region_named(before, "ears").mean_deg);
}

TEST_CASE("head surface quality rejects a bad level or missing regions with a message", "[head]") {
  const GenericHead& head = test::generic_head();
  HeadSurfaceQuality q;
  Status s = measure_head_surface(head, 0, q);
  CHECK(s.code == ErrorCode::InvalidInput);
  GenericHead no_cheeks = head;
  no_cheeks.annotations.regions.erase("cheeks");
  s = measure_head_surface(no_cheeks, 2, q);
  CHECK(s.code == ErrorCode::InvalidInput);
  CHECK(s.message.find("cheeks") != std::string::npos);
}
