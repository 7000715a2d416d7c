// The fit job of a head project: the scan in, the fitted head (jeong2002
// Sec. 4-5, pipeline/fit_head.h), its frame and its animation rig out; and
// the texture landmarks, the points a user clicks in each photo to
// calibrate it (tarini2002 Sec. 3: "about 12-15 corresponding feature
// points").
#pragma once
#include "project/project.h"

#include <optional>
#include <string>
#include <vector>

namespace lk {

// Fits generic to scan with options and makes project a new project of it
// (the scan's positions and faces are moved in). On an error (fit_head's) project.fit holds what
// the fit got to, for a report, and the project is not usable: keep the
// previous project elsewhere. Stage timing is the caller's, through observer.
Status fit_project(PointCloud scan, const GenericHead& generic, const FitHeadOptions& options,
                   HeadProject& project, const FitStageObserver& observer = {}, const ProgressFn& progress = {});

// What fitting a kept scan again changes of the options it was fitted with:
// levels > 0 replaces theirs; up and facing, when set, say anew how the scan
// is turned (the page's "Scan's axes", for a bust that came lying down).
struct RefitChanges {
  int levels = 0;
  std::optional<Vec3> up, facing;
};

// Fits the generic head again to the scan project keeps (a project opened
// from a file holds its scan's points and faces, not the scan file), with the
// options it was fitted with as changed. refitted becomes the new project;
// project is left as it was (also on an error). A project without a scan (a
// head from photos) is refused.
Status refit_project(const HeadProject& project, const GenericHead& generic, const RefitChanges& changes,
                     HeadProject& refitted, const FitStageObserver& observer = {}, const ProgressFn& progress = {});

// A named control vertex of the generic head (the fitted head has the same
// vertex indices). "right"/"left" are the person's own sides: +x is the
// head's left.
struct TextureLandmark {
  const char* id;
  const char* label;
  int vertex;
};

// Picked from the annotations (extremes of the eye rims, lips, ears, nose,
// chin, brow), in the order a user is asked for them; a landmark whose
// region is missing is left out.
std::vector<TextureLandmark> texture_landmarks(const GenericHead& generic);

}  // namespace lk
