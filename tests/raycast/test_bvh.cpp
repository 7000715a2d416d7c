// The BVH against brute force: every query must agree with testing every
// triangle, on meshes that stress the build (soups, flat grids, duplicates).
#include "mesh/primitives.h"
#include "raycast/bvh.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <cstdint>
#include <limits>

using namespace lk;

namespace {

struct Rng {
  std::uint64_t s;
  std::uint64_t next() {
    std::uint64_t z = (s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  double uniform(double a, double b) { return a + (b - a) * (next() >> 11) * 0x1.0p-53; }
  Vec3 in_box(double r) { return Vec3(uniform(-r, r), uniform(-r, r), uniform(-r, r)); }
  Vec3 direction() {
    for (;;) {
      Vec3 d = in_box(1);
      if (d.squaredNorm() > 1e-4 && d.squaredNorm() <= 1) return d.normalized();
    }
  }
};

// A lumpy UV sphere (closed, like a head).
TriMesh lumpy_sphere(int nu, int nv, Rng& rng) {
  TriMesh m;
  const double pi = 3.14159265358979323846;
  m.positions.push_back(Vec3(0, 0, 1));
  for (int j = 1; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const double th = pi * j / nv, ph = 2 * pi * i / nu;
      const double r = 1 + 0.1 * std::sin(3 * ph) * std::sin(2 * th) + rng.uniform(-0.01, 0.01);
      m.positions.push_back(r * Vec3(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)));
    }
  m.positions.push_back(Vec3(0, 0, -1));
  auto id = [nu](int j, int i) { return 1 + (j - 1) * nu + (i % nu); };
  const int south = static_cast<int>(m.positions.size()) - 1;
  for (int i = 0; i < nu; ++i) m.triangles.push_back({0, id(1, i), id(1, i + 1)});
  for (int j = 1; j < nv - 1; ++j)
    for (int i = 0; i < nu; ++i) {
      m.triangles.push_back({id(j, i), id(j + 1, i), id(j + 1, i + 1)});
      m.triangles.push_back({id(j, i), id(j + 1, i + 1), id(j, i + 1)});
    }
  for (int i = 0; i < nu; ++i) m.triangles.push_back({south, id(nv - 1, i + 1), id(nv - 1, i)});
  return m;
}

// Random, overlapping triangles of mixed sizes, plus degenerate ones.
TriMesh soup(int n, Rng& rng) {
  TriMesh m;
  for (int f = 0; f < n; ++f) {
    const Vec3 c = rng.in_box(1.0);
    const double s = rng.uniform(0.01, 0.3);
    const int base = m.num_vertices();
    m.positions.push_back(c + rng.in_box(s));
    m.positions.push_back(c + rng.in_box(s));
    m.positions.push_back(f % 50 == 0 ? m.positions[base] : c + rng.in_box(s));  // zero-area
    m.triangles.push_back({base, base + 1, base + 2});
  }
  return m;
}

// A flat grid: every box is flat in z, many centroids share coordinates.
TriMesh flat_grid(int n) {
  TriMesh m = make_regular_grid(n, n);  // on [0,n]^2
  for (Vec3& p : m.positions) p /= n;
  return m;
}

// Brute-force references.
RayHit brute_first(const TriMesh& m, const Ray& ray) {
  TriMesh one;
  one.positions = m.positions;
  RayHit best;
  for (int f = 0; f < m.num_triangles(); ++f) {
    one.triangles = {m.triangles[f]};
    MeshBvh b;
    REQUIRE(build_bvh(one, b).ok());
    RayHit h = intersect_first(b, ray);
    if (h.hit() && (!best.hit() || h.t < best.t)) {
      best = h;
      best.triangle = f;
    }
  }
  return best;
}

double brute_closest(const TriMesh& m, const Vec3& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const Tri& t : m.triangles) {
    Vec3 bary;
    const Vec3 q = closest_point_on_triangle(p, m.positions[t[0]], m.positions[t[1]], m.positions[t[2]], bary);
    best = std::min(best, (q - p).norm());
  }
  return best;
}

void compare_with_brute_force(const TriMesh& m, Rng& rng, int queries) {
  MeshBvh bvh;
  REQUIRE(build_bvh(m, bvh).ok());
  REQUIRE(bvh.triangle_order.size() == m.triangles.size());
  BBox box;
  for (const Vec3& p : m.positions) box.extend(p);
  auto in_mesh_box = [&]() {
    return Vec3(rng.uniform(box.min.x(), box.max.x()), rng.uniform(box.min.y(), box.max.y()),
                rng.uniform(box.min.z(), box.max.z()));
  };
  int hits = 0;
  for (int q = 0; q < queries; ++q) {
    Ray ray;
    ray.origin = rng.in_box(2.0);
    // Half the rays aim at the mesh, so there are plenty of hits to compare.
    ray.direction = (q % 2 == 0) ? rng.direction() : (in_mesh_box() - ray.origin);
    if (q % 7 == 0) ray.t_max = rng.uniform(0.1, 2.0);
    const RayHit want = brute_first(m, ray);
    const RayHit got = intersect_first(bvh, ray);
    REQUIRE(got.hit() == want.hit());
    CHECK(intersect_any(bvh, ray) == want.hit());
    if (want.hit()) {
      ++hits;
      CHECK(got.t == Approx(want.t).margin(1e-12));
      const Tri& t = m.triangles[got.triangle];
      const Vec3 p = got.barycentric[0] * m.positions[t[0]] + got.barycentric[1] * m.positions[t[1]] +
                     got.barycentric[2] * m.positions[t[2]];
      CHECK((p - (ray.origin + got.t * ray.direction)).norm() < 1e-9);
    }
    const Vec3 p = rng.in_box(1.5);
    const ClosestPoint cp = closest_point(bvh, p);
    REQUIRE(cp.found());
    CHECK(cp.distance == Approx(brute_closest(m, p)).margin(1e-12));
    CHECK((cp.point - p).norm() == Approx(cp.distance).margin(1e-12));
    const Tri& t = m.triangles[cp.triangle];
    const Vec3 bp = cp.barycentric[0] * m.positions[t[0]] + cp.barycentric[1] * m.positions[t[1]] +
                    cp.barycentric[2] * m.positions[t[2]];
    CHECK((bp - cp.point).norm() < 1e-9);
    // A search radius below the true distance finds nothing.
    CHECK_FALSE(closest_point(bvh, p, 0.5 * cp.distance).found());
  }
  CHECK(hits > queries / 5);  // the comparison is not vacuous
}

}  // namespace

TEST_CASE("bvh agrees with brute force on a lumpy sphere", "[raycast]") {
  Rng rng{1};
  compare_with_brute_force(lumpy_sphere(40, 20, rng), rng, 300);
}

TEST_CASE("bvh agrees with brute force on a triangle soup with degenerate triangles", "[raycast]") {
  Rng rng{2};
  compare_with_brute_force(soup(800, rng), rng, 300);
}

TEST_CASE("bvh agrees with brute force on a flat grid and on duplicated triangles", "[raycast]") {
  Rng rng{3};
  compare_with_brute_force(flat_grid(20), rng, 200);
  TriMesh dup = flat_grid(3);
  const auto tris = dup.triangles;
  for (int k = 0; k < 30; ++k) dup.triangles.insert(dup.triangles.end(), tris.begin(), tris.end());
  compare_with_brute_force(dup, rng, 100);
}

TEST_CASE("any-hit ignores the skipped triangle and respects the ray's extent", "[raycast]") {
  TriMesh m = flat_grid(4);
  MeshBvh bvh;
  REQUIRE(build_bvh(m, bvh).ok());
  Ray down;
  down.origin = Vec3(0.3, 0.6, 1.0);
  down.direction = Vec3(0, 0, -1);
  const RayHit h = intersect_first(bvh, down);
  REQUIRE(h.hit());
  CHECK(h.t == Approx(1.0));
  CHECK(intersect_any(bvh, down));
  CHECK_FALSE(intersect_any(bvh, down, h.triangle));  // the only triangle on this ray
  down.t_max = 0.99;
  CHECK_FALSE(intersect_any(bvh, down));
  CHECK_FALSE(intersect_first(bvh, down).hit());
}

TEST_CASE("refit follows moved vertices like a rebuild", "[raycast]") {
  Rng rng{4};
  TriMesh m = lumpy_sphere(24, 12, rng);
  MeshBvh bvh;
  REQUIRE(build_bvh(m, bvh).ok());
  for (Vec3& p : m.positions) p = Vec3(1.5 * p.x(), 0.7 * p.y(), p.z()) + Vec3(0.2, 0, 0);
  REQUIRE(refit_bvh(m, bvh).ok());
  MeshBvh fresh;
  REQUIRE(build_bvh(m, fresh).ok());
  for (int q = 0; q < 200; ++q) {
    Ray ray;
    ray.origin = rng.in_box(2.5);
    ray.direction = rng.in_box(0.5) - ray.origin;
    const RayHit a = intersect_first(bvh, ray), b = intersect_first(fresh, ray);
    REQUIRE(a.hit() == b.hit());
    if (a.hit()) CHECK(a.t == Approx(b.t).margin(1e-12));
    const Vec3 p = rng.in_box(2.0);
    CHECK(closest_point(bvh, p).distance == Approx(closest_point(fresh, p).distance).margin(1e-12));
  }
  TriMesh fewer = m;
  fewer.positions.pop_back();
  CHECK(refit_bvh(fewer, bvh).code == ErrorCode::InvalidInput);
}

TEST_CASE("bad meshes are refused with a message, empty meshes give misses", "[raycast]") {
  MeshBvh bvh;
  TriMesh bad = flat_grid(2);
  bad.triangles[3][1] = 99;
  Status s = build_bvh(bad, bvh);
  CHECK(s.code == ErrorCode::InvalidInput);
  CHECK(s.message.find("99") != std::string::npos);
  bad = flat_grid(2);
  bad.positions[2].y() = std::numeric_limits<double>::quiet_NaN();
  CHECK(build_bvh(bad, bvh).code == ErrorCode::InvalidInput);
  CHECK(build_bvh(flat_grid(2), bvh, BvhOptions{0, 16}).code == ErrorCode::InvalidInput);

  TriMesh empty;
  REQUIRE(build_bvh(empty, bvh).ok());
  Ray r;
  CHECK_FALSE(intersect_first(bvh, r).hit());
  CHECK_FALSE(intersect_any(bvh, r));
  CHECK_FALSE(closest_point(bvh, Vec3::Zero()).found());
}

TEST_CASE("closest point on a triangle lands in each Voronoi region", "[raycast]") {
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  Vec3 bary;
  CHECK((closest_point_on_triangle(Vec3(-1, -1, 1), a, b, c, bary) - a).norm() < 1e-15);
  CHECK(bary.isApprox(Vec3(1, 0, 0)));
  CHECK((closest_point_on_triangle(Vec3(2, -1, 0), a, b, c, bary) - b).norm() < 1e-15);
  CHECK((closest_point_on_triangle(Vec3(0.5, -2, 3), a, b, c, bary) - Vec3(0.5, 0, 0)).norm() < 1e-15);
  CHECK(bary.isApprox(Vec3(0.5, 0.5, 0)));
  CHECK((closest_point_on_triangle(Vec3(1, 1, -1), a, b, c, bary) - Vec3(0.5, 0.5, 0)).norm() < 1e-15);
  CHECK(bary.isApprox(Vec3(0, 0.5, 0.5)));
  CHECK((closest_point_on_triangle(Vec3(0.2, 0.3, 5), a, b, c, bary) - Vec3(0.2, 0.3, 0)).norm() < 1e-15);
  CHECK(bary.isApprox(Vec3(0.5, 0.2, 0.3)));
  // A degenerate triangle (a segment) still gives the nearest point on it.
  CHECK((closest_point_on_triangle(Vec3(0.5, 1, 0), a, b, b, bary) - Vec3(0.5, 0, 0)).norm() < 1e-15);
}

namespace {

void require_same_tree(const MeshBvh& a, const MeshBvh& b) {
  REQUIRE(a.nodes.size() == b.nodes.size());
  REQUIRE(a.triangle_order == b.triangle_order);
  for (size_t i = 0; i < a.nodes.size(); ++i) {
    REQUIRE(a.nodes[i].first == b.nodes[i].first);
    REQUIRE(a.nodes[i].count == b.nodes[i].count);
    // Bit for bit: the boxes are minima and maxima of the same coordinates.
    REQUIRE(a.nodes[i].box_min == b.nodes[i].box_min);
    REQUIRE(a.nodes[i].box_max == b.nodes[i].box_max);
  }
}

}  // namespace

TEST_CASE("a threaded build gives the serial build's tree", "[raycast]") {
  Rng rng{11};
  const TriMesh m = lumpy_sphere(200, 100, rng);  // 39600 triangles: above the threading threshold
  REQUIRE(m.num_triangles() >= 20000);
  MeshBvh threaded, serial;
  BvhOptions one_thread;
  one_thread.threads = false;
  REQUIRE(build_bvh(m, threaded).ok());
  REQUIRE(build_bvh(m, serial, one_thread).ok());
  require_same_tree(threaded, serial);
}

TEST_CASE("refitting the moved vertices only equals a full refit", "[raycast]") {
  Rng rng{5};
  TriMesh m = lumpy_sphere(64, 32, rng);
  MeshBvh partial;
  REQUIRE(build_bvh(m, partial).ok());
  MeshBvh full = partial;
  BvhRefitIndex index;
  build_refit_index(partial, index);
  // Several rounds of a few moved vertices (some repeated), as the fold
  // limiter does; after each the boxes must equal a full refit's exactly.
  for (int round = 0; round < 20; ++round) {
    std::vector<int> moved;
    for (int k = 0; k < 1 + round * 3; ++k) {
      const int v = static_cast<int>(rng.next() % m.positions.size());
      m.positions[v] += rng.in_box(0.3);
      moved.push_back(v);
      if (k % 4 == 0) moved.push_back(v);
    }
    REQUIRE(refit_bvh_vertices(partial, index, m.positions, moved).ok());
    REQUIRE(refit_bvh(m, full).ok());
    REQUIRE(partial.positions == full.positions);
    require_same_tree(partial, full);
  }
  // A vertex not listed keeps its old position in the BVH.
  const Vec3 old = partial.positions[0];
  m.positions[0] += Vec3(1, 0, 0);
  REQUIRE(refit_bvh_vertices(partial, index, m.positions, {1}).ok());
  CHECK(partial.positions[0] == old);
  // Bad input: nothing changes.
  CHECK(refit_bvh_vertices(partial, index, m.positions, {-1}).code == ErrorCode::InvalidInput);
  CHECK(refit_bvh_vertices(partial, index, m.positions, {m.num_vertices()}).code == ErrorCode::InvalidInput);
  std::vector<Vec3> fewer(m.positions.begin(), m.positions.end() - 1);
  CHECK(refit_bvh_vertices(partial, index, fewer, {1}).code == ErrorCode::InvalidInput);
  m.positions[2] = Vec3(std::nan(""), 0, 0);
  CHECK(refit_bvh_vertices(partial, index, m.positions, {2}).code == ErrorCode::InvalidInput);
  CHECK(partial.positions[2].allFinite());
  BvhRefitIndex empty;
  CHECK(refit_bvh_vertices(partial, empty, m.positions, {1}).code == ErrorCode::InvalidInput);
}
