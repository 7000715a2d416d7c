// Least-squares shape fit (fua1998 Sec. 2-3.3): the generic head's control
// mesh deformed so that its mapped landmarks project onto the photos'
// landmarks (eq. 12), with a stiffness term (eq. 4-5), Levenberg-Marquardt
// on the sparse normal equations and iterative reweighting.
//
// Parameters: a displacement per control-mesh vertex (eq. 3 with the control
// triangulation = our control mesh). Stiffness: ||L delta||^2 with L the
// uniform graph Laplacian (a thin-plate energy on the displacements rather
// than the paper's C0 membrane: with only landmark observations, a membrane
// pulls spikes at the landmarks); optionally relative to a fitted
// similarity with a term that makes unobserved parts follow it
// (ShapeFitOptions::follow, off by default). Coarse-to-fine: optionally first over
// coarse control triangulations (control_levels.h, eq. 3: each node moves a
// patch of the control mesh), then on the control mesh itself with the
// stiffness lowered over a schedule.
//
// Observation types plug in as ObservationSet (features now; silhouettes
// and stereo later), each scaled per eq. 7: w_type = lambda_type / G_type,
// with G_type the RMS gradient norm of the type's (robustly weighted)
// residuals at the start of each reweighting round. (The paper prints the
// square root of the sum divided by n_type; its stated aim, per-observation
// gradients of relative size lambda_type, is what the RMS gives.)
//
// Shapes: mesh #V, #F; parameters 3 #V (x, y, z of each vertex in turn).
#pragma once
#include "calib/camera.h"
#include "common/status.h"
#include "photos/landmarks.h"
#include "photos/sparse_lm.h"

#include <array>
#include <memory>
#include <string>
#include <vector>

namespace lk {

// One type of observation (fua1998 eq. 6): residual rows over vertex positions.
class ObservationSet {
 public:
  virtual ~ObservationSet() = default;
  virtual const char* type_name() const = 0;
  virtual int num_residuals() const = 0;
  // Residuals from row `row` on, Jacobian triplets (row, 3 v + axis, value)
  // with respect to the vertex positions. Invalid state (e.g. behind a
  // camera): return false.
  virtual bool evaluate(const std::vector<Vec3>& positions, Eigen::VectorXd& r, int row,
                        std::vector<Eigen::Triplet<double>>* jacobian) const = 0;
  // Iterative reweighting from the current residuals.
  virtual void reweight(const std::vector<Vec3>& positions) = 0;
  // Image-space errors of the observations that are inliers (weight >= 0.5),
  // for reports; sets without a pixel error (stereo) add nothing.
  virtual void inlier_pixel_errors(const std::vector<Vec3>& /*positions*/, std::vector<double>& /*out*/) const {}
};

// 2-D feature locations (eq. 12): surface point p seen at pixel (u, v) in a
// photo with a known camera; residual sqrt(weight) (project(p) - (u, v)) in
// pixels, Huber weights (threshold huber_px) on reweighting.
struct FeatureObservation {
  int camera = 0;                // index into the cameras
  SurfacePoint point;
  Vec2 pixel = Vec2::Zero();
  double weight = 1;             // current IRLS weight
  double prior_weight = 1;       // e.g. from the self-calibration; multiplies the Huber weight
  int landmark = -1;             // the detector's landmark index, for reports (fit_pulls.h); -1: none
};

class FeatureSet : public ObservationSet {
 public:
  FeatureSet(const TriMesh& mesh, std::vector<Camera> cameras, std::vector<FeatureObservation> observations,
             double huber_px);
  const char* type_name() const override { return "features"; }
  int num_residuals() const override { return 2 * int(obs_.size()); }
  bool evaluate(const std::vector<Vec3>& positions, Eigen::VectorXd& r, int row,
                std::vector<Eigen::Triplet<double>>* jacobian) const override;
  void reweight(const std::vector<Vec3>& positions) override;
  void inlier_pixel_errors(const std::vector<Vec3>& positions, std::vector<double>& out) const override;
  const std::vector<FeatureObservation>& observations() const { return obs_; }
  // Pixel error of each observation at the given positions (inf behind a camera).
  std::vector<double> errors(const std::vector<Vec3>& positions) const;

 private:
  std::vector<Tri> triangles_;
  std::vector<Camera> cameras_;
  std::vector<FeatureObservation> obs_;
  double huber_px_;
};

struct ShapeFitOptions {
  double lambda_features = 0.3;   // fua1998 Sec. 4: lambda_sil = lambda_feat = 0.3
  // Stiffness lambda_S per stage, coarse to fine (each stage: reweighting
  // rounds of LM). Units: the normalized observations are about lambda_type
  // times a 3-D error in metres, the stiffness term is in metres too.
  std::vector<double> stiffness_schedule = {100.0, 10.0, 3.0};
  // fua1998 Sec. 2.1's progressively finer control triangulations, run
  // before the stages above: one stage per entry on a coarse triangulation
  // of that many nodes (control_levels.h), with its stiffness on the
  // level's own graph. Each level fits displacements of its own nodes on
  // top of the shape the level before left (the stiffness and the tether
  // act on that level's displacements); the stiffness_schedule's stages
  // then do the same on the control mesh. Empty: none (the schedule alone).
  struct CoarseLevel {
    int nodes = 0;
    double stiffness = 1;
  };
  std::vector<CoarseLevel> coarse_levels;
  double tether = 1e-4;           // ||delta||^2 weight: fixes what nothing observes
  // What the photos do not observe (ears, the back of the jaw, the skull)
  // follows the head's overall shape: > 0 makes the stiffness act on the
  // displacement less a similarity of the level's start shape (regularizer_
  // matrix below; its 7 parameters fitted with the shape) and adds
  // follow * stiffness ||delta - similarity||^2. The thin plate alone
  // continues the nearest pull's slope into unobserved parts; with this
  // term their non-similar part decays over about follow^(-1/4) edges.
  // follow_observed: the term's weight at the nodes that observations
  // touch (observed_vertices), relative to the rest's 1; at 0 the photos'
  // observed parts keep the plain thin plate and the term acts only where
  // nothing is observed. 0: the plain thin plate.
  double follow = 0;
  double follow_observed = 0;
  // Binding edges (the scan fit's E_binding, global_fit.h): vertex pairs
  // whose difference x_a - x_b keeps its value on the start shape, rows
  // sqrt(binding_weight) ((x_a - x_b) - r_e) in metres beside the
  // stiffness's. The photos job binds the generic head's virtual lip edges
  // (each upper lip line vertex to the lower one under it, 0.3 mm apart):
  // landmarks on the two lips, each with pixels of noise, otherwise move
  // the lines independently and cross them (docs/design/photos.md, "Lips
  // that do not cross").
  std::vector<std::array<int, 2>> binding_edges;
  double binding_weight = 1e4;
  // Mirror symmetry about the plane x = 0 (the generic head's): for each
  // pair (a, b) of mirror vertices (mirror_vertex_pairs; a == b on the
  // midline) rows sqrt(symmetry_weight) (S (x_a - s_a) - (x_b - s_b)) in
  // metres, s the start shape, S = diag(-1, 1, 1): a displacement on one
  // side is asked for, mirrored, on the other. A face is close to
  // symmetric and its two sides' detector errors are not, so the term
  // keeps what both sides' landmarks agree on and damps what one side's
  // alone asks for (a crooked nose, one cheek wider). 0: off.
  std::vector<std::array<int, 2>> mirror_pairs;
  double symmetry_weight = 0;
  int reweighting_rounds = 2;
  int max_lm_iterations = 20;
  // An LM run stops when a step gains less than this share of the cost.
  double relative_tolerance = 1e-5;
  // The minimizer of each reweighting round: LM (the paper's, the app's),
  // or for fua1998 Fig. 6's comparison plain gradient descent or L-BFGS
  // (descent.h), each with up to max_descent_iterations.
  enum class Optimizer { LevenbergMarquardt, GradientDescent, QuasiNewton };
  Optimizer optimizer = Optimizer::LevenbergMarquardt;
  int max_descent_iterations = 500;
};

struct ShapeFitStage {
  int nodes = 0;                    // the level's nodes (the control mesh's #V on its own stages)
  double stiffness = 0;
  double initial_cost = 0, final_cost = 0;
  int lm_iterations = 0;
};

struct ShapeFitResult {
  TriMesh mesh;                     // the deformed control mesh (same triangles)
  std::vector<ShapeFitStage> stages;
  double initial_rms_px = 0, final_rms_px = 0;  // feature errors (weight >= 0.5), pixels
};

// eq. 7: each set's weight lambda_k / G_k at the given positions, G_k the
// RMS norm of the set's Jacobian rows (0 for a set without gradient).
std::vector<double> observation_type_weights(const std::vector<Vec3>& positions,
                                             const std::vector<std::unique_ptr<ObservationSet>>& sets,
                                             const std::vector<double>& lambdas);

// Fails with InvalidInput on a bad option (an empty schedule is allowed
// when coarse levels are given) or an observation set that
// does not match the mesh; NotConverged when no step lowers the cost.
Status fit_shape(const TriMesh& control, std::vector<std::unique_ptr<ObservationSet>>& sets,
                 const std::vector<double>& lambdas, const ShapeFitOptions& options, ShapeFitResult& result);

// The fit's regularizer rows on one level, linear in its state [delta (3 K);
// theta (regularizer_extra_parameters(follow))], nodes at `nodes`, K by K
// graph Laplacian L:
//   sqrt(stiffness) (L x I3) (delta - B theta)
//   sqrt(follow w_k stiffness) (delta_k - (B theta)_k)   (only when follow > 0)
//   sqrt(tether) delta
// with B theta = similarity_displacement: a linearized similarity about the
// nodes' centroid (theta = 0 and follow = 0: the plain thin plate and tether).
// follow_weights (K, or empty: all 1) multiply the follow rows' weight per node.
SparseMat regularizer_matrix(const std::vector<Vec3>& nodes, const SparseMat& laplacian, double stiffness,
                             double tether, double follow, const std::vector<double>& follow_weights = {});
// The same residuals evaluated directly (for tests of the matrix).
Eigen::VectorXd regularizer_residuals(const std::vector<Vec3>& nodes, const SparseMat& laplacian, double stiffness,
                                      double tether, double follow, const Eigen::VectorXd& state,
                                      const std::vector<double>& follow_weights = {});
// The follow term's weight per node: observed_weight at observed nodes, 1
// elsewhere, then smoothed over the level's graph (three passes of
// w <- w - L w / 2) so that the term does not switch on across one edge,
// which creases the surface there.
std::vector<double> follow_node_weights(const std::vector<bool>& observed_nodes, const SparseMat& laplacian,
                                        double observed_weight);
// The vertices (#V) some observation row depends on at these positions.
std::vector<bool> observed_vertices(const std::vector<std::unique_ptr<ObservationSet>>& sets,
                                    const std::vector<Vec3>& positions);
inline int regularizer_extra_parameters(double follow) { return follow > 0 ? 7 : 0; }
// s (x - c) + w x (x - c) + t for theta = (s, w, t), c the centroid.
Vec3 similarity_displacement(const Vec3& x, const Vec3& centroid, const Eigen::Matrix<double, 7, 1>& theta);

// The vertex pairs of a mesh symmetric about x = 0: (a, b) with b the
// vertex at a's mirror image (within tolerance_m), a <= b, every vertex in
// one pair (a == b on the plane). Empty when some vertex has no mirror.
std::vector<std::array<int, 2>> mirror_vertex_pairs(const TriMesh& mesh, double tolerance_m = 1e-6);
// The symmetry term's rows (ShapeFitOptions::mirror_pairs), 3 per pair, at
// `positions` against `start`; with `jacobian`, its entries over the vertex
// coordinates (column 3 v + axis).
void symmetry_residuals(const std::vector<Vec3>& start, const std::vector<Vec3>& positions,
                        const std::vector<std::array<int, 2>>& pairs, double weight, Eigen::VectorXd& r,
                        std::vector<Eigen::Triplet<double>>* jacobian);

// The uniform graph Laplacian, #V by #V: (L d)_i = d_i - mean of d over i's neighbours.
SparseMat uniform_laplacian(const TriMesh& mesh);

}  // namespace lk
