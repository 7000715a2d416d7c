// The generic head with open nostrils (GenericHeadBuildOptions::nostrils,
// issue 35): each nostril an oval rim on the nose's underside continued as a
// shallow closed pocket. The guard (test_generic_head_guard.cpp) checks the
// rims and pockets and every other annotation on it; here: the rest of the
// head is kept, the nostrils mirror, and no smooth level gains a crossing.
#include "head/generic_head_builder.h"
#include "head/surface_quality.h"
#include "mesh/topology.h"
#include "test_scan.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <set>

using namespace lk;

namespace {

const GenericHead& nostrils_head() {
  static const GenericHead head = [] {
    GenericHeadBuildOptions options;
    options.nostrils = true;
    return test::built_generic_head(options);
  }();
  return head;
}

const GenericHead& plain_head() {
  static const GenericHead head = test::built_generic_head(GenericHeadBuildOptions{});
  return head;
}

const CreaseCurve* crease_named(const HeadAnnotations& a, const std::string& name) {
  for (const CreaseCurve& c : a.creases)
    if (c.name == name) return &c;
  return nullptr;
}

// The vertices of `plain` (the head without nostrils) that `h` does not
// keep where they were; every one when h has fewer vertices.
int moved_vertices(const GenericHead& h, const GenericHead& plain) {
  if (h.mesh.num_vertices() < plain.mesh.num_vertices()) return plain.mesh.num_vertices();
  int moved = 0;
  for (int v = 0; v < plain.mesh.num_vertices(); ++v) moved += (h.mesh.positions[v] - plain.mesh.positions[v]).norm() > 1e-12;
  return moved;
}

}  // namespace

TEST_CASE("generic head, nostrils: two nostril pockets, every other vertex kept where it was", "[head]") {
  // The nostrils' own checks (rim, closed shallow pocket under the nose)
  // are the guard's: test_generic_head_guard.cpp.
  const GenericHead& h = nostrils_head();
  CHECK(moved_vertices(h, plain_head()) == 0);
  GenericHead moved = h;  // the check sees a moved vertex
  moved.mesh.positions[moved.annotations.regions.at("cheeks").front()].x() += 1e-4;
  CHECK(moved_vertices(moved, plain_head()) == 1);
  // Both pockets hold the same count, and the head gains only them and their rims.
  const auto& a = h.annotations;
  REQUIRE(a.regions.count("nostril_left"));
  REQUIRE(a.regions.count("nostril_right"));
  CHECK(a.regions.at("nostril_left").size() == a.regions.at("nostril_right").size());
  const size_t rims = crease_named(a, "nostril_rim_left")->vertices.size() + crease_named(a, "nostril_rim_right")->vertices.size();
  CHECK(h.mesh.num_vertices() ==
        plain_head().mesh.num_vertices() + int(rims + 2 * a.regions.at("nostril_left").size()));
  // The nostrils are the nose's: rim and pocket in the nose region.
  const std::vector<int>& nose = a.regions.at("nose");
  for (const char* name : {"nostril_left", "nostril_right"})
    for (int v : a.regions.at(name)) CHECK(std::binary_search(nose.begin(), nose.end(), v));
}

TEST_CASE("generic head, nostrils: the rims and pockets mirror each other", "[head]") {
  const GenericHead& h = nostrils_head();
  const TriMesh& m = h.mesh;
  auto mirror_of = [&](int v) {
    const Vec3 q(-m.positions[v].x(), m.positions[v].y(), m.positions[v].z());
    for (int w = 0; w < m.num_vertices(); ++w)
      if ((m.positions[w] - q).norm() < 1e-9) return w;
    return -1;
  };
  const std::vector<int>& left = crease_named(h.annotations, "nostril_rim_left")->vertices;
  const std::vector<int>& right = crease_named(h.annotations, "nostril_rim_right")->vertices;
  std::set<int> mirrored_rim, mirrored_pocket;
  for (int v : left) mirrored_rim.insert(mirror_of(v));
  for (int v : h.annotations.regions.at("nostril_left")) mirrored_pocket.insert(mirror_of(v));
  CHECK(mirrored_rim == std::set<int>(right.begin(), right.end()));
  const std::vector<int>& pocket_right = h.annotations.regions.at("nostril_right");
  CHECK(mirrored_pocket == std::set<int>(pocket_right.begin(), pocket_right.end()));
}

TEST_CASE("generic head, nostrils: no smooth level from 0 to 3 gains a crossing pair", "[head]") {
  // The head without nostrils crosses only at its outer mouth corners (its
  // own test); with nostrils every level has exactly those pairs, and with
  // the wide mouth ring too, none at all.
  HeadSurfaceQuality plain, nostrils, wide;
  REQUIRE(measure_head_surface(plain_head(), 3, plain).ok());
  REQUIRE(measure_head_surface(nostrils_head(), 3, nostrils).ok());
  GenericHeadBuildOptions options;
  options.nostrils = true;
  options.wide_mouth_ring = true;
  REQUIRE(measure_head_surface(test::built_generic_head(options), 3, wide).ok());
  REQUIRE(nostrils.crossing_pairs.size() == 4);
  REQUIRE(plain.crossing_pairs.size() == 4);
  REQUIRE(wide.crossing_pairs.size() == 4);
  for (int level = 0; level <= 3; ++level) {
    INFO("level " << level);
    CHECK(nostrils.crossing_pairs[level] == plain.crossing_pairs[level]);
    CHECK(wide.crossing_pairs[level] == 0);
  }
}
