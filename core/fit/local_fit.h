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
// Eye region (ours, not in the paper). jeong2002 boxes only ears, nose and
// mouth; on a real face the alignment can leave the generic eyes a
// centimetre off (menpo3d James: 10 mm too high, because the generic face
// is taller), and global fitting cannot slide a feature across the skin.
// An affine eye box was tried and failed (wild shears from ~180 points, 42
// turned triangles). So the eyes get a SOFT region: one transform with few
// parameters (translation and one scale, about the point between the eyes)
// moves the vertices by a weight that is 1 around both eyes and brows and
// falls smoothly to 0 (no wall, so no step), fitted to the region's points
// by the same E_local. The eye socket pockets stay in E_dist: in the eye
// opening a scanner sees the eyeball (a real face) or the socket itself
// (the synthetic heads), both within a few mm of the pocket's surface; left
// out, the points there pulled the eyes 1.5-5 mm too deep on synthetic
// heads (rims 1.0-1.7 mm off against 0.2-0.7 mm with the pockets).
// It runs before the boxes (fit_head, when FitHeadOptions::fit_eye_region
// is set: on by default, see docs/design/fit.md), so the nose box then fits
// a nose whose bridge already sits between the moved eyes.
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

// The parameters a feature's transform may change, about its centre c.
enum class RegionMotion {
  Affine,            // x -> c + A (x - c) + t: 12 parameters (the paper's boxes)
  TranslationScale,  // x -> c + s (x - c) + t: 4 parameters
  Translation,       // x -> x + t: 3 parameters
};

// A region of the generic head that moves as a whole with a smooth edge:
// weight 1 inside the ellipsoid (center, radii), falling to 0 at `falloff`
// times the radii (smoothstep in the ellipsoidal radius), 0 beyond. Its
// transform is fitted to the points within `data_extent` times the radii.
struct SoftRegion {
  std::string name;
  Vec3 center = Vec3::Zero();  // generic frame
  Vec3 radii = Vec3::Ones();   // generic frame, along x, y, z
  double falloff = 2.0;        // > 1
  double data_extent = 1.0;    // > 0
  RegionMotion motion = RegionMotion::TranslationScale;
  double radius(const Vec3& generic_point) const;  // ellipsoidal: 1 on the ellipsoid
  double weight(const Vec3& generic_point) const;
};

// The eye region's size in units of the distance between the two eye rim
// centroids (64 mm on the generic head): the weight-1 ellipsoid covers both
// eye openings, the lids and the brows. The falloff is long (weight 0 at
// three times the radii, 60 mm below the eyes) because global fitting's
// E_smooth keeps the template's umbrella vectors: a steep falloff bends the
// face there and the fit then pulls back against the data (James, mean of
// three runs: level 3 0.0534 % with falloff 2, 0.0504 % with 3).
struct EyeRegionOptions {
  Vec3 radii_per_eye_distance = Vec3(0.85, 0.32, 0.62);
  double falloff = 3.0;
  // Only the points in the weight-1 core are fitted: the falloff's temples,
  // cheeks and nose sides have misfits of their own (measured on James with
  // every point of the falloff: the eyes went from 10 mm too high to 4 mm
  // too low and 6 mm too deep; with the core's: within 1-3 mm).
  double data_extent = 1.0;
  RegionMotion motion = RegionMotion::TranslationScale;
};

// The eye region of a head from its eye rims (ann.eye_left.rim,
// ann.eye_right.rim: both needed), centred between their centroids.
// generic: the generic head's mesh (frame of the annotations).
Status eye_region(const TriMesh& generic, const HeadAnnotations& ann, const EyeRegionOptions& options,
                  SoftRegion& out);

struct LocalFitOptions {
  double stretch_weight = 1.0;       // k of E_stretch (relative to E_dist, see above)
  int max_iterations = 35;           // per box (the paper reports about 35)
  double relative_tolerance = 1e-4;  // stop when E_local changes less than this
  int max_points_per_box = 3000;     // random subsample of a box's points
  double falloff_fraction = 1.0 / 30.0;  // k_f in units of the cloud's bbox diagonal
  int min_points_per_box = 30;       // fewer points: the box is left as it is
  // Extra starts per box: its alignment shifted along the head's up axis by
  // these fractions of the box's height; every start runs
  // start_screen_iterations, the lowest E_local is minimized on (fit_local).
  // Empty: the alignment's map alone (the paper).
  std::vector<double> start_shifts = {-0.2, 0.2};
  int start_screen_iterations = 8;
  // A shifted start replaces the alignment's only when its screened E_local
  // is lower by more than this fraction (seed 6's mouth: 36 % lower; on
  // James gains of a few % moved his nose and ears into basins that
  // crossed: 6-7 pairs on two of five copies).
  double start_gain = 0.2;
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

// Fits one soft region (see the header comment) and moves the mesh by it:
// out = mesh + w (T(mesh) - mesh) per vertex, w = region.weight of the
// vertex's generic-frame position. points: the scan in the mesh's frame;
// those within region.data_extent are fitted (at most
// options.max_points_per_box, a random subset). result.transform is the
// fitted T (about the mesh frame's origin); too few points
// (options.min_points_per_box) leave the mesh as it is (skipped).
Status fit_soft_region(const std::vector<Vec3>& points, const TriMesh& mesh, const MeshTopology& topology,
                       const SoftRegion& region, const AffineMap& generic_to_mesh, const LocalFitOptions& options,
                       TriMesh& out, BoxFit& result, const ProgressFn& progress = {});

}  // namespace lk
