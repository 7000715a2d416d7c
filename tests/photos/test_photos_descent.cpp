// The alternatives to LM of fua1998 Fig. 6's comparison (photos/descent.h):
// on problems with a known minimum they find it (L-BFGS) or go downhill
// towards it (gradient descent), and in the shape fit they lower the cost
// as LM does.
#include "photos/descent.h"
#include "photos/shape_fit.h"
#include "photos_scenario.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <random>

namespace lk {
namespace {

// Rosenbrock as least squares: r = (10 (y - x^2), 1 - x), minimum 0 at (1, 1);
// a narrow curved valley that steepest descent crosses slowly. Cost_after
// refuses x < -5 (an invalid state) to check the line searches back off.
class Rosenbrock : public LeastSquaresProblem {
 public:
  Eigen::Vector2d x{-1.2, 1.0};
  int num_parameters() const override { return 2; }
  static Eigen::Vector2d residual(const Eigen::Vector2d& p) { return {10 * (p.y() - p.x() * p.x()), 1 - p.x()}; }
  void linearize(Eigen::VectorXd& r, SparseMat& J) override {
    r = residual(x);
    J.resize(2, 2);
    std::vector<Eigen::Triplet<double>> t = {{0, 0, -20 * x.x()}, {0, 1, 10}, {1, 0, -1}};
    J.setFromTriplets(t.begin(), t.end());
  }
  double cost_after(const Eigen::VectorXd& step) override {
    const Eigen::Vector2d p = x + step;
    return p.x() < -5 ? std::numeric_limits<double>::infinity() : residual(p).squaredNorm();
  }
  void apply(const Eigen::VectorXd& step) override { x += step; }
};

// A linear least-squares problem ||A x - b||^2 (A 40 x 12, well conditioned).
class Linear : public LeastSquaresProblem {
 public:
  Eigen::MatrixXd A;
  Eigen::VectorXd b, x;
  Linear() {
    std::mt19937 rng(7);
    std::normal_distribution<double> n;
    A = Eigen::MatrixXd::NullaryExpr(40, 12, [&] { return n(rng); });
    b = Eigen::VectorXd::NullaryExpr(40, [&] { return n(rng); });
    x = Eigen::VectorXd::Zero(12);
  }
  int num_parameters() const override { return 12; }
  void linearize(Eigen::VectorXd& r, SparseMat& J) override {
    r = A * x - b;
    J = A.sparseView();
  }
  double cost_after(const Eigen::VectorXd& step) override { return (A * (x + step) - b).squaredNorm(); }
  void apply(const Eigen::VectorXd& step) override { x += step; }
  double optimum() const {
    const Eigen::VectorXd best = A.colPivHouseholderQr().solve(b);
    return (A * best - b).squaredNorm();
  }
};

TEST_CASE("L-BFGS finds the minimum of a linear least-squares problem and of Rosenbrock's valley", "[photos]") {
  Linear lin;
  const LmReport a = quasi_newton(lin);
  CHECK(a.final_cost < a.initial_cost);
  CHECK(a.final_cost == Approx(lin.optimum()).epsilon(1e-6));
  CHECK(lin.cost_after(Eigen::VectorXd::Zero(12)) == Approx(a.final_cost));  // the state is the one reported

  Rosenbrock rb;
  DescentOptions o;
  o.max_iterations = 2000;
  o.relative_tolerance = 1e-14;
  const LmReport q = quasi_newton(rb, o);
  INFO("cost " << q.final_cost << " after " << q.iterations << " iterations at " << rb.x.transpose());
  CHECK(q.final_cost < 1e-8);
  CHECK(std::abs(rb.x.x() - 1) < 1e-3);
  CHECK(std::abs(rb.x.y() - 1) < 1e-3);
}

TEST_CASE("gradient descent goes downhill on every accepted step and approaches the minimum", "[photos]") {
  Linear lin;
  DescentOptions o;
  o.max_iterations = 3000;
  o.relative_tolerance = 1e-14;
  const LmReport g = gradient_descent(lin, o);
  REQUIRE(g.iterations > 0);
  for (size_t i = 1; i < g.costs.size(); ++i) CHECK(g.costs[i] <= g.costs[i - 1]);
  // Well conditioned: steepest descent gets there, only more slowly.
  CHECK(g.final_cost == Approx(lin.optimum()).epsilon(1e-4));

  Rosenbrock rb;
  const LmReport r = gradient_descent(rb);
  CHECK(r.final_cost < 0.1 * r.initial_cost);  // downhill, but far slower than L-BFGS in the valley
  CHECK(rb.x.x() >= -5);                       // never into the invalid state
}

TEST_CASE("the shape fit lowers its cost with gradient descent and L-BFGS too", "[photos]") {
  test::PhotoScenario s = test::make_photo_scenario(4);
  std::vector<FeatureObservation> obs;
  for (size_t c = 0; c < s.session.photos.size(); ++c)
    for (size_t m = 0; m < s.landmarks.size(); ++m)
      if (s.session.photos[c].present[m] && s.landmarks[m].valid())
        obs.push_back({int(c), s.landmarks[m], s.session.photos[c].points[m], 1, 1});
  for (auto optimizer : {ShapeFitOptions::Optimizer::GradientDescent, ShapeFitOptions::Optimizer::QuasiNewton}) {
    std::vector<std::unique_ptr<ObservationSet>> sets;
    sets.push_back(std::make_unique<FeatureSet>(s.generic.mesh, s.session.cameras, obs, 4.0));
    ShapeFitOptions o;
    o.optimizer = optimizer;
    o.max_descent_iterations = 100;
    ShapeFitResult r;
    REQUIRE(fit_shape(s.generic.mesh, sets, {0.3}, o, r));
    for (const ShapeFitStage& st : r.stages) {
      CHECK(st.lm_iterations > 0);
      CHECK(st.final_cost < st.initial_cost);
    }
    CHECK(r.final_rms_px < r.initial_rms_px);
  }
}

}  // namespace
}  // namespace lk
