#include "fit/closest_point.h"
#include "fit/global_fit.h"
#include "toy_shapes.h"

#include <catch2/catch.hpp>

using namespace lk;

namespace {

struct Case {
  TriMesh start, truth;
  MeshTopology topo;
};

Case make_case() {
  Case c;
  const TriMesh sphere = test::icosphere(3);
  c.start = test::bumpy_ellipsoid(sphere, Vec3(0.08, 0.11, 0.10), Vec3(0, 0, 1), 0.0, 0.2);
  c.truth = test::bumpy_ellipsoid(sphere, Vec3(0.075, 0.12, 0.095), Vec3(0, 0, 1), 0.02, 0.25);
  REQUIRE(build_topology(c.start, c.topo).ok());
  return c;
}

void check_monotonic(const GlobalFitResult& r) {
  REQUIRE(!r.iterations.empty());
  for (size_t i = 0; i < r.iterations.size(); ++i) {
    const auto& it = r.iterations[i];
    CHECK(it.energy_after <= it.energy_before);
    if (i > 0 && r.iterations[i - 1].round == it.round)
      CHECK(it.energy_before == Approx(r.iterations[i - 1].energy_after).epsilon(1e-12));
  }
}

}  // namespace

TEST_CASE("global fit pulls an ellipsoid onto a bumpy target, energy decreasing") {
  Case c = make_case();
  const auto pts = test::sample_surface(c.truth, 20000, 0.0002, 3);
  const double diag = bounding_box(pts).diagonal();
  const double before = point_to_surface_stats(pts, c.start, diag).mean_pct;
  TriMesh out;
  GlobalFitResult r;
  GlobalFitOptions o;
  REQUIRE(fit_global(pts, c.start, c.topo, {}, o, out, r).ok());
  check_monotonic(r);
  const DistanceStats after = point_to_surface_stats(pts, out, diag);
  INFO("mean % before " << before << " after " << after.mean_pct);
  CHECK(after.mean_pct < before / 8);
  CHECK(after.mean_pct < 0.15);
  // The other way round: the truth's surface (its vertices, never seen as
  // data) lies on the fit, the bump included.
  const DistanceStats back = point_to_surface_stats(c.truth.positions, out, diag);
  INFO("truth to fit: mean " << back.mean << " max " << back.max);
  CHECK(back.mean < 0.0005);
  CHECK(back.max < 0.002);
}

TEST_CASE("global fit ignores outliers and bridges a hole") {
  Case c = make_case();
  auto pts = test::sample_surface(c.truth, 20000, 0.0002, 5);
  // A hole: no data on the top cap (y > 0.09), where the truth is still a
  // plain ellipsoid cap like the start's.
  std::vector<Vec3> kept;
  for (const Vec3& p : pts)
    if (p.y() < 0.09) kept.push_back(p);
  // 3 % outliers in a shell well away from the surface.
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> U(-1, 1);
  const size_t n_out = kept.size() * 3 / 100;
  for (size_t i = 0; i < n_out; ++i) {
    Vec3 d(U(rng), U(rng), U(rng));
    kept.push_back(d.normalized() * 0.2);
  }
  TriMesh out;
  GlobalFitResult r;
  REQUIRE(fit_global(kept, c.start, c.topo, {}, GlobalFitOptions{}, out, r).ok());
  check_monotonic(r);
  // Inliers fit well despite the outliers.
  std::vector<Vec3> inliers(kept.begin(), kept.end() - n_out);
  const DistanceStats s = point_to_surface_stats(inliers, out, bounding_box(inliers).diagonal());
  INFO("inlier mean % " << s.mean_pct);
  CHECK(s.mean_pct < 0.2);
  // In the hole, the surface stays near the truth (no shrinking, no pull of the outliers).
  std::vector<Vec3> hole_truth;
  for (const Vec3& p : c.truth.positions)
    if (p.y() > 0.095) hole_truth.push_back(p);
  REQUIRE(hole_truth.size() > 10);
  // The truth's cap is 10 mm above the start's; with no data there the fit
  // must carry the cap up with its surroundings, not leave or flatten it.
  const DistanceStats hole0 = point_to_surface_stats(hole_truth, c.start, 1.0);
  const DistanceStats hole = point_to_surface_stats(hole_truth, out, 1.0);
  INFO("truth to surface in the hole: start mean " << hole0.mean << ", fit mean " << hole.mean
                                                   << " max " << hole.max);
  CHECK(hole.mean < 0.45 * hole0.mean);
  CHECK(hole.max < 0.5 * hole0.max);
  // The paper's pure umbrella (no rest shape) shrinks the cap: worse.
  GlobalFitOptions paper;
  paper.preserve_rest_shape = false;
  TriMesh out_paper;
  REQUIRE(fit_global(kept, c.start, c.topo, {}, paper, out_paper, r).ok());
  const DistanceStats hole_paper = point_to_surface_stats(hole_truth, out_paper, 1.0);
  INFO("pure umbrella: mean in the hole " << hole_paper.mean);
  CHECK(hole.mean < hole_paper.mean);
}

TEST_CASE("global fit keeps constrained vertices and binding edges") {
  Case c = make_case();
  const auto pts = test::sample_surface(c.truth, 8000, 0.0, 4);
  GlobalFitTerms terms;
  terms.constrained_vertices = {0, 1, 2};
  terms.binding_edges = {{{3, 4}}, {{5, 6}}};
  GlobalFitOptions o;
  o.constraint_weight = 1e4;
  o.binding_weight = 1e4;
  TriMesh out;
  GlobalFitResult r;
  REQUIRE(fit_global(pts, c.start, c.topo, terms, o, out, r).ok());
  check_monotonic(r);
  for (int v : terms.constrained_vertices) CHECK((out.positions[v] - c.start.positions[v]).norm() < 5e-4);
  for (auto e : terms.binding_edges) {
    const Vec3 d0 = c.start.positions[e[0]] - c.start.positions[e[1]];
    const Vec3 d1 = out.positions[e[0]] - out.positions[e[1]];
    CHECK((d1 - d0).norm() < 5e-4);
  }
}

TEST_CASE("global fit rejects bad input with a clear error") {
  Case c = make_case();
  TriMesh out;
  GlobalFitResult r;
  CHECK(fit_global({}, c.start, c.topo, {}, {}, out, r).code == ErrorCode::Empty);
  std::vector<Vec3> bad = {Vec3(0, 0, std::nan(""))};
  CHECK(fit_global(bad, c.start, c.topo, {}, {}, out, r).code == ErrorCode::InvalidInput);
  GlobalFitTerms terms;
  terms.binding_edges = {{{0, 100000}}};
  const auto pts = test::sample_surface(c.truth, 100, 0.0, 1);
  CHECK(fit_global(pts, c.start, c.topo, terms, {}, out, r).code == ErrorCode::InvalidInput);
  int calls = 0;
  auto cancel = [&](const char*, double) { return ++calls < 2; };
  CHECK(fit_global(pts, c.start, c.topo, {}, {}, out, r, cancel).code == ErrorCode::Cancelled);
}
