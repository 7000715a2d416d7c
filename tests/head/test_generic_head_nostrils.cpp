// The generic head with open nostrils (GenericHeadBuildOptions::nostrils,
// issue 35): each nostril an oval rim on the nose's underside continued as a
// shallow closed pocket. One function lists every way the nostrils can be
// wrong; the builder's variant must have none, and each broken copy below
// must show the defect it was given.
#include "head/generic_head_builder.h"
#include "head/surface_quality.h"
#include "mesh/topology.h"
#include "pipeline/head_pockets.h"
#include "test_scan.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <set>
#include <sstream>

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

// Everything wrong with the nostrils of `h`. `plain`: the head without
// nostrils from the same builder, whose vertices h must keep.
std::vector<std::string> nostril_defects(const GenericHead& h, const GenericHead& plain) {
  std::vector<std::string> defects;
  auto defect = [&](const std::string& kind, const auto&... what) {
    std::ostringstream s;
    s << kind << ": ";
    (s << ... << what);
    defects.push_back(s.str());
  };
  const TriMesh& m = h.mesh;
  const HeadAnnotations& a = h.annotations;
  const int n = m.num_vertices();
  MeshTopology topo;
  if (!build_topology(m, topo).ok()) {
    defect("topology", "not a manifold mesh");
    return defects;
  }
  // A disk whose only boundary is the neck's bottom, as without nostrils.
  if (topo.boundary_loops.size() != 1 || euler_characteristic(topo, m.num_triangles()) != 1)
    defect("topology", topo.boundary_loops.size(), " boundary loops, Euler characteristic ",
           euler_characteristic(topo, m.num_triangles()));
  else {
    MeshTopology plain_topo;
    if (!build_topology(plain.mesh, plain_topo).ok() || plain_topo.boundary_loops.size() != 1 ||
        std::set<int>(topo.boundary_loops[0].begin(), topo.boundary_loops[0].end()) !=
            std::set<int>(plain_topo.boundary_loops[0].begin(), plain_topo.boundary_loops[0].end()))
      defect("topology", "the boundary is not the neck's bottom");
  }
  // Every vertex of the head without nostrils is kept, where it was.
  if (n < plain.mesh.num_vertices()) defect("vertices", n, " vertices, fewer than without nostrils");
  for (int v = 0; v < std::min(n, plain.mesh.num_vertices()); ++v)
    if ((m.positions[v] - plain.mesh.positions[v]).norm() > 1e-12) {
      defect("vertices", "vertex ", v, " moved");
      break;
    }
  for (const std::string side : {"left", "right"}) {
    const CreaseCurve* rim = crease_named(a, "nostril_rim_" + side);
    const auto pocket_it = a.regions.find("nostril_" + side);
    if (!rim || !rim->closed || rim->vertices.size() < 6) {
      defect("rim", "no closed crease nostril_rim_", side, " of 6 or more vertices");
      continue;
    }
    if (pocket_it == a.regions.end() || pocket_it->second.empty()) {
      defect("pocket", "no region nostril_", side);
      continue;
    }
    const std::vector<int>& rv = rim->vertices;
    bool in_range = true;
    for (int v : rv) in_range = in_range && v >= 0 && v < n;
    for (int v : pocket_it->second) in_range = in_range && v >= 0 && v < n;
    if (!in_range) {
      defect("index", "nostril ", side, " holds a vertex out of range");
      continue;
    }
    for (size_t k = 0; k < rv.size(); ++k)
      if (topo.find_edge(rv[k], rv[(k + 1) % rv.size()]) < 0) defect("rim", side, " rim is not a loop of mesh edges");
    // Closed: the rim cuts off exactly the pocket, none of whose vertices
    // lies on a boundary.
    std::set<int> cut;
    const std::vector<char> cut_flags = vertices_cut_off(topo, rv);
    for (int v = 0; v < n; ++v)
      if (cut_flags[v]) cut.insert(v);
    if (cut != std::set<int>(pocket_it->second.begin(), pocket_it->second.end()))
      defect("pocket", "the ", side, " rim cuts off ", cut.size(), " vertices, not its pocket's ",
             pocket_it->second.size());
    for (int v : cut)
      if (topo.is_boundary(v)) defect("pocket", side, " pocket vertex ", v, " is on a boundary (open)");
    // On the nose's underside: the rim's plane faces down, its centre under
    // the nose's tip region and off the midline on its own side.
    Vec3 c = Vec3::Zero();
    for (int v : rv) c += m.positions[v];
    c /= double(rv.size());
    Vec3 normal = Vec3::Zero();  // Newell's normal of the rim polygon, oriented outwards below
    for (size_t k = 0; k < rv.size(); ++k) normal += (m.positions[rv[k]] - c).cross(m.positions[rv[(k + 1) % rv.size()]] - c);
    normal.normalize();
    if (normal.y() > 0) normal = -normal;
    if (normal.y() > -0.7) defect("rim", side, " rim does not face down (normal ", normal.transpose(), ")");
    if ((side == "left") != (c.x() > 0.002)) defect("rim", side, " rim is on the wrong side (x ", c.x(), ")");
    if (!(c.y() < -0.010 && c.y() > -0.030 && c.z() > 0.095 && c.z() < 0.125))
      defect("rim", side, " rim centre ", c.transpose(), " is not under the nose");
    // Open: the opening is a few mm across.
    double width = 0;
    for (int p : rv)
      for (int q : rv) width = std::max(width, (m.positions[p] - m.positions[q]).norm());
    if (!(width > 0.006 && width < 0.016)) defect("rim", side, " nostril is ", width * 1000, " mm long");
    // Shallow: every pocket vertex above the rim's plane (inside the nose),
    // the deepest 2-6 mm.
    double deepest = 0;
    for (int v : cut) {
      const double depth = -(m.positions[v] - c).dot(normal);
      if (depth < 0.0003) defect("pocket", side, " pocket vertex ", v, " is not behind the rim (", depth * 1000, " mm)");
      deepest = std::max(deepest, depth);
    }
    if (!(deepest > 0.002 && deepest < 0.006)) defect("pocket", side, " pocket is ", deepest * 1000, " mm deep");
  }
  return defects;
}

}  // namespace

TEST_CASE("generic head, nostrils: two open nostrils with shallow closed pockets, every other vertex kept", "[head]") {
  const GenericHead& h = nostrils_head();
  const std::vector<std::string> defects = nostril_defects(h, plain_head());
  std::string listed;
  for (const std::string& d : defects) listed += "\n  " + d;
  INFO(defects.size() << " defects:" << listed);
  CHECK(defects.empty());
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

TEST_CASE("generic head, nostrils: a broken copy shows its defect", "[head]") {
  const GenericHead& good = nostrils_head();
  auto expect = [&](const GenericHead& broken, const std::string& kind) {
    const std::vector<std::string> defects = nostril_defects(broken, plain_head());
    std::string listed;
    for (const std::string& d : defects) listed += "\n  " + d;
    INFO("expected a '" << kind << "' defect; got " << defects.size() << ":" << listed);
    bool found = false;
    for (const std::string& d : defects) found = found || d.rfind(kind + ":", 0) == 0;
    CHECK(found);
  };
  const std::vector<int>& pocket = good.annotations.regions.at("nostril_left");
  const std::vector<int>& rim = crease_named(good.annotations, "nostril_rim_left")->vertices;
  Vec3 down = Vec3::Zero();  // out of the pocket: from its centre to the rim's
  for (int v : rim) down += good.mesh.positions[v] / double(rim.size());
  for (int v : pocket) down -= good.mesh.positions[v] / double(pocket.size());
  down.normalize();
  SECTION("the pocket's floor removed (an open pocket)") {
    GenericHead b = good;
    const std::set<int> in(pocket.begin(), pocket.end());
    std::vector<Tri> kept;
    int removed = 0;
    for (const Tri& t : b.mesh.triangles) {
      const bool floor = in.count(t[0]) && in.count(t[1]) && in.count(t[2]);
      if (!floor) kept.push_back(t);
      removed += floor;
    }
    REQUIRE(removed > 0);
    b.mesh.triangles = kept;
    expect(b, "topology");
  }
  SECTION("the pocket pushed 8 mm deeper") {
    GenericHead b = good;
    for (int v : pocket) b.mesh.positions[v] -= 0.008 * down;
    expect(b, "pocket");
  }
  SECTION("the pocket pulled out below the rim") {
    GenericHead b = good;
    for (int v : pocket) b.mesh.positions[v] += 0.006 * down;
    expect(b, "pocket");
  }
  SECTION("a pocket vertex left out of its region") {
    GenericHead b = good;
    b.annotations.regions["nostril_left"].pop_back();
    expect(b, "pocket");
  }
  SECTION("the rim crease dropped") {
    GenericHead b = good;
    auto& c = b.annotations.creases;
    c.erase(std::remove_if(c.begin(), c.end(), [](const CreaseCurve& k) { return k.name == "nostril_rim_left"; }), c.end());
    expect(b, "rim");
  }
  SECTION("two rim vertices swapped") {
    GenericHead b = good;
    for (CreaseCurve& c : b.annotations.creases)
      if (c.name == "nostril_rim_left") std::swap(c.vertices[1], c.vertices[2]);
    expect(b, "rim");
  }
  SECTION("a cheek vertex of the head moved") {
    GenericHead b = good;
    b.mesh.positions[b.annotations.regions.at("cheeks").front()].x() += 1e-4;
    expect(b, "vertices");
  }
}
