// libFuzzer target: PlyStreamReader fed in chunks against read_ply on the
// same bytes. The first input byte picks the chunk sizes (up to 1, 2, 4, ...
// 2048 bytes, varied from chunk to chunk), the rest is the file. Beyond
// fuzz_check.h's promises, the stream must give exactly what read_ply gives:
// the same status, message and mesh, bit for bit.
#include "fuzz_check.h"
#include "io/scan_stream.h"

#include <cstring>

namespace {

template <typename T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* input, size_t input_size) {
  if (input_size == 0) return 0;
  const std::uint8_t pattern = input[0];
  const std::uint8_t* data = input + 1;
  const size_t size = input_size - 1;
  const std::uint32_t max_chunk = 1u << (pattern % 12);
  std::uint32_t rng = pattern * 2654435761u + 1;

  lk::TriMesh mesh;
  lk::GeometryKind kind = lk::GeometryKind::PointCloud;
  const lk::Status s = lk::fuzz::watched(size, [&] {
    lk::PlyStreamReader reader(size);
    size_t pos = 0;
    while (pos < size) {
      rng = rng * 1664525u + 1013904223u;
      const size_t n = std::min<size_t>(size - pos, 1 + (rng >> 8) % max_chunk);
      if (lk::Status e = reader.push(data + pos, n); !e) {
        lk::TriMesh unused;
        lk::fuzz::require(reader.finish(unused, kind).message == e.message);
        return e;
      }
      pos += n;
    }
    return reader.finish(mesh, kind);
  });
  lk::fuzz::check_mesh(s, mesh, kind);

  lk::TriMesh whole;
  lk::GeometryKind whole_kind = lk::GeometryKind::PointCloud;
  const lk::Status w = lk::read_ply(data, size, whole, whole_kind);
  lk::fuzz::require(s.ok() == w.ok() && s.code == w.code && s.message == w.message);
  if (s.ok()) {
    lk::fuzz::require(kind == whole_kind && mesh.uv_per_corner == whole.uv_per_corner);
    lk::fuzz::require(same_bits(mesh.positions, whole.positions) && same_bits(mesh.normals, whole.normals) &&
                      same_bits(mesh.colors, whole.colors) && same_bits(mesh.uvs, whole.uvs) &&
                      mesh.triangles == whole.triangles);
  }
  return 0;
}
