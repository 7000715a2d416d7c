// Least-squares shape fit (fua1998 Sec. 2-3.3): the generic head's control
// mesh deformed so that its mapped landmarks project onto the photos'
// landmarks (eq. 12), with a stiffness term (eq. 4-5), Levenberg-Marquardt
// on the sparse normal equations and iterative reweighting.
//
// Parameters: a displacement per control-mesh vertex (eq. 3 with the control
// triangulation = our control mesh). Stiffness: ||L delta||^2 with L the
// uniform graph Laplacian (a thin-plate energy on the displacements rather
// than the paper's C0 membrane: with only landmark observations, a membrane
// pulls spikes at the landmarks). Coarse-to-fine: optionally first over
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

// The uniform graph Laplacian, #V by #V: (L d)_i = d_i - mean of d over i's neighbours.
SparseMat uniform_laplacian(const TriMesh& mesh);

}  // namespace lk
