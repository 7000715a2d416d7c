#include "project/texture_job.h"

#include "project/pose.h"
#include "texture/refine_uv.h"

#include <algorithm>

namespace lk {

const std::vector<std::string>& texture_job_steps() {
  static const std::vector<std::string> steps = {"decode", "calibrate", "chart", "parameterize", "bind",
                                                 "fill holes", "resample", "spline", "dilate"};
  return steps;
}

int texture_job_step_index(const std::string& step) {
  const auto& steps = texture_job_steps();
  const auto it = std::find(steps.begin(), steps.end(), step);
  return it == steps.end() ? -1 : static_cast<int>(it - steps.begin());
}

Status calibrate_texture_photos(const std::vector<std::vector<Correspondence>>& points,
                                const std::vector<std::array<int, 2>>& sizes, const std::vector<std::string>& names,
                                const CalibOptions& options, CameraSharing sharing, PhotoCalibration& out) {
  if (points.size() != sizes.size() || names.size() != sizes.size())
    return Status::error(ErrorCode::InvalidInput, std::to_string(points.size()) + " sets of points for " +
                                                      std::to_string(sizes.size()) + " photos");
  out = PhotoCalibration{};
  out.results.resize(points.size());
  out.status.resize(points.size());
  Status first_failure;
  for (size_t i = 0; i < points.size(); ++i) {
    out.status[i] = calibrate_camera(points[i], sizes[i][0], sizes[i][1], options, out.results[i]);
    if (!out.status[i].ok() && first_failure.ok())
      first_failure = Status::error(out.status[i].code, names[i] + ": calibration failed: " + out.status[i].message);
  }
  if (!first_failure.ok()) return first_failure;
  const bool shared = sharing == CameraSharing::Same ||
                      (sharing == CameraSharing::Auto && photos_look_like_one_camera(sizes));
  if (shared && points.size() > 1) {
    std::vector<CalibResult> joint;
    if (calibrate_photos(points, sizes, options, joint, /*same_camera=*/true).ok()) {
      out.results = std::move(joint);
      out.shared = true;
    }
  }
  return Status::success();
}

Status level_chart(const TriMesh& control, const std::vector<ButterflyLevel>& levels, const UvOptions& options,
                   std::vector<Vec2>& fine_uv, UvStats& stats) {
  TriMesh mesh;  // positions and triangles only: the chart of the surface
  mesh.positions = control.positions;
  mesh.triangles = control.triangles;
  std::vector<Vec2> control_uv;
  Status st = parameterize_stretch(mesh, options, control_uv, stats);
  if (!st.ok()) return with_context(st, "parameterization of the control mesh");
  if (levels.empty()) {
    fine_uv = std::move(control_uv);
    return Status::success();
  }
  return refine_chart_uvs(levels, control_uv, fine_uv);
}

Status name_photos(Status status, const std::vector<std::string>& names) {
  for (size_t i = 0; i < names.size(); ++i) {
    const std::string tag = "photo " + std::to_string(i) + " ";
    if (status.message.rfind(tag, 0) == 0) status.message = names[i] + status.message.substr(tag.size() - 1);
  }
  return status;
}

namespace {

Status cancelled(const std::string& where) {
  return Status::error(ErrorCode::Cancelled, "texturing cancelled at " + where);
}

}  // namespace

Status texture_project(HeadProject& project, TextureJobInput& input, TextureJobResult& out,
                       const StepObserver& observer, const ProgressFn& progress) {
  MultiresMesh& mr = project.fit.multires;
  if (mr.num_levels() == 0)
    return Status::error(ErrorCode::InvalidInput, "fit a head first: there is no head to texture");
  const int level = input.level < 0 ? mr.num_levels() : input.level;
  if (level > mr.num_levels()) return Status::error(ErrorCode::InvalidInput, "no level " + std::to_string(level));
  const size_t count = input.photos.size();
  if (count == 0) return Status::error(ErrorCode::InvalidInput, "no photo to texture from");
  if (count > static_cast<size_t>(kMaxTexturePhotos))
    return Status::error(ErrorCode::InvalidInput, std::to_string(count) + " photos; at most " +
                                                      std::to_string(kMaxTexturePhotos) + " are used");
  if ((!input.cameras_given && input.points.size() != count) || input.names.size() != count)
    return Status::error(ErrorCode::InvalidInput, "one set of points and one name per photo");
  out = TextureJobResult{};
  out.level = level;
  const auto start = [&](const std::string& step) {
    if (observer.started) observer.started(step);
    return report(progress, step.c_str(), 0.0);
  };
  const auto finish = [&](const std::string& step) {
    if (observer.finished) observer.finished(step);
  };

  // 1. One camera per photo (unless given).
  if (!start("calibrate")) return cancelled("calibrate");
  if (!input.cameras_given) {
    std::vector<std::array<int, 2>> sizes;
    for (const TexturePhoto& p : input.photos) sizes.push_back({p.image.width, p.image.height});
    const Status calibrated = calibrate_texture_photos(input.points, sizes, input.names, input.calibration,
                                                       input.sharing, out.calibration);
    if (!calibrated.ok()) {
      finish("calibrate");
      return calibrated;
    }
    for (size_t i = 0; i < count; ++i) input.photos[i].camera = out.calibration.results[i].camera;
  }
  finish("calibrate");

  // 2. The chart on the fitted control mesh (head frame: the view weight
  // assumes the head looks along +z), refined to the finest level; the
  // level is textured at rest.
  if (!start("chart")) return cancelled("chart");
  // Re-evaluated at rest whatever the pose (the fit's own state differs
  // from an evaluation by rounding only), every level current.
  if (Status st = pose_project(project, 0.0); !st.ok()) return st;
  std::vector<Vec2> finest_uv;
  if (Status st = level_chart(project.fit.control, mr.levels, UvOptions{}, finest_uv, out.chart); !st.ok()) return st;
  finish("chart");

  // 3. The skin (texture_head's own steps).
  TriMesh mesh;
  mesh.positions = project.frame.to_scan(mr.state.displaced[level]);
  mesh.triangles = mr.triangles(level);
  mesh.uvs.assign(finest_uv.begin(), finest_uv.begin() + mesh.positions.size());
  std::string current;
  const ProgressFn inner = [&](const char* step, double fraction) {
    if (fraction <= 0 && current != step && texture_job_step_index(step) >= 0) {
      if (!current.empty()) finish(current);
      current = step;
      if (observer.started) observer.started(current);
    }
    return report(progress, step, fraction);
  };
  Status st = texture_head(mesh, input.photos, input.options, out.head, inner);
  if (!current.empty()) finish(current);
  if (!st.ok()) return name_photos(st, input.names);
  project.texture.uvs = std::move(finest_uv);
  project.texture.skin = out.head.skin;

  // 4. The iris from the same photos, where no eye photo gave one (or in
  // the one photo the user marked).
  const bool search = project.parts.eye_texture.empty() || input.replace_eye_texture || !input.iris_photo.empty();
  if (input.cameras_given && input.generic_for_eyes && search) {
    std::vector<const Image*> images;
    std::vector<Camera> cameras;
    for (const TexturePhoto& p : input.photos) {
      images.push_back(&p.image);
      cameras.push_back(p.camera);
    }
    EyeFromViewsOptions options;
    if (!input.iris_photo.empty()) options.only_photo = find_photo_name(input.names, input.iris_photo);
    if (!input.iris_photo.empty() && options.only_photo < 0)
      out.eye_status = Status::error(ErrorCode::InvalidInput, input.iris_photo + " is not one of the photos textured: " +
                                                                  "the iris was not looked for");
    else
      out.eye_status = find_project_iris(project, *input.generic_for_eyes, images, cameras, input.names, out.eye, options);
  }
  return Status::success();
}

}  // namespace lk
