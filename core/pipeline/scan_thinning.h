// Thinning a dense scan before the fit (issue 39): a 2-5 million point scan
// holds far more points than the fit can use, and the fit's memory grows
// with them (about 300 bytes a point in wasm). The scan is cut into cubic
// cells and each occupied cell is replaced by the average of its points
// (position, normal, colour): a voxel-grid average, as PCL's VoxelGrid and
// Open3D's voxel_down_sample do. An average, not one picked point, so the
// scanner's noise is averaged as the fit's own footprints would have
// averaged it. With normals, points facing different ways (the two sides
// of an ear's fold) are kept apart: a cell is split by its points' main
// normal direction (6 classes: the axis and sign of the largest component).
//
// Invariants (tests/pipeline/test_scan_thinning.cpp): every occupied cell
// keeps exactly one point per normal class present, inside the cell (the
// average of points in a convex cell), so no region is emptied and every
// scan point lies within sqrt(3) cells of a kept one.
//
// A scan given as a mesh (faces) is not thinned: its triangles index its
// vertices and are sampled by the displacements.
//
// Shapes: scan #P by 3 (normals and colours #P or empty); out #Q by 3.
#pragma once
#include "common/status.h"
#include "mesh/tri_mesh.h"

#include <vector>

namespace lk {

struct ScanThinning {
  bool thinned = false;
  int points = 0;       // the scan's
  int kept = 0;         // after thinning (== points when not thinned)
  double cell = 0;      // the cell's side, in the scan's units
  double bbox_diagonal = 0;  // the full scan's (thin_scan leaves it 0; fit_head's thinning sets it)
};

// Cell averages of scan over a grid of side `cell` (scan units) anchored at
// the scan's bbox minimum. Fails on a cell that is not positive and finite,
// or non-finite coordinates. A grid over 2^20 cells along an axis gets a
// larger cell (stats.cell says which). Colours are averaged, normals
// averaged and normalized (a zero average keeps the first point's normal).
// The output follows the order of each cell's first point in the scan.
// leave_out (#P flags, or empty): points left out of every average (and
// cells holding only those are left out). grid_order: the output in the
// cells' grid order (x, then y, then z) instead.
Status thin_scan(const PointCloud& scan, double cell, PointCloud& out, ScanThinning& stats,
                 const std::vector<char>& leave_out = {}, bool grid_order = false);

// The surface of a scan given as a mesh (positions, faces) as cell
// averages: its triangles sampled on a barycentric grid four times finer
// than `cell`, the samples averaged per cell (thin_scan), in the cells'
// grid order. The same surface gives nearly the same points however it was
// tessellated, which its vertices do not (docs/design/fit_real_scans.md,
// "The same surface, sampled more densely"). Positions only. Fails on an
// index out of range, or as thin_scan does.
Status surface_cell_averages(const std::vector<Vec3>& positions, const std::vector<Tri>& faces, double cell,
                             PointCloud& out);

}  // namespace lk
