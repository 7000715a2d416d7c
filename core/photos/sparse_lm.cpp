#include "photos/sparse_lm.h"

#include <cmath>
#include <limits>

namespace lk {

LmReport levenberg_marquardt(LeastSquaresProblem& problem, const LmOptions& options) {
  LmReport report;
  Eigen::VectorXd r;
  SparseMat J;
  problem.linearize(r, J);
  double cost = r.squaredNorm();
  report.initial_cost = report.final_cost = cost;
  double lambda = options.initial_lambda;
  Eigen::SimplicialLDLT<SparseMat> solver;
  bool analyzed = false;
  for (int it = 0; it < options.max_iterations; ++it) {
    const SparseMat JtJ = SparseMat(J.transpose()) * J;
    const Eigen::VectorXd g = J.transpose() * r;
    Eigen::VectorXd diag = JtJ.diagonal();
    const double floor = 1e-12 * std::max(1.0, diag.maxCoeff());
    bool improved = false;
    for (int tries = 0; tries < 12 && !improved; ++tries) {
      SparseMat A = JtJ;
      for (int j = 0; j < A.rows(); ++j) A.coeffRef(j, j) += lambda * std::max(diag[j], floor);
      if (!analyzed) {
        solver.analyzePattern(A);
        analyzed = true;
      }
      solver.factorize(A);
      if (solver.info() != Eigen::Success) {
        lambda *= 10;
        continue;
      }
      const Eigen::VectorXd step = solver.solve(-g);
      if (!step.allFinite()) {
        lambda *= 10;
        continue;
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
    analyzed = false;  // the pattern may change (a weight dropped to zero)
  }
  report.final_cost = cost;
  return report;
}

}  // namespace lk
