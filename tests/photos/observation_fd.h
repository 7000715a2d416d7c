// An observation set's Jacobian over vertex positions (photos/shape_fit.h)
// against central differences of its residuals, column by column: the
// check every observation type of the shape fit gets (features,
// silhouettes, stereo attractors).
#pragma once
#include "photos/shape_fit.h"
#include "photos/sparse_lm.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <vector>

namespace lk::test {

struct FdJacobian {
  Eigen::VectorXd residuals;  // at the positions
  SparseMat jacobian;         // the set's own, at the positions
  double worst_relative = 0;  // max over the columns of |fd - J col| / (1 + |J col|)
  double worst_abs = 0;       // max over the columns and rows of |fd - J|
};

// cols: the coordinates (3 v + axis) to differentiate; h: the step.
inline FdJacobian check_fd_jacobian(const ObservationSet& set, const std::vector<Vec3>& positions,
                                    const std::vector<int>& cols, double h = 1e-7) {
  FdJacobian out;
  out.residuals.resize(set.num_residuals());
  std::vector<Eigen::Triplet<double>> trip;
  REQUIRE(set.evaluate(positions, out.residuals, 0, &trip));
  out.jacobian.resize(set.num_residuals(), 3 * long(positions.size()));
  out.jacobian.setFromTriplets(trip.begin(), trip.end());
  for (int col : cols) {
    std::vector<Vec3> a = positions, b = positions;
    a[size_t(col / 3)][col % 3] += h;
    b[size_t(col / 3)][col % 3] -= h;
    Eigen::VectorXd ra(out.residuals.size()), rb(out.residuals.size());
    REQUIRE(set.evaluate(a, ra, 0, nullptr));
    REQUIRE(set.evaluate(b, rb, 0, nullptr));
    const Eigen::VectorXd fd = (ra - rb) / (2 * h);
    const Eigen::VectorXd an = out.jacobian.col(col);
    out.worst_relative = std::max(out.worst_relative, (fd - an).norm() / (1 + an.norm()));
    if (fd.size()) out.worst_abs = std::max(out.worst_abs, (fd - an).cwiseAbs().maxCoeff());
  }
  return out;
}

}  // namespace lk::test
