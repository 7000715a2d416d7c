#include "io/io.h"
#include "io_test_util.h"
#include "test_data.h"

#include <catch2/catch.hpp>

using namespace lk;
using lk::test::bytes_of;

namespace {

TriMesh tetrahedron() {
  TriMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  m.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  return m;
}

}  // namespace

TEST_CASE("read_file: missing files, directories and the size limit", "[io][files][errors]") {
  const std::string dir = lk::test::scratch_dir("io_files");
  Bytes b;
  Status s = read_file(dir + "/does_not_exist.ply", b);
  CHECK(s.code == ErrorCode::InvalidInput);
  CHECK(s.message == dir + "/does_not_exist.ply: cannot open: No such file or directory");
  s = read_file(dir, b);
  CHECK(s.message.find("is a directory") != std::string::npos);

  const std::string path = dir + "/ten.bin";
  REQUIRE(write_file(path, std::string("0123456789")).ok());
  s = read_file(path, b, 9);
  CHECK(s.code == ErrorCode::TooLarge);
  CHECK(s.message == path + ": too large: 10 bytes, the limit is 9");
  CHECK(b.empty());
  REQUIRE(read_file(path, b, 10).ok());
  CHECK(b == bytes_of("0123456789"));

  const std::string empty = dir + "/empty.ply";
  REQUIRE(write_file(empty, std::string()).ok());
  REQUIRE(read_file(empty, b).ok());
  CHECK(b.empty());
  TriMesh m;
  s = load_mesh_file(empty, m);
  CHECK(s.code == ErrorCode::Empty);
  CHECK(s.message.rfind(empty + ": empty", 0) == 0);
}

TEST_CASE("load_*_file: messages start with the path", "[io][files][errors]") {
  const std::string dir = lk::test::scratch_dir("io_files");
  // A binary PLY cut short on disk.
  const Bytes full = write_ply(tetrahedron());
  const std::string cut = dir + "/scan.ply";
  REQUIRE(write_file(cut, full.data(), full.size() - 20).ok());
  TriMesh m;
  Status s = load_mesh_file(cut, m);
  INFO(s.message);
  CHECK(s.code == ErrorCode::Truncated);
  CHECK(s.message.rfind(cut + ": truncated: header declares 4 faces but the data ends after 2", 0) == 0);

  // A point cloud where a mesh is needed.
  PointCloud cloud;
  cloud.positions = {{0, 0, 0}, {1, 1, 1}};
  const std::string xyz = dir + "/points.xyz";
  REQUIRE(write_file(xyz, write_xyz(cloud)).ok());
  s = load_mesh_file(xyz, m);
  CHECK_FALSE(s.ok());
  CHECK(s.message == xyz + ": has no faces (a point cloud), but a mesh is needed");
  PointCloud back;
  REQUIRE(load_point_cloud_file(xyz, back).ok());
  CHECK(back.positions == cloud.positions);

  // A text file passed as a photo.
  Image im;
  s = load_image_file(xyz, im);
  CHECK(s.code == ErrorCode::InvalidInput);
  CHECK(s.message.rfind(xyz + ": not an image", 0) == 0);
  s = save_png_file(dir + "/bad.png", Image());
  CHECK_FALSE(s.ok());
  CHECK(s.message.find("cannot encode PNG") != std::string::npos);
  s = write_file("/nonexistent_dir_for_io_test/x.bin", std::string("x"));
  CHECK(s.message.find("cannot create") != std::string::npos);
}

TEST_CASE("OBJ + MTL + PNG written to disk load back with the texture path", "[io][files]") {
  const std::string dir = lk::test::scratch_dir("io_files");
  TriMesh m = tetrahedron();
  m.uvs = {{0, 0}, {1, 0}, {0, 1}, {1, 1}};
  REQUIRE(write_file(dir + "/head.obj", write_obj(m, "head.mtl")).ok());
  REQUIRE(write_file(dir + "/head.mtl", write_mtl("head.png")).ok());
  Image tex = Image::make(8, 8, 3, 200);
  REQUIRE(save_png_file(dir + "/head.png", tex).ok());

  TriMesh back;
  REQUIRE(load_mesh_file(dir + "/head.obj", back).ok());
  CHECK(back.triangles == m.triangles);
  CHECK(back.uvs == m.uvs);
  CHECK(back.texture_name == dir + "/head.png");
  Image tex_back;
  REQUIRE(load_image_file(back.texture_name, tex_back).ok());
  CHECK(tex_back.pixels == tex.pixels);

  // Without the MTL the mesh still loads, with no texture name.
  REQUIRE(write_file(dir + "/lonely.obj", write_obj(m, "missing.mtl")).ok());
  REQUIRE(load_mesh_file(dir + "/lonely.obj", back).ok());
  CHECK(back.texture_name.empty());
}

TEST_CASE("read_geometry: dispatch by extension, then by content", "[io][files]") {
  const TriMesh tet = tetrahedron();
  const Bytes ply = write_ply(tet);
  const std::string obj = write_obj(tet);
  const std::string vtk =
      "# vtk DataFile Version 3.0\nt\nASCII\nDATASET POLYDATA\nPOINTS 3 float\n0 0 0 1 0 0 0 1 0\n"
      "POLYGONS 1 4\n3 0 1 2\n";
  const std::string xyz = "1 2 3\n4 5 6\n";
  struct Case {
    std::string name;
    Bytes bytes;
    GeometryKind kind;
    int vertices;
  };
  const std::vector<Case> cases = {
      {"a.PLY", ply, GeometryKind::Mesh, 4},           {"upload", ply, GeometryKind::Mesh, 4},
      {"b.obj", bytes_of(obj), GeometryKind::Mesh, 4}, {"blob.bin", bytes_of(obj), GeometryKind::Mesh, 4},
      {"c.vtk", bytes_of(vtk), GeometryKind::Mesh, 3}, {"noext", bytes_of(vtk), GeometryKind::Mesh, 3},
      {"d.xyz", bytes_of(xyz), GeometryKind::PointCloud, 2}, {"e.txt", bytes_of(xyz), GeometryKind::PointCloud, 2},
      {"f", bytes_of(xyz), GeometryKind::PointCloud, 2}};
  for (const Case& c : cases) {
    INFO(c.name);
    TriMesh m;
    PointCloud cloud;
    GeometryKind kind;
    const Status s = read_geometry(c.name, c.bytes.data(), c.bytes.size(), m, cloud, kind);
    INFO(s.message);
    REQUIRE(s.ok());
    CHECK(kind == c.kind);
    CHECK(m.num_vertices() == c.vertices);
    CHECK(cloud.size() == c.vertices);
  }
  TriMesh m;
  PointCloud cloud;
  GeometryKind kind;
  const Bytes junk = bytes_of("hello world\n");
  Status s = read_geometry("x.dat", junk.data(), junk.size(), m, cloud, kind);
  CHECK(s.code == ErrorCode::Unsupported);
  CHECK(s.message.find("unknown geometry format") != std::string::npos);
  // The extension wins: a PLY named .obj is read as OBJ and fails clearly.
  s = read_geometry("x.obj", ply.data(), ply.size(), m, cloud, kind);
  CHECK_FALSE(s.ok());
  s = read_geometry("x.ply", nullptr, 0, m, cloud, kind);
  CHECK(s.code == ErrorCode::Empty);
}
