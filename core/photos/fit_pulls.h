// Which observations move a region of the head in a photos shape fit, and
// which way (issue 37: Kira's lower face comes out wide). The fit's normal
// equations linearized at a shape x, H = J^T J + S (J: every observation
// row as the fit scales it, eq. 7, and the binding rows; S: the stiffness
// and the tether of one stage, shape_fit.h's regularizer_matrix; with its
// follow term the similarity's parameters join D), give each row group k its share of the
// displacement D = x - start:
//   D_k = H^-1 J_k^T (J_k D - r_k(x)),
// which sum to D when x is a minimum of that stage (the end of the fit)
// and to the Gauss-Newton step when x is the start (D = 0). The stiffness
// is in H: it spreads each group's pull, it makes none of its own. Beside
// the shares, each group's force (minus its gradient) at x, the stiffness's
// included, so the balance at the end shows.
//
// Reported per region as the mean outward component (away from the start
// shape's midline along `lateral`) over the region's vertices: + = the
// group widens the head there.
//
// Shapes: positions #V; sets' rows as shape_fit.h; row_groups: one vector
// per set, empty (the whole set is one group, its type name) or one group
// name per residual row.
#pragma once
#include "head/head_model.h"
#include "photos/landmarks.h"
#include "photos/photos_job.h"
#include "photos/shape_fit.h"

#include <memory>
#include <string>
#include <vector>

namespace lk {

struct PullRegion {
  std::string name;
  std::vector<int> vertices;
};

struct FitPullGroup {
  std::string name;
  int rows = 0;
  std::vector<double> share_m;  // per region: mean outward share of D (m)
  std::vector<double> force;    // per region: mean outward force, as a share of the regions' total |force| of all observations at the start
};

struct FitPulls {
  std::vector<double> displacement_m;  // per region: the mean outward D (m)
  std::vector<double> explained_m;     // per region: the sum of the groups' shares (= D at a minimum)
  std::vector<FitPullGroup> groups;    // observation groups, then "lip binding" (if any), then "stiffness" (force only)
};

// Linearized at x with `stiffness` (one stage's) and the sets' current
// weights; the scales per eq. 7 from `lambdas` at x (as the fit's rounds
// set them). force_unit: the force that is 1 (0: this call's own total
// |force| over the regions, returned in force_unit).
Status measure_fit_pulls(const TriMesh& start, const std::vector<Vec3>& x,
                         const std::vector<std::unique_ptr<ObservationSet>>& sets, const std::vector<double>& lambdas,
                         const std::vector<std::vector<std::string>>& row_groups, const ShapeFitOptions& options,
                         double stiffness, const std::vector<PullRegion>& regions, const Vec3& lateral,
                         double& force_unit, FitPulls& out);

// A landmark's group for these reports, by where the map puts it on the
// generic head: MediaPipe's face oval "outline", its lid contours "lids";
// else the region of the control vertex nearest its surface point: "lips",
// "eyes", "brows", "nose", "cheeks", "jaw" (jaw, chin), else "other".
std::string landmark_pull_group(const GenericHead& generic, const SurfacePoint& point, int landmark,
                                bool mediapipe);

// The generic head's regions the issue is about: "cheeks" (at the ears'
// height) and "jaw" (jaw and chin), and for reference "ears" (the head's
// width behind the face: a fit that widens them as much is wider as a
// whole, not in the lower face), each without the vertices within 2 cm of
// the midline (no side to be outward from).
std::vector<PullRegion> lateral_pull_regions(const GenericHead& generic);

// A photos fit's pulls on lateral_pull_regions, as fit_photos_shape builds
// its observations (make_photos_observations; outlines, stereo, slide as
// given to it): `start` at the generic head with the first stage's
// stiffness and the calibration's weights (the first step's split),
// `end` at `fitted` with the last stage's stiffness and the weights
// re-made there (the fitted displacement's split). Forces of both in the
// unit of the start's total. Coarse levels are not modelled (the control
// mesh's stages only).
// How the features are grouped: by landmark_pull_group, by photo (each
// used photo's name; the cameras' share: a photo whose camera is off pulls
// as a whole), or each landmark alone ("lm N (group)").
enum class PullGrouping { Landmarks, Photos, EachLandmark };
struct PhotosFitPulls {
  std::vector<PullRegion> regions;
  FitPulls start, end;
};
Status measure_photos_fit_pulls(const GenericHead& generic, const std::vector<SurfacePoint>& landmarks,
                                const std::vector<LandmarkPhoto>& photos, const SelfCalibResult& calib,
                                const PhotosJobOptions& options, const std::vector<Vec3>& fitted,
                                PhotosFitPulls& out, const std::vector<PhotoOutline>* outlines = nullptr,
                                const StereoResult* stereo = nullptr, const LandmarkSlide* slide = nullptr,
                                PullGrouping grouping = PullGrouping::Landmarks);

}  // namespace lk
