// The shape fit's follow term (photos/shape_fit.h, ShapeFitOptions::follow):
// the regularizer relative to a fitted similarity, so that what the photos
// do not observe follows the head rather than the nearest pull.
#include "photos/fit_pulls.h"
#include "photos/photos_job.h"
#include "photos/shape_fit.h"
#include "photos_scenario.h"
#include "test_data.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <random>

namespace lk {
namespace {

TEST_CASE("the regularizer's matrix matches its residuals and their finite differences", "[photos][follow]") {
  GenericHead g;
  REQUIRE(load_generic_head(g));
  const std::vector<Vec3>& nodes = g.mesh.positions;
  const SparseMat L = uniform_laplacian(g.mesh);
  const int n = 3 * g.mesh.num_vertices();
  std::mt19937 rng(7);
  std::normal_distribution<double> N(0.0, 1.0);
  // Per-node weights of the follow rows, some 0 (observed nodes), some 1, some between.
  std::vector<double> w(nodes.size());
  for (size_t i = 0; i < w.size(); ++i) w[i] = i % 3 == 0 ? 0.0 : (i % 3 == 1 ? 1.0 : 0.37);
  for (double follow : {0.0, 0.05}) {
    const int e = regularizer_extra_parameters(follow);
    const SparseMat R = regularizer_matrix(nodes, L, 3.0, 1e-4, follow, w);
    REQUIRE(R.cols() == n + e);
    Eigen::VectorXd x(n + e);
    for (int i = 0; i < n; ++i) x[i] = 0.002 * N(rng);
    for (int j = 0; j < e; ++j) x[n + j] = (j < 4 ? 0.05 : 0.003) * N(rng);
    const Eigen::VectorXd r = regularizer_residuals(nodes, L, 3.0, 1e-4, follow, x, w);
    REQUIRE(r.size() == R.rows());
    CHECK((R * x - r).norm() <= 1e-12 * (1 + r.norm()));
    // Central differences of the directly evaluated residuals, column by
    // column: every similarity parameter and a sample of displacements.
    std::vector<int> cols;
    for (int i = 0; i < n; i += 97) cols.push_back(i);
    for (int j = 0; j < e; ++j) cols.push_back(n + j);
    double worst = 0;
    for (int c : cols) {
      const double h = 1e-6;
      Eigen::VectorXd xp = x, xm = x;
      xp[c] += h;
      xm[c] -= h;
      const Eigen::VectorXd fd = (regularizer_residuals(nodes, L, 3.0, 1e-4, follow, xp, w) -
                                  regularizer_residuals(nodes, L, 3.0, 1e-4, follow, xm, w)) / (2 * h);
      const Eigen::VectorXd col = R.col(c);
      worst = std::max(worst, (fd - col).norm() / std::max(1e-12, col.norm()));
    }
    std::printf("follow %g: %zu columns, worst relative difference to finite differences %.2e\n", follow, cols.size(),
                worst);
    CHECK(worst < 1e-6);
  }
}

TEST_CASE("a similarity of the head costs the follow term's stiffness nothing", "[photos][follow]") {
  GenericHead g;
  REQUIRE(load_generic_head(g));
  const std::vector<Vec3>& nodes = g.mesh.positions;
  const int V = g.mesh.num_vertices(), n = 3 * V;
  Vec3 c = Vec3::Zero();
  for (const Vec3& p : nodes) c += p;
  c /= double(V);
  Eigen::Matrix<double, 7, 1> theta;
  theta << 0.04, 0.01, -0.02, 0.015, 0.002, -0.001, 0.003;
  Eigen::VectorXd x(n + 7);
  for (int i = 0; i < V; ++i) x.segment<3>(3 * i) = similarity_displacement(nodes[size_t(i)], c, theta);
  x.tail<7>() = theta;
  const Eigen::VectorXd r = regularizer_residuals(nodes, uniform_laplacian(g.mesh), 3.0, 1e-4, 0.05, x);
  // Stiffness and follow rows vanish; only the tether (on the displacement itself) is left.
  CHECK(r.head(2 * n).norm() < 1e-12);
  CHECK(r.tail(n).norm() > 1e-4);
  // Without the similarity in the state the thin plate does charge it.
  x.tail<7>().setZero();
  CHECK(regularizer_residuals(nodes, uniform_laplacian(g.mesh), 3.0, 1e-4, 0.05, x).head(n).norm() > 1e-4);
}

// Mean outward (away from the midline) displacement over a region, metres.
double outward_mean(const GenericHead& g, const std::vector<Vec3>& x, const PullRegion& reg, const Vec3& lateral) {
  double mid = 0;
  for (const Vec3& p : g.mesh.positions) mid += p.dot(lateral);
  mid /= double(g.mesh.num_vertices());
  double sum = 0;
  int cnt = 0;
  for (int v : reg.vertices) {
    const double side = g.mesh.positions[size_t(v)].dot(lateral) - mid;
    sum += (side > 0 ? 1.0 : -1.0) * (x[size_t(v)] - g.mesh.positions[size_t(v)]).dot(lateral);
    ++cnt;
  }
  return cnt ? sum / cnt : 0.0;
}

// Only the face observed: every mapped landmark seen by every camera at the
// generic head's own projection, except the cheeks group's, seen 3 mm
// farther out. The truth is the generic head with wider cheeks; the ears,
// which no landmark sees, are unchanged.
TEST_CASE("with the follow term the unobserved ears stay where the truth has them", "[photos][follow]") {
  test::PhotoScenario sc = test::make_photo_scenario(3);
  const GenericHead& g = sc.generic;
  const Vec3 lateral = g.annotations.up.cross(g.annotations.look).normalized();
  std::vector<FeatureObservation> obs;
  for (size_t c = 0; c < sc.session.cameras.size(); ++c)
    for (size_t m = 0; m < sc.landmarks.size(); ++m) {
      if (!sc.landmarks[m].valid()) continue;
      Vec3 X = surface_position(g.mesh, sc.landmarks[m]);
      if (landmark_pull_group(g, sc.landmarks[m], int(m), false) == "cheeks")
        X += (X.dot(lateral) > 0 ? 1.0 : -1.0) * 0.003 * lateral;
      FeatureObservation o;
      o.camera = int(c);
      o.point = sc.landmarks[m];
      if (sc.session.cameras[c].project(X, o.pixel)) obs.push_back(o);
    }
  const std::vector<PullRegion> regions = lateral_pull_regions(g);
  REQUIRE(regions.size() == 3);
  REQUIRE(regions[2].name == "ears");
  REQUIRE(regions[2].vertices.size() > 10);
  double cheeks[2], ears[2];
  for (int with = 0; with < 2; ++with) {
    std::vector<std::unique_ptr<ObservationSet>> sets;
    sets.push_back(std::make_unique<FeatureSet>(g.mesh, sc.session.cameras, obs, 4.0));
    ShapeFitOptions opt;
    opt.follow = with ? 0.05 : 0.0;
    ShapeFitResult r;
    REQUIRE(fit_shape(g.mesh, sets, {0.3}, opt, r));
    cheeks[with] = outward_mean(g, r.mesh.positions, regions[0], lateral);
    ears[with] = outward_mean(g, r.mesh.positions, regions[2], lateral);
    std::printf("follow %g: cheeks %+.3f mm, ears %+.3f mm outward (truth: cheeks about +3, ears 0)\n", opt.follow,
                1000 * cheeks[with], 1000 * ears[with]);
  }
  // Without the term the thin plate carries the cheeks' pull to the ears.
  CHECK(ears[0] > 1e-3);
  // With it the ears stay within 0.5 mm and the cheeks still widen.
  CHECK(std::abs(ears[1]) < 0.5e-3);
  CHECK(cheeks[1] > 0.5 * cheeks[0]);
}

// fit_pulls.h models the fit's regularizer: with the follow term on, the
// groups' shares at the end of a fit still add up to the displacement
// (with the plain thin plate in their normal equations they do not).
TEST_CASE("with the follow term the fit's pulls still add up to the fitted displacement", "[photos][follow][pulls]") {
  test::PhotoScenario sc = test::make_photo_scenario(2);
  PhotosJobOptions opt;
  opt.fit.follow = 0.01;
  PhotosJobResult r;
  REQUIRE(run_photos_job(sc.generic, sc.map, sc.session.photos, opt, r));
  PhotosFitPulls pulls;
  REQUIRE(measure_photos_fit_pulls(sc.generic, sc.landmarks, sc.session.photos, r.calib, opt, r.fit.mesh.positions, pulls));
  PhotosJobOptions plain = opt;
  plain.fit.follow = 0;
  PhotosFitPulls wrong;
  REQUIRE(measure_photos_fit_pulls(sc.generic, sc.landmarks, sc.session.photos, r.calib, plain, r.fit.mesh.positions, wrong));
  for (size_t k = 0; k < pulls.regions.size(); ++k) {
    std::printf("follow 0.01, %s: fitted %+.3f mm, the shares' sum %+.3f mm (modelled without the term %+.3f mm)\n",
                pulls.regions[k].name.c_str(), 1000 * pulls.end.displacement_m[k], 1000 * pulls.end.explained_m[k],
                1000 * wrong.end.explained_m[k]);
    CHECK(pulls.end.explained_m[k] == Approx(pulls.end.displacement_m[k]).epsilon(0.1).margin(5e-5));
  }
  // The check has power: the plain thin plate's normal equations miss the cheeks by more than 10 %.
  CHECK(std::abs(wrong.end.explained_m[0] - pulls.end.displacement_m[0]) > 0.1 * std::abs(pulls.end.displacement_m[0]));
}

TEST_CASE("likeness photos --follow takes K or K:W and refuses anything else", "[photos][follow][cli]") {
  LK_REQUIRE_LIKENESS();
  const std::string dir = test::scratch_dir("photos_follow_cli");
  const std::string points = test::source_dir() + "/tests/photos/data/kira/0001.json";
  CHECK(test::run_likeness("photos --points " + points + " --levels 0 --no-texture --out " + dir + " --follow 0.003:0") == 0);
  for (const char* bad : {"0.01x", "-1", "0.01:", ":1", "abc"})
    CHECK(test::run_likeness("photos --points " + points + " --levels 0 --no-texture --out " + dir + " --follow " + bad) != 0);
}

}  // namespace
}  // namespace lk
