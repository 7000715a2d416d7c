// libFuzzer target: load_project (project/project_file.h) on arbitrary bytes,
// its checksum off so mutations reach the checks behind it. A loaded project
// promises what the page and the CLI do next: every level exports as a mesh
// with indices in range and finite positions, the chart has one uv per
// finest vertex, the skin's pixels match its size.
#include "fuzz_check.h"
#include "project/export.h"
#include "project/project_file.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, size_t size) {
  lk::HeadProject project;
  const lk::Status s = lk::load_project(data, size, project, /*verify_checksum=*/false);
  if (!s) {
    lk::fuzz::require(!s.message.empty());
    return 0;
  }
  const int levels = project.fit.multires.num_levels();
  size_t finest_vertices = 0;
  for (int l = 0; l <= levels; ++l) {
    lk::TriMesh mesh;
    lk::fuzz::require(lk::project_level_mesh(project, l, lk::ExportFrame::Scan, mesh).ok());
    lk::fuzz::check_mesh(lk::Status::success(), mesh, lk::GeometryKind::Mesh);
    finest_vertices = mesh.positions.size();
  }
  const lk::ProjectTexture& t = project.texture;
  if (!t.uvs.empty()) lk::fuzz::require(t.uvs.size() == finest_vertices);
  for (const lk::Vec2& uv : t.uvs) lk::fuzz::require(uv.allFinite());
  if (!t.skin.empty())
    lk::fuzz::require(t.skin.pixels.size() ==
                      static_cast<size_t>(t.skin.width) * t.skin.height * static_cast<size_t>(t.skin.channels));
  return 0;
}
