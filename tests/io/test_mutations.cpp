// Deterministic mutation tests: valid files of every format with bytes
// flipped, cut, duplicated or deleted. Whatever a reader returns must be
// either an error with a message, or a mesh that keeps every invariant the
// rest of the pipeline relies on (indices in range, attribute sizes, finite
// positions). Run under -fsanitize=address during development.
#include "io/io.h"
#include "mesh/primitives.h"
#include "io_test_util.h"

#include <catch2/catch.hpp>

#include <random>

using namespace lk;
using lk::test::bytes_of;

namespace {

TriMesh textured_grid(int n) {
  TriMesh m = make_regular_grid(n, n);  // vertex (i, j) at (i, j, 0)
  for (Vec3& p : m.positions) {
    const double i = p.x(), j = p.y();
    p.z() = 0.1 * i * j;
    m.normals.push_back(Vec3(0, 0, 1));
    m.colors.push_back(Vec3(i / n, j / n, 0.5));
    m.uvs.push_back(Vec2(i / n, j / n));
  }
  return m;
}

Bytes mutate(const Bytes& in, std::mt19937& rng) {
  Bytes b = in;
  std::uniform_int_distribution<int> kind(0, 5);
  const int edits = 1 + static_cast<int>(rng() % 4);
  for (int e = 0; e < edits && !b.empty(); ++e) {
    const size_t at = rng() % b.size();
    switch (kind(rng)) {
      case 0: b[at] = static_cast<std::uint8_t>(rng()); break;                   // random byte
      case 1: b[at] ^= static_cast<std::uint8_t>(1u << (rng() % 8)); break;     // bit flip
      case 2: b.resize(at); break;                                               // truncate
      case 3: b.erase(b.begin() + at); break;                                    // delete a byte
      case 4: b.insert(b.begin() + at, b[at]); break;                            // duplicate a byte
      case 5: {                                                                  // digit -> other digit
        if (b[at] >= '0' && b[at] <= '9') b[at] = static_cast<std::uint8_t>('0' + rng() % 10);
        break;
      }
    }
  }
  return b;
}

void check_mesh_invariants(const TriMesh& m) {
  const size_t nv = m.positions.size();
  REQUIRE(nv > 0);
  for (const Vec3& p : m.positions) REQUIRE(p.allFinite());
  for (const Tri& t : m.triangles)
    for (int k = 0; k < 3; ++k) REQUIRE((t[k] >= 0 && static_cast<size_t>(t[k]) < nv));
  REQUIRE((m.normals.empty() || m.normals.size() == nv));
  REQUIRE((m.colors.empty() || m.colors.size() == nv));
  if (m.uv_per_corner) REQUIRE(m.uvs.size() == 3 * m.triangles.size());
  else REQUIRE((m.uvs.empty() || m.uvs.size() == nv));
}

}  // namespace

TEST_CASE("mutated geometry files: an error with a message, or a valid mesh", "[io][mutation]") {
  const TriMesh grid = textured_grid(6);
  TriMesh corner = grid;
  corner.uvs.clear();
  for (const Tri& t : grid.triangles)
    for (int k = 0; k < 3; ++k) corner.uvs.push_back(grid.uvs[t[k]]);
  corner.uv_per_corner = true;
  const std::string vtk =
      "# vtk DataFile Version 3.0\nt\nASCII\nDATASET POLYDATA\nPOINTS 5 float\n0 0 0 1 0 0 1 1 0 0 1 0 2 0 0\n"
      "POLYGONS 1 5\n4 0 1 2 3\nTRIANGLE_STRIPS 1 4\n3 1 4 2\nPOINT_DATA 5\nSCALARS s float 1\n"
      "LOOKUP_TABLE default\n1 2 3 4 5\nTEXTURE_COORDINATES t 2 float\n0 0 1 0 1 1 0 1 0.5 0.5\n";
  const std::vector<std::pair<std::string, Bytes>> seeds = {
      {"a.ply", write_ply(grid)},
      {"b.ply", write_ply(grid, true)},
      {"c.ply", write_ply(corner)},
      {"d.obj", bytes_of(write_obj(corner))},
      {"e.obj", bytes_of(write_obj(grid))},
      {"f.vtk", bytes_of(vtk)},
      {"g.xyz", bytes_of(write_xyz(to_point_cloud(grid)))},
  };
  std::mt19937 rng(20021);
  int accepted = 0, rejected = 0;
  for (const auto& [name, bytes] : seeds) {
    INFO(name);
    for (int trial = 0; trial < 1500; ++trial) {
      const Bytes b = mutate(bytes, rng);
      TriMesh m;
      PointCloud c;
      GeometryKind kind;
      const Status s = read_geometry(name, b.data(), b.size(), m, c, kind);
      if (s.ok()) {
        ++accepted;
        check_mesh_invariants(m);
        REQUIRE(c.size() == m.num_vertices());
      } else {
        ++rejected;
        REQUIRE_FALSE(s.message.empty());
        REQUIRE(m.positions.empty());
      }
    }
  }
  // Both outcomes occur: the mutations are neither all harmless nor all fatal.
  CHECK(accepted > 100);
  CHECK(rejected > 1000);
}

TEST_CASE("mutated images: an error with a message, or a consistent image", "[io][mutation]") {
  Image im = Image::make(24, 16, 3);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 24; ++x)
      for (int c = 0; c < 3; ++c) im.at(x, y)[c] = static_cast<std::uint8_t>(x * 10 + y * 3 + c * 40);
  const Bytes png = write_png(im);
  std::mt19937 rng(7);
  int rejected = 0;
  for (int trial = 0; trial < 1500; ++trial) {
    const Bytes b = mutate(png, rng);
    Image out;
    const Status s = read_image(b.data(), b.size(), out);
    if (s.ok()) {
      REQUIRE(out.pixels.size() == static_cast<size_t>(out.width) * out.height * out.channels);
    } else {
      ++rejected;
      REQUIRE_FALSE(s.message.empty());
      REQUIRE(out.empty());
    }
  }
  CHECK(rejected > 100);
}
