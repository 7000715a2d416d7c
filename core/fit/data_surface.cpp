#include "fit/data_surface.h"

#include <algorithm>

namespace lk {

using Triplet = Eigen::Triplet<double>;

DataSurface::VecX DataSurface::map(const VecX& x) const { return level > 0 ? VecX(S3 * x) : x; }

void DataSurface::set(const VecX& x) {
  const VecX y = map(x);
  for (size_t i = 0; i < mesh.positions.size(); ++i) mesh.positions[i] = y.segment<3>(3 * i);
}

Status DataSurface::build(const TriMesh& control, const ButterflyCreases& creases, int data_level) {
  level = 0;
  mesh = control;
  S3 = SpMat();
  if (data_level <= 0) return Status::success();
  std::vector<ButterflyLevel> levels;
  const Status st = build_butterfly_levels(control, creases, data_level, levels);
  if (!st) return st;
  build_levels(levels, control.num_vertices());
  return Status::success();
}

void DataSurface::build_levels(const std::vector<ButterflyLevel>& levels, int nv) {
  level = static_cast<int>(levels.size());
  SpMat scalar(nv, nv);
  scalar.setIdentity();
  for (const ButterflyLevel& lv : levels) {
    std::vector<Triplet> trip;
    const int nc = lv.num_coarse_vertices;
    for (int v = 0; v < nc; ++v) trip.emplace_back(v, v, 1.0);
    for (int k = 0; k < lv.num_new_vertices(); ++k)
      for (int i = lv.stencil_offsets[k]; i < lv.stencil_offsets[k + 1]; ++i)
        trip.emplace_back(nc + k, lv.stencil_indices[i], lv.stencil_weights[i]);
    SpMat step(lv.num_fine_vertices, nc);
    step.setFromTriplets(trip.begin(), trip.end());
    scalar = SpMat(step * scalar);
  }
  const Eigen::SparseMatrix<double, Eigen::RowMajor> rows = scalar;
  const int ny = static_cast<int>(rows.rows());
  row_offsets_.assign(ny + 1, 0);
  row_columns_.clear();
  row_weights_.clear();
  std::vector<Triplet> trip3;
  for (int j = 0; j < ny; ++j) {
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(rows, j); it; ++it) {
      row_columns_.push_back(static_cast<int>(it.col()));
      row_weights_.push_back(it.value());
      for (int c = 0; c < 3; ++c) trip3.emplace_back(3 * j + c, 3 * int(it.col()) + c, it.value());
    }
    row_offsets_[j + 1] = static_cast<int>(row_columns_.size());
  }
  S3.resize(3 * ny, 3 * nv);
  S3.setFromTriplets(trip3.begin(), trip3.end());
  mesh.triangles = levels.back().fine_triangles;
  mesh.positions.resize(ny);

  // Slots: the ordered corner pairs of the data triangles.
  std::vector<std::vector<std::array<int, 2>>> by_row(ny);  // (k, slot)
  auto slot_of = [&](int j, int k) {
    for (const auto& e : by_row[j])
      if (e[0] == k) return e[1];
    const int id = static_cast<int>(slots_.size());
    slots_.push_back({j, k});
    by_row[j].push_back({k, id});
    return id;
  };
  triangle_slots_.resize(mesh.triangles.size());
  for (size_t f = 0; f < mesh.triangles.size(); ++f)
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) triangle_slots_[f][3 * a + b] = slot_of(mesh.triangles[f][a], mesh.triangles[f][b]);

  // The control blocks the slots_ reach, as a pattern_ of zeros, built by
  // block-columns: column l meets slot (j, k) when l is in k's stencil,
  // and then has the rows of j's stencil.
  slot_entries_.assign(slots_.size() + 1, 0);
  std::vector<std::vector<std::array<int, 2>>> column_slots(nv);  // (slot, index of l in k's stencil)
  for (size_t sl = 0; sl < slots_.size(); ++sl) {
    const int j = slots_[sl][0], k = slots_[sl][1];
    const int nj = row_offsets_[j + 1] - row_offsets_[j], nk = row_offsets_[k + 1] - row_offsets_[k];
    slot_entries_[sl + 1] = slot_entries_[sl] + nj * nk;
    for (int b = 0; b < nk; ++b) column_slots[row_columns_[row_offsets_[k] + b]].push_back({int(sl), b});
  }
  entry_base_.assign(slot_entries_.back(), 0);
  column_length_.assign(nv, 0);
  std::vector<int> rank_of(nv, -1);
  std::vector<std::vector<int>> column_rows(nv);
  for (int l = 0; l < nv; ++l) {
    std::vector<int>& rows_l = column_rows[l];
    for (const auto& cs : column_slots[l]) {
      const int j = slots_[cs[0]][0];
      for (int a = row_offsets_[j]; a < row_offsets_[j + 1]; ++a)
        if (rank_of[row_columns_[a]] != l) rank_of[row_columns_[a]] = l, rows_l.push_back(row_columns_[a]);
    }
    std::sort(rows_l.begin(), rows_l.end());
    column_length_[l] = 3 * static_cast<int>(rows_l.size());
  }
  pattern_.resize(3 * nv, 3 * nv);
  Eigen::VectorXi per_column(3 * nv);
  for (int l = 0; l < nv; ++l) per_column.segment<3>(3 * l).setConstant(column_length_[l]);
  pattern_.reserve(per_column);
  for (int l = 0; l < nv; ++l)
    for (int e = 0; e < 3; ++e)
      for (int i : column_rows[l])
        for (int c = 0; c < 3; ++c) pattern_.insert(3 * i + c, 3 * l + e) = 0.0;
  pattern_.makeCompressed();
  const int* outer = pattern_.outerIndexPtr();
  std::vector<int> rank(nv, 0);
  for (int l = 0; l < nv; ++l) {
    for (size_t r = 0; r < column_rows[l].size(); ++r) rank[column_rows[l][r]] = static_cast<int>(r);
    for (const auto& cs : column_slots[l]) {
      const int j = slots_[cs[0]][0], k = slots_[cs[0]][1];
      const int nk = row_offsets_[k + 1] - row_offsets_[k];
      for (int a = 0; a < row_offsets_[j + 1] - row_offsets_[j]; ++a)
        entry_base_[slot_entries_[cs[0]] + a * nk + cs[1]] = outer[3 * l] + 3 * rank[row_columns_[row_offsets_[j] + a]];
    }
  }
}

DataSurface::SpMat DataSurface::to_control(const std::vector<Eigen::Matrix<double, 9, 9>>& blocks) const {
  std::vector<Eigen::Matrix3d> slot_blocks(slots_.size(), Eigen::Matrix3d::Zero());
  for (size_t f = 0; f < blocks.size(); ++f)
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) slot_blocks[triangle_slots_[f][3 * a + b]] += blocks[f].block<3, 3>(3 * a, 3 * b);
  SpMat out = pattern_;
  double* values = out.valuePtr();
  for (size_t s = 0; s < slots_.size(); ++s) {
    const Eigen::Matrix3d& B = slot_blocks[s];
    if (B.isZero(0)) continue;
    int entry = slot_entries_[s];
    for (int a = row_offsets_[slots_[s][0]]; a < row_offsets_[slots_[s][0] + 1]; ++a)
      for (int b = row_offsets_[slots_[s][1]]; b < row_offsets_[slots_[s][1] + 1]; ++b, ++entry) {
        const double w = row_weights_[a] * row_weights_[b];
        const int len = column_length_[row_columns_[b]];
        double* v = values + entry_base_[entry];
        for (int e = 0; e < 3; ++e)
          for (int c = 0; c < 3; ++c) v[e * len + c] += w * B(c, e);
      }
  }
  return out;
}

}  // namespace lk
