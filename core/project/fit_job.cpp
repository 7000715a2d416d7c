#include "project/fit_job.h"

#include "project/pose.h"

#include <algorithm>
#include <cmath>

namespace lk {

Status fit_project(PointCloud scan, const GenericHead& generic, const FitHeadOptions& options, HeadProject& project,
                   const FitStageObserver& observer, const ProgressFn& progress) {
  project = HeadProject{};
  project.options = options;
  // A dense cloud is thinned first (FitHeadOptions::thin_cells_per_edge), and
  // the full scan's normals and colours let go before the fit: its
  // positions stay for the checks.
  PointCloud thinned;
  ScanThinning thinning;
  Status status = thin_scan_for_fit(scan, generic, options, thinned, thinning);
  if (!status.ok()) return status;
  if (thinning.thinned) {
    std::vector<Vec3>().swap(scan.normals);
    std::vector<Vec3>().swap(scan.colors);
    status = fit_head_thinned(thinned, thinning, generic, options, project.fit, observer, progress);
    thinned = PointCloud{};
  } else {
    FitHeadOptions once = options;  // thin_scan_for_fit has decided
    once.thin_cells_per_edge = 0;
    status = fit_head(scan, generic, once, project.fit, observer, progress);
  }
  if (!status.ok()) return status;
  // Kept for the checks, which read positions and faces only: a large
  // scan's normals and colours would hold memory (the worker's heap) for
  // nothing.
  project.scan.positions = std::move(scan.positions);
  project.scan.faces = std::move(scan.faces);
  project.frame = HeadFrame::from(project.fit.scan_to_head);
  project.rig = make_animation_rig(project.fit.control, generic.annotations);
  return Status::success();
}

Status refit_project(const HeadProject& project, const GenericHead& generic, const RefitChanges& changes,
                     HeadProject& refitted, const FitStageObserver& observer, const ProgressFn& progress) {
  if (project.scan.positions.empty())
    return Status::error(ErrorCode::InvalidInput,
                         "this head keeps no scan to fit again (a head made from photos): drop a scan to fit one");
  FitHeadOptions options = project.options;
  if (changes.levels > 0) options.levels = changes.levels;
  if (changes.up) options.up = *changes.up;
  if (changes.facing) options.facing = *changes.facing;
  HeadProject fresh;
  const Status status = fit_project(project.scan, generic, options, fresh, observer, progress);
  if (!status.ok()) return status;
  fresh.parts = project.parts;  // the eyes' and teeth's textures do not depend on the fit
  refitted = std::move(fresh);
  return Status::success();
}

std::vector<TextureLandmark> texture_landmarks(const GenericHead& g) {
  const HeadAnnotations& ann = g.annotations;
  const std::vector<Vec3>& P = g.mesh.positions;
  auto region = [&](const char* name) {
    auto it = ann.regions.find(name);
    return it == ann.regions.end() ? std::vector<int>{} : it->second;
  };
  // The region's vertex that maximizes score (or -1 for an empty region).
  auto best = [&](const std::vector<int>& set, auto score) {
    int pick = -1;
    double top = -1e300;
    for (int v : set)
      if (v >= 0 && v < static_cast<int>(P.size()) && score(P[v]) > top) {
        top = score(P[v]);
        pick = v;
      }
    return pick;
  };
  std::vector<int> corners;  // the two mouth corners: in "lips" but in neither lip
  {
    const std::vector<int> up = region("upper_lip"), low = region("lower_lip");
    for (int v : region("lips"))
      if (std::find(up.begin(), up.end(), v) == up.end() && std::find(low.begin(), low.end(), v) == low.end() &&
          v >= 0 && v < static_cast<int>(P.size()))
        corners.push_back(v);
    // The mouth bag is in "lips" too: keep the frontmost candidates.
    std::sort(corners.begin(), corners.end(), [&](int a, int b) { return P[a].z() > P[b].z(); });
  }
  double front_z = -1e300;
  for (const Vec3& p : P) front_z = std::max(front_z, p.z());
  auto frontal = [&](const Vec3& p) { return p.z() - front_z; };
  std::vector<TextureLandmark> out = {
      {"eye_right_outer", "Right eye, outer corner", best(ann.eye_right.rim, [](const Vec3& p) { return -p.x(); })},
      {"eye_right_inner", "Right eye, inner corner", best(ann.eye_right.rim, [](const Vec3& p) { return p.x(); })},
      {"eye_left_inner", "Left eye, inner corner", best(ann.eye_left.rim, [](const Vec3& p) { return -p.x(); })},
      {"eye_left_outer", "Left eye, outer corner", best(ann.eye_left.rim, [](const Vec3& p) { return p.x(); })},
      {"brow_middle", "Between the brows", best(region("brow"), [&](const Vec3& p) { return frontal(p) - 4 * std::abs(p.x()); })},
      {"nose_tip", "Tip of the nose", best(region("nose"), [](const Vec3& p) { return p.z(); })},
      {"mouth_right", "Right mouth corner", best(corners, [&](const Vec3& p) { return -p.x() + 0.1 * frontal(p); })},
      {"mouth_left", "Left mouth corner", best(corners, [&](const Vec3& p) { return p.x() + 0.1 * frontal(p); })},
      {"upper_lip", "Middle of the upper lip", best(region("upper_lip"), [](const Vec3& p) { return p.z() - 4 * std::abs(p.x()); })},
      {"chin", "Tip of the chin", best(region("chin"), [](const Vec3& p) { return p.z() - p.y() - 4 * std::abs(p.x()); })},
      {"ear_right_lobe", "Right ear lobe (bottom)", best(region("ear_right"), [](const Vec3& p) { return -p.y(); })},
      {"ear_right_top", "Right ear, top", best(region("ear_right"), [](const Vec3& p) { return p.y(); })},
      {"ear_left_lobe", "Left ear lobe (bottom)", best(region("ear_left"), [](const Vec3& p) { return -p.y(); })},
      {"ear_left_top", "Left ear, top", best(region("ear_left"), [](const Vec3& p) { return p.y(); })},
  };
  out.erase(std::remove_if(out.begin(), out.end(), [](const TextureLandmark& l) { return l.vertex < 0; }), out.end());
  return out;
}

}  // namespace lk
