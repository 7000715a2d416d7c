// Reading a scan from chunks of bytes pushed by the caller, so that a large
// file never has to be held whole (the page reads a File in slices). The
// result is the same as the whole-buffer readers' (io.h) for every way of
// cutting the bytes into chunks, errors and messages included: read_ply is
// itself one push and a finish of PlyStreamReader.
//
// The caller declares the file's size up front (a File's size, a stat): the
// header's counts are checked against it before any body byte arrives, as
// the whole-buffer reader checks them against its buffer, and pushing more
// or fewer bytes than declared is an error.
#pragma once
#include "io/io.h"

#include <cstdint>
#include <memory>
#include <string>

namespace lk {

// PLY (ascii, binary little or big endian), parsed as the bytes come: only
// an unfinished header line, item or number is carried between pushes.
class PlyStreamReader {
 public:
  explicit PlyStreamReader(std::uint64_t total_size);
  ~PlyStreamReader();
  PlyStreamReader(const PlyStreamReader&) = delete;
  PlyStreamReader& operator=(const PlyStreamReader&) = delete;

  // The next bytes of the file. Once a push or finish fails, every later
  // call returns the same error.
  Status push(const std::uint8_t* data, size_t size);
  // After the last push: the mesh (or point cloud, kind PointCloud), or the
  // error; never half a mesh.
  Status finish(TriMesh& mesh, GeometryKind& kind);
  std::uint64_t bytes_received() const;
  // The vertex count the header declares (checked against the declared
  // size), once the header has been read; 0 before.
  std::uint64_t declared_vertices() const;

 private:
  struct State;
  std::unique_ptr<State> s_;
};

// Any scan read_geometry reads, from pushed chunks. PLY (by extension, or
// an unknown extension and the bytes "ply\n") is parsed as it comes; OBJ,
// XYZ and VTK are not streamed: their bytes are gathered and handed to
// read_geometry at finish. finish gives what read_geometry gives.
class ScanStreamReader {
 public:
  ScanStreamReader(std::string name, std::uint64_t total_size);
  ~ScanStreamReader();
  ScanStreamReader(const ScanStreamReader&) = delete;
  ScanStreamReader& operator=(const ScanStreamReader&) = delete;

  Status push(const std::uint8_t* data, size_t size);
  Status finish(TriMesh& mesh, PointCloud& cloud, GeometryKind& kind);
  // The same without the cloud (a copy of the mesh's vertices and faces:
  // to_point_cloud), for callers that move the mesh's arrays themselves.
  Status finish(TriMesh& mesh, GeometryKind& kind);
  // PLY: the header's vertex count once it has been read (0 before, and for
  // other formats), so a caller can refuse a scan too large for its memory
  // before the body is read.
  std::uint64_t declared_vertices() const { return ply_ ? ply_->declared_vertices() : 0; }
  // True once the bytes are known to be parsed as they come (PLY).
  bool streaming() const { return ply_ != nullptr; }
  std::uint64_t bytes_received() const { return received_; }

 private:
  Status decide(bool final);

  std::string name_;
  std::uint64_t total_ = 0, received_ = 0;
  Status error_;
  bool decided_ = false;
  Bytes gathered_;  // the bytes before the format is known, or all of a non-PLY file
  std::unique_ptr<PlyStreamReader> ply_;
};

}  // namespace lk
