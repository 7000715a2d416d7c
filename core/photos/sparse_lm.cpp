#include "photos/sparse_lm.h"

#include <Eigen/IterativeLinearSolvers>
#include <algorithm>
#include <cmath>
#include <limits>

namespace lk {
namespace {

// Eigen's preconditioner interface over an existing LDLT factor (of a
// nearby matrix): solve() applies its inverse.
struct FactorPreconditioner {
  const Eigen::SimplicialLDLT<SparseMat>* factor = nullptr;
  template <typename M> FactorPreconditioner& analyzePattern(const M&) { return *this; }
  template <typename M> FactorPreconditioner& factorize(const M&) { return *this; }
  template <typename M> FactorPreconditioner& compute(const M&) { return *this; }
  Eigen::VectorXd solve(const Eigen::VectorXd& b) const { return factor->solve(b); }
  Eigen::ComputationInfo info() const { return Eigen::Success; }
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
  Eigen::SimplicialLDLT<SparseMat> solver;
  // The symbolic analysis (fill-reducing ordering, elimination tree) is
  // redone only when J^T J's pattern changes (a weight dropped to zero
  // removes entries): the same pattern gives the same ordering.
  std::vector<int> analyzed_outer, analyzed_inner;
  const auto same_pattern = [&](const SparseMat& A) {
    return A.isCompressed() && analyzed_outer.size() == size_t(A.outerSize() + 1) &&
           std::equal(analyzed_outer.begin(), analyzed_outer.end(), A.outerIndexPtr()) &&
           analyzed_inner.size() == size_t(A.nonZeros()) &&
           std::equal(analyzed_inner.begin(), analyzed_inner.end(), A.innerIndexPtr());
  };
  // Once a matrix is factored, the next ones (a smaller lambda, the next
  // linearization: close to it) are solved by conjugate gradients with that
  // factor as the preconditioner, which converge in a few iterations at a
  // fraction of a factorization's cost; where they do not, the matrix is
  // factored anew.
  bool factored = false;
  Eigen::ConjugateGradient<SparseMat, Eigen::Lower | Eigen::Upper, FactorPreconditioner> cg;
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
        if (!same_pattern(A)) {
          solver.analyzePattern(A);
          analyzed_outer.assign(A.outerIndexPtr(), A.outerIndexPtr() + A.outerSize() + 1);
          analyzed_inner.assign(A.innerIndexPtr(), A.innerIndexPtr() + A.nonZeros());
        }
        solver.factorize(A);
        ++report.factorizations;
        factored = solver.info() == Eigen::Success;
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
