// The project's parts and photo helpers on the generic head, without a fit:
// the parts placed and the teeth split at the bite plane, the generic
// textures, and the calibration step's camera sharing.
#include "project/parts.h"
#include "project/texture_job.h"
#include "test_scan.h"

#include "texture/synthetic_photo.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>

using namespace lk;

TEST_CASE("project parts: the teeth split at the bite plane into the placed arch's triangles") {
  const GenericHead& g = test::generic_head();
  HeadParts parts;
  REQUIRE(place_head_parts(g.mesh, g, parts).ok());
  const TriMesh& teeth = parts.placed.teeth;
  const double bite = parts.placement.mouth_center.y();
  REQUIRE(!parts.upper_teeth.triangles.empty());
  REQUIRE(!parts.lower_teeth.triangles.empty());
  CHECK(parts.upper_teeth.triangles.size() + parts.lower_teeth.triangles.size() == teeth.triangles.size());
  auto centroid_y = [](const TriMesh& m, const Tri& t) {
    return (m.positions[t[0]].y() + m.positions[t[1]].y() + m.positions[t[2]].y()) / 3.0;
  };
  for (const Tri& t : parts.lower_teeth.triangles) CHECK(centroid_y(parts.lower_teeth, t) < bite);
  for (const Tri& t : parts.upper_teeth.triangles) CHECK(centroid_y(parts.upper_teeth, t) >= bite);
  // Each part keeps its own vertices only, with their uvs.
  CHECK(parts.lower_teeth.uvs.size() == parts.lower_teeth.positions.size());
  std::vector<char> used(teeth.positions.size(), 0);
  for (const Tri& t : teeth.triangles)
    for (int k = 0; k < 3; ++k) used[t[k]] = 1;
  const size_t referenced = static_cast<size_t>(std::count(used.begin(), used.end(), 1));
  CHECK(parts.upper_teeth.positions.size() + parts.lower_teeth.positions.size() >= referenced);
  CHECK(parts.upper_teeth.positions.size() < referenced);
  // A mesh of another topology is refused with a message.
  TriMesh other = g.mesh;
  other.positions.resize(10);
  other.triangles = {{0, 1, 2}};
  HeadParts none;
  const Status st = place_head_parts(other, g, none);
  CHECK(!st.ok());
  CHECK(!st.message.empty());
}

TEST_CASE("project parts: the generic eye and teeth textures") {
  EyeballTextureOptions eto;
  eto.size = 64;
  Image eye;
  REQUIRE(generic_eyeball_texture(eto, eye).ok());
  CHECK(eye.width == 64);
  CHECK(eye.height == 64);
  // Brown: red over green over blue at the iris (the texture's middle ring).
  const PolarIris iris = generic_polar_iris();
  const float* px = iris.at(10, 12);
  CHECK(px[0] > px[1]);
  CHECK(px[1] > px[2]);

  TeethCompositeOptions co;
  co.width = 128;
  co.height = 64;
  Image teeth;
  REQUIRE(generic_teeth_texture(co, teeth).ok());
  CHECK(teeth.width == 128);
  CHECK(teeth.height == 64);
  CHECK(teeth.channels == 4);
  // The voids between the teeth are transparent, the teeth opaque.
  int clear = 0, opaque = 0;
  for (int y = 0; y < teeth.height; ++y)
    for (int x = 0; x < teeth.width; ++x) (teeth.at(x, y)[3] == 0 ? clear : opaque) += 1;
  CHECK(clear > 0);
  CHECK(opaque > clear);
}

TEST_CASE("project texture: calibration shares one camera when asked or when the photos look alike") {
  const GenericHead& g = test::generic_head();
  // Two photos of the generic head, one camera (same size, same focal).
  std::vector<std::vector<Correspondence>> points(2);
  std::vector<std::array<int, 2>> sizes = {{640, 480}, {640, 480}};
  const std::vector<std::string> names = {"a.png", "b.png"};
  const double angles[] = {0.3, -0.4};
  for (int i = 0; i < 2; ++i) {
    const Vec3 eye(std::sin(angles[i]), 0.05, std::cos(angles[i]));
    const Camera cam = look_at_camera(eye, Vec3::Zero(), Vec3::UnitY(), 900, 640, 480);
    for (size_t v = 0; v < g.mesh.positions.size() && points[i].size() < 15; v += 97) {
      const Vec3& p = g.mesh.positions[v];
      Vec2 px;
      if (p.z() > 0.02 && cam.project(p, px) && px.x() > 0 && px.y() > 0 && px.x() < 640 && px.y() < 480)
        points[i].push_back({px, p});
    }
    REQUIRE(points[i].size() >= 8);
  }
  PhotoCalibration auto_cal, separate, same;
  REQUIRE(calibrate_texture_photos(points, sizes, names, CalibOptions{}, CameraSharing::Auto, auto_cal).ok());
  REQUIRE(calibrate_texture_photos(points, sizes, names, CalibOptions{}, CameraSharing::Separate, separate).ok());
  CHECK(auto_cal.shared);
  CHECK(!separate.shared);
  CHECK(auto_cal.results[0].camera.fx == auto_cal.results[1].camera.fx);
  for (int i = 0; i < 2; ++i) {
    CHECK(auto_cal.results[i].camera.fx == Approx(900).epsilon(0.01));
    CHECK(separate.results[i].camera.fx == Approx(900).epsilon(0.05));
  }
  // Photos of different sizes are calibrated apart unless told otherwise.
  sizes[1] = {800, 480};
  for (Correspondence& c : points[1]) c.pixel.x() += 80;  // the same view, centred in the wider frame
  REQUIRE(calibrate_texture_photos(points, sizes, names, CalibOptions{}, CameraSharing::Auto, separate).ok());
  CHECK(!separate.shared);
  REQUIRE(calibrate_texture_photos(points, sizes, names, CalibOptions{}, CameraSharing::Same, same).ok());
  CHECK(same.shared);
  // Counts that do not match are refused.
  CHECK(calibrate_texture_photos(points, {{640, 480}}, names, CalibOptions{}, CameraSharing::Auto, same).code ==
        ErrorCode::InvalidInput);
}

TEST_CASE("project texture: messages name photos by their names") {
  const std::vector<std::string> names = {"front.jpg", "side.jpg"};
  const Status st = name_photos(Status::error(ErrorCode::NotAHead, "photo 1 sees no vertex of the head"), names);
  CHECK(st.message == "side.jpg sees no vertex of the head");
  CHECK(st.code == ErrorCode::NotAHead);
  CHECK(name_photos(Status::error(ErrorCode::Internal, "a photo 1 elsewhere"), names).message == "a photo 1 elsewhere");
}

TEST_CASE("project texture: the chart of the control mesh without levels is its own") {
  const GenericHead& g = test::generic_head();
  std::vector<Vec2> chart;
  UvStats stats;
  REQUIRE(level_chart(g.mesh, {}, UvOptions{}, chart, stats).ok());
  CHECK(chart.size() == g.mesh.positions.size());
  for (const Vec2& uv : chart) {
    CHECK(uv.x() >= 0);
    CHECK(uv.x() <= 1);
    CHECK(uv.y() >= 0);
    CHECK(uv.y() <= 1);
  }
  CHECK(stats.flipped == 0);
  CHECK(std::isfinite(stats.l2_stretch));
  CHECK(stats.l2_stretch > 0);
}
