#include "fit/block_ldlt.h"

#include <Eigen/SparseCholesky>
#include <catch2/catch.hpp>
#include <random>

using lk::BlockLdlt;
using SpMat = Eigen::SparseMatrix<double>;

namespace {

// A symmetric positive definite 3n by 3n matrix with the block pattern of a
// w by h grid of vertices (each coupled to its 8 neighbours), random dense
// 3x3 couplings, made definite by its diagonal blocks: the shape of the
// global fit's normal equations.
SpMat grid_system(int w, int h, unsigned seed, double diagonal_margin = 1.0) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int n = w * h;
  std::vector<Eigen::Triplet<double>> t;
  std::vector<double> row_sum(3 * n, 0.0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int dy = 0; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          if (dy == 0 && dx <= 0) continue;
          const int x2 = x + dx, y2 = y + dy;
          if (x2 < 0 || x2 >= w || y2 >= h) continue;
          const int a = y * w + x, b = y2 * w + x2;
          for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) {
              const double v = u(rng);
              t.emplace_back(3 * a + r, 3 * b + c, v);
              t.emplace_back(3 * b + c, 3 * a + r, v);
              row_sum[3 * a + r] += std::abs(v);
              row_sum[3 * b + c] += std::abs(v);
            }
        }
  for (int i = 0; i < 3 * n; ++i) t.emplace_back(i, i, row_sum[i] + diagonal_margin);
  SpMat A(3 * n, 3 * n);
  A.setFromTriplets(t.begin(), t.end());
  return A;
}

}  // namespace

TEST_CASE("block LDLT solves a block-sparse SPD system like Eigen's LDLT", "[fit][block_ldlt]") {
  const SpMat A = grid_system(17, 13, 3);
  std::mt19937 rng(5);
  std::normal_distribution<double> g;
  Eigen::VectorXd b(A.rows());
  for (int i = 0; i < b.size(); ++i) b[i] = g(rng);

  BlockLdlt block;
  REQUIRE(block.analyze(A));
  REQUIRE(block.factorize(A));
  const Eigen::VectorXd x = block.solve(b);
  Eigen::SimplicialLDLT<SpMat> reference(A);
  REQUIRE(reference.info() == Eigen::Success);
  const Eigen::VectorXd x_ref = reference.solve(b);
  CHECK((A * x - b).norm() <= 1e-10 * b.norm());
  CHECK((x - x_ref).norm() <= 1e-10 * x_ref.norm());
  // A fill-reducing order: far fewer blocks than the dense lower triangle.
  const long long n = A.rows() / 3;
  CHECK(block.factor_blocks() < n * (n - 1) / 8);

  // New values in the same pattern: factorize again without analyzing.
  SpMat A2 = A;
  for (int k = 0; k < A2.rows(); ++k) A2.coeffRef(k, k) += 3.0 * (k % 5);
  REQUIRE(block.factorize(A2));
  const Eigen::VectorXd x2 = block.solve(b);
  CHECK((A2 * x2 - b).norm() <= 1e-10 * b.norm());
}

TEST_CASE("block LDLT refuses what it cannot factorize", "[fit][block_ldlt]") {
  BlockLdlt block;
  SECTION("not 3n by 3n") {
    CHECK_FALSE(block.analyze(SpMat(4, 4)));
    CHECK_FALSE(block.analyze(SpMat(6, 3)));
    CHECK_FALSE(block.factorize(SpMat(6, 6)));  // never analyzed
  }
  SECTION("indefinite") {
    SpMat A = grid_system(4, 4, 7);
    REQUIRE(block.analyze(A));
    A.coeffRef(10, 10) = -50.0;
    CHECK_FALSE(block.factorize(A));
    CHECK_FALSE(block.factorized());
  }
  SECTION("an entry outside the analyzed pattern") {
    const SpMat A = grid_system(4, 4, 7);
    REQUIRE(block.analyze(A));
    SpMat B = A;
    B.coeffRef(0, 3 * 15) = 0.01;  // vertex 0 and vertex 15 were not coupled
    B.coeffRef(3 * 15, 0) = 0.01;
    CHECK_FALSE(block.factorize(B));
    REQUIRE(block.analyze(B));
    CHECK(block.factorize(B));
  }
  SECTION("size of the matrix changed") {
    REQUIRE(block.analyze(grid_system(4, 4, 7)));
    CHECK_FALSE(block.factorize(grid_system(5, 4, 7)));
  }
}
