#include "fit/closest_point.h"
#include "common/prng.h"
#include "mesh/primitives.h"
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
    const SurfaceHit s = tree.closest(p);
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
    const SurfaceHit exact = tree.closest(p);
    // The right triangle, a random one (usually far), none, out of range.
    for (int guess : {exact.face, F(rng), -1, m.num_triangles() + 5}) {
      const SurfaceHit near = tree.closest_near(p, guess);
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

TEST_CASE("surface_to_reference: a spike over the scan counts, vertices over a hole or its far side do not") {
  // Reference: a 10 cm grid in z = 0 (an 11 x 11 vertex sheet, 1 cm cells)
  // with a hole: the cells of x, y in (4, 6) cm are gone.
  TriMesh sheet = make_regular_grid(10, 10);  // vertices on [0, 10]^2
  for (Vec3& p : sheet.positions) p = Vec3(p.x() * 0.01, p.y() * 0.01, 0);
  TriMesh reference = sheet;
  reference.triangles.clear();
  for (const Tri& t : sheet.triangles) {
    const Vec3 c = (sheet.positions[t[0]] + sheet.positions[t[1]] + sheet.positions[t[2]]) / 3;
    if (!(c.x() > 0.04 && c.x() < 0.06 && c.y() > 0.04 && c.y() < 0.06)) reference.triangles.push_back(t);
  }
  // Surface: a finer sheet 1 mm above it, one vertex raised to a 5 mm
  // spike over scanned cells, and a second sheet facing the other way.
  TriMesh surface = make_regular_grid(20, 20);
  for (Vec3& p : surface.positions) p = Vec3(p.x() * 0.005, p.y() * 0.005, 0.001);
  int spike = -1, over_hole = -1;
  for (int v = 0; v < surface.num_vertices(); ++v) {
    const Vec3& p = surface.positions[v];
    if (std::abs(p.x() - 0.025) < 1e-9 && std::abs(p.y() - 0.025) < 1e-9) spike = v;
    if (std::abs(p.x() - 0.05) < 1e-9 && std::abs(p.y() - 0.05) < 1e-9) over_hole = v;
  }
  REQUIRE(spike >= 0);
  REQUIRE(over_hole >= 0);
  surface.positions[spike].z() = 0.005;
  const int sheet_vertices = surface.num_vertices();
  TriMesh under = make_regular_grid(4, 4);
  for (Vec3& p : under.positions) p = Vec3(0.01 + p.x() * 0.005, 0.01 + p.y() * 0.005, -0.002);
  for (Tri t : under.triangles) {
    std::swap(t[1], t[2]);  // facing -z
    for (int& v : t) v += sheet_vertices;
    surface.triangles.push_back(t);
  }
  surface.positions.insert(surface.positions.end(), under.positions.begin(), under.positions.end());

  const CoveredDistances all = surface_to_reference(surface, {}, reference, inside_scan_mesh(reference));
  INFO(all.vertices << " vertices, mean " << all.mean << " max " << all.max << ", over 1 mm " << all.over_1mm);
  // The hole's 3 x 3 inner vertices (their closest point is on the hole's
  // rim), the sheet's own rim (its closest points are on the grid's
  // boundary) and the far-side sheet do not count.
  CHECK(all.vertices < sheet_vertices - 9);
  CHECK(all.vertices > sheet_vertices / 2);
  CHECK(all.max == Approx(0.005).epsilon(1e-9));
  CHECK(all.over_1mm >= 1);
  CHECK(all.over_1mm <= 5);  // the spike and its slopes only
  CHECK(all.mean == Approx(0.001).margin(2e-4));
  // Skipping the spike leaves 1 mm everywhere.
  std::vector<char> skip(surface.num_vertices(), 0);
  skip[spike] = 1;
  const CoveredDistances rest = surface_to_reference(surface, skip, reference, inside_scan_mesh(reference));
  CHECK(rest.max == Approx(0.001).epsilon(1e-6));
  // The vertex over the hole, alone: not counted.
  std::vector<char> only(surface.num_vertices(), 1);
  only[over_hole] = 0;
  CHECK(surface_to_reference(surface, only, reference, inside_scan_mesh(reference)).vertices == 0);
}

TEST_CASE("surface_to_cloud: the other direction on a point cloud, over its quadric patches") {
  // Scan: 12,000 points on a 3 cm sphere (spacing about 1 mm), 0.1 mm of
  // depth noise, 0.5 % outliers 2 mm out; the back (z < -1 cm) was not
  // scanned, nor a hole of 15 degrees around +x.
  const double R = 0.03;
  const Vec3 hole_axis = Vec3::UnitX();
  const double hole_cos = std::cos(15.0 * 3.14159265358979 / 180.0);
  SplitMix64 rng(7);
  std::vector<Vec3> points;
  const int n = 12000;
  for (int i = 0; i < n; ++i) {  // Fibonacci sphere
    const double z = 1 - (2.0 * i + 1) / n, r = std::sqrt(1 - z * z), phi = 2.39996322972865 * i;
    const Vec3 u(r * std::cos(phi), r * std::sin(phi), z);
    if (u.z() * R < -0.01 || u.dot(hole_axis) > hole_cos) continue;
    const double depth = (i % 200 == 0) ? 0.002 : 0.0001 * rng.gaussian();
    points.push_back((R + depth) * u);
  }
  // Surface: an icosphere 0.5 mm outside it, one vertex on the front raised
  // to a 5 mm spike.
  TriMesh surface = make_icosphere(4);  // 2,562 vertices, about 2 mm apart at this size
  int spike = -1, over_hole = -1, beyond_rim = -1;
  for (int v = 0; v < surface.num_vertices(); ++v) {
    const Vec3 u = surface.positions[v].normalized();
    surface.positions[v] = (R + 0.0005) * u;
    if (spike < 0 && u.z() > 0.99) spike = v;
    if (over_hole < 0 && u.dot(hole_axis) > 0.999) over_hole = v;
    if (beyond_rim < 0 && u.z() < -0.9) beyond_rim = v;
  }
  REQUIRE(spike >= 0);
  REQUIRE(over_hole >= 0);
  REQUIRE(beyond_rim >= 0);
  surface.positions[spike] *= (R + 0.005) / (R + 0.0005);

  const CoveredDistances all = surface_to_cloud(surface, {}, points);
  INFO(all.vertices << " vertices, mean " << all.mean << " p99 " << all.p99 << " max " << all.max << ", over 1 mm "
                    << all.over_1mm);
  CHECK(all.to_points);
  // The scanned part holds about 2/3 of the sphere less the hole.
  CHECK(all.vertices > surface.num_vertices() / 2);
  CHECK(all.vertices < surface.num_vertices() * 2 / 3);
  // 0.5 mm everywhere: the quadric follows the sphere (the patches' plane
  // would read 0.5 mm plus about half their sag, r^2 / 4R = 0.04 mm) and
  // drops the outliers.
  CHECK(all.mean == Approx(0.0005).margin(2e-5));
  // The spike counts, at about its height, and only it and its slopes.
  CHECK(all.max == Approx(0.005).margin(3e-4));
  CHECK(all.over_1mm >= 1);
  CHECK(all.over_1mm <= 7);
  // A vertex over the hole, or beyond the scan's border, alone: not counted.
  for (int v : {over_hole, beyond_rim}) {
    std::vector<char> only(surface.num_vertices(), 1);
    only[v] = 0;
    CHECK(surface_to_cloud(surface, only, points).vertices == 0);
  }
  // The per-vertex distances are the summary's, -1 where not counted.
  std::vector<double> per_vertex;
  const CoveredDistances again = surface_to_cloud(surface, {}, points, 16, &per_vertex);
  REQUIRE(per_vertex.size() == surface.positions.size());
  int counted = 0;
  double sum = 0;
  for (double x : per_vertex)
    if (x >= 0) ++counted, sum += x;
  CHECK(counted == again.vertices);
  CHECK(sum / counted == Approx(all.mean).epsilon(1e-12));
  CHECK(per_vertex[spike] == Approx(all.max).epsilon(1e-12));
  CHECK(per_vertex[over_hole] < 0);
  CHECK(per_vertex[beyond_rim] < 0);
  // Too few points: nothing measured, no crash.
  CHECK(surface_to_cloud(surface, {}, std::vector<Vec3>(5, Vec3::Zero())).vertices == 0);
}

TEST_CASE("surface_to_cloud: noise is not a fold, a fold stays one") {
  // A 40 x 40 mm scan of a plane sampled every 0.5 mm with 0.2 mm of depth
  // noise (a 16-point patch of radius ~1.1 mm: its flatness ratio is ~0.13
  // on average and passes 0.2 only by chance), and a surface 0.25 mm above
  // it, a vertex every mm. Every vertex away from the border is over one
  // sheet and counts; tried with 16 points alone, a few percent went
  // unmeasured at random (lone dots on the distance map).
  SplitMix64 rng(11);
  std::vector<Vec3> plane;
  for (int i = 0; i <= 80; ++i)
    for (int j = 0; j <= 80; ++j)
      plane.push_back(Vec3(0.0005 * i, 0.0005 * j, 0.0002 * rng.gaussian()));
  TriMesh grid = make_regular_grid(30, 30);  // 31 x 31 vertices, 1 mm apart, from 5 mm in
  for (Vec3& p : grid.positions) p = Vec3(0.005 + 0.001 * p.x(), 0.005 + 0.001 * p.y(), 0.00025);
  std::vector<double> per_vertex;
  const CoveredDistances flat = surface_to_cloud(grid, {}, plane, 16, &per_vertex);
  INFO(flat.vertices << " of " << grid.num_vertices() << " vertices, mean " << flat.mean << " max " << flat.max);
  CHECK(flat.vertices == grid.num_vertices());
  // The patches carry the noise too (a 16-point quadric's height varies by
  // about 0.1 mm here): close to 0.25 mm on average, nowhere far off.
  CHECK(flat.mean == Approx(0.00025).margin(6e-5));
  CHECK(flat.max < 0.0007);

  // A fold: the points on z = |x| (two sheets at 90 degrees), noise-free.
  // A surface vertex over the crease has points of both sheets among its
  // nearest at every patch size: never one sheet, never counted; those a
  // few mm off the crease are.
  std::vector<Vec3> fold;
  for (int i = -40; i <= 40; ++i)
    for (int j = 0; j <= 80; ++j) fold.push_back(Vec3(0.0005 * i, 0.0005 * j, std::abs(0.0005 * i)));
  // The surface: two rows of vertices across the crease, 1 mm apart,
  // 0.2 mm above the sheets.
  TriMesh strip;
  for (int row = 0; row < 2; ++row)
    for (int i = -5; i <= 5; ++i)
      strip.positions.push_back(Vec3(0.001 * i, 0.02 + 0.001 * row, std::abs(0.001 * i) + 0.0002));
  for (int i = 0; i < 10; ++i) {
    strip.triangles.push_back({i, i + 1, i + 12});
    strip.triangles.push_back({i, i + 12, i + 11});
  }
  std::vector<double> fold_per_vertex;
  surface_to_cloud(strip, {}, fold, 16, &fold_per_vertex);
  INFO("x = -5 / 0 / 5 mm: " << fold_per_vertex[0] << " / " << fold_per_vertex[5] << " / " << fold_per_vertex[10]);
  CHECK(fold_per_vertex[5] < 0);   // x = 0: on the crease
  CHECK(fold_per_vertex[0] == Approx(0.0002 / std::sqrt(2.0)).margin(1e-5));  // x = -5 mm: one sheet
  CHECK(fold_per_vertex[10] == Approx(0.0002 / std::sqrt(2.0)).margin(1e-5));
}
