#include "photos/sparse_lm.h"

#include "fit/block_ldlt.h"
#include "fit/factor_preconditioner.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace lk {
namespace {

// The damped normal matrix's factor: by 3x3 blocks (block_ldlt.h) for a
// problem of vertices, else Eigen's scalar LDLT, whose symbolic analysis
// (fill-reducing ordering, elimination tree) is redone only when the
// pattern changes (a weight dropped to zero removes entries): the same
// pattern gives the same ordering.
class Factor {
 public:
  explicit Factor(bool blocks) : blocks_(blocks) {}
  bool factorize(const SparseMat& A) {
    if (blocks_) return (block_.analyzed() && block_.factorize(A)) || (block_.analyze(A) && block_.factorize(A));
    if (!same_pattern(A)) {
      scalar_.analyzePattern(A);
      outer_.assign(A.outerIndexPtr(), A.outerIndexPtr() + A.outerSize() + 1);
      inner_.assign(A.innerIndexPtr(), A.innerIndexPtr() + A.nonZeros());
    }
    scalar_.factorize(A);
    return scalar_.info() == Eigen::Success;
  }
  Eigen::VectorXd solve(const Eigen::VectorXd& b) const { return blocks_ ? block_.solve(b) : scalar_.solve(b); }

 private:
  bool same_pattern(const SparseMat& A) const {
    return A.isCompressed() && outer_.size() == size_t(A.outerSize() + 1) &&
           std::equal(outer_.begin(), outer_.end(), A.outerIndexPtr()) && inner_.size() == size_t(A.nonZeros()) &&
           std::equal(inner_.begin(), inner_.end(), A.innerIndexPtr());
  }
  bool blocks_;
  BlockLdlt block_;
  Eigen::SimplicialLDLT<SparseMat> scalar_;
  std::vector<int> outer_, inner_;
};

}  // namespace

LmReport levenberg_marquardt(LeastSquaresProblem& problem, const LmOptions& options) {
  LmReport report;
  Eigen::VectorXd r;
  SparseMat J;
  problem.linearize(r, J);
  double cost = r.squaredNorm();
  report.initial_cost = report.final_cost = cost;
  double lambda = options.initial_lambda;
  report.vertex_blocks = problem.vertex_blocks() && problem.num_parameters() % 3 == 0;
  Factor solver(report.vertex_blocks);
  // Once a matrix is factored, the next ones (a smaller lambda, the next
  // linearization: close to it) are solved by conjugate gradients with that
  // factor as the preconditioner, which converge in a few iterations at a
  // fraction of a factorization's cost; where they do not, the matrix is
  // factored anew.
  bool factored = false;
  FactorPreconditionedCg<Factor> cg;
  cg.preconditioner().factor = &solver;
  cg.setMaxIterations(options.cg_max_iterations);
  cg.setTolerance(options.cg_tolerance);
  for (int it = 0; it < options.max_iterations; ++it) {
    const SparseMat JtJ = SparseMat(J.transpose()) * J;
    const Eigen::VectorXd g = J.transpose() * r;
    Eigen::VectorXd diag = JtJ.diagonal();
    const double floor = 1e-12 * std::max(1.0, diag.maxCoeff());
    bool improved = false;
    for (int tries = 0; tries < 12 && !improved; ++tries) {
      SparseMat A = JtJ;
      for (int j = 0; j < A.rows(); ++j) A.coeffRef(j, j) += lambda * std::max(diag[j], floor);
      A.makeCompressed();
      Eigen::VectorXd step;
      bool solved = false;
      if (factored && options.cg_max_iterations > 0) {
        cg.compute(A);
        step = cg.solve(-g);
        solved = cg.info() == Eigen::Success && step.allFinite();
        report.cg_solves += solved;
        // A slow solve: the factor has drifted from the matrices; the next is factored.
        if (cg.iterations() > options.cg_refactor_iterations) factored = false;
      }
      if (!solved) {
        factored = solver.factorize(A);
        ++report.factorizations;
        if (!factored) {
          lambda *= 10;
          continue;
        }
        step = solver.solve(-g);
        if (!step.allFinite()) {
          lambda *= 10;
          continue;
        }
      }
      const double trial = problem.cost_after(step);
      if (trial < cost) {
        problem.apply(step);
        const double gain = cost - trial;
        lambda = std::max(lambda * 0.3, 1e-12);
        improved = true;
        ++report.iterations;
        report.costs.push_back(trial);
        cost = trial;
        if (gain < options.relative_tolerance * cost) {
          report.final_cost = cost;
          return report;
        }
      } else {
        lambda *= 10;
      }
    }
    if (!improved) break;
    problem.linearize(r, J);
    cost = r.squaredNorm();
  }
  report.final_cost = cost;
  return report;
}

}  // namespace lk
