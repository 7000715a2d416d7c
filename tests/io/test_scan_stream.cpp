// The stream readers (scan_stream.h) against the whole-buffer readers: the
// same mesh, bit for bit, and the same error, for every way of cutting the
// file into chunks (1 byte, sizes that split the header and the items, the
// whole file at once).
#include "io/scan_stream.h"
#include "io_test_util.h"
#include "sample_mesh.h"
#include "test_data.h"

#include <catch2/catch.hpp>

#include <cstring>
#include <random>

using namespace lk;
using lk::test::ByteWriter;
using lk::test::bytes_of;

namespace {

template <typename T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

bool same_mesh(const TriMesh& a, const TriMesh& b) {
  return same_bits(a.positions, b.positions) && same_bits(a.normals, b.normals) && same_bits(a.colors, b.colors) &&
         same_bits(a.uvs, b.uvs) && a.uv_per_corner == b.uv_per_corner && a.triangles == b.triangles;
}

// Chunk sizes cycled through while pushing.
Status read_in_chunks(const Bytes& file, const std::vector<size_t>& sizes, TriMesh& mesh, GeometryKind& kind) {
  PlyStreamReader reader(file.size());
  size_t pos = 0;
  for (size_t i = 0; pos < file.size(); ++i) {
    const size_t n = std::min(sizes[i % sizes.size()], file.size() - pos);
    const Status s = reader.push(file.data() + pos, n);
    pos += n;
    if (!s) {
      // Every later call gives the same error.
      CHECK(reader.push(file.data(), 0).message == s.message);
      CHECK(reader.finish(mesh, kind).message == s.message);
      CHECK(mesh.positions.empty());
      return s;
    }
  }
  CHECK(reader.bytes_received() == file.size());
  return reader.finish(mesh, kind);
}

std::vector<std::vector<size_t>> chunkings(size_t file_size) {
  std::vector<std::vector<size_t>> out = {{1}, {2}, {3}, {5}, {7}, {11}, {13}, {64}, {1000}, {1, 17, 4}};
  // The file cut once at every byte (header lines and items split everywhere).
  for (size_t cut = 1; cut < file_size && file_size < 4000; ++cut) out.push_back({cut, file_size});
  std::mt19937 rng(7);
  for (int r = 0; r < 20; ++r) {
    std::vector<size_t> sizes;
    for (int k = 0; k < 50; ++k) sizes.push_back(1 + rng() % 97);
    out.push_back(sizes);
  }
  return out;
}

// The stream agrees with read_ply on `file` for every chunking.
void check_stream_matches(const Bytes& file) {
  TriMesh whole;
  GeometryKind whole_kind = GeometryKind::PointCloud;
  const Status expected = read_ply(file.data(), file.size(), whole, whole_kind);
  for (const std::vector<size_t>& sizes : chunkings(file.size())) {
    TriMesh mesh;
    GeometryKind kind = GeometryKind::PointCloud;
    const Status s = read_in_chunks(file, sizes, mesh, kind);
    INFO("first chunk " << sizes[0] << " of " << file.size() << " bytes; expected: " << expected.message
                        << "; got: " << s.message);
    REQUIRE(s.ok() == expected.ok());
    REQUIRE(s.code == expected.code);
    REQUIRE(s.message == expected.message);
    REQUIRE(kind == whole_kind);
    REQUIRE(same_mesh(mesh, whole));
  }
}

PointCloud sample_cloud(int n) {
  PointCloud c;
  for (int i = 0; i < n; ++i) {
    const double t = 0.37 * i;
    c.positions.push_back(Vec3(std::cos(t) * 0.1, std::sin(t) * 0.1, 0.001 * i));
    c.normals.push_back(Vec3(std::cos(t), std::sin(t), 0));
    c.colors.push_back(Vec3((i % 256) / 255.0, ((3 * i) % 256) / 255.0, ((7 * i) % 256) / 255.0));
  }
  return c;
}

TriMesh to_mesh_cloud(const PointCloud& c) {
  TriMesh m;
  m.positions = c.positions;
  m.normals = c.normals;
  m.colors = c.colors;
  return m;
}

}  // namespace

TEST_CASE("PLY stream: the same mesh as read_ply for every chunking, ascii and binary", "[io][ply][stream]") {
  const TriMesh mesh = sample_mesh();
  TriMesh corner = mesh;  // per-corner uvs: the faces' texcoord lists
  corner.uvs.clear();
  for (int f = 0; f < 3; ++f)
    for (int k = 0; k < 3; ++k) corner.uvs.push_back(Vec2(0.1 * f, 0.05 * k + 0.5));
  corner.uv_per_corner = true;
  for (bool ascii : {false, true}) {
    INFO("ascii " << ascii);
    check_stream_matches(write_ply(mesh, ascii));
    check_stream_matches(write_ply(corner, ascii));
    check_stream_matches(write_ply(sample_cloud(300), ascii));
  }
  // The test means something: the reference read succeeds with every vertex.
  TriMesh back;
  GeometryKind kind;
  const Bytes cloud_bytes = write_ply(sample_cloud(300));
  REQUIRE(read_ply(cloud_bytes.data(), cloud_bytes.size(), back, kind).ok());
  CHECK(back.positions.size() == 300);
  CHECK(kind == GeometryKind::PointCloud);
}

TEST_CASE("PLY stream: big-endian doubles, skipped elements and CRLF header lines", "[io][ply][stream]") {
  ByteWriter w(
      "ply\r\nformat binary_big_endian 1.0\r\ncomment made by hand\r\nelement camera 1\r\nproperty float f\r\n"
      "element vertex 3\r\nproperty double x\r\nproperty double y\r\nproperty double z\r\nproperty list uchar int junk\r\n"
      "element face 1\r\nproperty list uchar uint vertex_indices\r\nend_header\n",
      true);
  w.put(1.5f);
  for (int i = 0; i < 3; ++i) {
    w.put(0.5 * i).put(-1.25 * i).put(3.0 + i);
    w.put(std::uint8_t(i));
    for (int k = 0; k < i; ++k) w.put(std::int32_t(k));
  }
  w.put(std::uint8_t(3)).put(std::uint32_t(0)).put(std::uint32_t(1)).put(std::uint32_t(2));
  TriMesh m;
  GeometryKind kind;
  REQUIRE(read_ply(w.bytes.data(), w.bytes.size(), m, kind).ok());
  REQUIRE(m.positions.size() == 3);
  CHECK(m.positions[2] == Vec3(1.0, -2.5, 5.0));
  CHECK(kind == GeometryKind::Mesh);
  check_stream_matches(w.bytes);
}

TEST_CASE("PLY stream: every error is the whole-buffer reader's, wherever the chunks end", "[io][ply][stream]") {
  const Bytes good = write_ply(sample_mesh(), false);
  const Bytes good_ascii = write_ply(sample_mesh(), true);
  std::vector<Bytes> bad = {
      Bytes{},
      bytes_of("pl"),
      bytes_of("ply"),
      bytes_of("plyx\n"),
      bytes_of("ply\nformat ascii 1.0\n"),                                   // no end_header
      bytes_of("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header"),  // no y, z
      bytes_of("ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\nend_header"),
      bytes_of("ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
               "end_header\n1 2 3\n4 5 six\n"),
      bytes_of("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
               "end_header\n1 2 3\n4 5 6\n"),  // extra data
      bytes_of("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
               "end_header\n1 2 nan\n"),
      bytes_of("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
               "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0 1 0 0 0 1 0\n4000 0 1 2\n"),
      bytes_of("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
               "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0 1 0 0 0 1 0\n3 0 1 9\n"),
      bytes_of("ply\nformat ascii 1.0\nelement vertex 2147483648\nproperty float x\nend_header\n1\n"),
      bytes_of("ply\nformat ascii 1.0\nelement junk 5\nend_header\n"),
      bytes_of("ply\nformat utf8 1.0\nend_header\n"),
      bytes_of("ply\nformat ascii 1.0\nbogus line\nend_header\n"),
  };
  // The good files cut short (the last item unfinished) and with a byte more.
  for (const Bytes* g : {&good, &good_ascii}) {
    bad.emplace_back(g->begin(), g->end() - 3);
    Bytes longer = *g;
    longer.push_back('7');
    bad.push_back(longer);
  }
  for (const Bytes& file : bad) {
    TriMesh m;
    GeometryKind kind;
    INFO(std::string(file.begin(), file.begin() + std::min<size_t>(file.size(), 160)));
    REQUIRE_FALSE(read_ply(file.data(), file.size(), m, kind).ok());
    check_stream_matches(file);
  }
}

TEST_CASE("PLY stream: more or fewer bytes than declared are refused", "[io][ply][stream]") {
  const Bytes file = write_ply(sample_mesh(), false);
  TriMesh m;
  GeometryKind kind;
  {
    PlyStreamReader reader(file.size() - 1);
    lk::test::require_error(reader.push(file.data(), file.size()), ErrorCode::InvalidInput, "more bytes than the");
  }
  {
    PlyStreamReader reader(file.size() + 10);
    // The header promises more bytes than the body holds: refused at end.
    REQUIRE(reader.push(file.data(), file.size()).ok());
    lk::test::require_error(reader.finish(m, kind), ErrorCode::Truncated, "the data ends after");
    CHECK(m.positions.empty());
  }
  {
    PlyStreamReader reader(std::uint64_t(kMaxGeometryBytes) + 1);
    lk::test::require_error(reader.push(file.data(), 10), ErrorCode::TooLarge, "too large");
  }
}

TEST_CASE("Scan stream: what read_geometry gives, every format streamed once told", "[io][stream]") {
  const Bytes ply = write_ply(sample_cloud(200));
  const std::string xyz_text = write_xyz(sample_cloud(50));
  const Bytes xyz(xyz_text.begin(), xyz_text.end());
  const std::string obj_text = write_obj(sample_mesh());
  const Bytes obj(obj_text.begin(), obj_text.end());
  struct Case {
    std::string name;
    const Bytes* bytes;
    bool streamed;
  };
  const std::string vtk_text =
      "# vtk DataFile Version 3.0\nt\nASCII\nDATASET POLYDATA\nPOINTS 3 float\n0 0 0 1 0 0 0 1 0\nPOLYGONS 1 4\n3 0 1 2\n";
  const Bytes vtk(vtk_text.begin(), vtk_text.end());
  const Bytes junk = lk::test::garbage_bytes(5000);
  const Case cases[] = {{"scan.ply", &ply, true},   {"scan.PLY", &ply, true},   {"scan.bin", &ply, true},
                        {"scan.xyz", &xyz, true},   {"scan.obj", &obj, true},   {"scan", &xyz, true},
                        {"scan.xyz", &ply, true},   {"scan", &obj, true},       {"scan.vtk", &vtk, true},
                        {"scan", &vtk, true},      {"scan.obj", &vtk, true},   {"scan", &junk, false},
                        {"scan.pts", &junk, true}};
  for (const Case& c : cases) {
    TriMesh m0;
    PointCloud c0;
    GeometryKind k0;
    const Status expected = read_geometry(c.name, c.bytes->data(), c.bytes->size(), m0, c0, k0);
    for (size_t chunk : {size_t(1), size_t(3), size_t(100), c.bytes->size()}) {
      INFO(c.name << " in chunks of " << chunk);
      ScanStreamReader reader(c.name, c.bytes->size());
      Status s;
      for (size_t pos = 0; pos < c.bytes->size() && s.ok(); pos += chunk)
        s = reader.push(c.bytes->data() + pos, std::min(chunk, c.bytes->size() - pos));
      if (s.ok()) CHECK(reader.streaming() == c.streamed);
      TriMesh m;
      PointCloud cloud;
      GeometryKind k;
      if (s.ok()) s = reader.finish(m, cloud, k);
      REQUIRE(s.ok() == expected.ok());
      CHECK(s.message == expected.message);
      if (!s.ok()) continue;
      CHECK(k == k0);
      CHECK(same_mesh(m, m0));
      CHECK(same_bits(cloud.positions, c0.positions));
      CHECK(same_bits(cloud.normals, c0.normals));
      CHECK(same_bits(cloud.colors, c0.colors));
      CHECK(cloud.faces == c0.faces);
    }
  }
  // An empty file, whatever its name.
  for (const char* name : {"empty.ply", "empty", "empty.obj", "empty.xyz", "empty.vtk"})
    for (bool push_nothing : {false, true}) {
      // A push of no bytes first (found by fuzz_scan_stream: the unnamed
      // empty file was "unknown geometry format" instead of empty).
      ScanStreamReader reader(name, 0);
      if (push_nothing) REQUIRE(reader.push(ply.data(), 0).ok());
      TriMesh m;
      PointCloud cloud;
      GeometryKind k;
      lk::test::require_error(reader.finish(m, cloud, k), ErrorCode::Empty, "empty input");
    }
}

namespace {

// One reading of a file, whole or in chunks, as a mesh (an XYZ cloud's
// arrays in the mesh's).
struct Reading {
  Status status;
  TriMesh mesh;
  GeometryKind kind = GeometryKind::PointCloud;
  std::uint64_t counted = 0;  // the stream's vertices_read / points_read before finish
};

TriMesh mesh_of(PointCloud&& c) {
  TriMesh m;
  m.positions = std::move(c.positions);
  m.normals = std::move(c.normals);
  m.colors = std::move(c.colors);
  return m;
}

Reading whole_obj(const Bytes& file) {
  Reading r;
  r.status = read_obj(file.data(), file.size(), r.mesh, r.kind);
  return r;
}

Reading whole_xyz(const Bytes& file) {
  Reading r;
  PointCloud c;
  r.status = read_xyz(file.data(), file.size(), c);
  r.mesh = mesh_of(std::move(c));
  return r;
}

// Pushes `file` into reader in chunks cycling through sizes; every error is
// sticky (push and finish repeat it) and leaves nothing behind.
template <typename Reader, typename Finish, typename Count>
Reading stream_read(Reader& reader, const Bytes& file, const std::vector<size_t>& sizes, Finish finish, Count count) {
  Reading r;
  size_t pos = 0;
  for (size_t i = 0; pos < file.size(); ++i) {
    const size_t n = std::min(sizes[i % sizes.size()], file.size() - pos);
    r.status = reader.push(file.data() + pos, n);
    pos += n;
    if (!r.status) {
      CHECK(reader.push(file.data(), 0).message == r.status.message);
      Reading again;
      CHECK(finish(reader, again).message == r.status.message);
      CHECK(again.mesh.positions.empty());
      return r;
    }
  }
  CHECK(reader.bytes_received() == file.size());
  r.counted = count(reader);
  r.status = finish(reader, r);
  if (r.status) {
    // A second finish is refused: the mesh was handed over once.
    Reading again;
    CHECK(finish(reader, again).code == ErrorCode::Internal);
  }
  return r;
}

Reading chunked_obj(const Bytes& file, const std::vector<size_t>& sizes) {
  ObjStreamReader reader(file.size());
  return stream_read(reader, file, sizes, [](ObjStreamReader& rd, Reading& r) { return rd.finish(r.mesh, r.kind); },
                     [](const ObjStreamReader& rd) { return rd.vertices_read(); });
}

Reading chunked_xyz(const Bytes& file, const std::vector<size_t>& sizes) {
  XyzStreamReader reader(file.size());
  return stream_read(reader, file, sizes,
                     [](XyzStreamReader& rd, Reading& r) {
                       PointCloud c;
                       const Status s = rd.finish(c);
                       r.mesh = mesh_of(std::move(c));
                       return s;
                     },
                     [](const XyzStreamReader& rd) { return rd.points_read(); });
}

Reading whole_vtk(const Bytes& file) {
  Reading r;
  r.status = read_vtk(file.data(), file.size(), r.mesh, r.kind);
  return r;
}

Reading chunked_vtk(const Bytes& file, const std::vector<size_t>& sizes) {
  VtkStreamReader reader(file.size());
  Reading r = stream_read(reader, file, sizes, [](VtkStreamReader& rd, Reading& out) { return rd.finish(out.mesh, out.kind); },
                          [](const VtkStreamReader& rd) { return rd.declared_vertices(); });
  return r;
}

// The stream agrees with the whole-buffer reader on `file` for every chunking:
// status, code, message, kind and every array bit for bit; and on success its
// running count of vertices is the mesh's.
// counts_declared: the count is the file's declared one (VTK's POINTS).
template <typename Whole, typename Chunked>
void check_text_stream_matches(const Bytes& file, Whole whole, Chunked chunked, bool counts_declared = false) {
  const Reading expected = whole(file);
  for (const std::vector<size_t>& sizes : chunkings(file.size())) {
    const Reading got = chunked(file, sizes);
    INFO("first chunk " << sizes[0] << " of " << file.size() << " bytes; expected: " << expected.status.message
                        << "; got: " << got.status.message);
    REQUIRE(got.status.ok() == expected.status.ok());
    REQUIRE(got.status.code == expected.status.code);
    REQUIRE(got.status.message == expected.status.message);
    REQUIRE(got.kind == expected.kind);
    REQUIRE(same_mesh(got.mesh, expected.mesh));
    REQUIRE(got.mesh.texture_name == expected.mesh.texture_name);
    // The running count lags only by a last line without a newline.
    if (got.status && !counts_declared)
      REQUIRE(got.counted + (file.back() == '\n' ? 0 : 1) >= got.mesh.positions.size());
    if (got.status && !counts_declared) REQUIRE(got.counted <= got.mesh.positions.size());
    if (got.status && counts_declared) REQUIRE(got.counted == got.mesh.positions.size());
  }
}

}  // namespace

TEST_CASE("OBJ stream: the same mesh and the same errors as read_obj for every chunking", "[io][obj][stream]") {
  const TriMesh mesh = sample_mesh();
  TriMesh corner = mesh;  // per-corner uvs and no colors
  corner.colors.clear();
  corner.uvs.clear();
  for (int f = 0; f < 3; ++f)
    for (int k = 0; k < 3; ++k) corner.uvs.push_back(Vec2(0.1 * f, 0.05 * k + 0.5));
  corner.uv_per_corner = true;
  std::vector<Bytes> files = {
      bytes_of(write_obj(mesh)),
      bytes_of(write_obj(corner, "head.mtl")),
      bytes_of(write_obj(to_mesh_cloud(sample_cloud(300)))),
      // Quads, negative indices, v//vn, comments, CRLF, tabs, no final newline.
      bytes_of("# hand made\r\nv 0 0 0\r\nv 1 0 0\r\n\tv 1 1 0 \r\nv 0 1 0\r\nvn 0 0 2\r\n\r\n"
               "g quad\r\ns off\r\nf -4//1 -3//1 -2//1 -1//1\r\nf 1 2 3"),
      bytes_of("v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nvt 0 0 0\nvt 1 0\nvt 0 1\nusemtl skin\nf 1/1 2/2 3/3\n"),
      // Malformed: each of read_obj's errors, wherever the chunks end.
      Bytes{},
      bytes_of("v"),
      bytes_of("# only a comment\n\n"),
      bytes_of("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n"),
      bytes_of("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -4 1 2\n"),
      bytes_of("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2 3/1\n"),
      bytes_of("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/1\nf 1 2 3\n"),
      bytes_of("v 0 0 0\nv 1 nan 0\n"),
      bytes_of("v 0 0 0\nv 1 x 0\n"),
      bytes_of("v 0 0 0\nvn 0 0\n"),
      bytes_of("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2"),
      bytes_of("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99999999999999999999999\n"),
      lk::test::garbage_bytes(300),
  };
  const Bytes good = files[0];
  files.emplace_back(good.begin(), good.end() - 5);  // cut mid-face
  for (const Bytes& file : files) {
    INFO(std::string(file.begin(), file.begin() + std::min<size_t>(file.size(), 160)));
    check_text_stream_matches(file, whole_obj, chunked_obj);
  }
  // The test means something: the references read what was written.
  const Reading r = whole_obj(files[1]);
  REQUIRE(r.status.ok());
  CHECK(r.mesh.uv_per_corner);
  CHECK(r.mesh.triangles.size() == 3);
  CHECK_FALSE(whole_obj(files[8]).status.ok());
}

TEST_CASE("XYZ stream: the same cloud and the same errors as read_xyz for every chunking", "[io][xyz][stream]") {
  PointCloud with_colors = sample_cloud(200);
  with_colors.normals.clear();
  PointCloud with_normals = sample_cloud(200);
  with_normals.colors.clear();
  PointCloud positions_only;
  positions_only.positions = with_colors.positions;
  std::vector<Bytes> files = {
      bytes_of(write_xyz(sample_cloud(200))),  // 9 columns
      bytes_of(write_xyz(with_colors)),        // 6: colors 0..255
      bytes_of(write_xyz(with_normals)),       // 6: normals
      bytes_of(write_xyz(positions_only)),
      // 9 columns with the colors first, as fractions.
      bytes_of("1 2 3 0.5 0.25 0 0 0 1\n4,5,6,0.125,1,0,0,1,0\n"),
      // Leica .pts: a count line, intensity (and colors), CRLF, comments.
      bytes_of("2\r\n1 2 3 -100\r\n4 5 6 7\r\n"),
      bytes_of("// X Y Z\n2\n1 2 3 -100 255 0 0\n# a comment\n4;5;6;7;0;128;255"),
      // Malformed.
      Bytes{},
      bytes_of("\n"),
      bytes_of("1"),
      bytes_of("1.5\n"),
      bytes_of("1 2 3 4 5\n"),
      bytes_of("3\n1 2 3 4\n5 6 7 8\n"),
      bytes_of("1 2 3 4 5 6 7 8 9 10\n"),
      bytes_of("1 2 3\n4 5 6\n7 8\n"),
      bytes_of("1 2 3\n4 nan 6\n"),
      bytes_of("1 2 3\n4 5 1e999\n"),
      bytes_of("1 2 3\n4 five 6\n"),
      lk::test::garbage_bytes(300),
  };
  const Bytes good = files[0];
  files.emplace_back(good.begin(), good.end() - 4);  // the last row cut short
  for (const Bytes& file : files) {
    INFO(std::string(file.begin(), file.begin() + std::min<size_t>(file.size(), 160)));
    check_text_stream_matches(file, whole_xyz, chunked_xyz);
  }
  const Reading colors = whole_xyz(files[1]);
  REQUIRE(colors.status.ok());
  CHECK(colors.mesh.normals.empty());
  CHECK(colors.mesh.colors.size() == 200);
  const Reading normals = whole_xyz(files[2]);
  REQUIRE(normals.status.ok());
  CHECK(normals.mesh.normals.size() == 200);
  CHECK(normals.mesh.colors.empty());
  const Reading swapped = whole_xyz(files[4]);
  REQUIRE(swapped.status.ok());
  CHECK(swapped.mesh.normals[0] == Vec3(0, 0, 1));
  CHECK(swapped.mesh.colors[1] == Vec3(0.125, 1, 0));
}

TEST_CASE("Scan stream: the declared and the growing vertex counts, for an early refusal", "[io][stream]") {
  // A .pts count line is known after its line; an OBJ's and an XYZ's vertices
  // are counted as they come, before the file ends.
  const Bytes pts = bytes_of("5000000\n1 2 3 4\n");
  ScanStreamReader a("scan.pts", pts.size() + 100);
  REQUIRE(a.push(pts.data(), pts.size()).ok());
  CHECK(a.declared_vertices() == 5000000);
  CHECK(a.vertices_read() == 1);
  const std::string obj = write_obj(sample_mesh());
  ScanStreamReader b("scan.obj", obj.size());
  const size_t half = obj.find("f ");
  REQUIRE(b.push(reinterpret_cast<const std::uint8_t*>(obj.data()), half).ok());
  CHECK(b.streaming());
  CHECK(b.vertices_read() == 5);
  CHECK(b.declared_vertices() == 0);
  const Bytes ply = write_ply(sample_cloud(100));
  ScanStreamReader c("scan.ply", ply.size());
  REQUIRE(c.push(ply.data(), 400).ok());
  CHECK(c.declared_vertices() == 100);
  // A VTK's POINTS count once its head is read (the file declared big
  // enough to hold them), before any of the points.
  const Bytes vtk = bytes_of("# vtk DataFile Version 3.0\nscan\nASCII\nDATASET POLYDATA\nPOINTS 5000000 float\n0 0 0 ");
  ScanStreamReader d("scan.vtk", 40000000);
  REQUIRE(d.push(vtk.data(), vtk.size()).ok());
  CHECK(d.streaming());
  CHECK(d.declared_vertices() == 5000000);
  // Declared beyond what the file's size can hold: refused at the head.
  ScanStreamReader e("scan.vtk", 1000);
  lk::test::require_error(e.push(vtk.data(), vtk.size()), ErrorCode::Truncated, "POINTS declares 5000000 items");
}

TEST_CASE("VTK stream: the same mesh and the same errors as read_vtk for every chunking", "[io][vtk][stream]") {
  const std::string head = "# vtk DataFile Version 3.0\nscan\nASCII\nDATASET POLYDATA\n";
  std::vector<Bytes> files = {
      // Every section the reader knows or skips, split between lines anywhere.
      bytes_of(head +
               "POINTS 6 float\n0 0 0  1 0 0  1 1 0\n0 1 0  2 0 0  2 1 0\nVERTICES 1 2\n1 5\nLINES 1 3\n2 0 5\n"
               "POLYGONS 1 5\n4 0 1 2 3\nTRIANGLE_STRIPS 1 5\n4 1 4 2 5\nCELL_DATA 5\nSCALARS cell_id int 1\n"
               "LOOKUP_TABLE default\n0 1 2 3 4\nPOINT_DATA 6\nSCALARS height float\nLOOKUP_TABLE my_table\n0 1 2 3 4 5\n"
               "LOOKUP_TABLE my_table 2\n0 0 0 1  1 1 1 1\nNORMALS normals float\n0 0 1 0 0 1 0 0 1 0 0 1 0 0 1 0 0 1\n"
               "TEXTURE_COORDINATES t 2 float\n0 0  0.5 0  0.5 1  0 1  1 0  1 1\n"
               "COLOR_SCALARS c 3\n1 0 0 0 1 0 0 0 1 1 1 0 0 1 1 1 0 1\n"
               "VECTORS velocity double\n1 0 0 1 0 0 1 0 0 1 0 0 1 0 0 1 0 0\nFIELD FieldData 2\n"
               "temperature 1 6 float\n1 2 3 4 5 6\npair 2 3 int\n1 2 3 4 5 6\n"),
      // 5.1 cells and a METADATA block; CRLF and no final newline.
      bytes_of("# vtk DataFile Version 5.1\r\nvtk output\r\nASCII\r\nDATASET POLYDATA\r\n"
               "POINTS 4 float\r\n0 0 0 1 0 0 1 1 0 0 1 0\r\nMETADATA\r\nINFORMATION 0\r\n\r\n"
               "POLYGONS 3 7\r\nOFFSETS vtktypeint64\r\n0 3 7\r\nCONNECTIVITY vtktypeint64\r\n0 1 2 0 1 2 3"),
      bytes_of(head + "POINTS 2 double\n1 2 3 4 5 6\n"),
      // Malformed: the reader's errors, wherever the chunks end.
      Bytes{},
      bytes_of("# vtk DataFile"),
      bytes_of("# vtk DataFile Version 3.0\nt\nBINARY\nDATASET POLYDATA\n"),
      bytes_of("# vtk DataFile Version 3.0\nt\nASCII\nDATASET STRUCTURED_GRID\n"),
      bytes_of(head),
      bytes_of(head + "POINTS 3 float\n0 0 0 1 0 0\n"),
      bytes_of(head + "POINTS 3 float\n0 0 0 1 0 0 0 1 nan\n"),
      bytes_of(head + "POINTS 3 float\n0 0 0 1 0 0 0 1 x\n"),
      bytes_of(head + "POINTS 2147483648 float\n0 0 0\n"),
      bytes_of(head + "POINTS 3 float\n0 0 0 1 0 0 0 1 0\nPOLYGONS 1 4\n3 0 1 7\n"),
      bytes_of(head + "POINTS 3 float\n0 0 0 1 0 0 0 1 0\nPOLYGONS 2 4\n3 0 1 2\n"),
      bytes_of(head + "POINTS 3 float\n0 0 0 1 0 0 0 1 0\nPOLYGONS 1 4\n3 0 1.5 2\n"),
      bytes_of(head + "POINTS 3 float\n0 0 0 1 0 0 0 1 0\nPOLYGONS 2 3\nOFFSETS t\n0 3\nCONN t\n0 1 2\n"),
      bytes_of(head + "POINTS 3 float\n0 0 0 1 0 0 0 1 0\nPOINT_DATA 4\n"),
      bytes_of(head + "POINTS 3 float\n0 0 0 1 0 0 0 1 0\nNORMALS n float\n0 0 1\n"),
      bytes_of(head + "POINTS 3 float\n0 0 0 1 0 0 0 1 0\nPOINT_DATA 3\nNORMALS n float\n0 0 1 0 0 1\n"),
      bytes_of(head + "POINTS 3 float\n0 0 0 1 0 0 0 1 0\nPOINT_DATA 3\nBOGUS 1\n"),
      bytes_of(head + "POINTS 3 float\n0 0 0 1 0 0 0 1 0\nFIELD f 99999\n"),
      lk::test::garbage_bytes(300),
  };
  const Bytes good = files[0];
  files.emplace_back(good.begin(), good.end() - 4);  // the last numbers cut
  for (const Bytes& file : files) {
    INFO(std::string(file.begin(), file.begin() + std::min<size_t>(file.size(), 160)));
    check_text_stream_matches(file, whole_vtk, chunked_vtk, true);
  }
  const Reading r = whole_vtk(files[0]);
  REQUIRE(r.status.ok());
  CHECK(r.mesh.triangles.size() == 4);
  CHECK(r.mesh.colors.size() == 6);
  const Reading offsets = whole_vtk(files[1]);
  REQUIRE(offsets.status.ok());
  CHECK(offsets.mesh.triangles.size() == 3);
}

TEST_CASE("Scan stream: the real scans read in chunks are read_geometry's, bit for bit", "[io][stream][shared]") {
  // OBJ meshes with uvs and normals (photogrammetry, 3D scans), a Cyberware VTK.
  const char* const scans[] = {"head_scans/james_menpo3d/james.obj", "head_scans/threedscans_plato/plato.obj",
                               "head_scans/threedscans_gutenberg/gutenberg.obj",
                               "head_scans/demosthenes_photoscan/demosthenes-low-res.obj",
                               "head_scans/fran_cyberware/fran_cut.vtk"};
  int read = 0;
  for (const char* rel : scans) {
    const std::string path = lk::test::shared_data_dir() + "/" + rel;
    Bytes file;
    if (!read_file(path, file)) {
      WARN("skipped: ../shared/data/" << rel << " is absent (real data is not in the repo)");
      continue;
    }
    TriMesh whole;
    PointCloud whole_cloud;
    GeometryKind whole_kind;
    REQUIRE(read_geometry(path, file.data(), file.size(), whole, whole_cloud, whole_kind).ok());
    REQUIRE(whole.num_triangles() > 0);
    for (size_t chunk : {size_t(1), size_t(7), size_t(4093), size_t(1) << 20}) {
      INFO(rel << " in chunks of " << chunk);
      ScanStreamReader reader(path, file.size());
      for (size_t pos = 0; pos < file.size(); pos += chunk)
        REQUIRE(reader.push(file.data() + pos, std::min(chunk, file.size() - pos)).ok());
      TriMesh m;
      PointCloud cloud;
      GeometryKind kind;
      REQUIRE(reader.finish(m, cloud, kind).ok());
      CHECK(kind == whole_kind);
      CHECK(same_mesh(m, whole));
      CHECK(same_bits(cloud.positions, whole_cloud.positions));
    }
    ++read;
  }
  if (read == 0) WARN("no real scan read");
}
