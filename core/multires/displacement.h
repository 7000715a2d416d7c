// The scalar normal displacements of jeong2002 Sec. 5: before each Butterfly
// refinement, every vertex's signed distance along its normal to the surface
// the scan points sample near that normal line. One scalar per vertex and
// level (d_l, #V_l), stored in MultiresMesh::displacements.
#pragma once
#include "common/progress.h"
#include "common/status.h"
#include "mesh/tri_mesh.h"
#include "multires/multires.h"

#include <vector>

namespace lk {

struct DisplacementOptions {
  // Radius of the cylinder around a vertex's normal line that collects scan
  // points. 0: half the mean edge length of the level being measured (the
  // footprint shrinks with the triangles), but at least twice the mean point
  // spacing sqrt(level area / #points), so fine levels still find data.
  double radius = 0.0;
  // Points farther than this along the normal are ignored (another sheet of
  // the surface, outliers). 0: twice the larger of the mean edge length of
  // the level and the radius.
  double max_distance = 0.0;
  // On levels >= 1 the line is also at most this many times the larger of
  // the level's mean edge and the radius long (each side): the coarser
  // levels already put the surface near the data, and a long line only
  // reaches the other sheet of thin features and costs search time (1 vs
  // off on the synthetic heads: same mean distance, a third fewer folded
  // triangles to limit, ~20 % fewer crossing pairs). 0: off.
  double fine_line_edges = 1.0;
  // When the cloud has normals (#P, as scanners give them), a point counts
  // only if its normal and the vertex normal agree: dot of the unit normals
  // above this. Thin features put two sheets facing away from each other
  // within a normal line (upper against lower lip, the two sides of an ear
  // rim, lid against socket); their points face the other way and are not
  // taken for the vertex's own sheet. Below -1: off.
  double min_normal_agreement = 0.0;
  // Fewer points than this in the cylinder means "no data": displacement 0,
  // and the subdivision surface stays smooth there (Sec. 5).
  int min_points = 3;
  // The line may cross the scan more than once (ears, lips); only points
  // within this fraction of max_distance of the crossing nearest to the
  // vertex are used. Their crossing with the line comes from a least-squares
  // quadric height field over the cylinder (one outlier-rejection pass),
  // falling back to their median below 10 points.
  double cluster_fraction = 0.25;
  // jeong2002 stores one displacement per vertex introduced on each level;
  // vertices inherited from the coarser level already lie on the data. Set
  // to re-measure them on every level as well.
  bool remeasure_coarse_vertices = false;
};

struct DisplacementStats {
  std::vector<int> measured;       // L+1: vertices with data, per level
  std::vector<int> candidates;     // L+1: vertices measured for, per level
  std::vector<double> mean_abs;    // L+1: mean |d| over measured vertices
  std::vector<double> max_abs;     // L+1
};

// Measures d_0 .. d_L from a point cloud (jeong2002 Sec. 5): before each
// refinement, the signed distance along N_l from each vertex to the surface
// the points sample near the normal line (see DisplacementOptions). Overwrites mesh.displacements and re-evaluates. Fails with
// Empty on an empty cloud, InvalidInput on non-finite points, Cancelled when
// progress asks to stop (the mesh is then left with zero displacements).
Status measure_displacements(const PointCloud& cloud, const DisplacementOptions& options, MultiresMesh& mesh,
                             DisplacementStats* stats = nullptr, const ProgressFn& progress = {});

}  // namespace lk
