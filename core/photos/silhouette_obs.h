// Silhouette observations (fua1998 Sec. 3.2, eq. 11) for the shape fit: each
// outline point of a photo (outline.h) must lie on the line the head's rim
// projects to in that photo.
//
// The rim, found by "rendering" on the CPU: with the mesh's current
// positions and the photo's camera, the edges between a triangle facing the
// camera and one facing away, kept only where they lie on the border of the
// mesh's projected footprint (the pixel 2 px beyond the edge covered by no
// triangle: a rim over other surface, like the jaw seen over the neck, is no
// silhouette). Each outline point searches
// along its normal, within search_m (on the head, at the distance of the
// mesh's centre from the camera: the same reach on a 12-megapixel photo as
// on a small one), for the nearest such rim edge seen
// with the same outward direction (the paper searches its Facet-ID image
// along the normal). No edge, or an edge touching an excluded vertex (the
// neck: the mask's neck and shoulders are not the head's outline) or the
// mesh's open border, or the point below the chin's line in the image: the
// point is not used this round. Rims are re-found at every reweighting round.
//
// Residual per matched point s and rim edge (a, b) with projections p_a, p_b:
// eq. 11 for the pair (a, b), det[p_a p_b s; 1 1 1] = cross(p_b - p_a, s - p_a),
// divided by |p_b - p_a|: the signed distance in pixels from s to the line
// through p_a and p_b. The paper writes the three pairs of a facet, forcing
// the facet edge-on; on our coarse control mesh no facet is edge-on at a
// rim (the two facets at a rim edge fold over by the surface's curvature),
// so the default uses the rim edge, the one pair whose line the silhouette
// is. `facet_equations` writes the paper's three, on the rim edge's
// camera-facing facet. Huber weights (huber_px) on reweighting.
//
// Shapes: cameras and outlines #C (one outline per camera, maybe empty);
// excluded: #V flags.
#pragma once
#include "calib/camera.h"
#include "photos/outline.h"
#include "photos/shape_fit.h"

#include <array>
#include <cmath>
#include <string>
#include <vector>

namespace lk {

struct SilhouetteOptions {
  double search_m = 0.010;        // how far along an outline point's normal its rim may be (21 px at 1250 px, 0.6 m)
  double huber_px = 4;            // Huber threshold of the reweighting
  double min_normal_cos = 0.3;    // outline normal vs the rim's outward direction
  bool facet_equations = false;   // the paper's three determinants per point (see above)
  // The generic head's regions whose rims no outline point is matched to
  // (make_silhouette_set, photos_job.h). The neck: the mask's neck and
  // shoulders are not the head's outline. The scalp and the ears: a real
  // photo's outline there is mostly hair, and through the cameras the
  // detector's points give (their focal short) the scalp's outline bends the
  // back of the head (docs/design/photos.md, "The outline in the page").
  // `bench --only photos --photos-sil-exclude neck` measures the other case,
  // exact cameras and a bald head, where the scalp's outline helps.
  std::vector<std::string> excluded_regions = {"neck", "scalp", "ears"};
};

// Where the head ends downwards, for the chin line: the lowest of these
// vertices along `up` (e.g. the "chin" region), in each view.
struct ChinLine {
  std::vector<int> vertices;
  Vec3 up = Vec3::UnitY();
};

// Signed distance in pixels of s from the line through pa and pb (eq. 11's
// determinant over |pb - pa|); ga, gb (may be null): its gradients with
// respect to pa and pb.
double line_distance(const Vec2& pa, const Vec2& pb, const Vec2& s, Vec2* ga, Vec2* gb);

// Huber's IRLS weight of a residual of size |d| (0 for an infinite one).
inline double huber_weight(double abs_d, double threshold) {
  return abs_d <= threshold ? 1.0 : (std::isfinite(abs_d) ? threshold / abs_d : 0.0);
}

// A mesh's edges: a, b, the triangle on one side, the one on the other (-1: open border).
std::vector<std::array<int, 4>> mesh_edge_list(const std::vector<Tri>& triangles);

// An occluding-contour edge (a, b) of the mesh in one camera: between a
// triangle facing the camera and one facing away (or on the open border),
// c the camera-facing triangle's third vertex; projected, with the image
// direction away from that triangle.
struct RimEdge {
  int a = -1, b = -1, c = -1;
  Vec2 pa = Vec2::Zero(), pb = Vec2::Zero(), outward = Vec2::Zero();
  bool excluded = false;  // on the open border (callers add their own exclusions)
};
// silhouette_only: only the rims on the border of the mesh's projected
// footprint (not the jaw seen over the neck); else every occluding contour.
std::vector<RimEdge> find_rim_edges(const std::vector<Vec3>& positions, const std::vector<Tri>& triangles,
                                    const std::vector<std::array<int, 4>>& edges, const Camera& camera,
                                    bool silhouette_only);

struct SilhouetteStats {
  int points = 0;         // outline points given
  int matched = 0;        // with a rim within reach (search_m)
  double mean_px = 0, p95_px = 0;  // |distance| of the matched points to their rim line
};

class SilhouetteSet : public ObservationSet {
 public:
  // Rims are first matched at mesh.positions.
  SilhouetteSet(const TriMesh& mesh, std::vector<Camera> cameras, std::vector<PhotoOutline> outlines,
                std::vector<char> excluded, ChinLine chin, const SilhouetteOptions& options);
  const char* type_name() const override { return "silhouettes"; }
  int num_residuals() const override { return rows_per_match() * int(matches_.size()); }
  bool evaluate(const std::vector<Vec3>& positions, Eigen::VectorXd& r, int row,
                std::vector<Eigen::Triplet<double>>* jacobian) const override;
  // Re-finds every point's rim at these positions, then Huber weights.
  void reweight(const std::vector<Vec3>& positions) override;

  // Rims re-found at these positions (the set's own matches unchanged).
  SilhouetteStats stats(const std::vector<Vec3>& positions) const;

  struct Match {
    int camera = 0, point = 0;    // outline point `point` of camera's outline
    int a = -1, b = -1, c = -1;   // rim edge (a, b); c: the camera-facing facet's third vertex
    double weight = 1;
  };
  const std::vector<Match>& matches() const { return matches_; }

 private:
  int rows_per_match() const { return options_.facet_equations ? 3 : 1; }
  std::vector<Match> find_matches(const std::vector<Vec3>& positions) const;
  double distance(const std::vector<Vec3>& positions, const Match& m) const;

  std::vector<Tri> triangles_;
  std::vector<std::array<int, 4>> edges_;  // a, b, triangle left, triangle right (-1: open border)
  std::vector<Camera> cameras_;
  std::vector<PhotoOutline> outlines_;
  std::vector<char> excluded_;
  ChinLine chin_;
  SilhouetteOptions options_;
  std::vector<Match> matches_;
};

}  // namespace lk
