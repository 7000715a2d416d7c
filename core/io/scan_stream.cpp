// ScanStreamReader: the format told as read_geometry tells it, then parsed as it comes.
#include "io/scan_stream.h"
#include "io/text_scan.h"

#include <algorithm>

namespace lk {

namespace {

// read_geometry sniffs an unnamed format from at most this many first bytes.
constexpr size_t kSniffBytes = 4096;

}  // namespace

ScanStreamReader::ScanStreamReader(std::string name, std::uint64_t total_size)
    : name_(std::move(name)), total_(total_size) {
  if (total_size > kMaxGeometryBytes)
    error_ = Status::error(ErrorCode::TooLarge, "too large: " + std::to_string(total_size) + " bytes, the limit is " +
                                                    std::to_string(kMaxGeometryBytes));
}

ScanStreamReader::~ScanStreamReader() = default;

std::uint64_t ScanStreamReader::declared_vertices() const {
  if (ply_) return ply_->declared_vertices();
  if (xyz_) return xyz_->declared_points();
  if (vtk_) return vtk_->declared_vertices();
  return 0;
}

std::uint64_t ScanStreamReader::vertices_read() const {
  if (obj_) return obj_->vertices_read();
  if (xyz_) return xyz_->points_read();
  return 0;
}

// The format as read_geometry picks it: the name's extension, else the first
// bytes (as many as read_geometry looks at, so the guess is the same).
Status ScanStreamReader::decide(bool final) {
  std::string format = io_detail::geometry_format_by_name(name_);
  if (format.empty()) {
    // An empty file is read_geometry's "empty input" at finish, not an
    // unknown format.
    if (!final && (total_ == 0 || gathered_.size() < std::min<std::uint64_t>(total_, kSniffBytes)))
      return Status::success();
    format = io_detail::sniff_geometry_format(gathered_.data(), gathered_.size());
    if (format.empty())
      return Status::error(ErrorCode::Unsupported,
                           "unknown geometry format (expected PLY, OBJ, XYZ or legacy VTK by extension or content)");
  }
  decided_ = true;
  Bytes first;
  first.swap(gathered_);
  if (format == "ply") {
    ply_ = std::make_unique<PlyStreamReader>(total_);
    return ply_->push(first.data(), first.size());
  }
  if (format == "obj") {
    obj_ = std::make_unique<ObjStreamReader>(total_);
    return obj_->push(first.data(), first.size());
  }
  if (format == "vtk") {
    vtk_ = std::make_unique<VtkStreamReader>(total_);
    return vtk_->push(first.data(), first.size());
  }
  xyz_ = std::make_unique<XyzStreamReader>(total_);
  return xyz_->push(first.data(), first.size());
}

Status ScanStreamReader::push(const std::uint8_t* data, size_t size) {
  if (!error_.ok()) return error_;
  if (size > total_ - received_) {
    error_ = Status::error(ErrorCode::InvalidInput,
                           "more bytes than the " + std::to_string(total_) + " the file was declared to have");
    return error_;
  }
  received_ += size;
  Status s = io_detail::guard_allocation([&] {
    if (ply_) return ply_->push(data, size);
    if (obj_) return obj_->push(data, size);
    if (xyz_) return xyz_->push(data, size);
    if (vtk_) return vtk_->push(data, size);
    gathered_.insert(gathered_.end(), data, data + size);
    return decide(false);
  });
  if (!s) {
    error_ = s;
    gathered_ = Bytes();
  }
  return s;
}

Status ScanStreamReader::finish(TriMesh& mesh, GeometryKind& kind) {
  mesh = TriMesh();
  kind = GeometryKind::PointCloud;
  if (error_.ok() && received_ != total_)
    error_ = Status::error(ErrorCode::Truncated, "truncated: the data ends after " + std::to_string(received_) +
                                                     " of the file's " + std::to_string(total_) + " bytes");
  if (!error_.ok()) return error_;
  Status s = io_detail::guard_allocation([&] {
    if (total_ == 0) return Status::error(ErrorCode::Empty, "empty input: no bytes");
    if (!decided_)
      if (Status d = decide(true); !d) return d;
    if (ply_) return ply_->finish(mesh, kind);
    if (obj_) return obj_->finish(mesh, kind);
    if (xyz_) {
      PointCloud cloud;
      if (Status e = xyz_->finish(cloud); !e) return e;
      mesh.positions = std::move(cloud.positions);
      mesh.normals = std::move(cloud.normals);
      mesh.colors = std::move(cloud.colors);
      return Status::success();
    }
    return vtk_->finish(mesh, kind);
  });
  ply_.reset();
  obj_.reset();
  xyz_.reset();
  vtk_.reset();
  gathered_ = Bytes();
  if (!s) mesh = TriMesh();
  error_ = s.ok() ? Status::error(ErrorCode::Internal, "the reader has already finished") : s;
  return s;
}

Status ScanStreamReader::finish(TriMesh& mesh, PointCloud& cloud, GeometryKind& kind) {
  cloud = PointCloud();
  Status s = finish(mesh, kind);
  if (s) s = io_detail::guard_allocation([&] {
    cloud = to_point_cloud(mesh);
    return Status::success();
  });
  if (!s) mesh = TriMesh();
  return s;
}

}  // namespace lk
