#include "project/export.h"

#include "io/io.h"
#include "project/pose.h"

namespace lk {

Status project_level_mesh(HeadProject& project, int level, ExportFrame frame, TriMesh& out) {
  MultiresMesh& mr = project.fit.multires;
  if (mr.num_levels() == 0) return Status::error(ErrorCode::InvalidInput, "no fitted head to export");
  if (level < 0 || level > mr.num_levels())
    return Status::error(ErrorCode::InvalidInput, "no level " + std::to_string(level));
  // An animation may have updated only the coarser levels.
  if (Status st = ensure_current(mr); !st.ok()) return st;
  out = TriMesh{};
  out.positions = frame == ExportFrame::Scan ? project.frame.to_scan(mr.state.displaced[level])
                                             : mr.state.displaced[level];
  out.triangles = mr.triangles(level);
  return Status::success();
}

Status export_level(HeadProject& project, int level, LevelFormat format, ExportFrame frame, Bytes& out) {
  const bool map = format == LevelFormat::DistanceMap;
  if (map) {
    const ProjectQuality& q = project.quality;
    if (!q.measured || !q.to_scan_status.ok())
      return Status::error(ErrorCode::InvalidInput, "no distance map yet: it comes with the checks of the fitted head");
    level = project.fit.multires.num_levels();
    if (Status st = rest_pose(project); !st.ok()) return st;
  }
  TriMesh m;
  if (Status st = project_level_mesh(project, level, frame, m); !st.ok()) return st;
  if (map) {
    if (project.quality.to_scan_colors.size() != m.positions.size())
      return Status::error(ErrorCode::Internal, "the distance map does not match the finest level");
    m.colors = project.quality.to_scan_colors;
  }
  if (format == LevelFormat::Obj) {
    const std::string text = write_obj(m);
    out.assign(text.begin(), text.end());
  } else {
    out = write_ply(m);
  }
  return Status::success();
}

Status export_textured(HeadProject& project, int level, const std::string& base, ExportFrame frame,
                       TexturedFiles& out) {
  if (project.fit.multires.num_levels() == 0) return Status::error(ErrorCode::InvalidInput, "no fitted head to export");
  const ProjectTexture& tex = project.texture;
  if (tex.empty()) return Status::error(ErrorCode::InvalidInput, "the head is not textured yet");
  TriMesh m;
  if (Status st = project_level_mesh(project, level, frame, m); !st.ok()) return st;
  if (m.positions.size() > tex.uvs.size())
    return Status::error(ErrorCode::Internal, "the texture chart is smaller than the level");
  m.uvs.assign(tex.uvs.begin(), tex.uvs.begin() + m.positions.size());
  out.obj = write_obj(m, base + ".mtl");
  out.mtl = write_mtl(base + ".png");
  out.png = write_png(tex.skin);
  if (out.png.empty()) return Status::error(ErrorCode::Internal, "could not encode the skin PNG");
  return Status::success();
}

}  // namespace lk
