// Sparse LDL^T factorization by 3x3 blocks, for the normal equations of
// the global fit (jeong2002 Sec. 4.3; global_fit.h).
//
// The global fit's system has one 3 by 3 block per pair of coupled control
// vertices (point-to-plane distances couple a vertex's x, y, z), so it is
// factorized by vertices: Davis's up-looking LDL (Davis 2005, "Algorithm
// 849: a concise sparse Cholesky factorization package") with 3x3 blocks
// for the scalars, L unit lower block triangular, D block diagonal (each
// D_k a symmetric positive definite 3x3). Same ordering as before (AMD on
// the vertex graph), same factor; each block entry is a small dense product
// instead of nine scalar updates with their index work.
//
// Shapes: the matrix is 3n by 3n (n vertices, coordinates interleaved
// x0 y0 z0 x1 ...), symmetric, given whole (both triangles) as an Eigen
// column-major sparse matrix; right-hand sides are 3n vectors.
#pragma once
#include <Eigen/Core>
#include <Eigen/Sparse>
#include <vector>

namespace lk {

class BlockLdlt {
 public:
  using SpMat = Eigen::SparseMatrix<double>;
  using Block = Eigen::Matrix3d;

  // The block pattern, fill-reducing ordering and elimination tree of A.
  // False when A is not 3n by 3n.
  bool analyze(const SpMat& A);
  // Numeric factorization of A, whose non-zeros must lie in the analyzed
  // block pattern (otherwise call analyze first). False when A is not
  // positive definite (a pivot block is not) or its pattern differs.
  bool factorize(const SpMat& A);
  bool analyzed() const { return analyzed_; }
  bool factorized() const { return factorized_; }
  // x = A^-1 b for the last factorized A (b: 3n).
  Eigen::VectorXd solve(const Eigen::VectorXd& b) const;
  // Non-zero 3x3 blocks of L below the diagonal (for tests and reports).
  long long factor_blocks() const { return static_cast<long long>(lower_rows_.size()); }

 private:
  int n_ = 0;
  bool analyzed_ = false, factorized_ = false;
  std::vector<int> new_of_old_, old_of_new_;  // vertex permutation
  // Input blocks (whole matrix): per block column, sorted block rows.
  std::vector<int> a_start_, a_rows_;
  std::vector<Block> a_values_;
  // Upper part of the permuted matrix, per permuted column k: the input
  // block slots whose permuted row is <= k, with that row.
  std::vector<int> up_start_, up_slot_, up_row_;
  // Factor: elimination tree, per column the count and the rows of L's blocks.
  std::vector<int> parent_, lower_start_, lower_rows_;
  std::vector<Block> lower_values_, d_inverse_;
  // Workspace of factorize.
  std::vector<Block> y_;
  std::vector<int> flag_, pattern_, count_;
};

}  // namespace lk
