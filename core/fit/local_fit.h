// Local fitting of the facial features: jeong2002 Sec. 4.2 ("Adaptive Local
// Alignment").
//
// For each feature box b (ears, nose, mouth) a transform T_b of the mesh part
// G_b inside the box minimizes
//   E_local = E_dist + E_stretch
//   E_dist    = 1/#P_b sum_{p in P_b} |Pi(T_b G_b, p) - p|^2
//   E_stretch = k/2 * 1/#E_b sum_{e in E_b} (l_e - r_e)^2
// (the paper's sums, divided by the counts so k does not depend on the scan
// density; l_e the transformed and r_e the initial edge length). The paper
// calls T_b rigid in Sec. 3 and affine in Sec. 4.2; we use an AFFINE map
// (12 parameters, about the box's centroid), so a nose that is longer or an
// ear that is larger than the generic one can be matched, while E_stretch
// keeps it near a rigid motion. It is minimized by Gauss-Newton/ICP with
// Levenberg-Marquardt damping (exact closest points each iteration,
// point-to-plane residuals); a step is taken only when it lowers the true
// E_local, so the returned energies decrease monotonically.
//
// The vertices inside a box move with its transform; every other vertex v
// moves by the landmarks' displacements with exponential fall-off:
//   v <- v + sum_i w_i (l~_i - l_i) / max(1, sum_i w_i),  w_i = exp(-|v - l_i| / k_f)
// with k_f = cloud bbox diagonal / 30. The paper writes exp(-k |v - l_i|)
// with "k = 1/30 of the diagonal", which only makes sense dimensionally as a
// length scale; and its plain sum moves a vertex near the four nose
// landmarks by up to four times their displacement, hence the normalization.
//
// Shapes: points #P by 3; mesh positions #V by 3.
#pragma once
#include "common/progress.h"
#include "common/status.h"
#include "head/head_model.h"
#include "mesh/topology.h"

#include <string>
#include <vector>

namespace lk {

// x -> A x + t. Maps the generic head's frame (where the feature boxes are
// defined) to the frame of the mesh being fitted (the scan's).
struct AffineMap {
  Mat3 A = Mat3::Identity();
  Vec3 t = Vec3::Zero();
  Vec3 apply(const Vec3& p) const { return A * p + t; }
};

struct LocalFitOptions {
  double stretch_weight = 1.0;       // k of E_stretch (relative to E_dist, see above)
  int max_iterations = 35;           // per box (the paper reports about 35)
  double relative_tolerance = 1e-4;  // stop when E_local changes less than this
  int max_points_per_box = 3000;     // random subsample of a box's points
  double falloff_fraction = 1.0 / 30.0;  // k_f in units of the cloud's bbox diagonal
  int min_points_per_box = 30;       // fewer points: the box is left as it is
  std::uint32_t seed = 1;
};

struct BoxFit {
  std::string name;
  AffineMap transform;            // about the mesh frame's origin: x -> A x + t
  int points = 0;                 // scan points used
  int vertices = 0;               // mesh vertices in the box
  bool skipped = false;           // too few points: identity
  std::vector<double> energies;   // E_local per iteration, [0] before the first
};

struct LocalFitResult {
  std::vector<BoxFit> boxes;
};

// points: the scan (#P by 3), in the mesh's frame. mesh: the generic head
// after initial alignment; boxes: feature boxes in the GENERIC frame;
// generic_to_mesh: the alignment (so box membership is tested in the generic
// frame, as the boxes were drawn). cloud_diagonal: the scan's bbox diagonal.
Status fit_local(const std::vector<Vec3>& points, const TriMesh& mesh, const MeshTopology& topology,
                 const std::vector<FeatureBox>& boxes, const AffineMap& generic_to_mesh,
                 double cloud_diagonal, const LocalFitOptions& options, TriMesh& out,
                 LocalFitResult& result, const ProgressFn& progress = {});

}  // namespace lk
