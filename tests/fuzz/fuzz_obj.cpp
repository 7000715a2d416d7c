// libFuzzer target: read_obj on arbitrary bytes (see fuzz_check.h). A line
// "#mtl" splits the input: what follows is handed over as the MTL text, so
// the material parser is fuzzed too.
#include "fuzz_check.h"

#include <cstring>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, size_t size) {
  size_t obj_size = size;
  std::string mtl;
  static const char kSplit[] = "\n#mtl\n";
  const void* at = memmem(data, size, kSplit, sizeof(kSplit) - 1);
  if (at) {
    obj_size = static_cast<size_t>(static_cast<const std::uint8_t*>(at) - data);
    mtl.assign(reinterpret_cast<const char*>(data) + obj_size + sizeof(kSplit) - 1,
               size - obj_size - (sizeof(kSplit) - 1));
  }
  lk::TriMesh mesh;
  lk::GeometryKind kind;
  const lk::Status s = lk::fuzz::watched(size, [&] { return lk::read_obj(data, obj_size, mesh, kind, mtl); });
  lk::fuzz::check_mesh(s, mesh, kind);
  (void)lk::obj_mtllib(data, obj_size);
  return 0;
}
