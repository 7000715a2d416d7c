// ScanStreamReader: PLY parsed as it comes, other formats gathered whole.
#include "io/scan_stream.h"
#include "io/text_scan.h"


namespace lk {

ScanStreamReader::ScanStreamReader(std::string name, std::uint64_t total_size)
    : name_(std::move(name)), total_(total_size) {
  if (total_size > kMaxGeometryBytes)
    error_ = Status::error(ErrorCode::TooLarge, "too large: " + std::to_string(total_size) + " bytes, the limit is " +
                                                    std::to_string(kMaxGeometryBytes));
}

ScanStreamReader::~ScanStreamReader() = default;

// PLY is streamed when the name says .ply, or says no format read_geometry
// knows and the bytes start as read_geometry's sniffing recognises a PLY.
Status ScanStreamReader::decide(bool final) {
  const std::string format = io_detail::geometry_format_by_name(name_);
  bool ply = format == "ply";
  if (format.empty()) {
    if (gathered_.size() < 5 && !final) return Status::success();  // not enough bytes to tell
    ply = io_detail::sniff_geometry_format(gathered_.data(), gathered_.size()) == "ply";
  }
  decided_ = true;
  if (!ply) {
    // Gathered whole for read_geometry; the declared size is within the limit.
    gathered_.reserve(static_cast<size_t>(total_));
    return Status::success();
  }
  ply_ = std::make_unique<PlyStreamReader>(total_);
  Bytes first;
  first.swap(gathered_);
  return ply_->push(first.data(), first.size());
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
    gathered_.insert(gathered_.end(), data, data + size);
    if (!decided_) return decide(false);
    return Status::success();
  });
  if (!s) error_ = s;
  return s;
}

Status ScanStreamReader::finish(TriMesh& mesh, GeometryKind& kind) {
  mesh = TriMesh();
  kind = GeometryKind::PointCloud;
  if (!error_.ok()) return error_;
  Status s = io_detail::guard_allocation([&] {
    if (!decided_)
      if (Status d = decide(true); !d) return d;
    if (ply_) return ply_->finish(mesh, kind);
    if (received_ != total_)
      return Status::error(ErrorCode::Truncated, "truncated: the data ends after " + std::to_string(received_) +
                                                     " of the file's " + std::to_string(total_) + " bytes");
    Bytes bytes;
    bytes.swap(gathered_);
    PointCloud unused;
    return read_geometry(name_, bytes.data(), bytes.size(), mesh, unused, kind);
  });
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
