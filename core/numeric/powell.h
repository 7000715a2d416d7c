// Powell's direction-set minimization without derivatives, as used by
// jeong2002 Sec. 4.1 (initial alignment) and Sec. 4.2 (local alignment).
// Numerical Recipes in C, 2nd ed., Sec. 10.5 ("powell" with the heuristic
// that replaces the direction of largest decrease), with Sec. 10.1 bracketing
// ("mnbrak") and Sec. 10.2 Brent line minimization ("brent").
//
// Shapes: x is an n-vector; the direction set is n directions of n entries.
// Works on non-smooth objectives such as pixel counts: no gradients are used
// and the line search falls back to golden sections on plateaus.
#pragma once
#include "common/progress.h"
#include "common/status.h"

#include <Eigen/Core>
#include <functional>
#include <vector>

namespace lk {

// The function to minimize. It may return +infinity for infeasible points;
// NaN is treated as +infinity.
using ObjectiveFn = std::function<double(const Eigen::VectorXd& x)>;

struct PowellOptions {
  // Stop when one full sweep over the directions lowers f by less than this
  // fraction: 2|f_old - f_new| <= tolerance (|f_old| + |f_new|) + 1e-25 (NR's ftol).
  double tolerance = 1e-6;
  // Relative tolerance of each line minimization along a direction, in units
  // of that direction's length (NR's TOL for brent; 2e-4 is NR's default).
  double line_tolerance = 2e-4;
  // Absolute part of that tolerance, in the same units: a line search stops
  // once it knows the minimum to within line_tolerance * |t| + this. Raise it
  // to the scale below which f cannot change (e.g. a quarter pixel for pixel
  // counts) to save evaluations on plateaus.
  double line_absolute_tolerance = 1e-6;
  // Upper bounds on sweeps and on calls of the objective; reaching either
  // returns the best point so far with converged = false.
  int max_iterations = 200;
  int max_evaluations = 100000;
  // Initial length of the search direction along each coordinate: the step
  // the first line search brackets with. Empty means 1 for every parameter.
  // Choose it as "how far a parameter may plausibly be off".
  Eigen::VectorXd initial_step;
};

struct PowellResult {
  Eigen::VectorXd x;          // best point found (n)
  double value = 0.0;         // f(x)
  int evaluations = 0;        // calls of the objective
  int iterations = 0;         // full sweeps over the direction set
  bool converged = false;     // tolerance reached (not a budget limit)
  std::vector<double> value_per_iteration;  // f after each sweep, for monotonicity checks
};

// Minimizes f starting at x0. Fails with InvalidInput for an empty x0, a
// non-finite x0 or step, or a step of the wrong size; with InvalidInput when
// f(x0) is not finite; with Cancelled when progress returns false (checked
// once per sweep; out then holds the best point so far). Hitting
// max_iterations / max_evaluations is not an error: out.converged is false.
Status powell_minimize(const ObjectiveFn& f, const Eigen::VectorXd& x0,
                       const PowellOptions& options, PowellResult& out,
                       const ProgressFn& progress = {});

// One-dimensional minimization of g along the line through 0 and step
// (NR mnbrak + brent): returns the minimizing multiple t of the step in
// t_out and g(t_out) in value_out; g(0) must be given as g0. Counts calls
// of g in evaluations. Exposed for tests and for callers with one parameter.
void line_minimize(const std::function<double(double)>& g, double g0, double tolerance,
                   double& t_out, double& value_out, int& evaluations,
                   int max_evaluations = 1000, double absolute_tolerance = 1e-6);

}  // namespace lk
