// libFuzzer target: ScanStreamReader (scan_stream.h) fed in pieces cut at
// fuzzer-chosen points, against read_geometry on the same bytes. The input
// is: a byte naming the file (scan.ply, .obj, .xyz, .pts, .vtk or no
// extension: the format told from the bytes), a byte k, then k % 16 cut
// points (two bytes each, offsets into the file), then the file. Beyond
// fuzz_check.h's promises, the stream must give exactly what read_geometry
// gives: the same status, message, mesh (bit for bit) and cloud.
#include "fuzz_check.h"
#include "io/scan_stream.h"

#include <algorithm>
#include <cstring>
#include <vector>

namespace {

template <typename T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

bool same_mesh(const lk::TriMesh& a, const lk::TriMesh& b) {
  return same_bits(a.positions, b.positions) && same_bits(a.normals, b.normals) && same_bits(a.colors, b.colors) &&
         same_bits(a.uvs, b.uvs) && a.uv_per_corner == b.uv_per_corner && a.triangles == b.triangles;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* input, size_t input_size) {
  static const char* const kNames[] = {"scan.ply", "scan.obj", "scan.xyz", "scan.pts", "scan.vtk", "scan"};
  if (input_size < 2) return 0;
  const std::string name = kNames[input[0] % 6];
  const size_t cuts_wanted = input[1] % 16;
  size_t pos = 2;
  std::vector<size_t> cuts;
  for (size_t k = 0; k < cuts_wanted && pos + 2 <= input_size; ++k, pos += 2)
    cuts.push_back(static_cast<size_t>(input[pos]) << 8 | input[pos + 1]);
  const std::uint8_t* data = input + pos;
  const size_t size = input_size - pos;
  for (size_t& c : cuts) c = size ? c % (size + 1) : 0;
  cuts.push_back(size);
  std::sort(cuts.begin(), cuts.end());

  lk::TriMesh mesh;
  lk::PointCloud cloud;
  lk::GeometryKind kind = lk::GeometryKind::PointCloud;
  const lk::Status s = lk::fuzz::watched(size, [&] {
    lk::ScanStreamReader reader(name, size);
    size_t at = 0;
    for (size_t c : cuts) {
      // Empty pieces too (two equal cut points): a push of nothing is fine.
      if (lk::Status e = reader.push(data + at, c - at); !e) {
        lk::TriMesh unused;
        lk::fuzz::require(reader.finish(unused, kind).message == e.message && unused.positions.empty());
        return e;
      }
      at = c;
    }
    lk::fuzz::require(reader.bytes_received() == size);
    return reader.finish(mesh, cloud, kind);
  });
  lk::fuzz::check_mesh(s, mesh, kind);

  lk::TriMesh whole;
  lk::PointCloud whole_cloud;
  lk::GeometryKind whole_kind = lk::GeometryKind::PointCloud;
  const lk::Status w = lk::read_geometry(name, data, size, whole, whole_cloud, whole_kind);
  lk::fuzz::require(s.ok() == w.ok() && s.code == w.code && s.message == w.message);
  if (s.ok()) {
    lk::fuzz::require(kind == whole_kind && same_mesh(mesh, whole));
    lk::fuzz::require(same_bits(cloud.positions, whole_cloud.positions) &&
                      same_bits(cloud.normals, whole_cloud.normals) && same_bits(cloud.colors, whole_cloud.colors) &&
                      cloud.faces == whole_cloud.faces);
  }
  return 0;
}
