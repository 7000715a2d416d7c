// A head project from photos (issue 37): the photos job's fitted control
// mesh (photos/photos_job.h, run here unchanged) made into a HeadProject the
// way fit_project makes one from a scan, so the page and the CLI animate,
// check, export and save it like a fitted head.
//
// What differs from a scan's project: there is no scan (project.scan is
// empty, so the checks have no distance to a scan), the head frame is the
// scan frame (metres, the generic head's size: scale is not observable from
// uncalibrated photos), and the levels carry no measured displacements (no
// scan to measure them on): they are the fitted control mesh's Butterfly
// levels with the generic head's skin detail (head/skin_detail.h), as
// `likeness photos` writes them.
#pragma once
#include "photos/photos_job.h"
#include "project/project.h"

#include <vector>

namespace lk {

// Runs run_photos_job(generic, map, photos, options, result, outlines) and, when it
// succeeds, makes project a new project of its control mesh with `levels`
// (1..4) Butterfly levels (project_from_photos, with skin_detail). fit.aligned is the generic head (the shape the
// self-calibration starts from), fit.local and fit.control the fitted
// control mesh; fit.notes are the job's notes. On an error project is left
// empty and result holds what the job got to (each photo's refusal).
Status photos_project(const GenericHead& generic, const LandmarkMap& map, const std::vector<LandmarkPhoto>& photos,
                      const PhotosJobOptions& options, int levels, HeadProject& project, PhotosJobResult& result,
                      const std::vector<std::vector<double>>* skin_detail = nullptr,
                      const std::vector<PhotoOutline>* outlines = nullptr);

// The project of a finished photos job (what photos_project makes after
// running it): for `likeness photos`, which runs the job with its outlines
// and images itself.
// skin_detail: the generic head's skin detail (head/skin_detail.h,
// generic_skin_detail of `generic`, made once and reused by the caller: it
// costs a few hundred milliseconds), put on the levels as displacements, as
// `likeness photos` and the page do; null: the plain Butterfly levels
// (`likeness photos --no-skin-detail`), the furrows of the generic head's
// smooth levels left in.
Status project_from_photos(const GenericHead& generic, const PhotosJobResult& result, int levels, HeadProject& project,
                           const std::vector<std::vector<double>>* skin_detail = nullptr);

}  // namespace lk
