#include "project/quality_job.h"

#include "project/pose.h"

namespace lk {

Status measure_project_quality(HeadProject& project, const GenericHead& generic) {
  ProjectQuality& q = project.quality;
  if (q.measured) return Status::success();
  if (project.fit.multires.num_levels() == 0)
    return Status::error(ErrorCode::InvalidInput, "no fitted head to check");
  if (Status st = rest_pose(project); !st.ok()) return st;
  q.status = measure_fit_quality(project.fit, generic.annotations, q.fit);
  // The face's vertices to the scan's triangles, or to its points' local
  // patches: a bulge away from the scan shows only this way round.
  std::vector<double> per_vertex;
  q.to_scan_status = measure_fit_to_scan(project.fit, project.scan, generic, q.to_scan, "face", &per_vertex);
  if (q.to_scan_status.ok()) q.to_scan_colors = distance_colors(per_vertex);
  q.measured = true;
  return Status::success();
}

}  // namespace lk
