// File helpers for the native harness and tests: read whole files into bytes,
// write bytes out, and the load_* wrappers that prefix every message with the
// file's path. The parsers themselves never touch the file system.
#include "io/io.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <sys/stat.h>

namespace lk {

namespace {

std::string directory_of(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? "" : path.substr(0, slash + 1);
}

bool is_absolute(const std::string& path) { return !path.empty() && path[0] == '/'; }

}  // namespace

Status read_file(const std::string& path, Bytes& out, size_t max_bytes) {
  out.clear();
  struct stat st;
  if (::stat(path.c_str(), &st) != 0)
    return Status::error(ErrorCode::InvalidInput, path + ": cannot open: " + std::strerror(errno));
  if (S_ISDIR(st.st_mode)) return Status::error(ErrorCode::InvalidInput, path + ": is a directory, not a file");
  // A FIFO would block the open below forever, a device has no size to check.
  if (!S_ISREG(st.st_mode))
    return Status::error(ErrorCode::InvalidInput, path + ": not a regular file (a device, pipe or socket)");
  const std::uint64_t size = static_cast<std::uint64_t>(st.st_size);
  if (size > max_bytes)
    return Status::error(ErrorCode::TooLarge, path + ": too large: " + std::to_string(size) +
                                                  " bytes, the limit is " + std::to_string(max_bytes));
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return Status::error(ErrorCode::InvalidInput, path + ": cannot open: " + std::strerror(errno));
  out.resize(static_cast<size_t>(size));
  const size_t got = size ? std::fread(out.data(), 1, out.size(), f) : 0;
  const bool read_error = std::ferror(f) != 0;
  std::fclose(f);
  if (read_error || got != out.size()) {
    out.clear();
    return Status::error(ErrorCode::Truncated, path + ": read error: got " + std::to_string(got) + " of " +
                                                   std::to_string(size) + " bytes");
  }
  return Status::success();
}

Status write_file(const std::string& path, const void* data, size_t size) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) return Status::error(ErrorCode::InvalidInput, path + ": cannot create: " + std::strerror(errno));
  const size_t written = size ? std::fwrite(data, 1, size, f) : 0;
  const bool ok = written == size && std::fclose(f) == 0;
  if (!ok) return Status::error(ErrorCode::Internal, path + ": write failed: " + std::strerror(errno));
  return Status::success();
}

Status write_file(const std::string& path, const std::string& text) {
  return write_file(path, text.data(), text.size());
}

Status write_file(const std::string& path, const Bytes& bytes) { return write_file(path, bytes.data(), bytes.size()); }

Status load_geometry_file(const std::string& path, TriMesh& mesh, PointCloud& cloud, GeometryKind& kind) {
  Bytes bytes;
  if (Status s = read_file(path, bytes, kMaxGeometryBytes); !s) return s;
  // An OBJ's material library sits next to it; its map_Kd becomes a path the
  // caller can open directly. A missing MTL only means no texture name.
  std::string mtllib = obj_mtllib(bytes.data(), bytes.size());
  while (mtllib.compare(0, 2, "./") == 0) mtllib.erase(0, 2);
  Bytes mtl;
  if (!mtllib.empty()) {
    const std::string mtl_path = is_absolute(mtllib) ? mtllib : directory_of(path) + mtllib;
    if (read_file(mtl_path, mtl, kMaxMaterialBytes)) {
      if (Status s = read_obj(bytes.data(), bytes.size(), mesh, kind, std::string(mtl.begin(), mtl.end())); !s)
        return with_context(s, path);
      if (!mesh.texture_name.empty() && !is_absolute(mesh.texture_name))
        mesh.texture_name = directory_of(mtl_path) + mesh.texture_name;
      cloud = to_point_cloud(mesh);
      return Status::success();
    }
  }
  return with_context(read_geometry(path, bytes.data(), bytes.size(), mesh, cloud, kind), path);
}

Status load_mesh_file(const std::string& path, TriMesh& mesh) {
  PointCloud cloud;
  GeometryKind kind;
  if (Status s = load_geometry_file(path, mesh, cloud, kind); !s) return s;
  if (kind != GeometryKind::Mesh)
    return Status::error(ErrorCode::InvalidInput, path + ": has no faces (a point cloud), but a mesh is needed");
  return Status::success();
}

Status load_point_cloud_file(const std::string& path, PointCloud& cloud) {
  TriMesh mesh;
  GeometryKind kind;
  return load_geometry_file(path, mesh, cloud, kind);
}

Status load_image_file(const std::string& path, Image& image, int want_channels) {
  Bytes bytes;
  if (Status s = read_file(path, bytes, kMaxImageBytes); !s) return s;
  return with_context(read_image(bytes.data(), bytes.size(), image, want_channels), path);
}

Status save_png_file(const std::string& path, const Image& image) {
  const Bytes png = write_png(image);
  if (png.empty())
    return Status::error(ErrorCode::InvalidInput, path + ": cannot encode PNG: the image is empty or inconsistent (" +
                                                      std::to_string(image.width) + "x" + std::to_string(image.height) +
                                                      "x" + std::to_string(image.channels) + ")");
  return write_file(path, png);
}

}  // namespace lk
