#include "fit/block_ldlt.h"

#include <Eigen/Cholesky>
#include <Eigen/OrderingMethods>
#include <algorithm>

namespace lk {

bool BlockLdlt::analyze(const SpMat& A) {
  analyzed_ = factorized_ = false;
  if (A.rows() != A.cols() || A.rows() % 3 != 0) return false;
  n_ = static_cast<int>(A.rows() / 3);

  // Block pattern of the whole matrix, the diagonal always in.
  a_start_.assign(n_ + 1, 0);
  a_rows_.clear();
  std::vector<int> rows;
  for (int bj = 0; bj < n_; ++bj) {
    rows.assign(1, bj);
    for (int c = 0; c < 3; ++c)
      for (SpMat::InnerIterator it(A, 3 * bj + c); it; ++it) rows.push_back(static_cast<int>(it.row() / 3));
    std::sort(rows.begin(), rows.end());
    rows.erase(std::unique(rows.begin(), rows.end()), rows.end());
    a_rows_.insert(a_rows_.end(), rows.begin(), rows.end());
    a_start_[bj + 1] = static_cast<int>(a_rows_.size());
  }
  a_values_.assign(a_rows_.size(), Block::Zero());

  // Approximate minimum degree on the vertex graph (a vertex's x, y, z stay
  // together). Eigen's ordering gives, for each new position, the old index.
  {
    std::vector<Eigen::Triplet<double>> t;
    t.reserve(a_rows_.size());
    for (int bj = 0; bj < n_; ++bj)
      for (int s = a_start_[bj]; s < a_start_[bj + 1]; ++s) t.emplace_back(a_rows_[s], bj, 1.0);
    SpMat graph(n_, n_);
    graph.setFromTriplets(t.begin(), t.end());
    Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> amd;
    Eigen::AMDOrdering<int>()(graph, amd);
    old_of_new_.assign(amd.indices().data(), amd.indices().data() + n_);
    new_of_old_.assign(n_, 0);
    for (int k = 0; k < n_; ++k) new_of_old_[old_of_new_[k]] = k;
  }

  // Upper part of the permuted matrix by permuted columns: input block
  // (i, j) lands at (new i, new j); it is used where new i <= new j (its
  // mirror (j, i) serves the other triangle).
  up_start_.assign(n_ + 1, 0);
  for (int bj = 0; bj < n_; ++bj)
    for (int s = a_start_[bj]; s < a_start_[bj + 1]; ++s)
      if (new_of_old_[a_rows_[s]] <= new_of_old_[bj]) ++up_start_[new_of_old_[bj] + 1];
  for (int k = 0; k < n_; ++k) up_start_[k + 1] += up_start_[k];
  up_slot_.assign(up_start_[n_], 0);
  up_row_.assign(up_start_[n_], 0);
  {
    std::vector<int> next(up_start_.begin(), up_start_.end() - 1);
    for (int bj = 0; bj < n_; ++bj)
      for (int s = a_start_[bj]; s < a_start_[bj + 1]; ++s) {
        const int i = new_of_old_[a_rows_[s]], k = new_of_old_[bj];
        if (i > k) continue;
        up_slot_[next[k]] = s;
        up_row_[next[k]++] = i;
      }
  }

  // Elimination tree and column counts of L (Davis's ldl_symbolic).
  parent_.assign(n_, -1);
  flag_.assign(n_, -1);
  count_.assign(n_, 0);
  for (int k = 0; k < n_; ++k) {
    flag_[k] = k;
    for (int p = up_start_[k]; p < up_start_[k + 1]; ++p)
      for (int i = up_row_[p]; flag_[i] != k; i = parent_[i]) {
        if (parent_[i] == -1) parent_[i] = k;
        ++count_[i];
        flag_[i] = k;
      }
  }
  lower_start_.assign(n_ + 1, 0);
  for (int k = 0; k < n_; ++k) lower_start_[k + 1] = lower_start_[k] + count_[k];
  lower_rows_.assign(lower_start_[n_], 0);
  lower_values_.assign(lower_start_[n_], Block::Zero());
  d_inverse_.assign(n_, Block::Zero());
  y_.assign(n_, Block::Zero());
  pattern_.assign(n_, 0);
  analyzed_ = true;
  return true;
}

bool BlockLdlt::factorize(const SpMat& A) {
  factorized_ = false;
  if (!analyzed_ || A.rows() != 3 * n_ || A.cols() != 3 * n_) return false;
  // Gather A's scalars into the analyzed blocks.
  std::fill(a_values_.begin(), a_values_.end(), Block::Zero());
  for (int bj = 0; bj < n_; ++bj) {
    const auto first = a_rows_.begin() + a_start_[bj], last = a_rows_.begin() + a_start_[bj + 1];
    for (int c = 0; c < 3; ++c)
      for (SpMat::InnerIterator it(A, 3 * bj + c); it; ++it) {
        const int br = static_cast<int>(it.row() / 3);
        const auto at = std::lower_bound(first, last, br);
        if (at == last || *at != br) return false;  // outside the analyzed pattern
        a_values_[at - a_rows_.begin()](it.row() % 3, c) = it.value();
      }
  }

  // Up-looking block LDL^T (Davis's ldl_numeric with 3x3 blocks): row k of
  // L from the sparse triangular solve L y = A(0:k-1, k), whose pattern is
  // the union of the elimination tree paths from A's entries in column k.
  std::fill(flag_.begin(), flag_.end(), -1);
  for (int k = 0; k < n_; ++k) {
    int top = n_;
    flag_[k] = k;
    count_[k] = 0;
    for (int p = up_start_[k]; p < up_start_[k + 1]; ++p) {
      int i = up_row_[p];
      y_[i] += a_values_[up_slot_[p]];
      int len = 0;
      for (; flag_[i] != k; i = parent_[i]) {
        pattern_[len++] = i;
        flag_[i] = k;
      }
      while (len > 0) pattern_[--top] = pattern_[--len];
    }
    Block d = y_[k];
    y_[k].setZero();
    for (; top < n_; ++top) {
      const int i = pattern_[top];
      const Block yi = y_[i];
      y_[i].setZero();
      const int start = lower_start_[i], end = start + count_[i];
      for (int p = start; p < end; ++p) y_[lower_rows_[p]].noalias() -= lower_values_[p] * yi;
      const Block l_ki = yi.transpose() * d_inverse_[i];
      d.noalias() -= l_ki * yi;
      lower_rows_[end] = k;
      lower_values_[end] = l_ki;
      ++count_[i];
    }
    const Eigen::LLT<Block> pivot(0.5 * (d + d.transpose()));
    if (pivot.info() != Eigen::Success || !d.allFinite()) return false;
    d_inverse_[k] = pivot.solve(Block::Identity());
  }
  factorized_ = true;
  return true;
}

Eigen::VectorXd BlockLdlt::solve(const Eigen::VectorXd& b) const {
  std::vector<Eigen::Vector3d> y(n_);
  for (int k = 0; k < n_; ++k) y[k] = b.segment<3>(3 * old_of_new_[k]);
  for (int j = 0; j < n_; ++j)
    for (int p = lower_start_[j]; p < lower_start_[j + 1]; ++p) y[lower_rows_[p]].noalias() -= lower_values_[p] * y[j];
  for (int j = 0; j < n_; ++j) y[j] = d_inverse_[j] * y[j];
  for (int j = n_ - 1; j >= 0; --j)
    for (int p = lower_start_[j]; p < lower_start_[j + 1]; ++p)
      y[j].noalias() -= lower_values_[p].transpose() * y[lower_rows_[p]];
  Eigen::VectorXd x(3 * n_);
  for (int k = 0; k < n_; ++k) x.segment<3>(3 * old_of_new_[k]) = y[k];
  return x;
}

}  // namespace lk
