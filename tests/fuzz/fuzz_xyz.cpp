// libFuzzer target: read_xyz, and read_geometry's dispatch by content (a
// name without a known extension), on arbitrary bytes (see fuzz_check.h).
#include "fuzz_check.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, size_t size) {
  lk::PointCloud cloud;
  const lk::Status s = lk::fuzz::watched(size, [&] { return lk::read_xyz(data, size, cloud); });
  lk::fuzz::check_cloud(s, cloud);

  lk::TriMesh mesh;
  lk::GeometryKind kind;
  const lk::Status g =
      lk::fuzz::watched(size, [&] { return lk::read_geometry("dropped", data, size, mesh, cloud, kind); });
  lk::fuzz::check_mesh(g, mesh, kind);
  if (g) {
    lk::fuzz::check_cloud(g, cloud);
    lk::fuzz::require(cloud.positions.size() == mesh.positions.size());
  }
  return 0;
}
