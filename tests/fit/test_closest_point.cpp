#include "fit/closest_point.h"
#include "toy_shapes.h"

#include <catch2/catch.hpp>

using namespace lk;

TEST_CASE("closest point on a triangle: vertex, edge and face regions") {
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  auto s = closest_point_on_triangle(Vec3(0.2, 0.3, 2), a, b, c);
  CHECK(s.point.isApprox(Vec3(0.2, 0.3, 0)));
  CHECK(s.squared_distance == Approx(4.0));
  CHECK(s.barycentric.isApprox(Vec3(0.5, 0.2, 0.3)));
  s = closest_point_on_triangle(Vec3(-1, -1, 0), a, b, c);
  CHECK(s.point.isApprox(a));
  s = closest_point_on_triangle(Vec3(0.5, -2, 1), a, b, c);
  CHECK(s.point.isApprox(Vec3(0.5, 0, 0)));
  CHECK(s.squared_distance == Approx(5.0));
  s = closest_point_on_triangle(Vec3(1, 1, 0), a, b, c);
  CHECK(s.point.isApprox(Vec3(0.5, 0.5, 0)));
  // Degenerate triangle still gives the nearest point of its segment.
  s = closest_point_on_triangle(Vec3(0.5, 1, 0), a, b, Vec3(2, 0, 0));
  CHECK(s.point.isApprox(Vec3(0.5, 0, 0)));
}

TEST_CASE("BVH closest point equals brute force on a bumpy ellipsoid") {
  const TriMesh m = test::bumpy_ellipsoid(test::icosphere(3), Vec3(0.08, 0.11, 0.1), Vec3(0, 0, 1), 0.03, 0.2);
  ClosestPointTree tree(m);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(-0.2, 0.2);
  for (int i = 0; i < 500; ++i) {
    const Vec3 p(U(rng), U(rng), U(rng));
    double best = 1e300;
    for (const Tri& t : m.triangles)
      best = std::min(best, closest_point_on_triangle(p, m.positions[t[0]], m.positions[t[1]], m.positions[t[2]]).squared_distance);
    const SurfacePoint s = tree.closest(p);
    REQUIRE(s.face >= 0);
    CHECK(s.squared_distance == Approx(best).epsilon(1e-12));
    // The barycentric combination reproduces the point.
    const Tri& t = m.triangles[s.face];
    const Vec3 q = s.barycentric[0] * m.positions[t[0]] + s.barycentric[1] * m.positions[t[1]] +
                   s.barycentric[2] * m.positions[t[2]];
    CHECK((q - s.point).norm() < 1e-12);
  }
}

TEST_CASE("distance statistics of points sampled at a known offset") {
  // A unit-sphere icosphere: points at radius 1.1 along vertex directions are
  // exactly 0.1 from the surface at the vertices.
  const TriMesh m = test::icosphere(2);
  std::vector<Vec3> pts;
  for (const Vec3& p : m.positions) pts.push_back(1.1 * p);
  const DistanceStats s = point_to_surface_stats(pts, m, 2.0);
  CHECK(s.count == m.num_vertices());
  CHECK(s.mean == Approx(0.1).epsilon(1e-9));
  CHECK(s.max == Approx(0.1).epsilon(1e-9));
  CHECK(s.mean_pct == Approx(5.0).epsilon(1e-9));
  const DistanceStats empty = point_to_surface_stats(pts, TriMesh{}, 2.0);
  CHECK(empty.count == 0);
}

TEST_CASE("closest_near: the same point, triangle and distance as closest, from any guess") {
  const TriMesh m = test::bumpy_ellipsoid(test::icosphere(3), Vec3(0.08, 0.11, 0.1), Vec3(0, 0, 1), 0.03, 0.2);
  ClosestPointTree tree(m);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> U(-0.2, 0.2);
  std::uniform_int_distribution<int> F(-1, m.num_triangles() - 1);
  int guesses_far = 0;
  for (int i = 0; i < 2000; ++i) {
    // Points on the surface (ties between triangles at shared edges and
    // corners are common there) and off it.
    Vec3 p(U(rng), U(rng), U(rng));
    if (i % 2 == 0) {
      const Tri& t = m.triangles[i % m.num_triangles()];
      p = (i % 4 == 0) ? m.positions[t[0]] : Vec3(0.5 * (m.positions[t[0]] + m.positions[t[1]]));
    }
    const SurfacePoint exact = tree.closest(p);
    // The right triangle, a random one (usually far), none, out of range.
    for (int guess : {exact.face, F(rng), -1, m.num_triangles() + 5}) {
      const SurfacePoint near = tree.closest_near(p, guess);
      guesses_far += guess >= 0 && guess != exact.face;
      REQUIRE(near.face == exact.face);
      CHECK(near.squared_distance == exact.squared_distance);  // bit for bit
      CHECK(near.point == exact.point);
      CHECK(near.barycentric == exact.barycentric);
    }
  }
  CHECK(guesses_far > 1000);
}

TEST_CASE("distance statistics equal a point-by-point measurement, with and without stride") {
  const TriMesh m = test::bumpy_ellipsoid(test::icosphere(3), Vec3(0.08, 0.11, 0.1), Vec3(0, 0, 1), 0.03, 0.2);
  ClosestPointTree tree(m);
  // A few thousand points in scan-like runs (neighbours listed together)
  // and some scattered ones: more than one run of the parallel measurement.
  std::mt19937 rng(5);
  std::normal_distribution<double> N(0.0, 0.004);
  std::vector<Vec3> pts;
  for (int k = 0; k < 3000; ++k) {
    const Vec3& v = m.positions[(k / 3) % m.num_vertices()];
    pts.push_back(1.02 * v + Vec3(N(rng), N(rng), N(rng)));
  }
  for (int stride : {1, 3}) {
    std::vector<double> d;
    for (size_t i = 0; i < pts.size(); i += stride) d.push_back(std::sqrt(tree.closest(pts[i]).squared_distance));
    const DistanceStats want = summarize_distances(d, 0.3);
    const DistanceStats got = point_to_surface_stats(pts, m, 0.3, stride);
    CHECK(got.count == want.count);
    CHECK(got.mean == want.mean);  // same distances summed in the same order
    CHECK(got.max == want.max);
    CHECK(got.rms == want.rms);
    CHECK(got.p95 == want.p95);
    CHECK(got.mean_pct == want.mean_pct);
  }
}
