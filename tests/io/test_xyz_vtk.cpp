#include "io/io.h"
#include "io_test_util.h"
#include "test_data.h"

#include <catch2/catch.hpp>

using namespace lk;
using lk::test::garbage_bytes;
using lk::test::require_error;
using lk::test::bytes_of;

namespace {

Status xyz(const std::string& text, PointCloud& c) {
  const Bytes b = bytes_of(text);
  return read_xyz(b.data(), b.size(), c);
}

Status vtk(const std::string& text, TriMesh& m) {
  GeometryKind kind;
  const Bytes b = bytes_of(text);
  return read_vtk(b.data(), b.size(), m, kind);
}

}  // namespace

TEST_CASE("XYZ reader: 3, 6 and 9 columns, separators and comments", "[io][xyz]") {
  PointCloud c;
  REQUIRE(xyz("//X Y Z\n# comment\n1 2 3\n\n4,5,6\n\t7;8 9\r\n", c).ok());
  REQUIRE(c.size() == 3);
  CHECK(c.positions[1] == Vec3(4, 5, 6));
  CHECK(c.positions[2] == Vec3(7, 8, 9));
  CHECK(c.normals.empty());
  CHECK(c.colors.empty());

  // Unit-length extra triples are normals...
  REQUIRE(xyz("0 0 0 0 0 1\n1 0 0 0.6 0.8 0\n", c).ok());
  CHECK(c.normals.size() == 2);
  CHECK(c.colors.empty());
  // ...anything else colors, 0..255 when above 1.
  REQUIRE(xyz("0 0 0 255 0 0\n1 0 0 0 51 0\n", c).ok());
  REQUIRE(c.colors.size() == 2);
  CHECK(c.normals.empty());
  CHECK(c.colors[0] == Vec3(1, 0, 0));
  CHECK(c.colors[1].y() == Approx(0.2));
  REQUIRE(xyz("0 0 0 0.5 0.5 0.5\n", c).ok());
  CHECK(c.colors[0] == Vec3(0.5, 0.5, 0.5));
  // Nine columns: the unit triple is the normal, whichever comes first.
  REQUIRE(xyz("0 0 0 10 20 30 0 0 1\n", c).ok());
  CHECK(c.normals[0] == Vec3(0, 0, 1));
  CHECK(c.colors[0].x() == Approx(10 / 255.0));
  REQUIRE(xyz("0 0 0 0 1 0 10 20 30\n", c).ok());
  CHECK(c.normals[0] == Vec3(0, 1, 0));
}

TEST_CASE("XYZ reader: Leica .pts with a count line, intensity and colors", "[io][xyz]") {
  PointCloud c;
  REQUIRE(xyz("2\n1 2 3 -1200 255 0 0\n4 5 6 300 0 0 255\n", c).ok());
  REQUIRE(c.size() == 2);
  CHECK(c.positions[1] == Vec3(4, 5, 6));
  REQUIRE(c.colors.size() == 2);
  CHECK(c.colors[0] == Vec3(1, 0, 0));
  CHECK(c.colors[1] == Vec3(0, 0, 1));
  CHECK(c.normals.empty());
  REQUIRE(xyz("1 2 3 0.5\n4 5 6 0.25\n", c).ok());
  CHECK(c.size() == 2);
  CHECK(c.colors.empty());
}

TEST_CASE("XYZ round trip with normals and colors", "[io][xyz]") {
  PointCloud c;
  for (int i = 0; i < 20; ++i) {
    c.positions.push_back(Vec3(i * 0.1, -i / 3.0, 1e-5 * i));
    c.normals.push_back(Vec3(std::cos(i), std::sin(i), 0));
    c.colors.push_back(Vec3(i / 255.0, 1 - i / 255.0, (100 + i) / 255.0));
  }
  for (int variant = 0; variant < 3; ++variant) {
    PointCloud src = c;
    if (variant >= 1) src.colors.clear();
    if (variant == 2) src.normals.clear();
    PointCloud back;
    REQUIRE(xyz(write_xyz(src), back).ok());
    CHECK(back.positions == src.positions);
    REQUIRE(back.normals.size() == src.normals.size());
    for (size_t i = 0; i < src.normals.size(); ++i) CHECK(back.normals[i] == src.normals[i]);
    REQUIRE(back.colors.size() == src.colors.size());
    for (size_t i = 0; i < src.colors.size(); ++i) CHECK((back.colors[i] - src.colors[i]).norm() < 1e-12);
  }
}

TEST_CASE("XYZ reader rejects malformed input", "[io][xyz][errors]") {
  PointCloud c;
  require_error(read_xyz(nullptr, 0, c), ErrorCode::Empty, "empty");
  require_error(xyz("\n", c), ErrorCode::Empty, "no points");
  require_error(xyz("# nothing\n// here\n", c), ErrorCode::Empty, "no points");
  require_error(xyz("1", c), ErrorCode::Empty, "no points");  // a .pts count line alone
  require_error(xyz("1.5\n", c), ErrorCode::Unsupported, "line 1 has 1 values");
  require_error(xyz("1 2 3 4 5\n", c), ErrorCode::Unsupported, "has 5 values");
  require_error(xyz("3\n1 2 3 4\n5 6 7 8\n", c), ErrorCode::InvalidInput,
                "wrong counts: the first line declares 3 points but 2 follow");
  require_error(xyz("1 2 3 4 5 6 7 8 9 10\n", c), ErrorCode::Unsupported, "more than 9");
  require_error(xyz("1 2 3\n4 5 6\n7 8\n", c), ErrorCode::InvalidInput, "wrong counts: line 3 has 2 values but line 1 has 3");
  require_error(xyz("1 2 3\n4 nan 6\n", c), ErrorCode::InvalidInput, "line 2: NaN");
  require_error(xyz("1 2 3\n4 5 1e999\n", c), ErrorCode::InvalidInput, "line 2: NaN or infinite");
  require_error(xyz("1 2 3\n4 five 6\n", c), ErrorCode::InvalidInput, "'five' is not a number");
  const Bytes garbage = garbage_bytes(300);
  const Status s = read_xyz(garbage.data(), garbage.size(), c);
  CHECK_FALSE(s.ok());
  CHECK(c.positions.empty());
}

namespace {

// Every section kind the reader knows, in the order VTK writes them.
const char* kPolyData =
    "# vtk DataFile Version 3.0\n"
    "a hand-made test\n"
    "ASCII\n"
    "DATASET POLYDATA\n"
    "POINTS 6 float\n"
    "0 0 0  1 0 0  1 1 0\n"
    "0 1 0  2 0 0  2 1 0\n"
    "VERTICES 1 2\n"
    "1 5\n"
    "LINES 1 3\n"
    "2 0 5\n"
    "POLYGONS 1 5\n"
    "4 0 1 2 3\n"
    "TRIANGLE_STRIPS 1 5\n"
    "4 1 4 2 5\n"
    "CELL_DATA 5\n"
    "SCALARS cell_id int 1\n"
    "LOOKUP_TABLE default\n"
    "0 1 2 3 4\n"
    "POINT_DATA 6\n"
    "SCALARS height float\n"
    "LOOKUP_TABLE my_table\n"
    "0 1 2 3 4 5\n"
    "LOOKUP_TABLE my_table 2\n"
    "0 0 0 1  1 1 1 1\n"
    "NORMALS normals float\n"
    "0 0 1 0 0 1 0 0 1 0 0 1 0 0 1 0 0 1\n"
    "TEXTURE_COORDINATES textureCoords 2 float\n"
    "0 0  0.5 0  0.5 1  0 1  1 0  1 1\n"
    "VECTORS velocity double\n"
    "1 0 0 1 0 0 1 0 0 1 0 0 1 0 0 1 0 0\n"
    "FIELD FieldData 2\n"
    "temperature 1 6 float\n"
    "1 2 3 4 5 6\n"
    "pair 2 3 int\n"
    "1 2 3 4 5 6\n";

}  // namespace

TEST_CASE("VTK reader: POLYGONS, TRIANGLE_STRIPS and point attributes of a hand-made file", "[io][vtk]") {
  TriMesh m;
  GeometryKind kind;
  const Bytes b = bytes_of(kPolyData);
  const Status s = read_vtk(b.data(), b.size(), m, kind);
  INFO(s.message);
  REQUIRE(s.ok());
  CHECK(kind == GeometryKind::Mesh);
  REQUIRE(m.num_vertices() == 6);
  CHECK(m.positions[5] == Vec3(2, 1, 0));
  // Quad fan (2) + strip 1 4 2 5 -> (1,4,2), (4,2,5) flipped to (2,4,5).
  REQUIRE(m.num_triangles() == 4);
  CHECK(m.triangles[0] == Tri{0, 1, 2});
  CHECK(m.triangles[1] == Tri{0, 2, 3});
  CHECK(m.triangles[2] == Tri{1, 4, 2});
  CHECK(m.triangles[3] == Tri{2, 4, 5});
  REQUIRE(m.uvs.size() == 6);
  CHECK(m.uvs[2] == Vec2(0.5, 1));
  REQUIRE(m.normals.size() == 6);
  CHECK(m.normals[4] == Vec3(0, 0, 1));
  // Both strip triangles face +z like the quad: (b-a)x(c-a) has z > 0.
  for (const Tri& t : m.triangles) {
    const Vec3 n = (m.positions[t[1]] - m.positions[t[0]]).cross(m.positions[t[2]] - m.positions[t[0]]);
    CHECK(n.z() > 0);
  }
}

TEST_CASE("VTK reader: version 5.1 OFFSETS/CONNECTIVITY cells", "[io][vtk]") {
  TriMesh m;
  const Status s = vtk(
      "# vtk DataFile Version 5.1\nvtk output\nASCII\nDATASET POLYDATA\n"
      "POINTS 4 float\n0 0 0 1 0 0 1 1 0 0 1 0\n"
      "METADATA\nINFORMATION 0\n\n"
      "POLYGONS 3 7\nOFFSETS vtktypeint64\n0 3 7\nCONNECTIVITY vtktypeint64\n0 1 2 0 1 2 3\n",
      m);
  INFO(s.message);
  REQUIRE(s.ok());
  REQUIRE(m.num_triangles() == 3);
  CHECK(m.triangles[2] == Tri{0, 2, 3});
}

TEST_CASE("VTK reader: points only is a point cloud", "[io][vtk]") {
  TriMesh m;
  GeometryKind kind;
  const Bytes b = bytes_of("# vtk DataFile Version 2.0\nscan\nASCII\nDATASET POLYDATA\nPOINTS 2 double\n1 2 3 4 5 6\n");
  REQUIRE(read_vtk(b.data(), b.size(), m, kind).ok());
  CHECK(kind == GeometryKind::PointCloud);
  CHECK(m.positions[1] == Vec3(4, 5, 6));
}

TEST_CASE("VTK reader rejects malformed and unsupported input", "[io][vtk][errors]") {
  TriMesh m;
  GeometryKind kind;
  const std::string head = "# vtk DataFile Version 3.0\nt\nASCII\nDATASET POLYDATA\n";
  require_error(read_vtk(nullptr, 0, m, kind), ErrorCode::Empty, "empty");
  require_error(vtk("#", m), ErrorCode::InvalidInput, "not a legacy VTK file");
  require_error(vtk("# vtk DataFile Version 3.0\nt\nBINARY\nDATASET POLYDATA\n", m), ErrorCode::Unsupported,
                "binary");
  require_error(vtk("# vtk DataFile Version 3.0\nt\nASCII\nDATASET STRUCTURED_GRID\n", m), ErrorCode::Unsupported,
                "STRUCTURED_GRID");
  require_error(vtk(head, m), ErrorCode::Empty, "no POINTS");
  require_error(vtk(head + "POINTS 1000000000 float\n0 0 0\n", m), ErrorCode::Truncated,
                "POINTS declares 1000000000 items");
  require_error(vtk(head + "POINTS 3 float\n0 0 0 1 0 0 1 1\n", m), ErrorCode::Truncated,
                "POINTS declares 9 values but the data ends after 8");
  require_error(vtk(head + "POINTS 2 float\n0 0 0 1 nan 0\n", m), ErrorCode::InvalidInput, "NaN");
  require_error(vtk(head + "POINTS 2 float\n0 0 0 1 zero 0\n", m), ErrorCode::InvalidInput, "'zero' is not a number");
  require_error(vtk(head + "POINTS 3 float\n0 0 0 1 0 0 1 1 0\nPOLYGONS 1 4\n3 0 1 3\n", m), ErrorCode::InvalidInput,
                "refers to point 3 but there are only 3 points");
  require_error(vtk(head + "POINTS 3 float\n0 0 0 1 0 0 1 1 0\nPOLYGONS 2 4\n3 0 1 2\n", m),
                ErrorCode::InvalidInput, "wrong counts");
  require_error(vtk(head + "POINTS 3 float\n0 0 0 1 0 0 1 1 0\nPOLYGONS 1 5\n3 0 1 2 2\n", m),
                ErrorCode::InvalidInput, "wrong counts");
  require_error(vtk(head + "POINTS 3 float\n0 0 0 1 0 0 1 1 0\nPOLYGONS 1 3\n2 0 1\n", m), ErrorCode::InvalidInput,
                "polygon 0 has 2 points");
  require_error(vtk(head + "POINTS 3 float\n0 0 0 1 0 0 1 1 0\nPOINT_DATA 4\n", m), ErrorCode::InvalidInput,
                "POINT_DATA 4 but there are 3 points");
  require_error(vtk(head + "POINTS 3 float\n0 0 0 1 0 0 1 1 0\nNORMALS n float\n0 0 1\n", m),
                ErrorCode::InvalidInput, "outside a POINT_DATA");
  require_error(vtk(head + "POINTS 3 float\n0 0 0 1 0 0 1 1 0\nBLOB 3\n", m), ErrorCode::InvalidInput,
                "unknown keyword 'blob'");
  const Bytes garbage = garbage_bytes(300);
  require_error(read_vtk(garbage.data(), garbage.size(), m, kind), ErrorCode::InvalidInput, "not a legacy VTK");
  CHECK(m.positions.empty());
}

TEST_CASE("VTK reader: the real Cyberware scan fran_cut.vtk", "[io][vtk][shared]") {
  LK_REQUIRE_SHARED("head_scans/fran_cyberware/fran_cut.vtk");
  const std::string path = lk::test::shared_data_dir() + "/head_scans/fran_cyberware/fran_cut.vtk";
  TriMesh m;
  const Status s = load_mesh_file(path, m);
  INFO(s.message);
  REQUIRE(s.ok());
  CHECK(m.num_vertices() == 2205);
  CHECK(m.num_triangles() == 4224);
  REQUIRE(m.uvs.size() == 2205);
  CHECK_FALSE(m.uv_per_corner);
  for (const Vec2& uv : m.uvs) {
    CHECK(uv.x() >= 0.0);
    CHECK(uv.x() <= 1.0);
    CHECK(uv.y() >= 0.0);
    CHECK(uv.y() <= 1.0);
  }
  BBox box;
  for (const Vec3& p : m.positions) box.extend(p);
  CHECK(box.size().maxCoeff() < 0.5);  // "units are about +-0.2"
  CHECK(box.size().minCoeff() > 0.05);
}
