#include "project/photos_project.h"

#include "head/head_creases.h"
#include "head/skin_detail.h"
#include "project/pose.h"

namespace lk {

Status photos_project(const GenericHead& generic, const LandmarkMap& map, const std::vector<LandmarkPhoto>& photos,
                      const PhotosJobOptions& options, int levels, HeadProject& project, PhotosJobResult& result,
                      const std::vector<std::vector<double>>* skin_detail,
                      const std::vector<PhotoOutline>* outlines) {
  project = HeadProject{};
  result = PhotosJobResult{};
  if (levels < 1 || levels > 4) return Status::error(ErrorCode::InvalidInput, "photos: levels must be 1..4");
  Status s = run_photos_job(generic, map, photos, options, result, outlines);
  if (!s) return s;
  return project_from_photos(generic, result, levels, project, skin_detail);
}

Status project_from_photos(const GenericHead& generic, const PhotosJobResult& result, int levels, HeadProject& project,
                           const std::vector<std::vector<double>>* skin_detail) {
  project = HeadProject{};
  if (levels < 1 || levels > 4) return Status::error(ErrorCode::InvalidInput, "photos: levels must be 1..4");
  FitHeadResult& fit = project.fit;
  fit.aligned = generic.mesh;
  fit.local = result.fit.mesh;
  fit.control = result.fit.mesh;
  fit.notes = result.notes;
  // The levels as `likeness photos` writes them: the generic head's creases
  // (eye and lip rims, the canthi, the socket rings) and, no scan having
  // measured any, the generic head's skin detail as displacements
  // (head/skin_detail.h) when given.
  Status s = build_multires(fit.control, head_creases(generic.mesh, generic.annotations), levels, fit.multires);
  if (s && skin_detail) s = apply_skin_detail(*skin_detail, fit.multires);
  if (!s) {
    project = HeadProject{};
    return with_context(s, "photos (levels)");
  }
  for (int l = 1; l <= levels; ++l) fit.level_meshes.push_back(level_mesh(fit.multires, l));
  project.options.levels = levels;
  project.frame = HeadFrame{};  // head frame = shown frame: metres, +y up, +z facing
  project.rig = make_animation_rig(fit.control, generic.annotations);
  return Status::success();
}

}  // namespace lk
