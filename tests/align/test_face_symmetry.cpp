// The yaw at which a scanned face is most mirror-symmetric
// (core/align/face_symmetry.h): the generic head (mirror-symmetric by
// construction) turned by a known yaw about its face's vertical axis is the
// scan; seen from the unturned face, the most symmetric view must be that
// turn, on its triangles and on its points alone; a face whose one side is
// pushed in is less symmetric; bad input is refused.
#include "align/face_refine.h"
#include "align/face_symmetry.h"
#include "test_data.h"
#include "test_scan.h"

#include <catch2/catch.hpp>
#include <cmath>

using namespace lk;

namespace {

struct Turned {
  TriMesh mesh;
  MeshBvh surface;
};

// The generic head turned by yaw_deg about ann.up through the face's centre.
Turned turned_head(const GenericHead& g, const std::vector<Vec3>& face, double yaw_deg) {
  Vec3 c = Vec3::Zero();
  for (const Vec3& p : face) c += p;
  c /= double(face.size());
  const Mat3 R = Mat3(Eigen::AngleAxisd(yaw_deg * 3.14159265358979323846 / 180.0, g.annotations.up.normalized()));
  Turned t;
  t.mesh = g.mesh;
  for (Vec3& p : t.mesh.positions) p = R * (p - c) + c;
  REQUIRE(build_bvh(t.mesh, t.surface).ok());
  return t;
}

}  // namespace

TEST_CASE("face symmetry: the most symmetric view is the head's turn, on triangles and on points") {
  const GenericHead& g = test::generic_head();
  const std::vector<Vec3> face = upper_face_samples(g.mesh, g.annotations, 800);
  REQUIRE(face.size() > 100);
  const MeshBvh none;
  for (double yaw : {0.0, 25.0, -17.5, 35.0}) {
    const Turned t = turned_head(g, face, yaw);
    FaceSymmetry on_mesh, on_points;
    REQUIRE(face_symmetry_yaw(face, g.annotations.look, g.annotations.up, t.surface, {}, {}, on_mesh).ok());
    // Points alone: a grid of points on every triangle, a coarser map.
    std::vector<Vec3> points;
    for (const Tri& f : t.mesh.triangles)
      for (int a = 0; a <= 5; ++a)
        for (int b = 0; a + b <= 5; ++b)
          points.push_back((a * t.mesh.positions[f[0]] + b * t.mesh.positions[f[1]] + (5 - a - b) * t.mesh.positions[f[2]]) / 5.0);
    FaceSymmetryOptions coarse;
    coarse.cells_across = 24;
    REQUIRE(face_symmetry_yaw(face, g.annotations.look, g.annotations.up, none, points, coarse, on_points).ok());
    INFO("turned " << yaw << " deg: mesh " << on_mesh.yaw_deg << " (" << on_mesh.score << "), points "
                   << on_points.yaw_deg << " (" << on_points.score << ")");
    CHECK(std::fabs(on_mesh.yaw_deg - yaw) <= 5.0);
    CHECK(on_mesh.score > 0.85);
    CHECK(std::fabs(on_points.yaw_deg - yaw) <= 5.0);
    // Seen from the unturned face or turned as far the other way, the
    // relief is less symmetric: the map tells which way the head turned.
    for (size_t k = 0; k < on_mesh.yaws_deg.size(); ++k)
      if (yaw != 0 && (on_mesh.yaws_deg[k] == 0 || on_mesh.yaws_deg[k] == -yaw)) {
        INFO("seen at " << on_mesh.yaws_deg[k] << " deg: " << on_mesh.scores[k]);
        CHECK(on_mesh.scores[k] < on_mesh.score - 0.05);
      }
  }
}

TEST_CASE("face symmetry: a face pushed in on one side is less symmetric, and bad input is refused") {
  const GenericHead& g = test::generic_head();
  const std::vector<Vec3> face = upper_face_samples(g.mesh, g.annotations, 800);
  Turned t = turned_head(g, face, 0.0);
  FaceSymmetry whole;
  REQUIRE(face_symmetry_yaw(face, g.annotations.look, g.annotations.up, t.surface, {}, {}, whole).ok());
  // One cheek and eye pushed back along the face's direction.
  Vec3 c = Vec3::Zero();
  for (const Vec3& p : face) c += p;
  c /= double(face.size());
  const Vec3 look = g.annotations.look.normalized(), side = g.annotations.up.normalized().cross(look).normalized();
  double width = 0;
  for (const Vec3& p : face) width = std::max(width, std::fabs(side.dot(p - c)));
  // A bump on one cheek: a Gaussian of 0.25 face half-widths, 0.15 high
  // (clipped at 2.5 robust sigmas, partly taken by the quadric: 0.966 -> 0.915).
  const Vec3 up = g.annotations.up.normalized();
  for (Vec3& p : t.mesh.positions) {
    const double x = side.dot(p - c) / width - 0.5, y = up.dot(p - c) / width;
    if (look.dot(p - c) > -0.5 * width) p += 0.15 * width * std::exp(-(x * x + y * y) / (2 * 0.25 * 0.25)) * look;
  }
  REQUIRE(build_bvh(t.mesh, t.surface).ok());
  FaceSymmetry dented;
  REQUIRE(face_symmetry_yaw(face, g.annotations.look, g.annotations.up, t.surface, {}, {}, dented).ok());
  INFO("whole " << whole.score << ", dented " << dented.score);
  CHECK(dented.score < whole.score - 0.03);

  FaceSymmetry out;
  const MeshBvh none;
  CHECK(face_symmetry_yaw({face.begin(), face.begin() + 5}, g.annotations.look, g.annotations.up, t.surface, {}, {}, out)
            .code == ErrorCode::InvalidInput);
  CHECK(face_symmetry_yaw(face, g.annotations.up, g.annotations.up, t.surface, {}, {}, out).code ==
        ErrorCode::InvalidInput);
  FaceSymmetryOptions bad;
  bad.yaw_step_deg = 0;
  CHECK(face_symmetry_yaw(face, g.annotations.look, g.annotations.up, t.surface, {}, bad, out).code ==
        ErrorCode::InvalidInput);
  // Nothing to draw: no surface and no points.
  CHECK(face_symmetry_yaw(face, g.annotations.look, g.annotations.up, none, {}, {}, out).code == ErrorCode::Empty);
}
