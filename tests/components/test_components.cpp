// Generic components placed into the generic head and into a transformed copy.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>
#include <vector>

#include "components/components.h"
#include "head/generic_head.h"
#include "head/generic_head_builder.h"
#include "iris/iris.h"
#include "raycast/bvh.h"
#include "raycast/self_intersection.h"
#include "test_scan.h"

namespace {

double max_z(const lk::TriMesh& m) {
  double z = -1e300;
  for (const auto& p : m.positions) z = std::max(z, p.z());
  return z;
}

}  // namespace

TEST_CASE("components: generic meshes are closed and the eyeball uvs follow the texture layout") {
  const lk::TriMesh eye = lk::make_eyeball();
  REQUIRE(eye.uvs.size() == eye.positions.size());
  // Front pole at the texture centre; equator at rho = 1 (uv on the unit circle around 0.5).
  CHECK(eye.uvs[0].isApprox(lk::Vec2(0.5, 0.5)));
  for (size_t i = 0; i < eye.positions.size(); ++i) {
    CHECK(std::abs(eye.positions[i].norm() - 1) < 1e-12);
    if (std::abs(eye.positions[i].z()) < 1e-9)
      CHECK(std::abs((eye.uvs[i] - lk::Vec2(0.5, 0.5)).norm() - 0.5) < 1e-9);
  }
  // Closed meshes: every edge used exactly twice (Euler characteristic 2 per shell).
  for (const lk::TriMesh* m : {&eye}) {
    const long V = static_cast<long>(m->positions.size()), F = static_cast<long>(m->triangles.size());
    CHECK(V - F / 2 == 2);  // V - E + F = 2 with E = 3F/2
  }
  const lk::TriMesh teeth = lk::make_teeth_arch();
  CHECK(teeth.triangles.size() >= 300);
  CHECK(teeth.triangles.size() <= 500);
}

TEST_CASE("components: the eyeball's uvs are eyeball_uv of its vertices, as from its angles before") {
  const double pi = 3.14159265358979323846;
  for (int rings : {16, 7})
    for (int segments : {24, 9}) {
      const lk::TriMesh eye = lk::make_eyeball(rings, segments);
      REQUIRE(eye.uvs.size() == size_t(2 + (rings - 1) * segments));
      // The uvs as make_eyeball wrote them from the ring's and segment's angles.
      std::vector<lk::Vec2> before{lk::Vec2(0.5, 0.5)};
      for (int r = 1; r < rings; ++r)
        for (int s = 0; s < segments; ++s) {
          const double theta = pi * r / rings, phi = 2 * pi * s / segments;
          const double rho = std::min(1.0, theta / (pi / 2));
          before.push_back(lk::Vec2(0.5 + 0.5 * rho * std::cos(phi), 0.5 - 0.5 * rho * std::sin(phi)));
        }
      before.push_back(lk::Vec2(1.0, 0.5));
      double worst = 0;
      for (size_t i = 0; i < eye.uvs.size(); ++i) {
        CHECK(eye.uvs[i] == lk::eyeball_uv(eye.positions[i]));
        worst = std::max(worst, (eye.uvs[i] - before[i]).cwiseAbs().maxCoeff());
      }
      INFO(rings << " rings, " << segments << " segments: largest change " << worst);
      CHECK(worst < 1e-12);
    }
}

TEST_CASE("components: placed inside the generic head, following a transformed head") {
  lk::GenericHead generic;
  REQUIRE(lk::load_generic_head(generic).ok());
  lk::ComponentPlacement p;
  REQUIRE(lk::place_components(generic, generic, p).ok());
  const auto& a = generic.annotations;
  CHECK((p.eye_center[0] - a.eye_left.center).norm() < 1e-9);
  CHECK((p.eye_center[1] - a.eye_right.center).norm() < 1e-9);
  CHECK(std::abs(p.mouth_width - a.mouth_width) < 1e-12);
  CHECK((p.mouth_center - a.mouth_center).norm() < 1e-12);
  // The generic head's teeth are the measure of the others' room: full height.
  CHECK(p.teeth_height[0] == 1.0);
  CHECK(p.teeth_height[1] == 1.0);

  // Eyeballs inside their sockets: behind the rim's front-most vertex.
  const char* rims[2] = {"eye_rim_left", "eye_rim_right"};
  for (int e = 0; e < 2; ++e) {
    double rim_front = -1e300;
    for (int v : a.regions.at(rims[e])) rim_front = std::max(rim_front, generic.mesh.positions[static_cast<size_t>(v)].z());
    INFO("eye " << e << " front " << p.eye_center[e].z() + p.eye_radius[e] << " rim front " << rim_front);
    CHECK(p.eye_center[e].z() + p.eye_radius[e] < rim_front + 0.002);
    CHECK(p.eye_center[e].z() < rim_front);
  }
  // Left eye on +x.
  CHECK(p.eye_center[0].x() > p.eye_center[1].x());
  // Teeth and tongue behind the lips.
  const lk::PlacedComponents c = lk::build_placed_components(p);
  double lips_front = -1e300;
  for (int v : a.regions.at("lips")) lips_front = std::max(lips_front, generic.mesh.positions[static_cast<size_t>(v)].z());
  INFO("teeth front " << max_z(c.teeth) << ", tongue front " << max_z(c.tongue) << ", lips front " << lips_front);
  CHECK(max_z(c.teeth) < lips_front);
  CHECK(max_z(c.tongue) < max_z(c.teeth));

  // A fitted head = the generic one scaled by 1.2 and moved: placements follow the vertices.
  lk::GenericHead fitted = generic;
  const lk::Vec3 shift(0.01, -0.02, 0.03);
  for (auto& q : fitted.mesh.positions) q = 1.2 * q + shift;
  lk::ComponentPlacement pf;
  REQUIRE(lk::place_components(fitted, generic, pf).ok());
  CHECK((pf.eye_center[0] - (1.2 * a.eye_left.center + shift)).norm() < 1e-9);
  CHECK(std::abs(pf.eye_radius[1] - 1.2 * a.eye_right.radius) < 1e-9);
  CHECK((pf.mouth_center - (1.2 * a.mouth_center + shift)).norm() < 1e-9);
  CHECK(pf.teeth_height[0] == 1.0);
  CHECK(pf.teeth_height[1] == 1.0);
}

TEST_CASE("components: a head with another topology is refused") {
  lk::GenericHead generic;
  REQUIRE(lk::load_generic_head(generic).ok());
  lk::GenericHead other = generic;
  other.mesh.positions.pop_back();
  lk::ComponentPlacement p;
  const lk::Status s = lk::place_components(other, generic, p);
  CHECK(s.code == lk::ErrorCode::InvalidInput);
  CHECK(s.message.find("topology") != std::string::npos);
}

// The generic head built with the bag round the teeth
// (GenericHeadBuildOptions::teeth_mouth_bag, not yet the asset's) holds the
// placed teeth (issue 38): from every
// tooth vertex, the first surface a ray meets forwards, backwards, up, down
// and to either side is the bag (a triangle with a bag vertex: the inner
// lips' strip, the vestibule, the back and side walls), never the skin or
// nothing (but forwards, where the rays along the bite leave through the
// slit between the lips); and no tooth triangle crosses the head. With the
// asset's bag (8.5 mm tall, 23 mm deep behind the slit) the teeth's backs
// and gum ends are outside it (400 crossing pairs).
namespace {

// Rays from the placed teeth's vertices that do not meet the bag first, and
// the teeth's triangles crossing the head (see the test below).
std::pair<int, int> teeth_outside_bag(const lk::GenericHead& generic) {
  lk::ComponentPlacement p;
  REQUIRE(lk::place_components(generic, generic, p).ok());
  const lk::PlacedComponents c = lk::build_placed_components(p);
  const lk::TriMesh& head = generic.mesh;
  std::vector<char> bag(head.positions.size(), 0);
  for (int v : generic.annotations.constrained_vertices) bag[static_cast<size_t>(v)] = 1;
  lk::MeshBvh bvh;
  REQUIRE(lk::build_bvh(head, bvh).ok());
  int outside = 0;
  const lk::Vec3 dirs[6] = {lk::Vec3::UnitX(), -lk::Vec3::UnitX(), lk::Vec3::UnitY(),
                            -lk::Vec3::UnitY(), lk::Vec3::UnitZ(), -lk::Vec3::UnitZ()};
  for (const lk::Vec3& q : c.teeth.positions)
    for (const lk::Vec3& d : dirs) {
      lk::Ray ray;
      ray.origin = q;
      ray.direction = d;
      const lk::RayHit hit = lk::intersect_first(bvh, ray);
      if (!hit.hit() && d.z() > 0) continue;  // out through the slit between the lips (0.3 mm apart)
      const lk::Tri& t = head.triangles[static_cast<size_t>(std::max(hit.triangle, 0))];
      if (!hit.hit() || !(bag[static_cast<size_t>(t[0])] || bag[static_cast<size_t>(t[1])] || bag[static_cast<size_t>(t[2])]))
        ++outside;
    }
  lk::TriMesh both = head;
  const int base = static_cast<int>(both.positions.size()), head_triangles = static_cast<int>(both.triangles.size());
  both.positions.insert(both.positions.end(), c.teeth.positions.begin(), c.teeth.positions.end());
  for (const lk::Tri& t : c.teeth.triangles) both.triangles.push_back(lk::Tri{t[0] + base, t[1] + base, t[2] + base});
  std::vector<std::array<int, 2>> pairs;
  REQUIRE(lk::find_self_intersections(both, pairs).ok());
  int crossing = 0;
  for (const auto& pr : pairs) crossing += (pr[0] < head_triangles) != (pr[1] < head_triangles);
  return {outside, crossing};
}

}  // namespace

TEST_CASE("components: the placed teeth lie inside the mouth bag built round them") {
  lk::GenericHeadBuildOptions options;
  options.teeth_mouth_bag = true;
  const auto [outside, crossing] = teeth_outside_bag(lk::test::built_generic_head(options));
  INFO(outside << " rays from the teeth's vertices leave the bag, " << crossing << " crossing pairs");
  CHECK(outside == 0);
  CHECK(crossing == 0);
  // The asset's bag (the option off) does not hold them: the check can fail.
  lk::GenericHead asset;
  REQUIRE(lk::load_generic_head(asset).ok());
  const auto [asset_outside, asset_crossing] = teeth_outside_bag(asset);
  INFO("the asset: " << asset_outside << " rays leave, " << asset_crossing << " crossing pairs");
  CHECK(asset_outside > 0);
  CHECK(asset_crossing > 0);
}
