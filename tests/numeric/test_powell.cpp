// Powell's method (core/numeric/powell.h): known minima of smooth, curved
// and staircase objectives, budgets, cancellation and bad input.
#include "numeric/powell.h"

#include <catch2/catch.hpp>
#include <cmath>

using lk::ErrorCode;
using lk::PowellOptions;
using lk::PowellResult;
using lk::powell_minimize;

TEST_CASE("line_minimize finds the vertex of a parabola", "[powell]") {
  std::function<double(double)> g = [](double t) { return (t - 3.7) * (t - 3.7) + 2.0; };
  double t = 0, v = 0;
  int evals = 0;
  lk::line_minimize(g, g(0.0), 1e-6, t, v, evals);
  CHECK(t == Approx(3.7).margin(1e-4));
  CHECK(v == Approx(2.0).margin(1e-8));
  CHECK(evals > 2);
  CHECK(evals < 60);
}

TEST_CASE("powell minimizes a coupled quadratic to its known minimum", "[powell]") {
  Eigen::MatrixXd a(4, 4);
  a << 4, 1, 0.5, 0, 1, 3, 0.2, 0.1, 0.5, 0.2, 2, 0.3, 0, 0.1, 0.3, 1;
  Eigen::VectorXd c(4);
  c << 1.5, -2.0, 0.25, 7.0;
  lk::ObjectiveFn f = [&](const Eigen::VectorXd& x) { return (x - c).dot(a * (x - c)) + 5.0; };
  PowellOptions o;
  o.tolerance = 1e-12;
  PowellResult r;
  REQUIRE(powell_minimize(f, Eigen::VectorXd::Zero(4), o, r).ok());
  CHECK(r.converged);
  CHECK((r.x - c).norm() < 1e-4);
  CHECK(r.value == Approx(5.0).margin(1e-7));
  CHECK(r.evaluations > 0);
  CHECK(r.iterations >= 1);
  // Powell's conjugate directions: a quadratic needs only a few sweeps.
  CHECK(r.iterations <= 10);
}

TEST_CASE("powell follows the curved valley of Rosenbrock's function", "[powell]") {
  lk::ObjectiveFn f = [](const Eigen::VectorXd& x) {
    return 100.0 * std::pow(x[1] - x[0] * x[0], 2) + std::pow(1.0 - x[0], 2);
  };
  Eigen::VectorXd x0(2);
  x0 << -1.2, 1.0;
  PowellOptions o;
  o.tolerance = 1e-12;
  o.max_iterations = 500;
  PowellResult r;
  REQUIRE(powell_minimize(f, x0, o, r).ok());
  CHECK(r.x[0] == Approx(1.0).margin(1e-3));
  CHECK(r.x[1] == Approx(1.0).margin(2e-3));
  CHECK(r.value < 1e-6);
  // Never worse than the start, and non-increasing sweep by sweep.
  for (size_t i = 1; i < r.value_per_iteration.size(); ++i)
    CHECK(r.value_per_iteration[i] <= r.value_per_iteration[i - 1]);
}

TEST_CASE("powell handles a piecewise-constant staircase like a pixel count", "[powell]") {
  // Integer-valued, flat almost everywhere, like counting XOR pixels: the
  // count of "pixels" of size 1/40 between x and the target, per coordinate,
  // plus a coupled term.
  Eigen::VectorXd c(3);
  c << 0.3, -0.45, 0.8;
  lk::ObjectiveFn f = [&](const Eigen::VectorXd& x) {
    const Eigen::VectorXd d = x - c;
    double v = 0;
    for (int i = 0; i < 3; ++i) v += std::floor(std::fabs(d[i]) * 40.0);
    v += std::floor(std::fabs(d[0] + d[1]) * 40.0);
    return v;
  };
  PowellOptions o;
  o.initial_step = Eigen::VectorXd::Constant(3, 0.2);
  PowellResult r;
  REQUIRE(powell_minimize(f, Eigen::VectorXd::Zero(3), o, r).ok());
  CHECK(r.value == 0.0);
  CHECK((r.x - c).cwiseAbs().maxCoeff() < 1.0 / 40.0);
  CHECK(r.evaluations < 2000);
}

TEST_CASE("powell respects its evaluation budget and cancellation", "[powell]") {
  int calls = 0;
  lk::ObjectiveFn f = [&](const Eigen::VectorXd& x) {
    ++calls;
    return 100.0 * std::pow(x[1] - x[0] * x[0], 2) + std::pow(1.0 - x[0], 2);
  };
  Eigen::VectorXd x0(2);
  x0 << -1.2, 1.0;
  PowellOptions o;
  o.max_evaluations = 40;
  PowellResult r;
  REQUIRE(powell_minimize(f, x0, o, r).ok());
  CHECK(!r.converged);
  CHECK(r.evaluations <= 40);
  CHECK(calls == r.evaluations);
  CHECK(r.value <= f(x0));

  PowellResult rc;
  lk::ProgressFn stop = [](const char*, double) { return false; };
  const lk::Status st = powell_minimize(f, x0, PowellOptions{}, rc, stop);
  CHECK(st.code == ErrorCode::Cancelled);
  CHECK(rc.x.size() == 2);
}

TEST_CASE("powell rejects bad input with a clear error", "[powell]") {
  lk::ObjectiveFn f = [](const Eigen::VectorXd& x) { return x.squaredNorm(); };
  PowellResult r;
  CHECK(powell_minimize(f, Eigen::VectorXd(), PowellOptions{}, r).code == ErrorCode::InvalidInput);
  Eigen::VectorXd bad(2);
  bad << 1.0, std::nan("");
  CHECK(powell_minimize(f, bad, PowellOptions{}, r).code == ErrorCode::InvalidInput);
  PowellOptions wrong;
  wrong.initial_step = Eigen::VectorXd::Ones(3);
  const lk::Status st = powell_minimize(f, Eigen::VectorXd::Zero(2), wrong, r);
  CHECK(st.code == ErrorCode::InvalidInput);
  CHECK(st.message.find("initial_step") != std::string::npos);
  lk::ObjectiveFn nan_f = [](const Eigen::VectorXd&) { return std::nan(""); };
  CHECK(powell_minimize(nan_f, Eigen::VectorXd::Zero(2), PowellOptions{}, r).code == ErrorCode::InvalidInput);
  // NaN away from the start is treated as +inf, not followed.
  lk::ObjectiveFn holes = [](const Eigen::VectorXd& x) {
    return x[0] > 0.5 ? std::nan("") : (x[0] - 0.4) * (x[0] - 0.4);
  };
  REQUIRE(powell_minimize(holes, Eigen::VectorXd::Zero(1), PowellOptions{}, r).ok());
  CHECK(r.x[0] == Approx(0.4).margin(1e-3));
}
