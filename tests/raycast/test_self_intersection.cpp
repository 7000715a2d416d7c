// Self-intersection finder: exact small cases, clean closed surfaces (no
// pairs), surfaces pushed through themselves (the crossing pairs found), and
// the BVH traversal against testing every pair.
#include "raycast/self_intersection.h"

#include "mesh/primitives.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <set>

using namespace lk;

namespace {

// Icosahedron refined `levels` times by edge midpoints, projected on the unit sphere.
TriMesh icosphere(int levels) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  TriMesh m;
  m.positions = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                 {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  m.triangles = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                 {11, 10, 2}, {10, 7, 6}, {7, 1, 8},   {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                 {3, 8, 9},  {4, 9, 5},  {2, 4, 11},  {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (Vec3& p : m.positions) p.normalize();
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      m.positions.push_back((m.positions[a] + m.positions[b]).normalized());
      const int id = static_cast<int>(m.positions.size()) - 1;
      mid[key] = id;
      return id;
    };
    std::vector<Tri> fine;
    for (const Tri& f : m.triangles) {
      const int ab = midpoint(f[0], f[1]), bc = midpoint(f[1], f[2]), ca = midpoint(f[2], f[0]);
      fine.push_back({f[0], ab, ca});
      fine.push_back({f[1], bc, ab});
      fine.push_back({f[2], ca, bc});
      fine.push_back({ab, bc, ca});
    }
    m.triangles = fine;
  }
  return m;
}

// A torus (major radius R, minor r), nu x nv quads split in two.
TriMesh torus(int nu, int nv, double R, double r) {
  TriMesh m;
  const double pi = 3.14159265358979323846;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const double u = 2 * pi * i / nu, v = 2 * pi * j / nv;
      m.positions.push_back(Vec3((R + r * std::cos(v)) * std::cos(u), (R + r * std::cos(v)) * std::sin(u), r * std::sin(v)));
    }
  auto id = [&](int i, int j) { return ((i + nu) % nu) * nv + (j + nv) % nv; };
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return m;
}

TriMesh merged(const TriMesh& a, const TriMesh& b, const Vec3& shift) {
  TriMesh m = a;
  const int off = static_cast<int>(a.positions.size());
  for (const Vec3& p : b.positions) m.positions.push_back(p + shift);
  for (const Tri& t : b.triangles) m.triangles.push_back({t[0] + off, t[1] + off, t[2] + off});
  return m;
}

// The rule of the header, pair by pair: the reference for the BVH traversal.
std::vector<std::array<int, 2>> brute_force(const TriMesh& m) {
  std::vector<std::array<int, 2>> out;
  const auto& P = m.positions;
  for (int a = 0; a < m.num_triangles(); ++a)
    for (int b = a + 1; b < m.num_triangles(); ++b) {
      const Tri& ta = m.triangles[a];
      const Tri& tb = m.triangles[b];
      int shared = 0, ia = 0, ib = 0;
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          if (ta[i] == tb[j]) ++shared, ia = i, ib = j;
      bool hit = false;
      if (shared == 0)
        hit = triangles_intersect(P[ta[0]], P[ta[1]], P[ta[2]], P[tb[0]], P[tb[1]], P[tb[2]]);
      else if (shared == 1)
        hit = segment_intersects_triangle(P[ta[(ia + 1) % 3]], P[ta[(ia + 2) % 3]], P[tb[0]], P[tb[1]], P[tb[2]]) ||
              segment_intersects_triangle(P[tb[(ib + 1) % 3]], P[tb[(ib + 2) % 3]], P[ta[0]], P[ta[1]], P[ta[2]]);
      if (hit) out.push_back({a, b});
    }
  return out;
}

}  // namespace

TEST_CASE("triangle pairs: crossing, apart, touching, coplanar", "[raycast]") {
  const Vec3 a0(0, 0, 0), a1(1, 0, 0), a2(0, 1, 0);
  // Pierces the first through its interior.
  CHECK(triangles_intersect(a0, a1, a2, Vec3(0.2, 0.2, -1), Vec3(0.3, 0.2, 1), Vec3(0.2, 0.4, 1)));
  // Same shape lifted above the plane: apart.
  CHECK_FALSE(triangles_intersect(a0, a1, a2, Vec3(0.2, 0.2, 0.1), Vec3(0.3, 0.2, 1), Vec3(0.2, 0.4, 1)));
  // Crosses the plane but outside the triangle (beyond the hypotenuse).
  CHECK_FALSE(triangles_intersect(a0, a1, a2, Vec3(0.8, 0.8, -1), Vec3(0.9, 0.8, 1), Vec3(0.8, 0.9, 1)));
  // A corner touching the interior counts.
  CHECK(triangles_intersect(a0, a1, a2, Vec3(0.2, 0.2, 0), Vec3(0.3, 0.2, 1), Vec3(0.2, 0.4, 1)));
  // Coplanar: overlapping, one inside the other, and side by side.
  CHECK(triangles_intersect(a0, a1, a2, Vec3(0.5, 0.1, 0), Vec3(1.5, 0.1, 0), Vec3(0.5, 1, 0)));
  CHECK(triangles_intersect(a0, a1, a2, Vec3(0.1, 0.1, 0), Vec3(0.3, 0.1, 0), Vec3(0.1, 0.3, 0)));
  CHECK_FALSE(triangles_intersect(a0, a1, a2, Vec3(2, 0, 0), Vec3(3, 0, 0), Vec3(2, 1, 0)));
  // Segment against triangle.
  CHECK(segment_intersects_triangle(Vec3(0.25, 0.25, -1), Vec3(0.25, 0.25, 1), a0, a1, a2));
  CHECK_FALSE(segment_intersects_triangle(Vec3(0.25, 0.25, 0.01), Vec3(0.25, 0.25, 1), a0, a1, a2));
  CHECK_FALSE(segment_intersects_triangle(Vec3(0.75, 0.75, -1), Vec3(0.75, 0.75, 1), a0, a1, a2));
}

TEST_CASE("self-intersections: a known crossing pair is found, neighbours are not reported", "[raycast]") {
  TriMesh m;
  // Triangles 0 and 1 share an edge (a fan), triangle 2 pierces triangle 0,
  // triangle 3 shares vertex 0 with triangle 0 and folds back through it.
  m.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(1, 1, 0.2),                  // 0..3
                 Vec3(0.7, 0.1, -1), Vec3(0.8, 0.1, 1), Vec3(0.7, 0.2, 1),                      // 4..6
                 Vec3(0.6, 0.1, -0.5), Vec3(0.1, 0.6, 0.5)};                                    // 7, 8
  m.triangles = {{0, 1, 2}, {1, 3, 2}, {4, 5, 6}, {0, 7, 8}};
  std::vector<std::array<int, 2>> pairs;
  REQUIRE(find_self_intersections(m, pairs).ok());
  const std::vector<std::array<int, 2>> expected = {{0, 2}, {0, 3}};
  CHECK(pairs == expected);
  CHECK(pairs == brute_force(m));
  // max_pairs stops early.
  SelfIntersectionOptions one;
  one.max_pairs = 1;
  REQUIRE(find_self_intersections(m, pairs, one).ok());
  CHECK(pairs.size() == 1);
}

TEST_CASE("self-intersections: none on an icosphere and a torus", "[raycast]") {
  std::vector<std::array<int, 2>> pairs;
  const TriMesh sphere = icosphere(4);  // 5120 triangles
  REQUIRE(find_self_intersections(sphere, pairs).ok());
  CHECK(pairs.empty());
  const TriMesh ring = torus(96, 32, 1.0, 0.3);
  REQUIRE(find_self_intersections(ring, pairs).ok());
  CHECK(pairs.empty());
  // A thin torus: sheets close together but apart (like the lips).
  const TriMesh thin = torus(128, 12, 1.0, 0.002);
  REQUIRE(find_self_intersections(thin, pairs).ok());
  CHECK(pairs.empty());
}

TEST_CASE("self-intersections: surfaces pushed through each other", "[raycast]") {
  // Two spheres overlapping: every pair joins one triangle of each, along
  // the circle where they cross, and the BVH finds exactly the brute-force set.
  const TriMesh a = icosphere(2);
  const int na = a.num_triangles();
  const TriMesh two = merged(a, a, Vec3(1.2, 0.1, 0.05));
  std::vector<std::array<int, 2>> pairs;
  REQUIRE(find_self_intersections(two, pairs).ok());
  CHECK(pairs.size() > 20);
  for (const auto& p : pairs) CHECK((p[0] < na && p[1] >= na));
  CHECK(pairs == brute_force(two));
  // Moved apart: none.
  REQUIRE(find_self_intersections(merged(a, a, Vec3(2.1, 0, 0)), pairs).ok());
  CHECK(pairs.empty());

  // One vertex of a torus pulled through the opposite side of its tube.
  TriMesh ring = torus(48, 16, 1.0, 0.3);
  ring.positions[0] = Vec3(1.0 - 0.5, 0.0, 0.01);  // was (1.3, 0, 0), now past the inner wall at 0.7
  REQUIRE(find_self_intersections(ring, pairs).ok());
  CHECK(!pairs.empty());
  CHECK(pairs == brute_force(ring));
  std::set<int> involved;
  for (const auto& p : pairs) involved.insert(p[0]), involved.insert(p[1]);
  bool touches_moved = false;
  for (int f : involved)
    for (int v : ring.triangles[f]) touches_moved |= v == 0;
  CHECK(touches_moved);
}

TEST_CASE("self-intersections: bad input is refused, empty input gives nothing", "[raycast]") {
  std::vector<std::array<int, 2>> pairs = {{1, 2}};
  TriMesh bad;
  bad.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0)};
  bad.triangles = {{0, 1, 2}};
  CHECK(find_self_intersections(bad, pairs).code == ErrorCode::InvalidInput);
  CHECK(pairs.empty());
  bad.positions.push_back(Vec3(0, std::nan(""), 0));
  CHECK(find_self_intersections(bad, pairs).code == ErrorCode::InvalidInput);
  REQUIRE(find_self_intersections(TriMesh{}, pairs).ok());
  CHECK(pairs.empty());
}

TEST_CASE("self-intersections: the threaded search finds the serial search's set", "[raycast]") {
  // Large enough to be split over threads (>= 4096 triangles): two
  // overlapping spheres and a torus with dents pushed through its tube.
  const TriMesh sphere = icosphere(4);  // 5120 triangles
  TriMesh big = merged(sphere, sphere, Vec3(1.1, 0.2, 0.05));
  TriMesh ring = torus(96, 32, 1.0, 0.3);
  for (int k = 0; k < 12; ++k) ring.positions[k * 97 % ring.positions.size()] *= 0.5;
  big = merged(big, ring, Vec3(0, 0, 3));
  REQUIRE(big.num_triangles() > 4096);
  std::vector<std::array<int, 2>> threaded, serial;
  REQUIRE(find_self_intersections(big, threaded).ok());
  SelfIntersectionOptions capped;  // a cap keeps the search on one thread
  capped.max_pairs = 1 << 30;
  REQUIRE(find_self_intersections(big, serial, capped).ok());
  CHECK(threaded.size() > 100);
  CHECK(threaded == serial);
  // Both torus dents and sphere crossings are in it.
  const int ns = 2 * sphere.num_triangles();
  int in_spheres = 0, in_ring = 0;
  for (const auto& p : threaded) (p[0] < ns ? in_spheres : in_ring) += 1;
  CHECK(in_spheres > 0);
  CHECK(in_ring > 0);
}


TEST_CASE("self-intersections: re-checks around many triangles find the pairs touching them", "[raycast]") {
  // Hundreds of listed triangles: several runs of find_intersections_with's
  // threaded search; the result is the full search's pairs touching them.
  const TriMesh sphere = icosphere(3);  // 1280 triangles
  const TriMesh two = merged(sphere, sphere, Vec3(1.2, 0.1, 0.05));
  MeshBvh bvh;
  REQUIRE(build_bvh(two, bvh).ok());
  std::vector<std::array<int, 2>> all, around, expected;
  find_self_intersections(bvh, all);
  REQUIRE(all == brute_force(two));
  std::vector<int> listed;
  for (int f = 0; f < two.num_triangles(); f += 3) listed.push_back(f);
  listed.push_back(-1);  // out of range: ignored
  REQUIRE(listed.size() > 3 * 128);
  find_intersections_with(bvh, listed, around);
  for (const auto& p : all)
    if (p[0] % 3 == 0 || p[1] % 3 == 0) expected.push_back(p);
  CHECK(expected.size() > 10);
  CHECK(around == expected);
}

TEST_CASE("self-intersections: re-checks where both triangles of a pair are listed find every such pair", "[raycast]") {
  // find_intersections_with tests a pair of two listed triangles once, from
  // its larger id: listing every triangle, a region of both surfaces, or
  // the same in reverse with repeats gives the full search's pairs that
  // touch the list, with both triangles listed in many of them.
  const TriMesh sphere = icosphere(3);  // 1280 triangles
  const TriMesh two = merged(sphere, sphere, Vec3(1.2, 0.1, 0.05));
  MeshBvh bvh;
  REQUIRE(build_bvh(two, bvh).ok());
  std::vector<std::array<int, 2>> all, around;
  find_self_intersections(bvh, all);
  REQUIRE(all == brute_force(two));
  REQUIRE(all.size() > 20);
  std::vector<int> every(two.num_triangles());
  for (int f = 0; f < two.num_triangles(); ++f) every[f] = f;
  find_intersections_with(bvh, every, around);
  CHECK(around == all);

  // The triangles near the crossing: all of the first sphere's, every
  // other one of the second's.
  const int na = sphere.num_triangles();
  std::vector<int> region;
  std::vector<char> in_region(two.num_triangles(), 0);
  for (int f = 0; f < two.num_triangles(); ++f) {
    Vec3 c = Vec3::Zero();
    for (int v : two.triangles[f]) c += two.positions[v] / 3.0;
    if (c.x() > 0.45 && c.x() < 0.9 && (f < na || f % 2 == 0)) region.push_back(f), in_region[f] = 1;
  }
  std::vector<std::array<int, 2>> expected;
  int both = 0;
  for (const auto& p : all)
    if (in_region[p[0]] || in_region[p[1]]) {
      expected.push_back(p);
      both += in_region[p[0]] && in_region[p[1]];
    }
  CHECK(both > 10);
  CHECK(static_cast<int>(expected.size()) > both);  // and some with one listed triangle
  find_intersections_with(bvh, region, around);
  CHECK(around == expected);
  std::vector<int> reversed(region.rbegin(), region.rend());
  reversed.insert(reversed.end(), region.begin(), region.begin() + region.size() / 2);
  find_intersections_with(bvh, reversed, around);
  CHECK(around == expected);
}

namespace {

// The six-segment rule as first written (each segment test computing its
// own plane sides): the reference for triangles_intersect, which reuses its
// rejection tests' orientations and skips sides that already decide.
// The plain rule: a segment against a triangle (the shortcuts of
// triangles_intersect are under test, not the segment test).
bool reference_segment(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c) {
  return segment_intersects_triangle(p, q, a, b, c);
}
bool reference_triangles(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& b0, const Vec3& b1,
                         const Vec3& b2) {
  return reference_segment(a0, a1, b0, b1, b2) || reference_segment(a1, a2, b0, b1, b2) ||
         reference_segment(a2, a0, b0, b1, b2) || reference_segment(b0, b1, a0, a1, a2) ||
         reference_segment(b1, b2, a0, a1, a2) || reference_segment(b2, b0, a0, a1, a2);
}

}  // namespace

TEST_CASE("triangle pairs: the shortcut tests decide as the plain six-segment rule", "[raycast]") {
  // Random pairs on a coarse integer lattice (many touching, coplanar and
  // degenerate configurations, exact orientations) and continuous ones.
  std::uint64_t state = 12345;
  auto next = [&]() {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<int>((state >> 33) % 1000);
  };
  int crossing = 0, apart = 0;
  for (int k = 0; k < 40000; ++k) {
    const bool lattice = k % 2 == 0;
    auto point = [&]() {
      if (lattice) return Vec3(next() % 4, next() % 4, next() % 4);
      return Vec3(next() / 500.0, next() / 500.0, next() / 500.0);
    };
    const Vec3 a0 = point(), a1 = point(), a2 = point(), b0 = point(), b1 = point(), b2 = point();
    const bool want = reference_triangles(a0, a1, a2, b0, b1, b2);
    REQUIRE(triangles_intersect(a0, a1, a2, b0, b1, b2) == want);
    (want ? crossing : apart) += 1;
  }
  CHECK(crossing > 1000);  // both outcomes are exercised
  CHECK(apart > 1000);
}

TEST_CASE("triangle pairs: a mesh pair gets the same answer either way round", "[raycast]") {
  // find_intersections_with tests a pair of two listed triangles from one
  // side only, so mesh_triangles_cross(a, b) must equal (b, a): random
  // triangles over 7 lattice points and 7 random points (many shared
  // corners and edges, touching, coplanar) and their corner orders.
  std::uint64_t state = 777;
  auto next = [&]() {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<int>((state >> 33) % 1000);
  };
  std::vector<Vec3> positions;
  for (int i = 0; i < 7; ++i) positions.emplace_back(next() % 3, next() % 3, next() % 3);
  for (int i = 0; i < 7; ++i) positions.emplace_back(next() / 500.0, next() / 500.0, next() / 500.0);
  int crossing = 0, apart = 0, shared_one = 0, shared_one_crossing = 0;
  for (int k = 0; k < 60000; ++k) {
    const int base = k % 2 == 0 ? 0 : 7;  // lattice or random corners
    auto corner = [&]() { return base + next() % 7; };
    const Tri a{corner(), corner(), corner()}, b{corner(), corner(), corner()};
    if (a[0] == a[1] || a[1] == a[2] || a[0] == a[2] || b[0] == b[1] || b[1] == b[2] || b[0] == b[2]) continue;
    const bool ab = mesh_triangles_cross(positions, a, b);
    INFO("k " << k);
    REQUIRE(mesh_triangles_cross(positions, b, a) == ab);
    REQUIRE(mesh_triangles_cross(positions, Tri{b[1], b[2], b[0]}, Tri{a[2], a[1], a[0]}) == ab);
    (ab ? crossing : apart) += 1;
    int shared = 0;
    for (int i : a)
      for (int j : b) shared += i == j;
    if (shared == 1) shared_one += 1, shared_one_crossing += ab;
  }
  CHECK(crossing > 1000);  // both outcomes, and crossings at one shared corner, are exercised
  CHECK(apart > 1000);
  CHECK(shared_one > 1000);
  CHECK(shared_one_crossing > 100);
}

TEST_CASE("new self-intersections: only the pairs a move made, not those the reference had", "[raycast]") {
  // A flat square (triangles 0, 1, split along y = x) at z = 0; triangle 2
  // hovers at z = 1 over triangle 0; triangle 3 stands upright through
  // triangle 1 (crossing it already at the reference). Moving one corner of
  // triangle 2 to z = -1 makes exactly one new pair, (0, 2).
  TriMesh m;
  m.positions = {{-2, -2, 0}, {2, -2, 0},   {2, 2, 0},    {-2, 2, 0},  {0.5, -1, 1},
                 {1.5, -1, 1}, {1, -0.2, 1}, {-1, 0.5, -1}, {-1, 1.5, -1}, {-1, 1, 1}};
  m.triangles = {{0, 1, 2}, {0, 2, 3}, {4, 5, 6}, {7, 8, 9}};
  const std::vector<Vec3> reference = m.positions;
  MeshBvh bvh;
  REQUIRE(build_bvh(m, bvh).ok());
  std::vector<std::array<int, 2>> pairs;
  find_self_intersections(bvh, pairs);
  CHECK(pairs == std::vector<std::array<int, 2>>{{1, 3}});
  REQUIRE(find_new_self_intersections(bvh, reference, pairs).ok());
  CHECK(pairs.empty());  // nothing moved yet

  m.positions[6] = Vec3(1, -0.2, -1);
  REQUIRE(refit_bvh(m, bvh).ok());
  find_self_intersections(bvh, pairs);
  CHECK(pairs == std::vector<std::array<int, 2>>({{0, 2}, {1, 3}}));
  REQUIRE(find_new_self_intersections(bvh, reference, pairs).ok());
  CHECK(pairs == std::vector<std::array<int, 2>>{{0, 2}});
  // Searched from listed triangles only.
  const std::vector<int> old_one = {3}, moved_one = {2}, both = {0, 3};
  REQUIRE(find_new_self_intersections(bvh, reference, pairs, &old_one).ok());
  CHECK(pairs.empty());
  REQUIRE(find_new_self_intersections(bvh, reference, pairs, &moved_one).ok());
  CHECK(pairs == std::vector<std::array<int, 2>>{{0, 2}});
  REQUIRE(find_new_self_intersections(bvh, reference, pairs, &both).ok());
  CHECK(pairs == std::vector<std::array<int, 2>>{{0, 2}});
  // Against its own positions nothing is new.
  REQUIRE(find_new_self_intersections(bvh, m.positions, pairs).ok());
  CHECK(pairs.empty());

  // A reference of the wrong size or with a NaN is refused.
  std::vector<Vec3> short_reference = reference;
  short_reference.pop_back();
  pairs = {{0, 1}};
  CHECK(find_new_self_intersections(bvh, short_reference, pairs).code == ErrorCode::InvalidInput);
  CHECK(pairs.empty());
  std::vector<Vec3> nan_reference = reference;
  nan_reference[3].y() = std::nan("");
  CHECK(find_new_self_intersections(bvh, nan_reference, pairs).code == ErrorCode::InvalidInput);
}

namespace {

// The searches from listed triangles (every stride-th from `first`) and
// the new-pair search against `start` give the same pairs on both trees.
void check_local_searches_agree(const MeshBvh& refit, const MeshBvh& fresh, const std::vector<Vec3>& start, int first,
                                int stride) {
  std::vector<int> listed;
  for (int f = first; f < fresh.num_triangles(); f += stride) listed.push_back(f);
  std::vector<std::array<int, 2>> a, b;
  find_intersections_with(refit, listed, a);
  find_intersections_with(fresh, listed, b);
  CHECK(a == b);
  REQUIRE(find_new_self_intersections(refit, start, a).ok());
  REQUIRE(find_new_self_intersections(fresh, start, b).ok());
  CHECK(a == b);
}

}  // namespace

TEST_CASE("self-intersections: a refit tree finds what a fresh tree finds", "[raycast]") {
  // A torus and a sphere beside it, built once, then moved at random
  // (shrunk, pushed through each other, vertices jittered) and refit: the
  // full and the local searches equal those on a tree built afresh.
  TriMesh m = merged(torus(48, 16, 1.0, 0.3), icosphere(2), Vec3(2.6, 0, 0));
  const std::vector<Vec3> start = m.positions;
  const int n_torus = 48 * 16;
  MeshBvh refit;
  REQUIRE(build_bvh(m, refit).ok());
  uint64_t state = 12345;
  auto uniform = [&]() {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<double>(state >> 11) / 9007199254740992.0;
  };
  size_t crossings_seen = 0;
  for (int trial = 0; trial < 6; ++trial) {
    const Vec3 shift(-0.3 * trial, 0.05 * trial, 0);  // the sphere slides into the torus
    const double jitter = 0.01 * trial;
    for (size_t v = 0; v < m.positions.size(); ++v) {
      m.positions[v] = start[v] + (static_cast<int>(v) >= n_torus ? shift : Vec3::Zero());
      m.positions[v] += jitter * Vec3(uniform() - 0.5, uniform() - 0.5, uniform() - 0.5);
    }
    REQUIRE(refit_bvh(m, refit).ok());
    MeshBvh fresh;
    REQUIRE(build_bvh(m, fresh).ok());
    std::vector<std::array<int, 2>> a, b;
    find_self_intersections(refit, a);
    find_self_intersections(fresh, b);
    CHECK(a == b);
    CHECK(a == brute_force(m));
    crossings_seen += a.size();
    check_local_searches_agree(refit, fresh, start, trial, 7);
  }
  CHECK(crossings_seen > 50);  // the moves did make crossings to compare
}

TEST_CASE("self-intersections: a refit tree finds what a fresh tree finds, threaded and on thin folds", "[raycast]") {
  // The threaded search (>= 4096 triangles) on a refit tree, with the kind
  // of deformation the fits make: a tree built on a smooth shape, then
  // refit after a fold was pushed into it (a narrow pleat of a sheet, as
  // the fold relief's level 3, and a dented torus). The full, local and
  // new-pairs searches equal those of a tree built afresh, serial and
  // threaded alike.
  TriMesh m = merged(torus(128, 40, 1.0, 0.3), icosphere(3), Vec3(2.6, 0, 0));
  REQUIRE(m.num_triangles() > 4096);
  const std::vector<Vec3> start = m.positions;
  const int n_torus = 128 * 40;
  MeshBvh refit;
  REQUIRE(build_bvh(m, refit).ok());
  BvhRefitIndex index;
  build_refit_index(refit, index);
  MeshBvh partial = refit;  // refit through refit_bvh_vertices
  uint64_t state = 777;
  auto uniform = [&]() {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<double>(state >> 11) / 9007199254740992.0;
  };
  size_t crossings_seen = 0;
  for (int trial = 1; trial <= 5; ++trial) {
    std::vector<int> moved;
    for (int v = 0; v < static_cast<int>(m.positions.size()); ++v) {
      Vec3 p = start[v];
      if (v < n_torus) {
        // A pleat: a band of the tube folded back on itself by a sharp
        // sideways kink whose depth grows with the trial.
        const double angle = std::atan2(p.y(), p.x());
        const double band = std::exp(-std::pow((angle - 0.5) / 0.04, 2));
        p += 0.08 * trial * band * Vec3(-std::sin(angle), std::cos(angle), 0) *
             std::sin(40.0 * p.z());
        p += 0.002 * trial * Vec3(uniform() - 0.5, uniform() - 0.5, uniform() - 0.5);
      } else {
        p += Vec3(-0.35 * trial, 0.03 * trial, 0);  // the sphere slides into the torus
      }
      if (p != m.positions[v]) moved.push_back(v);
      m.positions[v] = p;
    }
    REQUIRE(refit_bvh(m, refit).ok());
    REQUIRE(refit_bvh_vertices(partial, index, m.positions, moved).ok());
    MeshBvh fresh;
    REQUIRE(build_bvh(m, fresh).ok());
    std::vector<std::array<int, 2>> a, b, c, serial;
    find_self_intersections(refit, a);
    find_self_intersections(fresh, b);
    find_self_intersections(partial, c);
    SelfIntersectionOptions capped;  // a cap keeps the search on one thread
    capped.max_pairs = 1 << 30;
    find_self_intersections(refit, serial, capped);
    INFO("trial " << trial << ": refit " << a.size() << ", fresh " << b.size() << ", partial refit " << c.size()
                  << ", serial on the refit tree " << serial.size());
    CHECK(a == b);
    CHECK(c == b);
    CHECK(serial == b);
    crossings_seen += b.size();
    check_local_searches_agree(refit, fresh, start, trial, 5);
  }
  CHECK(crossings_seen > 200);  // the folds did make crossings to compare
}

TEST_CASE("self-intersections: a flat sheet with rounding noise does not cross itself", "[raycast]") {
  // A 40 x 40 grid at z = 0.2 whose heights carry noise of 1e-14 (what
  // subdividing a flat control mesh leaves): four nearly coplanar points
  // have the sign of their rounding noise, and unfiltered orientations
  // reported side-by-side triangles as crossing. Every pair is tested
  // (brute force), so no tree decides which noise is seen.
  const int n = 40;
  uint64_t state = 99;
  auto noise = [&]() {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return (static_cast<double>(state >> 11) / 9007199254740992.0 - 0.5) * 2e-14;
  };
  TriMesh sheet = make_regular_grid(n, n);
  for (Vec3& p : sheet.positions) p = Vec3(0.05 + 0.00625 * p.x() + noise(), 0.1 + 0.00625 * p.y() + noise(), 0.2 + noise());
  CHECK(brute_force(sheet).empty());
  std::vector<std::array<int, 2>> pairs;
  REQUIRE(find_self_intersections(sheet, pairs).ok());
  CHECK(pairs.empty());
  // A copy laid on a noise-free sheet (exactly coplanar, shifted by a third
  // of a cell): every copy triangle overlaps sheet triangles in the plane,
  // and coplanar overlap counts as crossing.
  TriMesh flat = sheet;
  for (Vec3& p : flat.positions) p.z() = 0.2;
  TriMesh both = merged(flat, flat, Vec3(0.00625 / 3, 0.00625 / 3, 0));
  REQUIRE(find_self_intersections(both, pairs).ok());
  const int nf = sheet.num_triangles();
  std::vector<char> copy_hit(nf, 0);
  for (const auto& p : pairs) {
    CHECK(p[0] < nf);  // every pair is sheet x copy
    CHECK(p[1] >= nf);
    if (p[1] >= nf) copy_hit[p[1] - nf] = 1;
  }
  CHECK(std::count(copy_hit.begin(), copy_hit.end(), 1) == nf);
  // Two triangles of a subdivided flat sheet (the fold relief's test level),
  // side by side and a cell apart (their boxes are apart), once reported
  // crossing.
  {
    const Vec3 a0(0.56249999999981692, 0.86249999999981231, 0.20000000000001703),
        a1(0.5687499999998199, 0.86249999999981419, 0.20000000000001961),
        a2(0.56874999999982156, 0.86874999999981528, 0.20000000000001922),
        b0(0.56249999999982059, 0.87499999999981459, 0.20000000000001636),
        b1(0.56874999999982323, 0.87499999999981637, 0.20000000000001883),
        b2(0.5687499999998249, 0.88124999999981746, 0.20000000000001844);
    CHECK_FALSE(triangles_intersect(a0, a1, a2, b0, b1, b2));
    CHECK_FALSE(triangles_intersect(b0, b1, b2, a0, a1, a2));
    CHECK_FALSE(segment_intersects_triangle(b0, b2, a0, a1, a2));
    CHECK_FALSE(segment_intersects_triangle(b0, b1, a0, a1, a2));
    CHECK_FALSE(segment_intersects_triangle(b1, b2, a0, a1, a2));
    CHECK_FALSE(segment_intersects_triangle(a0, a1, b0, b1, b2));
    CHECK_FALSE(segment_intersects_triangle(a1, a2, b0, b1, b2));
    CHECK_FALSE(segment_intersects_triangle(a2, a0, b0, b1, b2));
  }
  // Orientation: sure signs are kept, noise is 0.
  CHECK(orient3d(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0.3, 0.3, 1e-9)) > 0);
  CHECK(orient3d(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0.3, 0.3, -1e-9)) < 0);
  CHECK(orient3d(Vec3(0.1, 0.2, 0.3), Vec3(0.4, 0.5, 0.6), Vec3(0.7, 0.8, 0.9), Vec3(1.0, 1.1, 1.2)) == 0.0);
}

namespace {

// Exact integer geometry for lattice points: an independent reference for
// the segment-triangle test (no filter, no rounding).
using I3 = std::array<long long, 3>;
long long exact_orient3d(const I3& a, const I3& b, const I3& c, const I3& d) {
  const long long ux = b[0] - a[0], uy = b[1] - a[1], uz = b[2] - a[2];
  const long long vx = c[0] - a[0], vy = c[1] - a[1], vz = c[2] - a[2];
  const long long wx = d[0] - a[0], wy = d[1] - a[1], wz = d[2] - a[2];
  return wx * (uy * vz - uz * vy) + wy * (uz * vx - ux * vz) + wz * (ux * vy - uy * vx);
}
int sgn(long long v) { return (v > 0) - (v < 0); }
long long exact_orient2d(long long ax, long long ay, long long bx, long long by, long long cx, long long cy) {
  return (bx - ax) * (cy - ay) - (by - ay) * (cx - ax);
}
bool exact_on_segment_2d(long long px, long long py, long long ax, long long ay, long long bx, long long by) {
  return exact_orient2d(ax, ay, bx, by, px, py) == 0 && std::min(ax, bx) <= px && px <= std::max(ax, bx) &&
         std::min(ay, by) <= py && py <= std::max(ay, by);
}
bool exact_segments_2d(long long px, long long py, long long qx, long long qy, long long ax, long long ay, long long bx,
                       long long by) {
  const int d1 = sgn(exact_orient2d(ax, ay, bx, by, px, py)), d2 = sgn(exact_orient2d(ax, ay, bx, by, qx, qy));
  const int d3 = sgn(exact_orient2d(px, py, qx, qy, ax, ay)), d4 = sgn(exact_orient2d(px, py, qx, qy, bx, by));
  if (d1 * d2 < 0 && d3 * d4 < 0) return true;
  return exact_on_segment_2d(px, py, ax, ay, bx, by) || exact_on_segment_2d(qx, qy, ax, ay, bx, by) ||
         exact_on_segment_2d(ax, ay, px, py, qx, qy) || exact_on_segment_2d(bx, by, px, py, qx, qy);
}
bool exact_point_in_triangle_2d(long long px, long long py, const long long* t) {
  const int s1 = sgn(exact_orient2d(t[0], t[1], t[2], t[3], px, py));
  const int s2 = sgn(exact_orient2d(t[2], t[3], t[4], t[5], px, py));
  const int s3 = sgn(exact_orient2d(t[4], t[5], t[0], t[1], px, py));
  return (s1 >= 0 && s2 >= 0 && s3 >= 0) || (s1 <= 0 && s2 <= 0 && s3 <= 0);
}
// Does the closed segment pq meet the closed triangle abc (non-degenerate)?
bool exact_segment_triangle(const I3& p, const I3& q, const I3& a, const I3& b, const I3& c) {
  const long long dp = exact_orient3d(a, b, c, p), dq = exact_orient3d(a, b, c, q);
  if ((dp > 0 && dq > 0) || (dp < 0 && dq < 0)) return false;
  const long long nx = (b[1] - a[1]) * (c[2] - a[2]) - (b[2] - a[2]) * (c[1] - a[1]);
  const long long ny = (b[2] - a[2]) * (c[0] - a[0]) - (b[0] - a[0]) * (c[2] - a[2]);
  const long long nz = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
  const long long an[3] = {std::llabs(nx), std::llabs(ny), std::llabs(nz)};
  const int drop = an[0] >= an[1] && an[0] >= an[2] ? 0 : (an[1] >= an[2] ? 1 : 2);
  const int i = (drop + 1) % 3, j = (drop + 2) % 3;
  const long long t[6] = {a[i], a[j], b[i], b[j], c[i], c[j]};
  if (dp == 0 && dq == 0) {
    if (exact_point_in_triangle_2d(p[i], p[j], t) || exact_point_in_triangle_2d(q[i], q[j], t)) return true;
    return exact_segments_2d(p[i], p[j], q[i], q[j], t[0], t[1], t[2], t[3]) ||
           exact_segments_2d(p[i], p[j], q[i], q[j], t[2], t[3], t[4], t[5]) ||
           exact_segments_2d(p[i], p[j], q[i], q[j], t[4], t[5], t[0], t[1]);
  }
  if (dp == 0) return exact_point_in_triangle_2d(p[i], p[j], t);
  if (dq == 0) return exact_point_in_triangle_2d(q[i], q[j], t);
  const int s1 = sgn(exact_orient3d(p, q, a, b)), s2 = sgn(exact_orient3d(p, q, b, c)), s3 = sgn(exact_orient3d(p, q, c, a));
  return (s1 >= 0 && s2 >= 0 && s3 >= 0) || (s1 <= 0 && s2 <= 0 && s3 <= 0);
}

}  // namespace

TEST_CASE("segment against triangle: exact on lattice points, touching and coplanar cases included", "[raycast]") {
  std::uint64_t state = 4242;
  auto next = [&]() {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<long long>((state >> 33) % 5);
  };
  int meet = 0, miss = 0, coplanar = 0;
  for (int k = 0; k < 100000; ++k) {
    I3 p{next(), next(), next()}, q{next(), next(), next()}, a{next(), next(), next()}, b{next(), next(), next()},
        c{next(), next(), next()};
    auto v = [](const I3& x) { return Vec3(double(x[0]), double(x[1]), double(x[2])); };
    if ((v(b) - v(a)).cross(v(c) - v(a)).squaredNorm() == 0) continue;  // degenerate triangle
    const bool want = exact_segment_triangle(p, q, a, b, c);
    INFO("k " << k << " p " << v(p).transpose() << " q " << v(q).transpose() << " a " << v(a).transpose() << " b "
              << v(b).transpose() << " c " << v(c).transpose());
    REQUIRE(segment_intersects_triangle(v(p), v(q), v(a), v(b), v(c)) == want);
    (want ? meet : miss) += 1;
    coplanar += exact_orient3d(a, b, c, p) == 0 && exact_orient3d(a, b, c, q) == 0;
  }
  CHECK(meet > 5000);
  CHECK(miss > 5000);
  CHECK(coplanar > 1000);
}

TEST_CASE("self-intersections: a sheet folded along a line does not cross itself", "[raycast]") {
  // A grid folded about x = 5 by angles from 20 to 170 degrees: both halves
  // are planes whose rotated corners are not exactly coplanar in floating
  // point, and triangles sharing a corner on the fold were reported
  // crossing (the far end of one touched the other's plane within noise).
  for (double deg = 20; deg <= 170; deg += 15) {
    TriMesh g = make_regular_grid(10, 10);
    const double t = deg * 3.14159265358979323846 / 180;
    for (Vec3& p : g.positions) {
      const double r = p.x() - 5;
      if (r > 0) p = Vec3(5 + r * std::cos(t), p.y(), r * std::sin(t));
    }
    std::vector<std::array<int, 2>> pairs;
    REQUIRE(find_self_intersections(g, pairs).ok());
    INFO(deg << " degrees");
    CHECK(pairs.empty());
    CHECK(brute_force(g).empty());
  }
}

TEST_CASE("moved triangles: those with a corner that moved, flagged and listed", "[raycast]") {
  const std::vector<Tri> triangles = {{0, 1, 2}, {1, 3, 2}, {3, 4, 2}, {4, 5, 3}};
  const std::vector<Vec3> before = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {0, 2, 0}, {1, 2, 0}};
  std::vector<Vec3> after = before;
  std::vector<char> changed = {1, 1};  // stale contents are replaced
  std::vector<int> list = {7};
  moved_triangles(triangles, before, after, changed, list);
  CHECK(changed == std::vector<char>(4, 0));
  CHECK(list.empty());
  after[3].z() = 1e-12;  // any change counts, however small
  moved_triangles(triangles, before, after, changed, list);
  CHECK(changed == std::vector<char>{0, 1, 1, 1});
  CHECK(list == std::vector<int>{1, 2, 3});
  // Pairs of before with a changed triangle give way to the new search's.
  const std::vector<std::array<int, 2>> kept = pairs_after_change({{0, 1}, {0, 2}}, changed, {{1, 3}});
  CHECK(kept == std::vector<std::array<int, 2>>{{1, 3}});
}
