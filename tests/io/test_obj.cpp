#include "io/io.h"
#include "io_test_util.h"
#include "test_data.h"

#include <catch2/catch.hpp>

using namespace lk;
using lk::test::garbage_bytes;
using lk::test::require_error;
using lk::test::bytes_of;

namespace {

Status read(const std::string& text, TriMesh& m, const std::string& mtl = "") {
  GeometryKind kind;
  const Bytes b = bytes_of(text);
  return read_obj(b.data(), b.size(), m, kind, mtl);
}

}  // namespace

TEST_CASE("OBJ reader: quads, negative indices, v//vn and per-vertex uvs", "[io][obj]") {
  const std::string text =
      "# a unit square and a roof\n"
      "mtllib roof.mtl\n"
      "o square\n"
      "v 0 0 0\n"
      "v 1 0 0\n"
      "v 1 1 0\n"
      "v 0 1 0\n"
      "vt 0 0\n"
      "vt 1 0\n"
      "vt 1 1\n"
      "vt 0 1\n"
      "vn 0 0 1\n"
      "usemtl roof\n"
      "s off\n"
      "f 1/1/1 2/2/1 3/3/1 4/4/1\n"
      "g second\n"
      "f -4/-4/1 -2/-2/1 -1/-1/1\n";
  TriMesh m;
  GeometryKind kind;
  const Bytes b = bytes_of(text);
  const Status s = read_obj(b.data(), b.size(), m, kind, "newmtl other\nmap_Kd wrong.png\nnewmtl roof\nKd 1 1 1\n"
                                                         "map_Kd -s 1 1 1 roof_diffuse.jpg\n");
  INFO(s.message);
  REQUIRE(s.ok());
  CHECK(kind == GeometryKind::Mesh);
  REQUIRE(m.num_vertices() == 4);
  REQUIRE(m.num_triangles() == 3);
  CHECK(m.triangles[0] == Tri{0, 1, 2});
  CHECK(m.triangles[1] == Tri{0, 2, 3});
  CHECK(m.triangles[2] == Tri{0, 2, 3});
  // Every vertex used one uv throughout: per-vertex.
  CHECK_FALSE(m.uv_per_corner);
  REQUIRE(m.uvs.size() == 4);
  CHECK(m.uvs[2] == Vec2(1, 1));
  REQUIRE(m.normals.size() == 4);
  CHECK(m.normals[3] == Vec3(0, 0, 1));
  CHECK(m.texture_name == "roof_diffuse.jpg");
  CHECK(obj_mtllib(b.data(), b.size()) == "roof.mtl");
}

TEST_CASE("OBJ reader: a uv seam gives per-corner uvs", "[io][obj]") {
  // Vertex 1 and 3 are on a seam: different uvs in the two triangles.
  TriMesh m;
  REQUIRE(read("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 0.5 0\nvt 0.5 0.5\nvt 0.9 0.9\nvt 0.1 0.9\n"
               "f 1/1 2/2 3/3\nf 1/4 3/5 4/1\n",
               m)
              .ok());
  REQUIRE(m.uv_per_corner);
  REQUIRE(m.uvs.size() == 6);
  CHECK(m.uvs[2] == Vec2(0.5, 0.5));
  CHECK(m.uvs[3] == Vec2(0.9, 0.9));
  CHECK(m.uvs[4] == Vec2(0.1, 0.9));
  CHECK(m.uvs[5] == Vec2(0, 0));
  CHECK(m.normals.empty());
}

TEST_CASE("OBJ reader: vertex colors, per-corner normals averaged, point-cloud OBJ", "[io][obj]") {
  TriMesh m;
  REQUIRE(read("v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nvn 1 0 0\nvn 0 1 0\nf 1//1 2//1 3//1\nf 1//2 3//2 2//2\n",
               m)
              .ok());
  REQUIRE(m.colors.size() == 3);
  CHECK(m.colors[1] == Vec3(0, 1, 0));
  REQUIRE(m.normals.size() == 3);
  CHECK((m.normals[0] - Vec3(1, 1, 0).normalized()).norm() < 1e-15);

  TriMesh cloud;
  GeometryKind kind;
  const Bytes b = bytes_of("v 1 2 3\nv 4 5 6\nvn 0 0 1\nvn 0 1 0\n");
  REQUIRE(read_obj(b.data(), b.size(), cloud, kind).ok());
  CHECK(kind == GeometryKind::PointCloud);
  CHECK(cloud.num_vertices() == 2);
  CHECK(cloud.normals.size() == 2);
}

TEST_CASE("OBJ round trip with per-vertex and per-corner uvs, normals and colors", "[io][obj]") {
  TriMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0.1}, {0, 1, 1.0 / 3.0}};
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  m.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0.6, 0.8}, {0.6, 0, 0.8}};
  m.colors = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0.2, 0.4, 0.6}};
  m.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  for (bool per_corner : {false, true}) {
    TriMesh src = m;
    if (per_corner) {
      src.uvs = {{0, 0}, {0.5, 0}, {0.5, 0.5}, {0.6, 0.6}, {0.9, 0.9}, {0.6, 0.9}};
      src.uv_per_corner = true;
    }
    TriMesh back;
    const std::string text = write_obj(src, "head.mtl");
    REQUIRE(read(text, back, write_mtl("head texture.png")).ok());
    CHECK(back.positions == src.positions);
    CHECK(back.triangles == src.triangles);
    CHECK(back.colors == src.colors);
    CHECK(back.uv_per_corner == per_corner);
    CHECK(back.uvs == src.uvs);
    REQUIRE(back.normals.size() == 4);
    for (int i = 0; i < 4; ++i) CHECK((back.normals[i] - src.normals[i]).norm() < 1e-15);
    // map_Kd takes the last token: a file name with spaces is not supported.
    CHECK(back.texture_name == "texture.png");
  }
}

TEST_CASE("OBJ and MTL writers give exactly this text", "[io][obj]") {
  TriMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 0.5, 0}};
  m.triangles = {{0, 1, 2}};
  m.uvs = {{0, 0}, {1, 0}, {0, 1}};
  CHECK(write_obj(m, "a.mtl") ==
        "# written by likeness\n"
        "mtllib a.mtl\n"
        "v 0 0 0\n"
        "v 1 0 0\n"
        "v 0 0.5 0\n"
        "vt 0 0\n"
        "vt 1 0\n"
        "vt 0 1\n"
        "usemtl material_0\n"
        "f 1/1 2/2 3/3\n");
  CHECK(write_mtl("tex.png") ==
        "# written by likeness\nnewmtl material_0\nKa 1 1 1\nKd 1 1 1\nKs 0 0 0\nillum 1\nmap_Kd tex.png\n");
}

TEST_CASE("OBJ reader rejects malformed input with the line and problem", "[io][obj][errors]") {
  TriMesh m;
  GeometryKind kind;
  require_error(read_obj(nullptr, 0, m, kind), ErrorCode::Empty, "empty");
  require_error(read("v", m), ErrorCode::InvalidInput, "line 1: a vertex needs 3 coordinates");
  require_error(read("# only a comment\n\n", m), ErrorCode::Empty, "no vertices");
  require_error(read("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", m), ErrorCode::InvalidInput,
                "line 4: face refers to vertex 4 but only 3 vertices");
  require_error(read("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", m), ErrorCode::InvalidInput, "refers to vertex 0");
  require_error(read("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -4 1 2\n", m), ErrorCode::InvalidInput, "refers to vertex -4");
  require_error(read("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n", m), ErrorCode::InvalidInput, "a face has 2 corners");
  require_error(read("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/2 3/1\n", m), ErrorCode::InvalidInput,
                "texture coordinate '2'");
  require_error(read("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2 3/1\n", m), ErrorCode::InvalidInput,
                "some corners but not others");
  require_error(read("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/1\nf 1 2 3\n", m), ErrorCode::InvalidInput,
                "some faces have texture coordinates");
  require_error(read("v 0 0 0\nv 1 nan 0\n", m), ErrorCode::InvalidInput, "line 2: vertex 2 has a NaN");
  require_error(read("v 0 0 0\nv 1 inf 0\n", m), ErrorCode::InvalidInput, "NaN or infinite");
  require_error(read("v 0 0 0\nv 1 x 0\n", m), ErrorCode::InvalidInput, "'x' is not a number");
  require_error(read("v 0 0 0\nvn 0 0\n", m), ErrorCode::InvalidInput, "a normal needs 3");
  require_error(read("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/a 2 3\n", m), ErrorCode::InvalidInput, "texture coordinate 'a'");
  // Binary garbage is not OBJ.
  const Bytes garbage = garbage_bytes(300);
  require_error(read_obj(garbage.data(), garbage.size(), m, kind), ErrorCode::InvalidInput, "not an OBJ statement");
  // An OBJ ending mid-face.
  require_error(read("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2", m), ErrorCode::InvalidInput, "a face has 2 corners");
  CHECK(m.positions.empty());
}

TEST_CASE("OBJ reader: real scan james.obj with its MTL", "[io][obj][shared]") {
  LK_REQUIRE_SHARED("head_scans/james_menpo3d/james.obj");
  const std::string path = lk::test::shared_data_dir() + "/head_scans/james_menpo3d/james.obj";
  TriMesh m;
  const Status s = load_mesh_file(path, m);
  INFO(s.message);
  REQUIRE(s.ok());
  CHECK(m.num_vertices() == 6393);
  CHECK(m.num_triangles() == 12228);
  CHECK(m.normals.empty());
  // 6,680 vt for 6,393 v: the atlas has seams, so uvs are per corner.
  CHECK(m.uv_per_corner);
  CHECK(m.uvs.size() == 3 * 12228u);
  for (const Vec2& uv : m.uvs) {
    CHECK(uv.x() >= 0.0);
    CHECK(uv.x() <= 1.0);
  }
  BBox box;
  for (const Vec3& p : m.positions) box.extend(p);
  CHECK(box.min.x() == Approx(-126).margin(2));
  CHECK(box.max.y() == Approx(150).margin(2));
  CHECK(box.max.z() == Approx(38).margin(2));
  // The MTL's map_Kd resolved next to the MTL, and it is there.
  CHECK(m.texture_name == lk::test::shared_data_dir() + "/head_scans/james_menpo3d/james.jpg");
  CHECK(lk::test::exists(m.texture_name));
  // First face "f 2261/1 4093/2 926/3".
  CHECK(m.triangles[0] == Tri{2260, 4092, 925});
}
