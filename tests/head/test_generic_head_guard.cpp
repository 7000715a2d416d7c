// Guards of the generic head asset (issue 35): one function lists every
// defect of a head (mirror symmetry of positions, triangles and annotations;
// annotation indices, landmarks, regions, creases, binding edges, clip
// planes, eye sockets, boxes; the nostrils where a head has them). The
// committed asset and the builder's head with nostrils must have none, and each
// deliberately broken copy below must show the defect it was given, so the
// guard cannot pass on a broken asset.
#include "head/generic_head.h"
#include "head/generic_head_builder.h"
#include "mesh/topology.h"
#include "head/head_pockets.h"
#include "test_scan.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <set>
#include <sstream>

using namespace lk;

namespace {

// Connected components of the vertices in `set`, joined by mesh edges
// between two of them.
int components(const TriMesh& m, const std::vector<int>& set) {
  std::map<int, int> parent;
  for (int v : set) parent[v] = v;
  std::function<int(int)> root = [&](int v) { return parent[v] == v ? v : parent[v] = root(parent[v]); };
  for (const Tri& t : m.triangles)
    for (int k = 0; k < 3; ++k) {
      const int a = t[k], b = t[(k + 1) % 3];
      if (parent.count(a) && parent.count(b)) parent[root(a)] = root(b);
    }
  std::set<int> roots;
  for (const auto& [v, p] : parent) roots.insert(root(v));
  return int(roots.size());
}

// How many connected pieces each region must be: the two ears, the two
// cheeks and the jaw's two sides are apart, the rest is one piece of skin. (Measured on the asset;
// a region that falls apart or gains a stray vertex elsewhere changes it.)
const std::map<std::string, int>& expected_components() {
  static const std::map<std::string, int> n = {
      {"face", 1},  {"scalp", 1},  {"ears", 2},  {"ear_left", 1},      {"ear_right", 1},     {"neck", 1},
      {"lips", 1},  {"upper_lip", 1}, {"lower_lip", 1}, {"eye_rim_left", 1}, {"eye_rim_right", 1},
      {"nose", 1},  {"brow", 1},   {"jaw", 2},   {"chin", 1},          {"cheeks", 2}};
  return n;
}

// The region's mirror partner: left onto right, the others onto themselves.
std::string mirror_name(const std::string& name) {
  for (const auto& [l, r] : {std::pair<std::string, std::string>{"_left", "_right"}, {"_right", "_left"}})
    if (name.size() > l.size() && name.compare(name.size() - l.size(), l.size(), l) == 0)
      return name.substr(0, name.size() - l.size()) + r;
  return name;
}

std::vector<std::string> generic_head_defects(const GenericHead& h, double mirror_tolerance = 1e-6) {
  const TriMesh& m = h.mesh;
  const HeadAnnotations& a = h.annotations;
  const int n = m.num_vertices();
  std::vector<std::string> defects;
  auto defect = [&](const std::string& kind, const auto&... what) {
    std::ostringstream s;
    s << kind << ": ";
    (s << ... << what);
    defects.push_back(s.str());
  };
  auto in_range = [&](int v) { return v >= 0 && v < n; };

  // --- indices in range (everything below relies on it) -------------------
  bool indices_ok = true;
  auto check_indices = [&](const std::string& field, const std::vector<int>& ids) {
    for (int v : ids)
      if (!in_range(v)) defect("index", field, " holds ", v, " (", n, " vertices)"), indices_ok = false;
  };
  for (const Tri& t : m.triangles) check_indices("a triangle", {t[0], t[1], t[2]});
  for (const FeatureBox& b : a.boxes) check_indices("box " + b.name, b.landmarks);
  for (const auto& e : a.binding_edges) check_indices("binding edges", {e[0], e[1]});
  check_indices("constrained vertices", a.constrained_vertices);
  for (const auto& [name, ids] : a.regions) check_indices("region " + name, ids);
  check_indices("eye_left.rim", a.eye_left.rim);
  check_indices("eye_right.rim", a.eye_right.rim);
  for (const CreaseCurve& c : a.creases) check_indices("crease " + c.name, c.vertices);
  if (!indices_ok) return defects;

  MeshTopology topo;
  if (!build_topology(m, topo).ok()) {
    defect("mesh", "no manifold topology");
    return defects;
  }

  // --- mirror symmetry: positions, triangles, annotations ------------------
  std::vector<int> mirror(n, -1);
  for (int v = 0; v < n; ++v) {
    const Vec3 q(-m.positions[v].x(), m.positions[v].y(), m.positions[v].z());
    double best = mirror_tolerance;
    for (int w = 0; w < n; ++w)
      if (const double d = (m.positions[w] - q).norm(); d <= best) best = d, mirror[v] = w;
    if (mirror[v] < 0) defect("mirror", "vertex ", v, " at ", m.positions[v].transpose(), " has no mirror image");
  }
  const bool all_mirrored = std::find(mirror.begin(), mirror.end(), -1) == mirror.end();
  if (all_mirrored) {
    auto canonical = [](std::array<int, 3> t) {
      while (!(t[0] < t[1] && t[0] < t[2])) t = {t[1], t[2], t[0]};
      return t;
    };
    std::set<std::array<int, 3>> tris;
    for (const Tri& t : m.triangles) tris.insert(canonical({t[0], t[1], t[2]}));
    for (int f = 0; f < m.num_triangles(); ++f) {
      const Tri& t = m.triangles[f];
      if (!tris.count(canonical({mirror[t[0]], mirror[t[2]], mirror[t[1]]})))
        defect("triangle mirror", "triangle ", f, " (", t[0], " ", t[1], " ", t[2], ") has no mirror image");
    }
    auto mirrored = [&](std::vector<int> ids) {
      for (int& v : ids) v = mirror[v];
      return ids;
    };
    auto as_set = [](const std::vector<int>& ids) { return std::set<int>(ids.begin(), ids.end()); };
    for (const auto& [name, ids] : a.regions) {
      const auto it = a.regions.find(mirror_name(name));
      if (it == a.regions.end() || as_set(mirrored(ids)) != as_set(it->second))
        defect("region mirror", "region ", name, " does not mirror onto ", mirror_name(name));
    }
    if (as_set(mirrored(a.eye_left.rim)) != as_set(a.eye_right.rim)) defect("eye", "the eye rims do not mirror");
    std::set<std::pair<int, int>> binding;
    for (const auto& e : a.binding_edges) binding.insert(std::minmax(e[0], e[1]));
    for (const auto& [p, q] : binding)
      if (!binding.count(std::minmax(mirror[p], mirror[q])))
        defect("binding mirror", "binding edge ", p, "-", q, " has no mirror image");
  }

  // --- regions: the required ones, non-empty, in their pieces --------------
  for (const std::string& name : required_head_regions()) {
    const auto it = a.regions.find(name);
    if (it == a.regions.end() || it->second.empty()) {
      defect("region", name, " is missing or empty");
      continue;
    }
    const auto want = expected_components().find(name);
    if (want != expected_components().end())
      if (const int got = components(m, it->second); got != want->second)
        defect("region", name, " is ", got, " connected pieces, not ", want->second);
  }

  // --- boxes: their landmarks on the skin, their feature inside ------------
  std::vector<char> used(n, 0);
  for (const Tri& t : m.triangles)
    for (int v : t) used[v] = 1;
  // The outer skin: the face and the ears without the pockets (the mouth
  // bag's constrained vertices, the eye sockets round the eyeballs).
  std::vector<char> skin = vertex_mask(a.regions.count("face") ? a.regions.at("face") : std::vector<int>{}, n);
  const std::vector<char> ears = vertex_mask(a.regions.count("ears") ? a.regions.at("ears") : std::vector<int>{}, n);
  for (int v : a.constrained_vertices) skin[v] = 0;
  for (const EyeSocket* eye : {&a.eye_left, &a.eye_right})
    for (int v = 0; v < n; ++v)
      if ((m.positions[v] - eye->center).norm() < eye->radius + 0.002) skin[v] = 0;
  const std::map<std::string, std::pair<std::string, size_t>> box_feature = {
      {"ear_left", {"ear_left", 3}}, {"ear_right", {"ear_right", 3}}, {"nose", {"nose", 4}}, {"mouth", {"lips", 4}}};
  std::set<std::string> boxes_seen;
  for (const FeatureBox& b : a.boxes) {
    boxes_seen.insert(b.name);
    const auto feature = box_feature.find(b.name);
    if (feature == box_feature.end()) {
      defect("box", "unknown box ", b.name);
      continue;
    }
    if (b.landmarks.size() != feature->second.second ||
        std::set<int>(b.landmarks.begin(), b.landmarks.end()).size() != b.landmarks.size())
      defect("box", b.name, " has ", b.landmarks.size(), " landmarks, not ", feature->second.second, " distinct ones");
    for (int v : b.landmarks) {
      if (!b.contains(m.positions[v])) defect("box", b.name, " landmark ", v, " is outside its box");
      if (!used[v] || !(skin[v] || ears[v])) defect("landmark", b.name, " landmark ", v, " is not on the skin");
    }
    if (a.regions.count(feature->second.first))
      for (int v : a.regions.at(feature->second.first))
        if (!b.contains(m.positions[v])) defect("box", b.name, " does not hold ", feature->second.first, " vertex ", v);
  }
  if (boxes_seen != std::set<std::string>{"ear_left", "ear_right", "nose", "mouth"})
    defect("box", "the boxes are not exactly ear_left, ear_right, nose and mouth");

  // --- creases: consecutive vertices share a mesh edge ---------------------
  for (const CreaseCurve& c : a.creases) {
    const size_t count = c.vertices.size();
    if (count < (c.closed ? 3u : 2u)) defect("crease", c.name, " has ", count, " vertices");
    for (size_t k = 0; k + (c.closed ? 0 : 1) < count; ++k)
      if (topo.find_edge(c.vertices[k], c.vertices[(k + 1) % count]) < 0)
        defect("crease", c.name, ": ", c.vertices[k], " to ", c.vertices[(k + 1) % count], " is not a mesh edge");
  }

  // --- binding edges: mesh edges behind the ears or virtual ones across the lips
  if (a.regions.count("upper_lip") && a.regions.count("lower_lip")) {
    const std::vector<char> upper = vertex_mask(a.regions.at("upper_lip"), n);
    const std::vector<char> lower = vertex_mask(a.regions.at("lower_lip"), n);
    for (const auto& e : a.binding_edges) {
      if (e[0] == e[1]) defect("binding", "edge ", e[0], "-", e[1], " joins a vertex to itself");
      const bool mesh_edge = topo.find_edge(e[0], e[1]) >= 0;
      const bool across_lips = (upper[e[0]] && lower[e[1]]) || (lower[e[0]] && upper[e[1]]);
      if (!mesh_edge && !(across_lips && (m.positions[e[0]] - m.positions[e[1]]).norm() < 0.001))
        defect("binding", "edge ", e[0], "-", e[1], " is neither a mesh edge nor a short one across the lips");
    }
  }

  // --- constrained vertices: inside the mouth, behind the lips ------------
  for (const FeatureBox& b : a.boxes)
    if (b.name == "mouth")
      for (int v : a.constrained_vertices)
        if (!b.contains(m.positions[v]) || m.positions[v].z() > a.mouth_center.z() + 0.006)
          defect("constrained", "vertex ", v, " is not inside the mouth");

  // --- clip planes: unit normals; the neck's keeps the head and cuts the
  //     neck's bottom, the back's keeps the face and cuts some of the scalp
  for (const auto& [name, plane] : {std::pair<std::string, ClipPlane>{"neck_clip", a.neck_clip}, {"back_clip", a.back_clip}})
    if (!plane.point.allFinite() || !plane.normal.allFinite() || std::abs(plane.normal.norm() - 1) > 1e-9)
      defect("clip", name, " has no unit normal");
  if (a.neck_clip.normal.y() < 0.9) defect("clip", "neck_clip does not face up");
  if (a.back_clip.normal.z() < 0.8) defect("clip", "back_clip does not face forward");
  for (const char* region : {"face", "ears"})
    if (a.regions.count(region))
      for (int v : a.regions.at(region))
        if (!a.neck_clip.keeps(m.positions[v])) defect("clip", "neck_clip cuts ", region, " vertex ", v);
  for (const char* region : {"nose", "lips", "eye_rim_left", "eye_rim_right", "chin"})
    if (a.regions.count(region))
      for (int v : a.regions.at(region))
        if (!a.back_clip.keeps(m.positions[v])) defect("clip", "back_clip cuts ", region, " vertex ", v);
  if (topo.boundary_loops.size() != 1) defect("mesh", topo.boundary_loops.size(), " boundary loops, not 1");
  for (const auto& loop : topo.boundary_loops)
    for (int v : loop)
      if (a.neck_clip.keeps(m.positions[v])) defect("clip", "neck_clip keeps the neck's bottom vertex ", v);

  // --- eye sockets: the eyeball fits, its rim is a loop round it ----------
  for (const auto& [name, eye] : {std::pair<std::string, const EyeSocket*>{"eye_left", &a.eye_left}, {"eye_right", &a.eye_right}}) {
    if (!(eye->radius > 0.008 && eye->radius < 0.016)) defect("eye", name, " radius ", eye->radius, " m");
    for (int v = 0; v < n; ++v)
      if ((m.positions[v] - eye->center).norm() <= eye->radius)
        defect("eye", "vertex ", v, " is inside the ", name, " eyeball");
    if (eye->rim.size() < 6) defect("eye", name, " rim has ", eye->rim.size(), " vertices");
    for (size_t k = 0; k < eye->rim.size(); ++k) {
      const int p = eye->rim[k], q = eye->rim[(k + 1) % eye->rim.size()];
      if (topo.find_edge(p, q) < 0) defect("eye", name, " rim: ", p, " to ", q, " is not a mesh edge");
      // The lids rest on the eyeball: the rim lies just outside its sphere.
      if ((m.positions[p] - eye->center).norm() > eye->radius + 0.004)
        defect("eye", name, " rim vertex ", p, " is more than 4 mm off the eyeball");
    }
  }
  if (a.eye_left.center.x() <= 0 || a.eye_right.center.x() >= 0) defect("eye", "the left eye is not on +x");
  // --- nostrils, where the head has them (GenericHeadBuildOptions::nostrils):
  //     each a rim crease facing down under the nose, cutting off a closed,
  //     shallow pocket that is its region nostril_left / nostril_right
  {
  for (const std::string side : {"left", "right"}) {
      const CreaseCurve* rim = nullptr;
      for (const CreaseCurve& c : a.creases)
        if (c.name == "nostril_rim_" + side) rim = &c;
      const auto pocket_it = a.regions.find("nostril_" + side);
      if (!rim && pocket_it == a.regions.end()) continue;  // no nostril (the asset)
      if (!rim || !rim->closed || rim->vertices.size() < 6) {
        defect("nostril", "no closed crease nostril_rim_", side, " of 6 or more vertices");
        continue;
      }
      if (pocket_it == a.regions.end() || pocket_it->second.empty()) {
        defect("nostril", "no region nostril_", side);
        continue;
      }
      const std::vector<int>& rv = rim->vertices;
      for (size_t k = 0; k < rv.size(); ++k)
        if (topo.find_edge(rv[k], rv[(k + 1) % rv.size()]) < 0) defect("nostril", side, " rim is not a loop of mesh edges");
      // Closed: the rim cuts off exactly the pocket, none of whose vertices
      // lies on a boundary.
      std::set<int> cut;
      const std::vector<char> cut_flags = vertices_cut_off(topo, rv);
      for (int v = 0; v < n; ++v)
        if (cut_flags[v]) cut.insert(v);
      if (cut != std::set<int>(pocket_it->second.begin(), pocket_it->second.end()))
        defect("nostril", "the ", side, " rim cuts off ", cut.size(), " vertices, not its pocket's ",
               pocket_it->second.size());
      for (int v : cut)
        if (topo.is_boundary(v)) defect("nostril", side, " pocket vertex ", v, " is on a boundary (open)");
      // On the nose's underside: the rim's plane faces down, its centre under
      // the nose's tip region and off the midline on its own side.
      Vec3 c = Vec3::Zero();
      for (int v : rv) c += m.positions[v];
      c /= double(rv.size());
      Vec3 normal = Vec3::Zero();  // Newell's normal of the rim polygon, oriented outwards below
      for (size_t k = 0; k < rv.size(); ++k) normal += (m.positions[rv[k]] - c).cross(m.positions[rv[(k + 1) % rv.size()]] - c);
      normal.normalize();
      if (normal.y() > 0) normal = -normal;
      if (normal.y() > -0.7) defect("nostril", side, " rim does not face down (normal ", normal.transpose(), ")");
      if ((side == "left") != (c.x() > 0.002)) defect("nostril", side, " rim is on the wrong side (x ", c.x(), ")");
      if (!(c.y() < -0.010 && c.y() > -0.030 && c.z() > 0.095 && c.z() < 0.125))
        defect("nostril", side, " rim centre ", c.transpose(), " is not under the nose");
      // Open: the opening is a few mm across.
      double width = 0;
      for (int p : rv)
        for (int q : rv) width = std::max(width, (m.positions[p] - m.positions[q]).norm());
      if (!(width > 0.006 && width < 0.016)) defect("nostril", side, " nostril is ", width * 1000, " mm long");
      // Shallow: every pocket vertex above the rim's plane (inside the nose),
      // the deepest 2-6 mm.
      double deepest = 0;
      for (int v : cut) {
        const double depth = -(m.positions[v] - c).dot(normal);
        if (depth < 0.0003) defect("nostril", side, " pocket vertex ", v, " is not behind the rim (", depth * 1000, " mm)");
        deepest = std::max(deepest, depth);
      }
      if (!(deepest > 0.002 && deepest < 0.006)) defect("nostril", side, " pocket is ", deepest * 1000, " mm deep");
    }
  }
  return defects;
}

bool has_kind(const std::vector<std::string>& defects, const std::string& kind) {
  for (const std::string& d : defects)
    if (d.rfind(kind + ":", 0) == 0) return true;
  return false;
}

std::string listed(const std::vector<std::string>& defects) {
  std::string s;
  for (size_t k = 0; k < defects.size() && k < 12; ++k) s += "\n  " + defects[k];
  if (defects.size() > 12) s += "\n  ... " + std::to_string(defects.size() - 12) + " more";
  return s;
}

// A vertex of `region` (off the midline), for breaking a copy there.
int off_midline_vertex(const GenericHead& h, const std::string& region) {
  for (int v : h.annotations.regions.at(region))
    if (h.mesh.positions[v].x() > 0.01) return v;
  FAIL("no off-midline vertex in " << region);
  return -1;
}

// The left nostril's rim crease (the head must have one).
const std::vector<int>& nostril_rim_left(const GenericHead& h) {
  for (const CreaseCurve& c : h.annotations.creases)
    if (c.name == "nostril_rim_left") return c.vertices;
  FAIL("no crease nostril_rim_left");
  return h.annotations.creases.front().vertices;
}

}  // namespace

TEST_CASE("generic head guard: the asset has no defect", "[head]") {
  const std::vector<std::string> defects = generic_head_defects(test::generic_head());
  INFO(defects.size() << " defects:" << listed(defects));
  CHECK(defects.empty());
}

TEST_CASE("generic head guard: a broken copy of the asset shows its defect", "[head]") {
  const GenericHead& asset = test::generic_head();
  const int n = asset.mesh.num_vertices();
  auto expect = [&](const GenericHead& broken, const std::string& kind) {
    const std::vector<std::string> defects = generic_head_defects(broken);
    INFO("expected a '" << kind << "' defect; got " << defects.size() << ":" << listed(defects));
    CHECK(has_kind(defects, kind));
  };
  SECTION("one cheek vertex moved 0.1 mm sideways") {
    GenericHead b = asset;
    b.mesh.positions[off_midline_vertex(b, "cheeks")].x() += 1e-4;
    expect(b, "mirror");
  }
  SECTION("one triangle's diagonal flipped on one side") {
    // Two triangles sharing an edge, both off the midline, re-split along
    // the quad's other diagonal: positions still mirror, triangles do not.
    GenericHead b = asset;
    MeshTopology topo;
    REQUIRE(build_topology(b.mesh, topo).ok());
    bool flipped = false;
    for (const Edge& e : topo.edges) {
      if (e.f1 < 0 || b.mesh.positions[e.v0].x() < 0.03 || b.mesh.positions[e.v1].x() < 0.03) continue;
      const int p = topo.opposite_vertex(b.mesh, e.f0, topo.find_edge(e.v0, e.v1));
      const int q = topo.opposite_vertex(b.mesh, e.f1, topo.find_edge(e.v0, e.v1));
      if (topo.find_edge(p, q) >= 0) continue;
      // Keep the winding: f0 runs v0 -> v1 or v1 -> v0.
      const Tri& t0 = b.mesh.triangles[e.f0];
      int k = 0;
      while (t0[k] != e.v0) ++k;
      const bool forward = t0[(k + 1) % 3] == e.v1;
      const int a0 = forward ? e.v0 : e.v1, a1 = forward ? e.v1 : e.v0;  // f0 is (a0, a1, p)
      b.mesh.triangles[e.f0] = {a0, q, p};
      b.mesh.triangles[e.f1] = {a1, p, q};
      flipped = true;
      break;
    }
    REQUIRE(flipped);
    expect(b, "triangle mirror");
  }
  SECTION("a landmark index out of range") {
    GenericHead b = asset;
    b.annotations.boxes[0].landmarks[0] = n;
    expect(b, "index");
  }
  SECTION("a nose landmark moved onto the scalp") {
    GenericHead b = asset;
    for (FeatureBox& box : b.annotations.boxes)
      if (box.name == "nose") box.landmarks[0] = b.annotations.regions.at("scalp").front();
    expect(b, "box");
  }
  SECTION("a mouth landmark moved into the mouth bag") {
    GenericHead b = asset;
    const int inside = b.annotations.constrained_vertices.front();
    for (FeatureBox& box : b.annotations.boxes)
      if (box.name == "mouth") box.landmarks[0] = inside;
    expect(b, "landmark");
  }
  SECTION("a scalp vertex added to the nose region") {
    GenericHead b = asset;
    b.annotations.regions["nose"].push_back(off_midline_vertex(b, "scalp"));
    expect(b, "region");
  }
  SECTION("a region emptied") {
    GenericHead b = asset;
    b.annotations.regions["chin"].clear();
    expect(b, "region");
  }
  SECTION("two vertices of a crease swapped") {
    GenericHead b = asset;
    REQUIRE(!b.annotations.creases.empty());
    std::vector<int>& c = b.annotations.creases.front().vertices;
    REQUIRE(c.size() >= 4);
    std::swap(c[1], c[2]);
    expect(b, "crease");
  }
  SECTION("the neck clip turned upside down") {
    GenericHead b = asset;
    b.annotations.neck_clip.normal = -b.annotations.neck_clip.normal;
    expect(b, "clip");
  }
  SECTION("the back clip moved behind the nose") {
    GenericHead b = asset;
    b.annotations.back_clip.point.z() = 0.2;
    expect(b, "clip");
  }
  SECTION("an eyeball centre moved 4 mm forward") {
    GenericHead b = asset;
    b.annotations.eye_left.center.z() += 0.004;
    expect(b, "eye");
  }
  SECTION("a binding edge between two far vertices") {
    GenericHead b = asset;
    b.annotations.binding_edges.push_back({b.annotations.regions.at("nose").front(), b.annotations.regions.at("chin").front()});
    expect(b, "binding");
  }
  SECTION("the mouth box shrunk off the lips") {
    GenericHead b = asset;
    for (FeatureBox& box : b.annotations.boxes)
      if (box.name == "mouth") box.max.x() -= 0.01;
    expect(b, "box");
  }
}

TEST_CASE("generic head guard: the builder's head with nostrils has no defect", "[head]") {
  GenericHeadBuildOptions options;
  options.nostrils = true;
  const GenericHead h = test::built_generic_head(options);
  const std::vector<std::string> defects = generic_head_defects(h);
  INFO(defects.size() << " defects:" << listed(defects));
  CHECK(defects.empty());
}

TEST_CASE("generic head guard: a broken copy of the head with nostrils shows its defect", "[head]") {
  GenericHeadBuildOptions options;
  options.nostrils = true;
  const GenericHead good = test::built_generic_head(options);
  auto expect = [&](const GenericHead& broken, const std::string& kind) {
    const std::vector<std::string> defects = generic_head_defects(broken);
    INFO("expected a '" << kind << "' defect; got " << defects.size() << ":" << listed(defects));
    CHECK(has_kind(defects, kind));
  };
  const std::vector<int>& pocket = good.annotations.regions.at("nostril_left");
  const std::vector<int>& rim = nostril_rim_left(good);
  Vec3 down = Vec3::Zero();  // out of the pocket: from its centre to the rim's
  for (int v : rim) down += good.mesh.positions[v] / double(rim.size());
  for (int v : pocket) down -= good.mesh.positions[v] / double(pocket.size());
  down.normalize();
  // Each break: what it does, the defect kind it must show, and how.
  struct Break {
    const char* what;
    const char* kind;
    std::function<void(GenericHead&)> apply;
  };
  const std::set<int> in_pocket(pocket.begin(), pocket.end());
  const std::vector<Break> breaks = {
      {"the pocket's floor and walls removed (an open pocket)", "mesh",
       [&](GenericHead& b) {
         std::vector<Tri> kept;
         for (const Tri& t : b.mesh.triangles)
           if (!(in_pocket.count(t[0]) && in_pocket.count(t[1]) && in_pocket.count(t[2]))) kept.push_back(t);
         REQUIRE(kept.size() < b.mesh.triangles.size());
         b.mesh.triangles = kept;
       }},
      {"the pocket pushed 8 mm deeper", "nostril", [&](GenericHead& b) { for (int v : pocket) b.mesh.positions[v] -= 0.008 * down; }},
      {"the pocket pulled out below the rim", "nostril", [&](GenericHead& b) { for (int v : pocket) b.mesh.positions[v] += 0.006 * down; }},
      {"a pocket vertex left out of its region", "nostril", [](GenericHead& b) { b.annotations.regions["nostril_left"].pop_back(); }},
      {"the rim crease dropped", "nostril",
       [](GenericHead& b) {
         auto& c = b.annotations.creases;
         c.erase(std::remove_if(c.begin(), c.end(), [](const CreaseCurve& k) { return k.name == "nostril_rim_left"; }), c.end());
       }},
      {"two rim vertices swapped", "nostril",
       [](GenericHead& b) {
         for (CreaseCurve& c : b.annotations.creases)
           if (c.name == "nostril_rim_left") std::swap(c.vertices[1], c.vertices[2]);
       }},
  };
  for (const Break& k : breaks) {
    INFO(k.what);
    GenericHead b = good;
    k.apply(b);
    expect(b, k.kind);
  }
}
