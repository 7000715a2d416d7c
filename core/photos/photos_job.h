// Photos to head, the native core's job (issue 37): landmark files of
// several photos + the landmark map -> cameras (self_calibration.h) and the
// generic head's control mesh deformed to the person (shape_fit.h). The CLI
// (`likeness photos`) and the benchmark are thin shells over it.
//
// Shapes: photos #P; the result's cameras/refusals #P (photo order kept).
#pragma once
#include "head/head_model.h"
#include "photos/landmarks.h"
#include "photos/self_calibration.h"
#include "photos/shape_fit.h"

#include <string>
#include <vector>

namespace lk {

struct PhotosJobOptions {
  SelfCalibOptions calib;
  ShapeFitOptions fit;
  double map_max_distance_m = 0.005;  // a map point farther from the head: a map for another head
};

struct PhotosJobResult {
  SelfCalibResult calib;
  ShapeFitResult fit;          // fit.mesh: the person's control mesh
  std::vector<std::string> notes;  // for people: one photo only, photos dropped, ...
};

// The shape-fit stage alone, from a finished self-calibration: every used
// photo's landmarks (with their calibration weights) as feature
// observations. landmarks: the map attached to generic.mesh.
Status fit_photos_shape(const GenericHead& generic, const std::vector<SurfacePoint>& landmarks,
                        const std::vector<LandmarkPhoto>& photos, const SelfCalibResult& calib,
                        const PhotosJobOptions& options, ShapeFitResult& fit);

// Both stages. Fails with the first stage's status (the message names the stage and, for
// a refused photo, the photo by its name).
Status run_photos_job(const GenericHead& generic, const LandmarkMap& map, const std::vector<LandmarkPhoto>& photos,
                      const PhotosJobOptions& options, PhotosJobResult& result);

}  // namespace lk
