// Reading a scan from chunks of bytes pushed by the caller, so that a large
// file never has to be held whole (the page reads a File in slices). The
// result is the same as the whole-buffer readers' (io.h) for every way of
// cutting the bytes into chunks, errors and messages included: read_ply,
// read_obj, read_xyz and read_vtk are themselves one push and a finish of
// these readers.
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

// OBJ, parsed line by line as the bytes come: only an unfinished line is
// carried between pushes. The vertices, uvs and normals are kept as read;
// each face becomes triangles as it is read, its corners' normals summed per
// vertex and (faces with uvs) their uv indices kept, not the corners whole;
// finish resolves them into the mesh as read_obj does (uvs per vertex or per
// corner, normals averaged per vertex), and takes the texture
// name from the MTL text given here (read_obj's mtl_text).
class ObjStreamReader {
 public:
  explicit ObjStreamReader(std::uint64_t total_size, std::string mtl_text = "");
  ~ObjStreamReader();
  ObjStreamReader(const ObjStreamReader&) = delete;
  ObjStreamReader& operator=(const ObjStreamReader&) = delete;

  Status push(const std::uint8_t* data, size_t size);
  Status finish(TriMesh& mesh, GeometryKind& kind);
  std::uint64_t bytes_received() const;
  // The "v" lines read so far (an OBJ declares no count).
  std::uint64_t vertices_read() const;

 private:
  struct State;
  std::unique_ptr<State> s_;
};

// XYZ (and Leica .pts), parsed line by line as the bytes come. Whether six
// or nine columns hold normals or colors, and the colors' scale, depend on
// every row, so they are decided at finish.
class XyzStreamReader {
 public:
  explicit XyzStreamReader(std::uint64_t total_size);
  ~XyzStreamReader();
  XyzStreamReader(const XyzStreamReader&) = delete;
  XyzStreamReader& operator=(const XyzStreamReader&) = delete;

  Status push(const std::uint8_t* data, size_t size);
  Status finish(PointCloud& cloud);
  std::uint64_t bytes_received() const;
  std::uint64_t points_read() const;
  // A .pts file's count line, once read (0 when none).
  std::uint64_t declared_points() const;

 private:
  struct State;
  std::unique_ptr<State> s_;
};

// Legacy VTK (ASCII POLYDATA), parsed as the bytes come: a section's head
// (keyword, counts, type names) is read once all of it is at hand, its
// numbers one by one; only an unfinished head or number is carried.
class VtkStreamReader {
 public:
  explicit VtkStreamReader(std::uint64_t total_size);
  ~VtkStreamReader();
  VtkStreamReader(const VtkStreamReader&) = delete;
  VtkStreamReader& operator=(const VtkStreamReader&) = delete;

  Status push(const std::uint8_t* data, size_t size);
  Status finish(TriMesh& mesh, GeometryKind& kind);
  std::uint64_t bytes_received() const;
  // The POINTS count once its section's head has been read (0 before).
  std::uint64_t declared_vertices() const;

 private:
  struct State;
  std::unique_ptr<State> s_;
};

// Any scan read_geometry reads, from pushed chunks. The format is told as
// read_geometry tells it (the name's extension, else the first 4 KiB), then
// parsed as the bytes come by that format's stream reader. finish gives what
// read_geometry gives.
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
  // The vertex count the file declares once it has been read (a PLY
  // header's, a VTK POINTS head's, a .pts count line's; 0 before, and for
  // OBJ),
  // so a caller can refuse a scan too large for its memory before the body
  // is read.
  std::uint64_t declared_vertices() const;
  // The vertices parsed so far (OBJ, XYZ; a PLY's once finished), so a
  // caller can refuse a scan whose count grows too large while it is read.
  std::uint64_t vertices_read() const;
  // True once the format is known (its stream reader has the bytes).
  bool streaming() const { return ply_ || obj_ || xyz_ || vtk_; }
  std::uint64_t bytes_received() const { return received_; }

 private:
  Status decide(bool final);

  std::string name_;
  std::uint64_t total_ = 0, received_ = 0;
  Status error_;
  bool decided_ = false;
  Bytes gathered_;  // the bytes before the format is known
  std::unique_ptr<PlyStreamReader> ply_;
  std::unique_ptr<ObjStreamReader> obj_;
  std::unique_ptr<XyzStreamReader> xyz_;
  std::unique_ptr<VtkStreamReader> vtk_;
};

}  // namespace lk
