// The surface the global fit measures the scan against
// (GlobalFitOptions::data_level).
//
// jeong2002 Sec. 4.3 fits the control mesh's own triangles to the points.
// But the head the user gets is the control mesh's Modified Butterfly
// refinement, which interpolates the control vertices and bulges off the
// flat triangles by about e^2 / 8R (edge e, curvature radius R: ~0.6 mm
// for a 10 mm edge on a 20 mm nose bridge). Points fitted by the flat
// triangles push the vertices outward by that much, more where the
// triangles are long, so the refinement ripples with the control layout
// (the creases on Fran's nose bridge and brow, docs/design/fit.md). Butterfly is
// linear in the control positions, so its level L, y = S x with S the
// levels' stencils composed, can be the data surface instead: the closest
// points are taken on level L and E_dist's rows are carried to the control
// vertices through S (Hoppe et al. 1994 fit Loop surfaces the same way).
//
// The data term's hessian over y has a 3x3 block for each pair of corners
// of a data triangle; S^T H_y S is formed without either sparse product:
// block (j, k) adds w_ji w_kl times itself to control block (i, l) for
// every i in j's stencil and l in k's, at value positions found once
// (build) in a fixed pattern (to_control).
#pragma once
#include "common/status.h"
#include "mesh/tri_mesh.h"
#include "subdiv/butterfly.h"

#include <Eigen/Sparse>
#include <array>
#include <vector>

namespace lk {

struct DataSurface {
  using SpMat = Eigen::SparseMatrix<double>;
  using VecX = Eigen::VectorXd;

  int level = 0;   // 0: the control mesh itself (S the identity, not stored)
  SpMat S3;        // 3#Vy by 3#V: S per coordinate (x0 y0 z0 x1 ...), level > 0
  TriMesh mesh;    // the data triangles; positions: scratch of the last set()

  // Level 0 of `control`, or its Butterfly level `level` with `creases`
  // (falls back to level 0 and fails when Butterfly cannot refine it).
  Status build(const TriMesh& control, const ButterflyCreases& creases, int level);
  // y = S x, and the same written into mesh.positions.
  VecX map(const VecX& x) const;
  void set(const VecX& x);
  // S^T H_y S (3#V by 3#V) for H_y given as one 9x9 block per data
  // triangle over its corners' coordinates (corner a's at rows 3a..3a+2).
  // Level > 0 only. Its pattern does not depend on the blocks' values.
  SpMat to_control(const std::vector<Eigen::Matrix<double, 9, 9>>& blocks) const;

 private:
  void build_levels(const std::vector<ButterflyLevel>& levels, int nv);
  std::vector<int> row_offsets_, row_columns_;  // S by rows (the stencils), #Vy + 1
  std::vector<double> row_weights_;
  std::vector<std::array<int, 2>> slots_;           // data vertex pairs (j, k) met in a triangle
  std::vector<std::array<int, 9>> triangle_slots_;  // per data triangle: slot of corners (a, b) at 3a + b
  std::vector<int> slot_entries_;                   // #slots + 1: ranges into entry_base_
  std::vector<int> entry_base_;                     // per (slot, i, l): value index of (3i, 3l)
  std::vector<int> column_length_;                  // #V: entries of each scalar column of block-column l
  SpMat pattern_;                                   // zeros at every control block the slots reach
};

}  // namespace lk
