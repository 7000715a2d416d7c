// Stereo attractors as observations of the shape fit (fua1998 Sec. 3.1,
// eq. 8-10): each stereo patch centre a is attached to its closest facet of
// the current surface, and its residual is the orthogonal distance from a to
// that facet's plane, d = D / |(C_x, C_y, C_z)| (eq. 9), a function of the
// facet's three vertices. The paper finds the facet through a facet-ID
// render; here it is the closest point on the current mesh (a BVH query),
// recomputed at every reweighting round, together with the weight of eq. 10,
// w = exp(-d / median d), times the cosine between the patch's normal and
// the facet's (0 when they face apart; the paper's added robustness).
//
// Shapes: mesh #V, #F; attractors #A; one residual row per attractor.
#pragma once
#include "photos/shape_fit.h"
#include "photos/stereo.h"

#include <vector>

namespace lk {

struct StereoAttractor {
  Vec3 point = Vec3::Zero();
  Vec3 normal = Vec3::Zero();  // unit; zero: no normal test
  int triangle = -1;           // attached facet (-1: none)
  double weight = 0;           // current IRLS weight (eq. 10 x normal agreement)
};

// d, the signed distance of a to the plane of (x1, x2, x3) (positive on the
// side of (x2 - x1) x (x3 - x1)), and optionally its gradient with respect
// to (x1, x2, x3) (9 entries). False (d = 0) for a degenerate facet.
bool point_facet_distance(const Vec3& a, const Vec3& x1, const Vec3& x2, const Vec3& x3, double& d,
                          Eigen::Matrix<double, 1, 9>* gradient);

class StereoAttractorSet : public ObservationSet {
 public:
  // Attaches the attractors to `positions` (the start shape) at once.
  StereoAttractorSet(const TriMesh& mesh, const std::vector<StereoPatch>& patches, const std::vector<Vec3>& positions);
  const char* type_name() const override { return "stereo"; }
  int num_residuals() const override { return int(att_.size()); }
  bool evaluate(const std::vector<Vec3>& positions, Eigen::VectorXd& r, int row,
                std::vector<Eigen::Triplet<double>>* jacobian) const override;
  void reweight(const std::vector<Vec3>& positions) override;
  const std::vector<StereoAttractor>& attractors() const { return att_; }
  // Distance of every attractor to the surface at `positions` (closest point), world units.
  std::vector<double> surface_distances(const std::vector<Vec3>& positions) const;

 private:
  std::vector<Tri> triangles_;
  std::vector<StereoAttractor> att_;
};

}  // namespace lk
