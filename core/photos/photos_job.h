// Photos to head, the native core's job (issue 37): landmark files of
// several photos + the landmark map -> cameras (self_calibration.h) and the
// generic head's control mesh deformed to the person (shape_fit.h); with the
// photos' images, stereo patches between pairs of them (stereo.h) join the
// landmarks as attractors (stereo_obs.h, lambda_stereo). The CLI
// (`likeness photos`) and the benchmark are thin shells over it.
//
// Shapes: photos #P; images #P (an empty image: none for that photo); the
// result's cameras/refusals #P (photo order kept).
#pragma once
#include "head/head_model.h"
#include "image/image.h"
#include "photos/contour_obs.h"
#include "photos/eye_lids.h"
#include "photos/landmarks.h"
#include "photos/lips.h"
#include "photos/outline.h"
#include "photos/self_calibration.h"
#include "photos/shape_fit.h"
#include "photos/silhouette_obs.h"
#include "photos/stereo.h"
#include "pipeline/untangle.h"

#include <memory>
#include <string>
#include <vector>

namespace lk {

class StereoAttractorSet;

// The scan fit's untangle on the photos head's level 3 (its other fields
// the scan fit's defaults).
inline UntangleOptions photos_untangle_options() {
  UntangleOptions o;
  o.level = 3;
  return o;
}

// The shape fit as the photos job runs it: ShapeFitOptions' defaults with
// the mirror-symmetry term on (weight 0.3; the job pairs the generic head's
// mirror vertices): on the detector's points the two sides' errors differ
// and the face does not (docs/design/photos.md, "A symmetric shape fit").
inline ShapeFitOptions photos_fit_options() {
  ShapeFitOptions o;
  o.symmetry_weight = 0.3;
  return o;
}

struct PhotosJobOptions {
  SelfCalibOptions calib;
  ShapeFitOptions fit = photos_fit_options();
  double map_max_distance_m = 0.016;  // a map point farther from the head: a map for another head (a re-made map sits up to 12 mm off it: landmark_learning.h)
  double lambda_silhouettes = 0.3;    // fua1998 Sec. 4
  SilhouetteOptions silhouettes;
  bool stereo = true;                 // use the images, when given, for stereo attractors
  StereoOptions stereo_options;
  double lambda_stereo = 1.0;         // fua1998 Sec. 4
  // MediaPipe's landmarks' focal over the true one with the shipped map's
  // slide (mean over its training sessions, seeds 11-20; docs/design/
  // photos.md, "The focal from the landmarks, honestly weighed"): given to
  // the self-calibration (calib.slide_focal_ratio) when the map is
  // MediaPipe's and its slide is used. Re-measure it with a re-made map.
  double mediapipe_focal_ratio = 0.853;
  // The map's slide model (landmark_slide.h), when it has one: each
  // landmark seen where the detector puts it from that camera's view, in
  // the self-calibration and the shape fit; its scatter weighs the
  // landmarks (calib.use_slide_sigma).
  bool use_slide = true;
  // The face-outline landmarks (MediaPipe's face oval, jaw and chin; other
  // detectors: none) seen at a grazing angle as contour observations
  // (contour_obs.h) instead of fixed surface points in the shape fit; their
  // lambda is the features' (with its noise factor) times
  // contour_lambda_scale. The self-calibration still uses them as points.
  // Off by default: on the real detector's points of synthetic renders
  // (bench --photos-detected) the face comes out farther from the truth
  // (docs/design/photos.md, "The face outline as contours").
  bool contour_landmarks = false;
  ContourOptions contours;
  double contour_lambda_scale = 1.0;
  // Lips that stay whole (photos/lips.h): the generic head's virtual lip
  // edges bound in the shape fit (with fit.binding_weight), and the mouth
  // bag kept inside the mouth afterwards.
  bool bind_lips = true;
  // MediaPipe's lid contour observed on the eye rims (eye_lids.h,
  // lid_margin_points) instead of at the map's lid points, which were
  // learned on renders without eyeballs and open the lids too wide. Off by
  // default: on the real detector's points from those eyeless renders
  // (tests/photos/data/detected) it pulls the rims to lids the detector
  // cannot see and folds the face (docs/design/photos.md, "Lids that follow
  // the photos"); `likeness photos --lids` turns it on.
  bool lids_on_rim = false;
  // Then the lids turned over the eyeballs to the photos' lid contour
  // (eye_lids.h, fit_lid_pose; with lids_on_rim and MediaPipe points).
  bool fit_lids = true;
  bool keep_mouth_bag = true;
  MouthBagOptions mouth_bag;
  // Then what still crosses on the smooth level untangle.level that the
  // generic head's does not (a silhouette folds an ear's control face into
  // itself) is untangled by the scan fit's step (pipeline/untangle.h:
  // erosion, then part of the way back to the generic's umbrella shape),
  // with the generic head as the reference; a head that crosses nothing
  // new is left as it is. untangle.level = 0: off.
  UntangleOptions untangle = photos_untangle_options();
};

// What the stereo attractors came to in a fit (fua1998 Fig. 7's measure).
struct PhotosStereoFit {
  int attractors = 0;
  int inliers = 0;                    // eq. 10 weight >= exp(-3) at the end (within ~3 median distances)
  double median_start_m = 0;          // patch centres to the start surface (generic head)
  double median_fit_m = 0, p95_fit_m = 0;  // to the fitted surface
  std::vector<double> distances_fit_m;     // each patch centre to the fitted surface, ascending (fua1998 Fig. 6)
  std::vector<double> weights;        // #patches, each attractor's final weight (eq. 10 x normal agreement)
};

struct PhotosJobResult {
  SelfCalibResult calib;
  StereoResult stereo;         // pairs tried and their patches (empty without images)
  PhotosStereoFit stereo_fit;
  ShapeFitResult fit;          // fit.mesh: the person's control mesh
  MouthBagResult mouth_bag;    // what keeping the mouth bag inside did (PhotosJobOptions::keep_mouth_bag)
  UntangleResult untangle;     // what the untangle did (PhotosJobOptions::untangle; zero when nothing crossed)
  LidPoseResult lids;          // the lids' turn to the photos (PhotosJobOptions::fit_lids; zero when not run)
  std::vector<std::string> notes;  // for people: one photo only, photos dropped, ...
};

// The stereo stage alone, from a finished self-calibration: pairs of used
// photos with images, each searched inside its landmarks' hull, the depth
// range from the generic head. Fails on bad options or #images != #photos.
Status run_photos_stereo(const GenericHead& generic, const std::vector<LandmarkPhoto>& photos,
                         const SelfCalibResult& calib, const std::vector<Image>& images, const StereoOptions& options,
                         StereoResult& stereo);

// The shape-fit stage alone, from a finished self-calibration: every used
// photo's landmarks (with their calibration weights) as feature
// observations, the outlines (if any) as silhouette observations and the
// stereo patches (if any) as attractors; with options.bind_lips the lips
// bound, with options.keep_mouth_bag the bag kept inside afterwards
// (photos/lips.h; mouth_bag: null or its report), then options.untangle
// (untangled: null or its report). landmarks: the map attached to
// generic.mesh. outlines: null, or one per photo (empty points: none for
// that photo), each used photo's as silhouette observations
// (silhouette_obs.h; the neck region excluded, the chin region's lowest
// point as the chin line). slide: null, or the map's slide model: each
// landmark observed at its point plus its shift for that photo's camera,
// weighted by its scatter there (as the self-calibration). With MediaPipe
// points, options.lids_on_rim observes the lid contour on the eye rims and
// options.fit_lids then turns the lids to it (eye_lids.h; lids: null or
// its report).
Status fit_photos_shape(const GenericHead& generic, const std::vector<SurfacePoint>& landmarks,
                        const std::vector<LandmarkPhoto>& photos, const SelfCalibResult& calib,
                        const PhotosJobOptions& options, ShapeFitResult& fit,
                        const std::vector<PhotoOutline>* outlines = nullptr, const StereoResult* stereo = nullptr,
                        PhotosStereoFit* stereo_fit = nullptr, const LandmarkSlide* slide = nullptr,
                        MouthBagResult* mouth_bag = nullptr, LidPoseResult* lids = nullptr,
                        UntangleResult* untangled = nullptr);

// The observations fit_photos_shape fits with, as it builds them (for
// measurements of a fit, fit_pulls.h): the sets with one lambda each, the
// fit's options with the lips bound, the lid points seen on the rims (empty
// without options.lids_on_rim), and the stereo attractors' set (or null).
// Each feature's FeatureObservation::landmark is its landmark index.
struct PhotosObservations {
  std::vector<std::unique_ptr<ObservationSet>> sets;
  std::vector<double> lambdas;
  ShapeFitOptions fit;
  std::vector<SurfacePoint> lid_points;
  const StereoAttractorSet* attractors = nullptr;
};
Status make_photos_observations(const GenericHead& generic, const std::vector<SurfacePoint>& landmarks,
                                const std::vector<LandmarkPhoto>& photos, const SelfCalibResult& calib,
                                const PhotosJobOptions& options, const std::vector<PhotoOutline>* outlines,
                                const StereoResult* stereo, const LandmarkSlide* slide, PhotosObservations& out);

// The silhouette set fit_photos_shape builds (for reports: its stats at the
// generic and the fitted shape). Null when no used photo has an outline.
std::unique_ptr<SilhouetteSet> make_silhouette_set(const GenericHead& generic, const TriMesh& start,
                                                   const SelfCalibResult& calib,
                                                   const std::vector<PhotoOutline>& outlines,
                                                   const SilhouetteOptions& options);

// All stages. Fails with the first stage's status (the message names the
// stage and, for a refused photo, the photo by its name). outlines: as for
// fit_photos_shape (checked: one per photo, each of its photo's size);
// images: empty, or one per photo (for stereo).
Status run_photos_job(const GenericHead& generic, const LandmarkMap& map, const std::vector<LandmarkPhoto>& photos,
                      const PhotosJobOptions& options, PhotosJobResult& result,
                      const std::vector<PhotoOutline>* outlines = nullptr, const std::vector<Image>& images = {});

}  // namespace lk
