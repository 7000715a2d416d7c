// First-order and quasi-Newton minimizers of the same least-squares problems
// LM solves (sparse_lm.h), for fua1998's Fig. 6-7 comparison ("the same
// weighing parameters and the same schedule ... but different optimization
// techniques"; the paper compares LM with an Euler-Lagrange solver and
// MINOS, we with plain gradient descent and L-BFGS). Not used by the app:
// LM is the one the paper and the page use.
//
// Both minimize f(x) = ||r(x)||^2 with gradient 2 J^T r from the problem's
// linearize(); the state moves by apply(), so x is the sum of the steps.
#pragma once
#include "photos/sparse_lm.h"

namespace lk {

struct DescentOptions {
  int max_iterations = 500;
  double relative_tolerance = 1e-9;  // stop when an iteration gains less than this share of the cost
  int lbfgs_memory = 8;              // L-BFGS: corrections kept
};

// Steepest descent with a backtracking (Armijo) line search; the step
// length carries over between iterations (doubled after an accepted step).
LmReport gradient_descent(LeastSquaresProblem& problem, const DescentOptions& options = {});

// L-BFGS (LBFGS++, Debian's liblbfgspp-dev) with a strong-Wolfe line
// search (Nocedal and Wright's; Armijo alone lets the curvature pairs go
// bad). A line search that fails ends the run at the best state found.
LmReport quasi_newton(LeastSquaresProblem& problem, const DescentOptions& options = {});

}  // namespace lk
