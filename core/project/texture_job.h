// The texture job of a head project (tarini2002 Sec. 3): the photos'
// cameras from their clicked points, the stretch-minimizing chart on the
// control mesh refined to the level, then texture/texture.h's skin. Its
// calibration and chart steps serve `likeness texture` on a fit's files too.
#pragma once
#include "calib/calibrate.h"
#include "project/eye_from_views.h"
#include "project/project.h"
#include "subdiv/butterfly.h"
#include "texture/texture.h"

#include <functional>
#include <string>
#include <vector>

namespace lk {

// The job's steps in order: "calibrate", "chart", then texture_head's
// ("parameterize" only measures the chart's stretch there, "bind", "fill
// holes", "resample", "spline", "dilate"). A shell that decodes the photos
// itself reports "decode" before them (texture_job_steps() starts with it).
const std::vector<std::string>& texture_job_steps();
int texture_job_step_index(const std::string& step);  // -1: not a step

// Step boundaries, for the shells' clocks (core has none).
struct StepObserver {
  std::function<void(const std::string& step)> started, finished;
};

// Whether the photos share one camera (one focal length, calibrated
// jointly: far steadier than one focal per photo from 12-15 clicks).
// Auto: when photos_look_like_one_camera says so.
enum class CameraSharing { Auto, Same, Separate };

struct PhotoCalibration {
  std::vector<CalibResult> results;  // #P
  std::vector<Status> status;        // #P: each photo calibrated alone
  bool shared = false;               // results are the joint calibration's
};

// Each photo is calibrated alone first (so every photo's outcome is known);
// the first failure is returned, "calibration failed" with names[i]. Then,
// when shared, all jointly; a joint failure keeps the separate results.
// InvalidInput when the counts differ.
Status calibrate_texture_photos(const std::vector<std::vector<Correspondence>>& points,
                                const std::vector<std::array<int, 2>>& sizes, const std::vector<std::string>& names,
                                const CalibOptions& options, CameraSharing sharing, PhotoCalibration& out);

// The stretch-minimizing chart of control (tarini2002 Sec. 3.1), refined
// to the last of levels (texture/refine_uv.h; no levels: the control
// mesh's own chart). stats: the control chart's stretch.
Status level_chart(const TriMesh& control, const std::vector<ButterflyLevel>& levels, const UvOptions& options,
                   std::vector<Vec2>& fine_uv, UvStats& stats);

// texture_head names photos by index ("photo 2 ..."): the message with
// names[i] instead.
Status name_photos(Status status, const std::vector<std::string>& names);

struct TextureJobInput {
  std::vector<TexturePhoto> photos;                 // decoded images; cameras are set here
  std::vector<std::vector<Correspondence>> points;  // per photo, scan frame
  // The photos' cameras are already set (a head from photos: the
  // self-calibration's, scan frame): nothing is calibrated, points are not read.
  bool cameras_given = false;
  std::vector<std::string> names;                   // per photo, for messages
  int level = -1;                                   // -1: the finest
  TextureOptions options;
  CalibOptions calibration;
  CameraSharing sharing = CameraSharing::Auto;
  // With cameras_given (a head from photos) and no eye texture in the
  // project yet: the iris is looked for in these photos too
  // (eye_from_views.h) when the generic head is given.
  const GenericHead* generic_for_eyes = nullptr;
  // The iris is looked for even when the project holds one (a shell whose
  // own eye texture is not the user's: the one held may be an older head's
  // or have been given up).
  bool replace_eye_texture = false;
  // The photo the user marked as the eye's (one of names, find_photo_name):
  // the iris is looked for in it only, whatever the project holds; empty:
  // in every photo, the most frontal eye first.
  std::string iris_photo;
};

struct TextureJobResult {
  PhotoCalibration calibration;
  int level = 0;
  UvStats chart;       // the control mesh's chart
  TexturedHead head;   // the level in the scan frame, its skin and report
  // The iris from the photos (generic_for_eyes): eye_status says whether it
  // was looked for and found (not looked for: Empty); a failure to find it
  // is not the job's failure.
  Status eye_status = Status::error(ErrorCode::Empty, "the iris was not looked for");
  EyeFromViewsResult eye;
};

// Textures the project at rest; on success project.texture holds the
// finest level's chart and the skin, and project.parts the iris found in
// the photos (generic_for_eyes). InvalidInput on no fit, a missing
// level, no photo or too many, fewer than 6 points on a photo; calibration
// and texture_head errors name the photos; Cancelled from progress
// (called with the step names above).
Status texture_project(HeadProject& project, TextureJobInput& input, TextureJobResult& out,
                       const StepObserver& observer = {}, const ProgressFn& progress = {});

}  // namespace lk
