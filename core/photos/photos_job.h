// Photos to head, the native core's job (issue 37): landmark files of
// several photos + the landmark map -> cameras (self_calibration.h) and the
// generic head's control mesh deformed to the person (shape_fit.h). The CLI
// (`likeness photos`) and the benchmark are thin shells over it.
//
// Shapes: photos #P; the result's cameras/refusals #P (photo order kept).
#pragma once
#include "head/head_model.h"
#include "photos/landmarks.h"
#include "photos/outline.h"
#include "photos/self_calibration.h"
#include "photos/shape_fit.h"
#include "photos/silhouette_obs.h"

#include <memory>
#include <string>
#include <vector>

namespace lk {

struct PhotosJobOptions {
  SelfCalibOptions calib;
  ShapeFitOptions fit;
  double map_max_distance_m = 0.005;  // a map point farther from the head: a map for another head
  double lambda_silhouettes = 0.3;    // fua1998 Sec. 4
  SilhouetteOptions silhouettes;
};

struct PhotosJobResult {
  SelfCalibResult calib;
  ShapeFitResult fit;          // fit.mesh: the person's control mesh
  std::vector<std::string> notes;  // for people: one photo only, photos dropped, ...
};

// The shape-fit stage alone, from a finished self-calibration: every used
// photo's landmarks (with their calibration weights) as feature
// observations. landmarks: the map attached to generic.mesh. outlines:
// null, or one per photo (empty points: none for that photo), each used
// photo's as silhouette observations (silhouette_obs.h; the neck region
// excluded, the chin region's lowest point as the chin line).
Status fit_photos_shape(const GenericHead& generic, const std::vector<SurfacePoint>& landmarks,
                        const std::vector<LandmarkPhoto>& photos, const SelfCalibResult& calib,
                        const PhotosJobOptions& options, ShapeFitResult& fit,
                        const std::vector<PhotoOutline>* outlines = nullptr);

// The silhouette set fit_photos_shape builds (for reports: its stats at the
// generic and the fitted shape). Null when no used photo has an outline.
std::unique_ptr<SilhouetteSet> make_silhouette_set(const GenericHead& generic, const TriMesh& start,
                                                   const SelfCalibResult& calib,
                                                   const std::vector<PhotoOutline>& outlines,
                                                   const SilhouetteOptions& options);

// Both stages. Fails with the first stage's status (the message names the stage and, for
// a refused photo, the photo by its name).
// outlines: as for fit_photos_shape (checked: one per photo, each of its photo's size).
Status run_photos_job(const GenericHead& generic, const LandmarkMap& map, const std::vector<LandmarkPhoto>& photos,
                      const PhotosJobOptions& options, PhotosJobResult& result,
                      const std::vector<PhotoOutline>* outlines = nullptr);

}  // namespace lk
