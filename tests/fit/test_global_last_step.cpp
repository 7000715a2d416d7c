#include "fit/closest_point.h"
#include "fit/global_fit.h"
#include "test_scan.h"
#include "toy_shapes.h"

#include <algorithm>
#include <catch2/catch.hpp>

using namespace lk;

// The fit's last step is accepted on an upper bound of E_dist when that
// bound already lowers E_global (global_fit.h, energy_after_is_bound): the
// bound must lie above the true E_dist of the result, and only the last
// iteration may carry one.
TEST_CASE("global fit: the last step's bounded E_dist lies above the true one") {
  const TriMesh sphere = test::icosphere(3);
  const TriMesh start = test::bumpy_ellipsoid(sphere, Vec3(0.08, 0.11, 0.10), Vec3(0, 0, 1), 0.0, 0.2);
  const TriMesh truth = test::bumpy_ellipsoid(sphere, Vec3(0.075, 0.12, 0.095), Vec3(0, 0, 1), 0.02, 0.25);
  MeshTopology topo;
  REQUIRE(build_topology(start, topo).ok());
  const auto pts = test::sample_surface(truth, 20000, 0.0002, 3);
  GlobalFitOptions o;
  o.subsample_points = 5000;  // the final pass then sees all 20k points
  TriMesh out;
  GlobalFitResult r;
  REQUIRE(fit_global(pts, start, topo, {}, o, out, r).ok());
  REQUIRE(r.iterations.size() >= 2);
  for (size_t i = 0; i + 1 < r.iterations.size(); ++i) CHECK_FALSE(r.iterations[i].energy_after_is_bound);
  const GlobalFitIteration& last = r.iterations.back();
  CHECK(last.points == static_cast<int>(pts.size()));
  CHECK(last.energy_after <= last.energy_before);
  // The true E_dist of the result, trimmed at the round's tau.
  ClosestPointTree tree(out);
  double sum = 0;
  for (const Vec3& p : pts) sum += std::min(tree.closest(p).squared_distance, last.trim_distance * last.trim_distance);
  const double exact = sum / pts.size();
  INFO("bound " << last.e_dist << " exact " << exact << " bounded " << last.energy_after_is_bound);
  CHECK(last.step > 0);
  if (last.energy_after_is_bound) {
    CHECK(exact <= last.e_dist);
    CHECK(exact >= 0.5 * last.e_dist);  // a near bound: the step is small, the triangles the same
  } else {
    CHECK(exact == Approx(last.e_dist).epsilon(1e-12));
  }
}
