#include "photos/descent.h"

#include <LBFGS.h>

#include <cmath>
#include <limits>
#include <stdexcept>

namespace lk {
namespace {

// f and its gradient at the problem's current state.
double cost_and_gradient(LeastSquaresProblem& problem, Eigen::VectorXd& grad) {
  Eigen::VectorXd r;
  SparseMat J;
  problem.linearize(r, J);
  grad = 2.0 * (J.transpose() * r);
  return r.squaredNorm();
}

}  // namespace

LmReport gradient_descent(LeastSquaresProblem& problem, const DescentOptions& options) {
  LmReport report;
  Eigen::VectorXd g;
  double cost = cost_and_gradient(problem, g);
  report.initial_cost = report.final_cost = cost;
  double alpha = 0;  // step length along -g; first guess: a step of 1e-3 of the cost's scale
  for (int it = 0; it < options.max_iterations; ++it) {
    const double gg = g.squaredNorm();
    if (!(gg > 0)) break;
    if (alpha <= 0) alpha = 1e-3 * std::max(cost, 1e-300) / gg;
    bool accepted = false;
    for (int tries = 0; tries < 40; ++tries) {
      const Eigen::VectorXd step = -alpha * g;
      const double trial = problem.cost_after(step);
      if (trial <= cost - 1e-4 * alpha * gg) {  // Armijo's sufficient decrease
        problem.apply(step);
        const double gain = cost - trial;
        cost = trial;
        report.costs.push_back(cost);
        ++report.iterations;
        accepted = true;
        alpha *= 2;
        if (gain < options.relative_tolerance * cost) {
          report.final_cost = cost;
          return report;
        }
        break;
      }
      alpha *= 0.5;
    }
    if (!accepted) break;
    cost = cost_and_gradient(problem, g);
  }
  report.final_cost = cost;
  return report;
}

LmReport quasi_newton(LeastSquaresProblem& problem, const DescentOptions& options) {
  LmReport report;
  const int n = problem.num_parameters();
  // x: the sum of the steps applied so far (the problem keeps its state).
  Eigen::VectorXd applied = Eigen::VectorXd::Zero(n);
  double best = std::numeric_limits<double>::infinity();
  Eigen::VectorXd best_x = applied;
  int improvements = 0;
  auto objective = [&](const Eigen::VectorXd& x, Eigen::VectorXd& grad) {
    const Eigen::VectorXd step = x - applied;
    if (problem.cost_after(step) == std::numeric_limits<double>::infinity()) {
      grad.setZero(n);  // an invalid state (behind a camera): the line search backs off
      return std::numeric_limits<double>::infinity();
    }
    problem.apply(step);
    applied = x;
    const double f = cost_and_gradient(problem, grad);
    if (best == std::numeric_limits<double>::infinity()) report.initial_cost = f;  // the first call, at x = 0
    else if (f < best) ++improvements;
    if (f < best) {
      best = f;
      best_x = x;
    }
    return f;
  };
  LBFGSpp::LBFGSParam<double> param;
  param.m = options.lbfgs_memory;
  param.max_iterations = options.max_iterations;
  param.epsilon = 1e-12;
  param.epsilon_rel = 1e-12;
  param.past = 1;
  param.delta = options.relative_tolerance;
  param.linesearch = LBFGSpp::LBFGS_LINESEARCH_BACKTRACKING_STRONG_WOLFE;
  LBFGSpp::LBFGSSolver<double, LBFGSpp::LineSearchNocedalWright> solver(param);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
  double fx = 0;
  try {
    report.iterations = solver.minimize(objective, x, fx);
  } catch (const std::exception&) {
    report.iterations = improvements;  // the line search gave up: the best state is kept
  }
  problem.apply(best_x - applied);
  report.final_cost = best;
  report.costs.push_back(best);
  return report;
}

}  // namespace lk
