// libFuzzer target: read_ply on arbitrary bytes (see fuzz_check.h).
#include "fuzz_check.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, size_t size) {
  lk::TriMesh mesh;
  lk::GeometryKind kind;
  const lk::Status s = lk::fuzz::watched(size, [&] { return lk::read_ply(data, size, mesh, kind); });
  lk::fuzz::check_mesh(s, mesh, kind);
  return 0;
}
