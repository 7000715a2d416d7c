// A factor of one matrix as the preconditioner of conjugate gradients on
// the next: the global fit (global_fit.cpp) and the photos' sparse LM
// (photos/sparse_lm.cpp) factor their normal matrix once and solve the
// following, nearby ones (moved correspondences, a smaller damping) by
// Eigen's ConjugateGradient with that factor, a few cheap triangular
// solves instead of a new factorization.
//
// Factor: anything with `Eigen::VectorXd solve(const Eigen::VectorXd&) const`
// (BlockLdlt, Eigen's SimplicialLDLT, ...). The factor is not owned and is
// never recomputed here: compute() on the solver leaves it as it is.
#pragma once
#include <Eigen/Core>
#include <Eigen/IterativeLinearSolvers>
#include <Eigen/Sparse>

namespace lk {

template <typename Factor>
struct FactorPreconditioner {
  const Factor* factor = nullptr;
  template <typename M> FactorPreconditioner& analyzePattern(const M&) { return *this; }
  template <typename M> FactorPreconditioner& factorize(const M&) { return *this; }
  template <typename M> FactorPreconditioner& compute(const M&) { return *this; }
  Eigen::VectorXd solve(const Eigen::VectorXd& b) const { return factor->solve(b); }
  Eigen::ComputationInfo info() const { return Eigen::Success; }
};

// Conjugate gradients on a symmetric matrix given whole (both triangles),
// preconditioned by a factor of a nearby matrix.
template <typename Factor>
using FactorPreconditionedCg =
    Eigen::ConjugateGradient<Eigen::SparseMatrix<double>, Eigen::Lower | Eigen::Upper, FactorPreconditioner<Factor>>;

}  // namespace lk
