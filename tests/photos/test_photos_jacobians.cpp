// Residual Jacobians against central finite differences; LM lowers the cost.
#include "common/prng.h"
#include "photos/self_calibration.h"
#include "photos/shape_fit.h"
#include "observation_fd.h"
#include "photos_scenario.h"

namespace lk {
namespace {

TEST_CASE("the projection residual's Jacobian matches finite differences", "[photos]") {
  SplitMix64 rng(7);
  for (int trial = 0; trial < 20; ++trial) {
    Camera c;
    c.fx = c.fy = rng.uniform(800, 2000);
    c.cx = 600;
    c.cy = 800;
    c.R = Eigen::AngleAxisd(rng.uniform(-3, 3), Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)).normalized())
              .toRotationMatrix();
    const Vec3 X(rng.uniform(-0.1, 0.1), rng.uniform(-0.1, 0.1), rng.uniform(-0.1, 0.1));
    c.t = Vec3(rng.uniform(-0.05, 0.05), rng.uniform(-0.05, 0.05), 0.6);
    const Vec2 obs(rng.uniform(0, 1200), rng.uniform(0, 1600));
    ProjectionJacobian J;
    REQUIRE(projection_jacobian(c, X, obs, J));
    auto res = [&](const Camera& cc, const Vec3& XX) {
      ProjectionJacobian j;
      REQUIRE(projection_jacobian(cc, XX, obs, j));
      return j.residual;
    };
    const double h = 1e-6;
    // focal
    {
      Camera a = c, b = c;
      a.fx = a.fy = c.fx + h * 1000;
      b.fx = b.fy = c.fx - h * 1000;
      const Vec2 fd = (res(a, X) - res(b, X)) / (2 * h * 1000);
      CHECK((fd - J.d_focal).norm() < 1e-6 * (1 + J.d_focal.norm()));
    }
    for (int k = 0; k < 3; ++k) {
      Vec3 e = Vec3::Zero();
      e[k] = h;
      Camera a = c, b = c;
      a.R = Eigen::AngleAxisd(h, Vec3::Unit(k)).toRotationMatrix() * c.R;
      b.R = Eigen::AngleAxisd(-h, Vec3::Unit(k)).toRotationMatrix() * c.R;
      const Vec2 fr = (res(a, X) - res(b, X)) / (2 * h);
      CHECK((fr - J.d_rotation.col(k)).norm() < 1e-4 * (1 + J.d_rotation.col(k).norm()));
      a = c;
      b = c;
      a.t += e;
      b.t -= e;
      const Vec2 ft = (res(a, X) - res(b, X)) / (2 * h);
      CHECK((ft - J.d_translation.col(k)).norm() < 1e-4 * (1 + J.d_translation.col(k).norm()));
      const Vec2 fx = (res(c, X + e) - res(c, X - e)) / (2 * h);
      CHECK((fx - J.d_point.col(k)).norm() < 1e-4 * (1 + J.d_point.col(k).norm()));
    }
  }
}

TEST_CASE("the feature observations' Jacobian over vertex positions matches finite differences", "[photos]") {
  test::PhotoScenario s = test::make_photo_scenario(3);
  std::vector<FeatureObservation> obs;
  for (size_t c = 0; c < s.session.photos.size(); ++c)
    for (size_t m = 0; m < s.landmarks.size(); m += 37)
      if (s.session.photos[c].present[m]) obs.push_back({int(c), s.landmarks[m], s.session.photos[c].points[m], 0.7, 0.7});
  REQUIRE(obs.size() > 20);
  // Some points off the surface (a re-made map's offsets, landmark_learning.h).
  for (size_t i = 0; i < obs.size(); i += 2) obs[i].point.offset = Vec3(0.001, -0.002, 0.004);
  FeatureSet set(s.generic.mesh, s.session.cameras, obs, 4.0);
  // Every coordinate of the vertices the observations touch.
  std::vector<int> cols;
  for (const auto& o : obs)
    for (int v : s.generic.mesh.triangles[size_t(o.point.triangle)])
      for (int k = 0; k < 3; ++k) cols.push_back(3 * v + k);
  const double worst = test::check_fd_jacobian(set, s.generic.mesh.positions, cols).worst_relative;
  CHECK(worst < 1e-4);
}

TEST_CASE("Levenberg-Marquardt lowers the shape fit's cost at every stage", "[photos]") {
  test::PhotoScenario s = test::make_photo_scenario(4);
  std::vector<FeatureObservation> obs;
  for (size_t c = 0; c < s.session.photos.size(); ++c)
    for (size_t m = 0; m < s.landmarks.size(); ++m)
      if (s.session.photos[c].present[m] && s.landmarks[m].valid())
        obs.push_back({int(c), s.landmarks[m], s.session.photos[c].points[m], 1, 1});
  std::vector<std::unique_ptr<ObservationSet>> sets;
  sets.push_back(std::make_unique<FeatureSet>(s.generic.mesh, s.session.cameras, obs, 4.0));
  ShapeFitResult r;
  REQUIRE(fit_shape(s.generic.mesh, sets, {0.3}, ShapeFitOptions{}, r));
  REQUIRE(!r.stages.empty());
  for (const ShapeFitStage& st : r.stages) {
    CHECK(st.lm_iterations > 0);
    CHECK(st.final_cost < st.initial_cost);
  }
  // With the true cameras the landmarks come within about the noise.
  CHECK(r.final_rms_px < 0.5 * r.initial_rms_px);
  CHECK(r.final_rms_px < 4.0);
}

}  // namespace
}  // namespace lk

namespace lk {
namespace {

// eq. 7: after weighting, each type's rows have RMS gradient norm lambda,
// whatever the type's own units (here: the same features seen by cameras of
// twice the focal, i.e. residuals and gradients twice as large).
TEST_CASE("eq. 7 gives every observation type the RMS gradient lambda", "[photos]") {
  test::PhotoScenario s = test::make_photo_scenario(3);
  std::vector<FeatureObservation> obs;
  for (size_t c = 0; c < s.session.photos.size(); ++c)
    for (size_t m = 0; m < s.landmarks.size(); m += 5)
      if (s.session.photos[c].present[m]) obs.push_back({int(c), s.landmarks[m], s.session.photos[c].points[m], 1, 1});
  std::vector<Camera> doubled = s.session.cameras;
  for (Camera& c : doubled) c.fx = c.fy = 2 * c.fx;
  std::vector<std::unique_ptr<ObservationSet>> sets;
  sets.push_back(std::make_unique<FeatureSet>(s.generic.mesh, s.session.cameras, obs, 4.0));
  sets.push_back(std::make_unique<FeatureSet>(s.generic.mesh, doubled, obs, 4.0));
  const std::vector<double> lambdas = {0.3, 1.0};
  const std::vector<double> w = observation_type_weights(s.generic.mesh.positions, sets, lambdas);
  REQUIRE(w.size() == 2);
  for (size_t k = 0; k < 2; ++k) {
    Eigen::VectorXd r(sets[k]->num_residuals());
    std::vector<Eigen::Triplet<double>> trip;
    REQUIRE(sets[k]->evaluate(s.generic.mesh.positions, r, 0, &trip));
    SparseMat J(r.size(), 3 * s.generic.mesh.num_vertices());
    J.setFromTriplets(trip.begin(), trip.end());
    const double rms = w[k] * std::sqrt(J.squaredNorm() / double(r.size()));
    CHECK(rms == Approx(lambdas[k]).epsilon(1e-9));
  }
  // Twice the focal: about twice the gradient, so about half the weight per unit lambda.
  CHECK(w[1] / lambdas[1] == Approx(0.5 * w[0] / lambdas[0]).epsilon(0.02));
}

}  // namespace
}  // namespace lk
