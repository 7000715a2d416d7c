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
