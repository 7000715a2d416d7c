// The multiresolution head follows the muscle layer by the local update
// (jeong2002 Sec. 6): bit-identical to a full recompute at every pose, back
// at rest exactly; and the shapes baked per head as offsets on a level.
#include "anim/bake.h"
#include "anim/expression.h"
#include "anim/face_pose.h"
#include "head/head_creases.h"
#include "test_scan.h"

#include <catch2/catch.hpp>

using namespace lk;

namespace {

struct Scene {
  GenericHead head = test::make_test_head(2);
  FaceRig rig;
  MultiresMesh rest;
  Scene() {
    REQUIRE(make_face_rig(head.mesh, test::generic_head(), rig).ok());
    REQUIRE(build_multires(head.mesh, head_creases(head.mesh, head.annotations), 2, rest).ok());
    // Some detail on every level, so the update has displacements to carry.
    for (std::size_t l = 1; l < rest.displacements.size(); ++l)
      for (std::size_t i = 0; i < rest.displacements[l].size(); ++i) rest.displacements[l][i] = 2e-4 * std::sin(0.37 * double(i));
    REQUIRE(evaluate(rest).ok());
  }
};

FaceControls named(const std::string& n) {
  FaceControls c;
  REQUIRE(face_shape(n, c).ok());
  return c;
}

}  // namespace

TEST_CASE("face pose on the multires head: the local update equals a full recompute, and rest comes back exactly") {
  Scene s;
  MultiresMesh live = s.rest;
  for (const char* name : {"smile", "jawOpen", "eyeBlinkLeft", "viseme_O", "surprise"}) {
    INFO(name);
    UpdateFootprint fp;
    REQUIRE(pose_multires(live, s.rig, named(name), -1, &fp).ok());
    MultiresMesh full = s.rest;
    full.control = pose_face(s.rig, named(name));
    REQUIRE(evaluate(full).ok());
    for (int l = 0; l <= live.num_levels(); ++l) CHECK(live.state.displaced[l] == full.state.displaced[l]);
    // Local: the update recomputed a part of the finest level only.
    CHECK(fp.displaced_changed.back() > 0);
    CHECK(fp.displaced_changed.back() < static_cast<int>(live.state.displaced.back().size()));
  }
  REQUIRE(pose_multires(live, s.rig, FaceControls{}).ok());
  for (int l = 0; l <= live.num_levels(); ++l) CHECK(live.state.displaced[l] == s.rest.state.displaced[l]);
  // A mesh of another head is refused.
  MultiresMesh other;
  REQUIRE(build_multires(test::generic_head().mesh, 1, other).ok());
  other.control.pop_back();
  CHECK(pose_multires(other, s.rig, named("smile")).code == ErrorCode::InvalidInput);
}

TEST_CASE("baked shapes: offsets of the control mesh and of the level, the head left at rest") {
  Scene s;
  MultiresMesh mr = s.rest;
  std::vector<BakedShape> baked;
  REQUIRE(bake_face_shapes(s.rig, &mr, 2, {}, baked).ok());
  REQUIRE(baked.size() == face_shape_names().size());
  for (int l = 0; l <= mr.num_levels(); ++l) CHECK(mr.state.displaced[l] == s.rest.state.displaced[l]);
  const std::size_t V0 = s.rig.rest.size();
  for (const BakedShape& b : baked) {
    INFO(b.name);
    const std::vector<Vec3> posed = pose_face(s.rig, b.controls);
    REQUIRE(b.control.size() == V0);
    REQUIRE(b.level.size() == mr.state.displaced[2].size());
    double largest = 0;
    for (std::size_t i = 0; i < V0; ++i) {
      CHECK(b.control[i] == posed[i] - s.rig.rest[i]);
      largest = std::max(largest, b.control[i].norm());
    }
    // The level's offsets where the shape moves it: the finest surface
    // moves by about what the control mesh does (within 40 %), nowhere
    // far beyond.
    double level_largest = 0;
    for (const Vec3& d : b.level) level_largest = std::max(level_largest, d.norm());
    if (b.name == "neutral" || b.name == "viseme_sil") {
      CHECK(largest == 0);
      CHECK(level_largest == 0);
    } else {
      CHECK(largest > 5e-4);
      CHECK(level_largest > 0.6 * largest);
      CHECK(level_largest < 1.4 * largest);
    }
  }
  std::vector<BakedShape> few;
  REQUIRE(bake_face_shapes(s.rig, nullptr, 0, {"smile", "jawOpen"}, few).ok());
  CHECK(few.size() == 2);
  CHECK(few[0].level.empty());
  CHECK(bake_face_shapes(s.rig, nullptr, 0, {"grin"}, few).code == ErrorCode::InvalidInput);
}

TEST_CASE("set_expression: weights per name pose the head as their summed recipes do") {
  Scene s;
  MultiresMesh a = s.rest, b = s.rest;
  REQUIRE(set_expression(a, s.rig, {{"smile", 0.5}, {"eyeBlinkLeft", 1.0}}).ok());
  FaceControls smile = named("smile"), blink = named("eyeBlinkLeft"), sum;
  for (int c = 0; c < kChannelCount; ++c) sum[c] = 0.5 * smile[c] + blink[c];
  REQUIRE(pose_multires(b, s.rig, sum).ok());
  CHECK(a.state.displaced.back() == b.state.displaced.back());
  CHECK(a.state.displaced.back() != s.rest.state.displaced.back());
  // An unknown name changes nothing.
  const std::vector<Vec3> before = a.state.displaced.back();
  CHECK(set_expression(a, s.rig, {{"smile", 1.0}, {"smirk", 1.0}}).code == ErrorCode::InvalidInput);
  CHECK(a.state.displaced.back() == before);
  REQUIRE(set_expression(a, s.rig, {}).ok());
  CHECK(a.state.displaced.back() == s.rest.state.displaced.back());
}
