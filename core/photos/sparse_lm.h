// Levenberg-Marquardt on the sparse normal equations (fua1998 Sec. 2: "the
// optimization is performed using the Levenberg-Marquardt algorithm", the
// stiffness added "to the matrix that appears in the normal equations").
//
// Our own loop on Eigen's SimplicialLDLT rather than Eigen's unsupported
// LevenbergMarquardt: that module solves each step by QR of the Jacobian
// (SparseQR for sparse problems, far slower than a Cholesky of J^T J here),
// and the stages need hooks it lacks: states that are not vectors (rotations
// updated multiplicatively), iterative reweighting between runs, and a
// trial-step cost without re-linearizing. Marquardt's scaling: the damped
// matrix is J^T J + lambda * diag(J^T J).
#pragma once
#include "common/types.h"

#include <Eigen/Sparse>
#include <vector>

namespace lk {

using SparseMat = Eigen::SparseMatrix<double>;

// A problem: minimize ||r(x)||^2 over a state the problem keeps.
class LeastSquaresProblem {
 public:
  virtual ~LeastSquaresProblem() = default;
  virtual int num_parameters() const = 0;
  // Residuals and their Jacobian (#r by num_parameters) at the current state.
  virtual void linearize(Eigen::VectorXd& r, SparseMat& J) = 0;
  // ||r||^2 at the current state moved by step (the state is unchanged);
  // +inf when the moved state is invalid (e.g. a point behind a camera).
  virtual double cost_after(const Eigen::VectorXd& step) = 0;
  virtual void apply(const Eigen::VectorXd& step) = 0;
  // True when the parameters are vertices' x, y, z (interleaved) and
  // J^T J couples them by 3x3 blocks: the steps are then factored by
  // blocks (fit/block_ldlt.h), the same factor at less cost.
  virtual bool vertex_blocks() const { return false; }
};

struct LmOptions {
  int max_iterations = 50;
  double initial_lambda = 1e-3;
  double relative_tolerance = 1e-9;  // stop when a step gains less than this share of the cost
  // Steps after a factorization: conjugate gradients preconditioned by it,
  // to this relative residual within cg_max_iterations (else the matrix is
  // factored); a solve that took more than cg_refactor_iterations has the
  // next matrix factored (on the photos head's control mesh a factorization
  // costs about 50 iterations: 25-30 ms by vertex blocks, 0.55 ms an
  // iteration). cg_max_iterations 0: every step factored.
  double cg_tolerance = 1e-10;
  int cg_refactor_iterations = 20;
  int cg_max_iterations = 40;
};

struct LmReport {
  int iterations = 0;
  double initial_cost = 0, final_cost = 0;
  std::vector<double> costs;  // after each accepted step
  int factorizations = 0, cg_solves = 0;  // how the steps were solved
  bool vertex_blocks = false;             // factored by 3x3 vertex blocks
};

LmReport levenberg_marquardt(LeastSquaresProblem& problem, const LmOptions& options = {});

}  // namespace lk
