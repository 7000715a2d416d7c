// Format dispatch for geometry files: by extension, else by content.
#include "io/io.h"
#include "io/text_scan.h"

#include <cstring>

namespace lk {

namespace {

bool starts_with(const std::uint8_t* data, size_t size, const char* prefix) {
  const size_t n = std::strlen(prefix);
  return size >= n && std::memcmp(data, prefix, n) == 0;
}

}  // namespace

std::string io_detail::geometry_format_by_name(const std::string& name) {
  const std::string ext = io_detail::lower_extension(name);
  if (ext == "txt" || ext == "pts" || ext == "asc" || ext == "xyzn" || ext == "xyzrgb") return "xyz";
  return ext == "ply" || ext == "obj" || ext == "xyz" || ext == "vtk" ? ext : "";
}

// Guesses the format from the first meaningful line.
std::string io_detail::sniff_geometry_format(const std::uint8_t* data, size_t size) {
  if (starts_with(data, size, "ply\n") || starts_with(data, size, "ply\r\n")) return "ply";
  if (starts_with(data, size, "# vtk DataFile")) return "vtk";
  const char* p = reinterpret_cast<const char*>(data);
  io_detail::Tokenizer tok(p, p + (size < 4096 ? size : 4096));
  while (!tok.at_end()) {
    const std::string_view key = tok.next_on_line();
    if (!key.empty() && key[0] != '#') {
      if (key == "v" || key == "vn" || key == "vt" || key == "f" || key == "o" || key == "g" || key == "mtllib" ||
          key == "usemtl")
        return "obj";
      double x;
      if (io_detail::parse_double(key.data(), key.data() + key.size(), x)) return "xyz";
      return "";
    }
    tok.skip_line();
  }
  return "";
}

Status read_geometry(const std::string& name, const std::uint8_t* data, size_t size, TriMesh& mesh,
                     PointCloud& cloud, GeometryKind& kind) {
  mesh = TriMesh();
  cloud = PointCloud();
  kind = GeometryKind::PointCloud;
  if (size == 0) return Status::error(ErrorCode::Empty, "empty input: no bytes");
  if (Status s = io_detail::check_input_size(size, kMaxGeometryBytes); !s) return s;
  std::string format = io_detail::geometry_format_by_name(name);
  if (format.empty()) {
    format = io_detail::sniff_geometry_format(data, size);
    if (format.empty())
      return Status::error(ErrorCode::Unsupported,
                           "unknown geometry format (expected PLY, OBJ, XYZ or legacy VTK by extension or content)");
  }
  Status s;
  if (format == "ply") {
    s = read_ply(data, size, mesh, kind);
  } else if (format == "obj") {
    s = read_obj(data, size, mesh, kind);
  } else if (format == "vtk") {
    s = read_vtk(data, size, mesh, kind);
  } else {
    s = read_xyz(data, size, cloud);
    if (s) {
      mesh.positions = cloud.positions;
      mesh.normals = cloud.normals;
      mesh.colors = cloud.colors;
      kind = GeometryKind::PointCloud;
    }
    return s;
  }
  if (!s) return s;
  cloud = to_point_cloud(mesh);
  return s;
}

PointCloud to_point_cloud(const TriMesh& mesh) {
  PointCloud cloud;
  cloud.positions = mesh.positions;
  if (mesh.normals.size() == mesh.positions.size()) cloud.normals = mesh.normals;
  if (mesh.colors.size() == mesh.positions.size()) cloud.colors = mesh.colors;
  cloud.faces = mesh.triangles;
  return cloud;
}

}  // namespace lk
