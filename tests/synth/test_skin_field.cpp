// The synthetic photo session (synth/skin_field.h): a deterministic skin
// albedo with the features it promises where the annotations put them, a
// camera ring that frames the head as asked with lk::Camera's conventions,
// and feature vertices a profile photo can still see.
#include "synth/skin_field.h"

#include "test_scan.h"

#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <set>

using namespace lk;

namespace {

const GenericHead& generic() { return test::generic_head(); }

Vec3 mean_albedo(const SkinField& f, const GenericHead& head, const char* region) {
  Vec3 sum = Vec3::Zero();
  const auto& vs = head.annotations.regions.at(region);
  for (int v : vs) sum += skin_albedo(f, head.mesh.positions[v]);
  return sum / double(vs.size());
}

}  // namespace

TEST_CASE("skin albedo is deterministic, bounded, and varies with the seed", "[skin_field]") {
  SkinField a, b, c;
  REQUIRE(make_skin_field(generic(), 5, {}, a).ok());
  REQUIRE(make_skin_field(generic(), 5, {}, b).ok());
  REQUIRE(make_skin_field(generic(), 6, {}, c).ok());
  const auto& pos = generic().mesh.positions;
  const std::vector<Vec3> ca = skin_albedo(a, pos), cb = skin_albedo(b, pos), cc = skin_albedo(c, pos);
  double differ = 0;
  for (size_t i = 0; i < pos.size(); ++i) {
    CHECK(ca[i] == cb[i]);
    CHECK(ca[i].minCoeff() >= 0.02);
    CHECK(ca[i].maxCoeff() <= 0.7);  // below the renderer's tone-mapping shoulder with gains to 1.14
    differ = std::max(differ, (ca[i] - cc[i]).norm());
  }
  CHECK(differ > 0.05);
}

TEST_CASE("skin albedo has redder lips, dark brows and freckles where the head says", "[skin_field]") {
  SkinField f;
  REQUIRE(make_skin_field(generic(), 1, {}, f).ok());
  const Vec3 cheeks = mean_albedo(f, generic(), "cheeks");
  // Skin: red > green > blue.
  CHECK(cheeks.x() > cheeks.y());
  CHECK(cheeks.y() > cheeks.z());
  // Lips: most lip vertices clearly redder (relative to green) than skin.
  int red = 0, lip_vertices = 0;
  for (const char* lip : {"upper_lip", "lower_lip"})
    for (int v : generic().annotations.regions.at(lip)) {
      const Vec3 c = skin_albedo(f, generic().mesh.positions[v]);
      red += c.x() / c.y() > 1.4 * cheeks.x() / cheeks.y();
      ++lip_vertices;
    }
  INFO(red << " of " << lip_vertices << " lip vertices are lip-coloured");
  CHECK(red > 0.6 * lip_vertices);
  // Brows: sample just above each eye socket, on the brow centre.
  for (int i = 0; i < 2; ++i) {
    const Vec3 brow = skin_albedo(f, f.brow_center[i] + f.brow_arch * 0.9 * f.up);
    INFO("brow " << i << ": " << brow.transpose() << ", cheeks " << cheeks.transpose());
    CHECK(brow.sum() < 0.6 * cheeks.sum());
  }
  // Freckles: dense sampling of a face patch finds dark spots well below
  // the local mean, and they cover only a small share.
  SkinFieldOptions none;
  none.freckle_probability = 0;
  SkinField plain;
  REQUIRE(make_skin_field(generic(), 1, none, plain).ok());
  int dark = 0, total = 0;
  for (double x = -0.03; x <= 0.03; x += 0.0005)
    for (double y = -0.02; y <= 0.02; y += 0.0005) {
      const Vec3 p = f.face_center + x * f.side + y * f.up;
      const double with = skin_albedo(f, p).sum(), without = skin_albedo(plain, p).sum();
      CHECK(with <= without + 1e-12);
      dark += with < 0.85 * without;
      ++total;
    }
  INFO(dark << " of " << total << " samples in freckles");
  CHECK(dark > total / 200);
  CHECK(dark < total / 4);
}

TEST_CASE("camera ring frames the head with lk::Camera conventions", "[skin_field]") {
  const auto& pos = generic().mesh.positions;
  CameraRingOptions opt;
  opt.jitter_deg = 0;
  opt.aim_jitter_m = 0;
  std::vector<Camera> cams;
  REQUIRE(camera_ring(pos, Vec3::UnitZ(), Vec3::UnitY(), default_ring_views(5), 1, opt, cams).ok());
  REQUIRE(cams.size() == 5);
  BBox box;
  for (const Vec3& p : pos) box.extend(p);
  for (const Camera& c : cams) {
    CHECK(c.fx == Approx(cams[0].fx));  // one lens
    CHECK((c.center() - box.center()).norm() == Approx(opt.distance_m));
    Vec2 px;
    REQUIRE(c.project(box.center(), px));
    CHECK(px.x() == Approx(600).margin(1e-6));
    CHECK(px.y() == Approx(400).margin(1e-6));
    CHECK(c.R.determinant() == Approx(1.0));
    // The whole head is inside the image and spans most of its height.
    double top = 1e9, bottom = -1e9;
    for (const Vec3& p : pos) {
      REQUIRE(c.project(p, px));
      CHECK(px.x() > 0);
      CHECK(px.x() < 1200);
      top = std::min(top, px.y());
      bottom = std::max(bottom, px.y());
    }
    CHECK(top > 0);
    CHECK(bottom < 800);
    CHECK(bottom - top > 0.6 * 800);
  }
  // Front view: the head's left (+x) appears on the image's right, the top
  // of the head (+y) at the top (small v).
  Vec2 left, right, top, chin;
  cams[0].project(Vec3(0.05, 0, 0.05), left);
  cams[0].project(Vec3(-0.05, 0, 0.05), right);
  cams[0].project(Vec3(0, 0.1, 0.0), top);
  cams[0].project(Vec3(0, -0.1, 0.0), chin);
  CHECK(left.x() > right.x());
  CHECK(top.y() < chin.y());
  // View 1 is on the head's left (+x side).
  CHECK(cams[1].center().x() > 0.3);
  CHECK(cams[2].center().x() < -0.3);
  // Bad input.
  CHECK(camera_ring({}, Vec3::UnitZ(), Vec3::UnitY(), default_ring_views(1), 1, opt, cams).code ==
        ErrorCode::InvalidInput);
  opt.distance_m = 0.05;
  CHECK(camera_ring(pos, Vec3::UnitZ(), Vec3::UnitY(), default_ring_views(1), 1, opt, cams).code ==
        ErrorCode::InvalidInput);
}

TEST_CASE("feature vertices are distinct, valid and cover both profiles", "[skin_field]") {
  const std::vector<int> fv = feature_vertices(generic());
  CHECK(fv.size() >= 30);
  CHECK(std::set<int>(fv.begin(), fv.end()).size() == fv.size());
  int left = 0, right = 0;
  for (int v : fv) {
    REQUIRE(v >= 0);
    REQUIRE(v < generic().mesh.num_vertices());
    const double x = generic().mesh.positions[v].x();
    left += x > 0.04;
    right += x < -0.04;
  }
  CHECK(left >= 6);
  CHECK(right >= 6);
}

TEST_CASE("skin field rejects a head without lip regions", "[skin_field]") {
  GenericHead broken = generic();
  broken.annotations.regions.erase("upper_lip");
  SkinField f;
  Status s = make_skin_field(broken, 1, {}, f);
  CHECK(s.code == ErrorCode::InvalidInput);
  CHECK(s.message.find("upper_lip") != std::string::npos);
  GenericHead empty;
  CHECK(make_skin_field(empty, 1, {}, f).code == ErrorCode::InvalidInput);
}
