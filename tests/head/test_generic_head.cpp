// The generic head (jeong2002 Sec. 4, Fig. 4): the embedded asset must load,
// be a clean disk-shaped control mesh with the eye/mouth pockets, ears and
// annotations the later stages rely on, and match what the builder makes.
#include "head/generic_head.h"
#include "head/generic_head_builder.h"
#include "head/surface_quality.h"
#include "mesh/geometry.h"
#include "mesh/topology.h"
#include "multires/multires.h"
#include "raycast/self_intersection.h"
#include "test_scan.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

using namespace lk;

namespace {

// The embedded asset, loaded once (load_generic_head; fails with its message).
const GenericHead& asset() { return test::generic_head(); }

// Vertices with no vertex at their mirror image in x = 0 (within tolerance m).
int vertices_without_mirror(const TriMesh& m, double tolerance) {
  int unmatched = 0;
  for (int v = 0; v < m.num_vertices(); ++v) {
    const Vec3 mirrored(-m.positions[v].x(), m.positions[v].y(), m.positions[v].z());
    bool found = false;
    for (int w = 0; w < m.num_vertices() && !found; ++w) found = (m.positions[w] - mirrored).norm() < tolerance;
    if (!found) ++unmatched;
  }
  return unmatched;
}

const FeatureBox& box_named(const HeadAnnotations& a, const std::string& name) {
  for (const FeatureBox& b : a.boxes)
    if (b.name == name) return b;
  FAIL("no box " << name);
  return a.boxes.front();
}

double min_angle_degrees(const TriMesh& m, int f) {
  double best = 180;
  for (int k = 0; k < 3; ++k) {
    const Vec3& p = m.positions[m.triangles[f][k]];
    const Vec3 a = (m.positions[m.triangles[f][(k + 1) % 3]] - p).normalized();
    const Vec3 b = (m.positions[m.triangles[f][(k + 2) % 3]] - p).normalized();
    best = std::min(best, std::acos(std::clamp(a.dot(b), -1.0, 1.0)) * 180 / M_PI);
  }
  return best;
}

// Segment p->q against triangle (a, b, c), excluding the end points.
bool segment_hits_triangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c,
                           double* t_out = nullptr) {
  const Vec3 d = q - p, e1 = b - a, e2 = c - a;
  const Vec3 h = d.cross(e2);
  const double det = e1.dot(h);
  if (std::abs(det) < 1e-18) return false;
  const double inv = 1 / det;
  const Vec3 s = p - a;
  const double u = s.dot(h) * inv;
  if (u < 0 || u > 1) return false;
  const Vec3 qv = s.cross(e1);
  const double v = d.dot(qv) * inv;
  if (v < 0 || u + v > 1) return false;
  const double t = e2.dot(qv) * inv;
  if (t_out) *t_out = t;
  return t > 1e-9 && t < 1 - 1e-9;
}

}  // namespace

TEST_CASE("generic head loads from the embedded asset", "[head]") {
  const GenericHead& h = asset();
  CHECK(h.mesh.num_vertices() > 500);
  std::string why;
  CHECK(is_valid(h.mesh, &why));
  INFO(why);
  CHECK(h.mesh.normals.empty());
}

TEST_CASE("generic head has 1000..3000 triangles", "[head]") {
  const int f = asset().mesh.num_triangles();
  CHECK(f >= 1000);
  CHECK(f <= 3000);
}

TEST_CASE("generic head is a disk whose only boundary is the neck's bottom", "[head]") {
  const TriMesh& m = asset().mesh;
  MeshTopology topo;
  Status s = build_topology(m, topo);
  INFO(s.message);
  REQUIRE(s.ok());  // manifold, consistently oriented
  CHECK(euler_characteristic(topo, m.num_triangles()) == 1);
  REQUIRE(topo.boundary_loops.size() == 1);
  const BBox box = bounding_box(m.positions);
  double highest_boundary = -1e9;
  for (int v : topo.boundary_loops[0]) highest_boundary = std::max(highest_boundary, m.positions[v].y());
  double lowest_inner = 1e9;
  for (int v = 0; v < m.num_vertices(); ++v)
    if (!topo.is_boundary(v)) lowest_inner = std::min(lowest_inner, m.positions[v].y());
  CHECK(highest_boundary < box.min.y() + 0.001);
  CHECK(highest_boundary < lowest_inner);
  // Pockets add no boundary: eye rims and lip lines are interior vertices.
  for (int v : asset().annotations.eye_left.rim) CHECK_FALSE(topo.is_boundary(v));
  for (int v : asset().annotations.regions.at("lips")) CHECK_FALSE(topo.is_boundary(v));
}

TEST_CASE("generic head is oriented outwards", "[head]") {
  const TriMesh& m = asset().mesh;
  MeshTopology topo;
  REQUIRE(build_topology(m, topo).ok());
  // Close the neck with a fan to its centroid: the closed volume must be
  // positive and close to a head's (~3.5..6 litres incl. the neck).
  Vec3 c = Vec3::Zero();
  for (int v : topo.boundary_loops[0]) c += m.positions[v];
  c /= double(topo.boundary_loops[0].size());
  double volume = 0;
  for (const Tri& t : m.triangles)
    volume += m.positions[t[0]].dot(m.positions[t[1]].cross(m.positions[t[2]])) / 6;
  const auto& loop = topo.boundary_loops[0];
  // The fan's orientation follows the open boundary's direction in the triangles.
  double fan = 0;
  for (size_t k = 0; k < loop.size(); ++k) {
    const int a = loop[k], b = loop[(k + 1) % loop.size()];
    const Edge& e = topo.edges[topo.find_edge(a, b)];
    const Tri& t = m.triangles[e.f0];
    bool a_then_b = false;
    for (int i = 0; i < 3; ++i) a_then_b = a_then_b || (t[i] == a && t[(i + 1) % 3] == b);
    const Vec3 &pa = m.positions[a], &pb = m.positions[b];
    fan += (a_then_b ? c.dot(pb.cross(pa)) : c.dot(pa.cross(pb))) / 6;
  }
  volume += fan;
  CHECK(volume > 0.0035);
  CHECK(volume < 0.0065);
  // On the scalp every face normal points away from the head's centre.
  const std::vector<Vec3> normals = vertex_normals(m);
  const Vec3 center(0, 0.02, -0.01);
  int outward = 0, total = 0;
  for (int v : asset().annotations.regions.at("scalp")) {
    ++total;
    if (normals[v].dot(m.positions[v] - center) > 0) ++outward;
  }
  CHECK(total > 100);
  CHECK(outward == total);
}

TEST_CASE("generic head has no degenerate or self-intersecting triangles", "[head]") {
  const TriMesh& m = asset().mesh;
  double worst = 180;
  for (int f = 0; f < m.num_triangles(); ++f) worst = std::min(worst, min_angle_degrees(m, f));
  INFO("smallest angle " << worst << " deg");
  CHECK(worst > 5.0);
  // Every edge against every triangle not sharing a vertex with it.
  MeshTopology topo;
  REQUIRE(build_topology(m, topo).ok());
  std::vector<BBox> boxes(m.num_triangles());
  for (int f = 0; f < m.num_triangles(); ++f)
    for (int v : m.triangles[f]) boxes[f].extend(m.positions[v]);
  int crossings = 0;
  for (const Edge& e : topo.edges) {
    const Vec3 &p = m.positions[e.v0], &q = m.positions[e.v1];
    BBox eb;
    eb.extend(p);
    eb.extend(q);
    for (int f = 0; f < m.num_triangles(); ++f) {
      const Tri& t = m.triangles[f];
      if (std::find(t.begin(), t.end(), e.v0) != t.end() || std::find(t.begin(), t.end(), e.v1) != t.end())
        continue;
      if ((eb.max.array() < boxes[f].min.array()).any() || (eb.min.array() > boxes[f].max.array()).any())
        continue;
      if (segment_hits_triangle(p, q, m.positions[t[0]], m.positions[t[1]], m.positions[t[2]])) {
        ++crossings;
        UNSCOPED_INFO("edge " << e.v0 << "-" << e.v1 << " crosses triangle " << f);
      }
    }
  }
  CHECK(crossings == 0);
}

TEST_CASE("generic head is human-sized and in the house's frame", "[head]") {
  const GenericHead& h = asset();
  const TriMesh& m = h.mesh;
  double crown = -1e9, chin = 1e9, nose_z = -1e9, back_z = 1e9;
  for (const Vec3& p : m.positions) crown = std::max(crown, p.y()), back_z = std::min(back_z, p.z());
  for (int v : h.annotations.regions.at("chin")) chin = std::min(chin, m.positions[v].y());
  for (int v : h.annotations.regions.at("nose")) nose_z = std::max(nose_z, m.positions[v].z());
  INFO("chin to crown " << crown - chin << " m");
  CHECK(crown - chin > 0.22);
  CHECK(crown - chin < 0.26);
  CHECK(nose_z > 0.09);   // looks along +z
  CHECK(back_z < -0.09);  // back of the head behind the origin
  CHECK(crown > 0.1);     // up is +y
  CHECK(h.annotations.look.isApprox(Vec3::UnitZ()));
  CHECK(h.annotations.up.isApprox(Vec3::UnitY()));
  // +x is the head's left: the left ear and eye are on +x.
  for (int v : h.annotations.regions.at("ear_left")) CHECK(m.positions[v].x() > 0.03);
  for (int v : h.annotations.regions.at("ear_right")) CHECK(m.positions[v].x() < -0.03);
  CHECK(h.annotations.eye_left.center.x() > 0.02);
}

TEST_CASE("generic head is mirror-symmetric", "[head]") { CHECK(vertices_without_mirror(asset().mesh, 1e-6) == 0); }

TEST_CASE("generic head annotations are consistent with the mesh", "[head]") {
  const GenericHead& h = asset();
  const TriMesh& m = h.mesh;
  const HeadAnnotations& a = h.annotations;
  MeshTopology topo;
  REQUIRE(build_topology(m, topo).ok());

  SECTION("boxes hold their landmarks and their feature") {
    REQUIRE(a.boxes.size() == 4);
    const std::pair<const char*, const char*> box_region[] = {
        {"ear_left", "ear_left"}, {"ear_right", "ear_right"}, {"nose", "nose"}, {"mouth", "lips"}};
    for (const auto& [box_name, region] : box_region) {
      const FeatureBox& b = box_named(a, box_name);
      const size_t want = std::string(box_name).rfind("ear", 0) == 0 ? 3 : 4;
      CHECK(b.landmarks.size() == want);
      CHECK(std::set<int>(b.landmarks.begin(), b.landmarks.end()).size() == want);
      for (int v : b.landmarks) CHECK(b.contains(m.positions[v]));
      for (int v : a.regions.at(region)) CHECK(b.contains(m.positions[v]));
    }
    // Boxes do not swallow each other: the nose box holds no ear vertex, etc.
    for (int v : a.regions.at("ears")) CHECK_FALSE(box_named(a, "nose").contains(m.positions[v]));
    CHECK_FALSE(box_named(a, "mouth").contains(m.positions[box_named(a, "nose").landmarks[1]]));
  }

  SECTION("binding edges: mesh edges behind the ears, virtual edges across the lips") {
    const std::set<int> upper(a.regions.at("upper_lip").begin(), a.regions.at("upper_lip").end());
    const std::set<int> lower(a.regions.at("lower_lip").begin(), a.regions.at("lower_lip").end());
    int virtual_edges = 0, ear_edges = 0;
    for (const auto& e : a.binding_edges) {
      if (topo.find_edge(e[0], e[1]) >= 0) {
        ++ear_edges;
        // Behind an ear: on the ear side, behind the ear's front.
        const Vec3 mid = 0.5 * (m.positions[e[0]] + m.positions[e[1]]);
        CHECK(std::abs(mid.x()) > 0.05);
        CHECK(mid.z() < 0.01);
        continue;
      }
      ++virtual_edges;
      const bool ul = upper.count(e[0]) && lower.count(e[1]);
      const bool lu = lower.count(e[0]) && upper.count(e[1]);
      CHECK((ul || lu));
      CHECK(e[0] != e[1]);
      CHECK((m.positions[e[0]] - m.positions[e[1]]).norm() < 0.001);
    }
    CHECK(virtual_edges >= 3);
    CHECK(ear_edges >= 6);
  }

  SECTION("constrained vertices are the inside of the mouth") {
    REQUIRE(!a.constrained_vertices.empty());
    const FeatureBox& mouth = box_named(a, "mouth");
    for (int v : a.constrained_vertices) {
      CHECK(mouth.contains(m.positions[v]));
      CHECK(m.positions[v].z() < a.mouth_center.z() + 0.006);
    }
    CHECK(mouth.contains(a.mouth_center));
    CHECK(a.mouth_width > 0.04);
    CHECK(a.mouth_width < 0.06);
  }

  SECTION("eye sockets: the eyeball fits inside and shows through the lids") {
    for (const EyeSocket* eye : {&a.eye_left, &a.eye_right}) {
      CHECK(eye->radius == Approx(0.012).margin(0.002));
      // The rim is a closed loop of mesh edges.
      REQUIRE(eye->rim.size() >= 6);
      for (size_t k = 0; k < eye->rim.size(); ++k)
        CHECK(topo.find_edge(eye->rim[k], eye->rim[(k + 1) % eye->rim.size()]) >= 0);
      // No vertex inside the eyeball.
      for (const Vec3& p : m.positions) CHECK((p - eye->center).norm() > eye->radius);
      // Nothing covers the front of the eyeball: a ray from the front hits it first.
      const Vec3 apex = eye->center + eye->radius * Vec3::UnitZ();
      const Vec3 from = apex + Vec3(0, 0, 0.3);
      int blocked = 0;
      for (const Tri& t : m.triangles)
        if (segment_hits_triangle(from, apex, m.positions[t[0]], m.positions[t[1]], m.positions[t[2]]))
          ++blocked;
      CHECK(blocked == 0);
      // ...but from behind, the socket pocket is closed around it.
      const Vec3 back = eye->center - Vec3(0, 0, 0.03);
      int pocket = 0;
      for (const Tri& t : m.triangles)
        if (segment_hits_triangle(eye->center, back, m.positions[t[0]], m.positions[t[1]], m.positions[t[2]]))
          ++pocket;
      CHECK(pocket >= 1);
    }
  }

  SECTION("regions") {
    for (const std::string& name : required_head_regions()) {
      INFO(name);
      REQUIRE(a.regions.count(name));
      CHECK(!a.regions.at(name).empty());
    }
    // The lip chains: upper above lower at the mouth's middle.
    double upper_y = 0, lower_y = 0;
    for (int v : a.regions.at("upper_lip")) upper_y += m.positions[v].y();
    for (int v : a.regions.at("lower_lip")) lower_y += m.positions[v].y();
    CHECK(upper_y / a.regions.at("upper_lip").size() > lower_y / a.regions.at("lower_lip").size());
    CHECK(a.regions.at("eye_rim_left").size() == a.eye_left.rim.size());
  }

  SECTION("clipping planes cut the neck and the back, keep the face") {
    for (int v : a.regions.at("chin")) CHECK(a.neck_clip.keeps(m.positions[v]));
    for (int v : a.regions.at("nose")) CHECK(a.back_clip.keeps(m.positions[v]));
    for (int v : topo.boundary_loops[0]) CHECK_FALSE(a.neck_clip.keeps(m.positions[v]));
    int back_cut = 0;
    for (int v : a.regions.at("scalp")) back_cut += a.back_clip.keeps(m.positions[v]) ? 0 : 1;
    CHECK(back_cut > 20);
    CHECK(a.back_clip.normal.z() > 0.8);
  }
}

TEST_CASE("generic head ears stand out over a real hollow", "[head]") {
  const GenericHead& h = asset();
  const TriMesh& m = h.mesh;
  for (int side : {1, -1}) {
    const std::vector<int>& ear = h.annotations.regions.at(side > 0 ? "ear_left" : "ear_right");
    const std::set<int> ear_set(ear.begin(), ear.end());
    // The flap stands out: its outermost vertex is well outside the skull.
    double ear_out = 0, head_out = 0;
    for (int v = 0; v < m.num_vertices(); ++v) {
      const double out = side * m.positions[v].x();
      (ear_set.count(v) ? ear_out : head_out) = std::max(ear_set.count(v) ? ear_out : head_out, out);
    }
    INFO("ear reaches " << ear_out << " m, head " << head_out << " m");
    CHECK(ear_out > head_out + 0.004);
    // Behind the ear, skin is covered by the ear when looking from the side:
    // a ray from the skin straight outwards hits the ear (the scanner's
    // shadow). The skin probed: midpoints of the binding edges that leave the
    // ear's root backwards over the head.
    std::set<int> ear_tris;
    for (int f = 0; f < m.num_triangles(); ++f)
      for (int v : m.triangles[f])
        if (ear_set.count(v)) ear_tris.insert(f);
    int shadowed = 0, probes = 0;
    for (const auto& e : h.annotations.binding_edges) {
      if (ear_set.count(e[0]) == ear_set.count(e[1]) || side * m.positions[e[0]].x() < 0.03) continue;
      ++probes;
      const Vec3 from = 0.5 * (m.positions[e[0]] + m.positions[e[1]]) + Vec3(side * 1e-4, 0, 0);
      const Vec3 to = from + Vec3(side * 0.05, 0, 0);
      bool hit_ear = false;
      for (int f : ear_tris) {
        const Tri& t = m.triangles[f];
        hit_ear = hit_ear || segment_hits_triangle(from, to, m.positions[t[0]], m.positions[t[1]], m.positions[t[2]]);
      }
      shadowed += hit_ear ? 1 : 0;
    }
    INFO(shadowed << " of " << probes << " skin probes behind the ear are shadowed");
    CHECK(shadowed >= 3);
  }
}

TEST_CASE("generic head asset is what the builder makes", "[head]") {
  GenericHead built;
  Status s = build_generic_head(GenericHeadBuildOptions{}, built);
  INFO(s.message);
  REQUIRE(s.ok());
  const GenericHead& h = asset();
  REQUIRE(built.mesh.num_vertices() == h.mesh.num_vertices());
  REQUIRE(built.mesh.num_triangles() == h.mesh.num_triangles());
  double worst = 0;
  for (int v = 0; v < h.mesh.num_vertices(); ++v)
    worst = std::max(worst, (built.mesh.positions[v] - h.mesh.positions[v]).norm());
  INFO("regenerate with: likeness make-generic-head --out core/head/data");
  CHECK(worst < 1e-9);
  CHECK(built.mesh.triangles == h.mesh.triangles);
  // Indices exactly, coordinates to 1e-9 m (compilers may round differently).
  const HeadAnnotations &a = built.annotations, &b = h.annotations;
  CHECK(a.regions == b.regions);
  CHECK(a.binding_edges == b.binding_edges);
  CHECK(a.constrained_vertices == b.constrained_vertices);
  CHECK(a.eye_left.rim == b.eye_left.rim);
  CHECK(a.eye_right.rim == b.eye_right.rim);
  REQUIRE(a.creases.size() == b.creases.size());
  for (size_t k = 0; k < a.creases.size(); ++k) {
    CHECK(a.creases[k].name == b.creases[k].name);
    CHECK(a.creases[k].vertices == b.creases[k].vertices);
    CHECK(a.creases[k].closed == b.creases[k].closed);
  }
  REQUIRE(a.boxes.size() == b.boxes.size());
  for (size_t k = 0; k < a.boxes.size(); ++k) {
    CHECK(a.boxes[k].name == b.boxes[k].name);
    CHECK(a.boxes[k].landmarks == b.boxes[k].landmarks);
    CHECK((a.boxes[k].min - b.boxes[k].min).norm() < 1e-9);
    CHECK((a.boxes[k].max - b.boxes[k].max).norm() < 1e-9);
  }
  CHECK((a.eye_left.center - b.eye_left.center).norm() < 1e-9);
  CHECK((a.mouth_center - b.mouth_center).norm() < 1e-9);
  CHECK(a.mouth_width == Approx(b.mouth_width).margin(1e-9));
  CHECK((a.neck_clip.point - b.neck_clip.point).norm() < 1e-9);
  CHECK((a.back_clip.normal - b.back_clip.normal).norm() < 1e-9);
}

TEST_CASE("head annotations round-trip through JSON", "[head]") {
  const GenericHead& h = asset();
  const std::string text = head_annotations_to_json(h.annotations, h.mesh.num_vertices());
  HeadAnnotations back;
  Status s = parse_head_annotations(text, h.mesh.num_vertices(), back);
  INFO(s.message);
  REQUIRE(s.ok());
  CHECK(head_annotations_to_json(back, h.mesh.num_vertices()) == text);
  CHECK(back.binding_edges == h.annotations.binding_edges);
  CHECK(back.regions == h.annotations.regions);
  CHECK(back.eye_left.center == h.annotations.eye_left.center);
  CHECK(back.boxes[2].max == h.annotations.boxes[2].max);
  REQUIRE(back.creases.size() == h.annotations.creases.size());
  for (size_t k = 0; k < back.creases.size(); ++k) {
    CHECK(back.creases[k].name == h.annotations.creases[k].name);
    CHECK(back.creases[k].vertices == h.annotations.creases[k].vertices);
    CHECK(back.creases[k].closed == h.annotations.creases[k].closed);
  }
  // Creases are optional: a file without them loads with none.
  HeadAnnotations without = h.annotations;
  without.creases.clear();
  HeadAnnotations none;
  REQUIRE(parse_head_annotations(head_annotations_to_json(without, h.mesh.num_vertices()), h.mesh.num_vertices(), none).ok());
  CHECK(none.creases.empty());
}

TEST_CASE("broken head annotations are rejected with a message", "[head]") {
  const GenericHead& h = asset();
  const int n = h.mesh.num_vertices();
  const std::string good = head_annotations_to_json(h.annotations, n);
  auto reject = [&](const std::string& text, const std::string& expect_in_message, int num_vertices) {
    HeadAnnotations out;
    Status s = parse_head_annotations(text, num_vertices, out);
    INFO("expected \"" << expect_in_message << "\" in: " << s.message);
    CHECK(s.code == ErrorCode::InvalidInput);
    CHECK(s.message.find(expect_in_message) != std::string::npos);
  };
  auto replaced = [&](const std::string& from, const std::string& to) {
    std::string t = good;
    const size_t at = t.find(from);
    REQUIRE(at != std::string::npos);
    return t.replace(at, from.size(), to);
  };
  reject("", "not valid JSON", n);
  reject(good.substr(0, good.size() / 2), "not valid JSON", n);
  reject("[1,2,3]", "must be a JSON object", n);
  reject(good, "num_vertices", n + 1);
  // An index past the mesh's vertices, and a negative one.
  const std::string face_key = "\"face\": [";
  reject(replaced(face_key, face_key + std::to_string(n) + ","), "out of range", n);
  reject(replaced(face_key, face_key + "-1,"), "out of range", n);
  reject(replaced(face_key, face_key + "1.5,"), "must be an integer", n);
  reject(replaced("\"name\":\"nose\"", "\"name\":\"chin\""), "unknown box", n);
  reject(replaced("\"name\":\"nose\"", "\"name\":\"mouth\""), "duplicate box", n);
  reject(replaced("\"constrained_vertices\"", "\"constrained\""), "constrained_vertices", n);
  reject(replaced("\"neck_clip\": {\"normal\":[", "\"neck_clip\": {\"normal\":[\"x\","), "neck_clip", n);
  reject(replaced("\"landmarks\":[", "\"landmarks\":[0,"), "landmarks", n);
  reject(replaced("\"face\":", "\"face_renamed\":"), "regions.face", n);
  reject(replaced("\"radius\":", "\"radius\":-1,\"r\":"), "radius", n);
  reject(replaced("\"vertices\":[", "\"vertices\":[" + std::to_string(n) + ","), "creases[0].vertices", n);
  reject(replaced("\"closed\":true", "\"closed\":1"), "creases[0].closed", n);
  reject(replaced("\"creases\": [", "\"creases\": [{\"closed\":true,\"name\":\"x\",\"vertices\":[1,2]},"),
         "at least 3", n);
  HeadAnnotations out;
  CHECK_FALSE(parse_head_annotations(good, 0, out).ok());
}

TEST_CASE("generic head builder rejects impossible options", "[head]") {
  GenericHead h;
  GenericHeadBuildOptions o;
  o.eyeball_radius = 0.02;
  CHECK(build_generic_head(o, h).code == ErrorCode::InvalidInput);
  o = GenericHeadBuildOptions{};
  o.lip_gap = 0;
  CHECK(build_generic_head(o, h).code == ErrorCode::InvalidInput);
}

TEST_CASE("generic head crease curves are the eye rims and lip lines, cutting off the pockets", "[head]") {
  const GenericHead& h = asset();
  const TriMesh& m = h.mesh;
  const HeadAnnotations& a = h.annotations;
  MeshTopology topo;
  REQUIRE(build_topology(m, topo).ok());
  std::map<std::string, const CreaseCurve*> by_name;
  for (const CreaseCurve& c : a.creases) by_name[c.name] = &c;
  REQUIRE(by_name.size() == 4);
  for (const char* name : {"eye_rim_left", "eye_rim_right", "upper_lip_line", "lower_lip_line"})
    REQUIRE(by_name.count(name));
  CHECK(by_name["eye_rim_left"]->closed);
  CHECK(by_name["eye_rim_left"]->vertices == a.eye_left.rim);
  CHECK(by_name["eye_rim_right"]->vertices == a.eye_right.rim);
  const CreaseCurve& upper = *by_name["upper_lip_line"];
  const CreaseCurve& lower = *by_name["lower_lip_line"];
  CHECK_FALSE(upper.closed);
  CHECK_FALSE(lower.closed);
  // The lines share the mouth corners and nothing else.
  CHECK(upper.vertices.front() == lower.vertices.front());
  CHECK(upper.vertices.back() == lower.vertices.back());
  std::set<int> shared;
  for (int v : upper.vertices)
    if (std::find(lower.vertices.begin(), lower.vertices.end(), v) != lower.vertices.end()) shared.insert(v);
  CHECK(shared.size() == 2);
  const std::set<int> upper_lip(a.regions.at("upper_lip").begin(), a.regions.at("upper_lip").end());
  const std::set<int> lower_lip(a.regions.at("lower_lip").begin(), a.regions.at("lower_lip").end());
  for (size_t k = 1; k + 1 < upper.vertices.size(); ++k) CHECK(upper_lip.count(upper.vertices[k]));
  for (size_t k = 1; k + 1 < lower.vertices.size(); ++k) CHECK(lower_lip.count(lower.vertices[k]));

  // Every step is an interior mesh edge; cutting the faces along all of them
  // leaves exactly four pieces: the skin, two eye pockets, the mouth bag.
  std::set<int> cut;
  for (const CreaseCurve& c : a.creases) {
    const size_t n = c.vertices.size();
    for (size_t k = 0; k + (c.closed ? 0 : 1) < n; ++k) {
      const int e = topo.find_edge(c.vertices[k], c.vertices[(k + 1) % n]);
      INFO(c.name << " step " << k);
      REQUIRE(e >= 0);
      CHECK_FALSE(topo.edges[e].boundary());
      cut.insert(e);
    }
  }
  std::vector<int> piece(m.num_triangles(), -1);
  std::vector<int> piece_size;
  for (int f0 = 0; f0 < m.num_triangles(); ++f0) {
    if (piece[f0] >= 0) continue;
    const int id = static_cast<int>(piece_size.size());
    piece_size.push_back(0);
    std::vector<int> stack{f0};
    piece[f0] = id;
    while (!stack.empty()) {
      const int f = stack.back();
      stack.pop_back();
      ++piece_size[id];
      for (int e : topo.face_edges[f]) {
        if (cut.count(e)) continue;
        const int g = topo.edges[e].f0 == f ? topo.edges[e].f1 : topo.edges[e].f0;
        if (g >= 0 && piece[g] < 0) piece[g] = id, stack.push_back(g);
      }
    }
  }
  std::sort(piece_size.begin(), piece_size.end());
  REQUIRE(piece_size.size() == 4);
  CHECK(piece_size[3] > 20 * piece_size[2]);  // the skin; the pockets are small
}

namespace {

// Triangles of the pairs whose centroid lies within 3 cm of an eyeball's
// centre (a triangle counted once per pair it is in).
int triangles_near_eyes(const TriMesh& fine, const std::vector<std::array<int, 2>>& pairs,
                        const HeadAnnotations& annotations) {
  int near = 0;
  for (const auto& p : pairs)
    for (int t : p) {
      const Tri& tri = fine.triangles[t];
      const Vec3 c = (fine.positions[tri[0]] + fine.positions[tri[1]] + fine.positions[tri[2]]) / 3;
      if ((c - annotations.eye_left.center).norm() < 0.03 || (c - annotations.eye_right.center).norm() < 0.03) ++near;
    }
  return near;
}

}  // namespace

TEST_CASE("generic head: with the rims as creases its smooth level 3 crosses only at the mouth corners", "[head]") {
  // The skin's plain Butterfly stencils reach over the rims into the
  // pockets ~0.3-1.3 mm behind them, and the refined lips and lids cross
  // their pockets (measured: 447 pairs at level 3 without creases,
  // although the control mesh has none). As creases the slit is clean, and
  // since the ring around each eye leaves the skin room to turn into the
  // opening (the builder's comments) nothing crosses at the eyes: the lid
  // skin folded over the outer eye corners before (373 of 397 pairs,
  // inherited by every fit). 24 pairs are left at the outer mouth corners.
  const GenericHead& h = asset();
  ButterflyCreases creases;
  for (const CreaseCurve& c : h.annotations.creases) add_crease_polyline(c.vertices, c.closed, creases);
  MultiresMesh plain, creased;
  REQUIRE(build_multires(h.mesh, 3, plain).ok());
  REQUIRE(build_multires(h.mesh, creases, 3, creased).ok());
  std::vector<std::array<int, 2>> plain_pairs, creased_pairs;
  REQUIRE(find_self_intersections(level_mesh(plain, 3), plain_pairs).ok());
  REQUIRE(find_self_intersections(level_mesh(creased, 3), creased_pairs).ok());
  INFO("level-3 crossing pairs: plain " << plain_pairs.size() << ", with creases " << creased_pairs.size());
  CHECK(creased_pairs.size() * 2 < plain_pairs.size());
  CHECK(creased_pairs.size() <= 24);
  const TriMesh fine = level_mesh(creased, 3);
  const int at_eyes = triangles_near_eyes(fine, creased_pairs, h.annotations);
  CHECK(at_eyes == 0);
  // No crossing between the inner lips: no pair has triangles on both
  // sides of the slit (the control faces of the two lip lines' vertices
  // below and above it, away from the corners).
  std::set<int> upper_faces, lower_faces;
  const auto& cr = h.annotations.creases;
  auto faces_of = [&](const std::string& name, std::set<int>& out) {
    for (const CreaseCurve& c : cr)
      if (c.name == name)
        for (size_t k = 1; k + 1 < c.vertices.size(); ++k)
          for (int f = 0; f < h.mesh.num_triangles(); ++f)
            for (int v : h.mesh.triangles[f])
              if (v == c.vertices[k]) out.insert(f);
  };
  faces_of("upper_lip_line", upper_faces);
  faces_of("lower_lip_line", lower_faces);
  int across_slit_plain = 0, across_slit = 0;
  auto across = [&](const std::array<int, 2>& p) {
    const int a = p[0] / 64, b = p[1] / 64;  // control face of a level-3 triangle
    return (upper_faces.count(a) && lower_faces.count(b)) || (upper_faces.count(b) && lower_faces.count(a));
  };
  for (const auto& p : plain_pairs) across_slit_plain += across(p);
  for (const auto& p : creased_pairs) across_slit += across(p);
  INFO("pairs across the slit: plain " << across_slit_plain << ", with creases " << across_slit);
  CHECK(across_slit_plain > 0);
  CHECK(across_slit == 0);
}

namespace {

// Longest over shortest edge: 1 for an equilateral triangle, ~1.4 for half a
// square, ~5 for half of a 5:1 quad.
double edge_ratio(const TriMesh& m, const Tri& t) {
  double lo = 1e300, hi = 0;
  for (int k = 0; k < 3; ++k) {
    const double e = (m.positions[t[(k + 1) % 3]] - m.positions[t[k]]).norm();
    lo = std::min(lo, e);
    hi = std::max(hi, e);
  }
  return hi / lo;
}

// The head's smooth level 3 with its rim creases, as the fit refines it.
TriMesh smooth_level3(const GenericHead& h) {
  ButterflyCreases creases;
  for (const CreaseCurve& c : h.annotations.creases) add_crease_polyline(c.vertices, c.closed, creases);
  MultiresMesh smooth;
  REQUIRE(build_multires(h.mesh, creases, 3, smooth).ok());
  return level_mesh(smooth, 3);
}

// Angles (deg, sorted) between the normals of adjacent faces of m, over the
// edges between two faces that keep(f0, f1) accepts.
template <class Keep>
std::vector<double> normal_angles(const TriMesh& m, Keep keep) {
  std::vector<Vec3> normal(m.num_triangles());
  for (int f = 0; f < m.num_triangles(); ++f) {
    const Tri& t = m.triangles[f];
    const Vec3 &a = m.positions[t[0]], &b = m.positions[t[1]], &c = m.positions[t[2]];
    normal[f] = (b - a).cross(c - a).normalized();
  }
  MeshTopology topo;
  REQUIRE(build_topology(m, topo).ok());
  std::vector<double> angles;
  for (const Edge& e : topo.edges)
    if (e.f1 >= 0 && keep(e.f0, e.f1))
      angles.push_back(std::acos(std::clamp(normal[e.f0].dot(normal[e.f1]), -1.0, 1.0)) * 180 / M_PI);
  std::sort(angles.begin(), angles.end());
  return angles;
}

// A face's centroid.
Vec3 centroid(const TriMesh& m, int f) {
  const Tri& t = m.triangles[f];
  return (m.positions[t[0]] + m.positions[t[1]] + m.positions[t[2]]) / 3;
}

// Triangles inside `region` (all three corners) whose mirror image in x = 0
// is not a triangle of m, with the opposite winding; every region vertex
// must have its mirror vertex (REQUIRE).
int triangles_without_mirror(const TriMesh& m, const std::vector<char>& region) {
  std::vector<int> mirror(m.num_vertices(), -1);
  for (int v = 0; v < m.num_vertices(); ++v) {
    if (!region[v]) continue;
    const Vec3 q(-m.positions[v].x(), m.positions[v].y(), m.positions[v].z());
    for (int w = 0; w < m.num_vertices() && mirror[v] < 0; ++w)
      if ((m.positions[w] - q).norm() < 1e-9) mirror[v] = w;
    REQUIRE(mirror[v] >= 0);
  }
  auto canonical = [](std::array<int, 3> t) {
    while (!(t[0] < t[1] && t[0] < t[2])) t = {t[1], t[2], t[0]};
    return t;
  };
  std::set<std::array<int, 3>> triangles;
  for (const Tri& t : m.triangles) triangles.insert(canonical({t[0], t[1], t[2]}));
  int unmatched = 0;
  for (const Tri& t : m.triangles)
    if (region[t[0]] && region[t[1]] && region[t[2]])
      unmatched += triangles.count(canonical({mirror[t[0]], mirror[t[2]], mirror[t[1]]})) ? 0 : 1;
  return unmatched;
}

}  // namespace

TEST_CASE("generic head, even eye corners: no short brow edge, and the smooth level 3 stays clean at the eyes", "[head]") {
  // GenericHeadBuildOptions::even_eye_corners (the asset's since 22 Nov):
  // each eye ring's corner sits halfway (in angle) between its neighbours
  // instead of at 45 deg of the square, which left a 4.6 mm edge over each
  // brow among 13-27 mm ones (where fitted clean scans folded:
  // docs/journal.md "Even corners of the eye rings"). Same vertices and
  // regions; only the corners move (and the diagonals of a few quads, which
  // the builder picks by shape).
  const GenericHead& even = asset();
  const GenericHead& plate = test::corner45_generic_head();
  REQUIRE(even.mesh.num_vertices() == plate.mesh.num_vertices());
  CHECK(even.mesh.num_triangles() == plate.mesh.num_triangles());
  CHECK(even.annotations.regions == plate.annotations.regions);
  auto shortest_brow_edge = [](const GenericHead& h) {
    const std::vector<char> brow = vertex_mask(h.annotations.regions.at("brow"), h.mesh.num_vertices());
    double shortest = 1e9;
    for (const Tri& t : h.mesh.triangles)
      for (int k = 0; k < 3; ++k)
        if (brow[t[k]] && brow[t[(k + 1) % 3]])
          shortest = std::min(shortest, (h.mesh.positions[t[k]] - h.mesh.positions[t[(k + 1) % 3]]).norm());
    return shortest;
  };
  const double before = shortest_brow_edge(plate), after = shortest_brow_edge(even);
  INFO("shortest brow edge: " << 1e3 * before << " mm with corners at 45 deg, " << 1e3 * after << " mm with even corners");
  CHECK(before < 0.005);  // 4.57 mm measured
  CHECK(after > 0.006);   // 6.43 mm measured
  // Mirror-symmetric still: every vertex has its mirror image.
  CHECK(vertices_without_mirror(even.mesh, 1e-9) == 0);
  // Its smooth level 3 with the rim creases does not cross itself at the
  // eyes (the asset's crosses only at the mouth corners).
  const TriMesh fine = smooth_level3(even);
  std::vector<std::array<int, 2>> pairs;
  REQUIRE(find_self_intersections(fine, pairs).ok());
  const int at_eyes = triangles_near_eyes(fine, pairs, even.annotations);
  INFO(pairs.size() << " smooth level-3 pairs, " << at_eyes << " triangles of them near an eye");
  CHECK(pairs.size() <= 24);
  CHECK(at_eyes == 0);
}

TEST_CASE("generic head: the neck is meshed in round triangles, mirror-symmetric, within the vertex budget", "[head]") {
  // The neck used to continue the head's 40 meridians (5 mm apart at the
  // throat) in 22-26 mm rows: 5:1 slivers (edge ratio up to 6.2, p90 4.5)
  // whose smooth surface rippled in columns, read as streaks under the jaw
  // on fitted heads. It is now rings with fewer meridians.
  const GenericHead& h = asset();
  const TriMesh& m = h.mesh;
  const std::vector<int>& neck = h.annotations.regions.at("neck");
  const std::vector<char> in_neck = vertex_mask(neck, m.num_vertices());
  std::vector<double> ratios;
  for (const Tri& t : m.triangles)
    if (in_neck[t[0]] && in_neck[t[1]] && in_neck[t[2]]) ratios.push_back(edge_ratio(m, t));
  REQUIRE(ratios.size() > 100);
  std::sort(ratios.begin(), ratios.end());
  const double p90 = ratios[ratios.size() * 9 / 10], worst = ratios.back();
  INFO("neck triangles " << ratios.size() << ", edge ratio p90 " << p90 << ", worst " << worst);
  CHECK(p90 < 2.2);
  CHECK(worst < 2.6);
  // Every vertex costs fit time: the remeshed neck (and ears) stay within
  // 5 % of the 1358 control vertices the head had before.
  CHECK(m.num_vertices() <= 1426);
  // Exact mirror symmetry of the neck's triangles too (the strip joining
  // rings of different meridian counts is built by a merge that only stays
  // symmetric if no two mid-azimuths coincide).
  CHECK(triangles_without_mirror(m, in_neck) == 0);
}

TEST_CASE("generic head: the smooth level 3 of the neck does not ripple", "[head]") {
  // Angle between the normals of adjacent level-3 triangles (with the rim
  // creases, as the fit refines) in the band from 50 mm below the neck cut
  // to 15 mm above it, i.e. the neck under the jaw: a smooth neck of 60 mm
  // radius with ~2 mm triangles turns by ~1-2 deg per edge. The 5:1 neck
  // slivers rippled: p95 5.3 deg, worst 26.5 deg; the remeshed neck 2.9 / 14.1.
  const GenericHead& h = asset();
  const TriMesh fine = smooth_level3(h);
  const double cut = h.annotations.neck_clip.point.y();
  auto height = [&](int f) {
    const Tri& t = fine.triangles[f];
    return (fine.positions[t[0]].y() + fine.positions[t[1]].y() + fine.positions[t[2]].y()) / 3;
  };
  const std::vector<double> angles = normal_angles(fine, [&](int f0, int f1) {
    const double y = 0.5 * (height(f0) + height(f1));
    return y >= cut - 0.05 && y <= cut + 0.015;
  });
  REQUIRE(angles.size() > 5000);
  const double p95 = angles[angles.size() * 95 / 100];
  INFO("neck band: " << angles.size() << " edges, normal angle p95 " << p95 << " deg, worst " << angles.back());
  CHECK(p95 < 4.0);
  CHECK(angles.back() < 20.0);
}

namespace {

// Triangles of the back of the head behind the ears (all corners 30 mm or
// more behind the ear line, within 65 mm of the midline, from under the
// skull to the crown's start): where the face's row elevations made slivers.
bool behind_ears(const Vec3& p) { return p.z() < -0.03 && std::abs(p.x()) < 0.065 && p.y() > -0.12 && p.y() < 0.06; }

struct BackShape {
  double ratio_p90 = 0, ratio_worst = 0;  // control triangles' longest / shortest edge
  double angle_p99 = 0, angle_worst = 0;  // smooth level 3: angle between adjacent faces' normals (deg)
};

BackShape back_shape(const GenericHead& h) {
  BackShape out;
  const TriMesh& m = h.mesh;
  std::vector<double> ratios;
  for (const Tri& t : m.triangles)
    if (behind_ears(m.positions[t[0]]) && behind_ears(m.positions[t[1]]) && behind_ears(m.positions[t[2]]))
      ratios.push_back(edge_ratio(m, t));
  if (ratios.size() < 50) return out;
  std::sort(ratios.begin(), ratios.end());
  out.ratio_p90 = ratios[ratios.size() * 9 / 10];
  out.ratio_worst = ratios.back();
  const TriMesh fine = smooth_level3(h);
  const std::vector<double> angles =
      normal_angles(fine, [&](int f0, int) { return behind_ears(centroid(fine, f0)); });
  if (angles.size() < 5000) return out;
  out.angle_p99 = angles[angles.size() * 99 / 100];
  out.angle_worst = angles.back();
  return out;
}

}  // namespace

TEST_CASE("generic head: behind the ears the rows are even and the smooth level 3 has no crease", "[head]") {
  // At the face's row elevations the back's rows were 22 mm apart under
  // the skull and 5 mm at the nape's bend, against 17 mm between the
  // meridians: slivers whose smooth level 3 rippled into a wavy crease
  // across the back of every head (docs/journal.md "Even rows at the
  // back"). The builder now spreads those rows evenly along the meridians.
  GenericHeadBuildOptions before_options;
  before_options.even_back_rows = false;
  before_options.regular_nape = false;  // the asset's layout of then
  const BackShape before = back_shape(test::built_generic_head(before_options));
  const BackShape now = back_shape(asset());
  INFO("behind the ears, face rows: edge ratio p90 " << before.ratio_p90 << " worst " << before.ratio_worst
                                                     << "; level-3 normal angle p99 " << before.angle_p99
                                                     << " worst " << before.angle_worst << " deg");
  INFO("even rows (the asset): edge ratio p90 " << now.ratio_p90 << " worst " << now.ratio_worst
                                                << "; level-3 normal angle p99 " << now.angle_p99 << " worst "
                                                << now.angle_worst << " deg");
  REQUIRE(before.angle_worst > 0);
  REQUIRE(now.angle_worst > 0);
  // Face rows: edge ratio p90 3.66, worst 4.06; level-3 normal angle p99
  // 3.63, worst 7.77 deg. Even rows: 2.83 / 3.49; 3.13 / 5.78 deg (17 mm
  // meridians over 10 mm rows still give ratios near 2); with the regular
  // nape too (the asset since its test below): 3.10 / 3.49; 3.12 / 4.21.
  CHECK(now.ratio_p90 < 3.2);
  CHECK(now.ratio_worst < 3.8);
  CHECK(now.angle_p99 < 3.4);
  CHECK(now.angle_worst < 6.8);
}

namespace {

// Behind the ears and down the back of the neck, above the boundary: where
// quads split by shape left irregular vertices (4 to 8 neighbours).
bool behind_ears_and_neck(const Vec3& p) {
  return p.z() < -0.03 && std::abs(p.x()) < 0.065 && p.y() > -0.19 && p.y() < 0.06;
}

struct NapeShape {
  int irregular = 0;      // vertices there without six neighbours
  int vertices = 0;       // vertices there
  double angle_max = 0;   // smooth level 3: largest angle between adjacent faces' normals (deg)
  double angle_p999 = 0;  // ... its 99.9th percentile
};

NapeShape nape_shape(const GenericHead& h) {
  NapeShape out;
  const TriMesh& m = h.mesh;
  MeshTopology topo;
  REQUIRE(build_topology(m, topo).ok());
  for (int v = 0; v < m.num_vertices(); ++v)
    if (behind_ears_and_neck(m.positions[v])) {
      ++out.vertices;
      out.irregular += topo.valence(v) != 6;
    }
  const TriMesh fine = smooth_level3(h);
  const std::vector<double> angles =
      normal_angles(fine, [&](int f0, int) { return behind_ears_and_neck(centroid(fine, f0)); });
  REQUIRE(angles.size() > 5000);
  out.angle_max = angles.back();
  out.angle_p999 = angles[angles.size() * 999 / 1000];
  return out;
}

}  // namespace

TEST_CASE("generic head: the nape and the back of the neck are regular and their smooth level 3 has no wavy lines", "[head]") {
  // Quads behind the ears and down the neck were split along their better
  // diagonal, nearly at random where they are close to squares, and the
  // strip joining the head's 40 meridians to the neck's 24 was 8 mm deep
  // at the back against 17-25 mm edges: 4- to 8-valent vertices and
  // slivers, whose Butterfly surface rippled into wavy lines across the
  // nape and where the skull meets the neck (docs/journal.md "A
  // regular nape"). GenericHeadBuildOptions::regular_nape splits them
  // along same-leaning diagonals and deepens the strip at the back.
  GenericHeadBuildOptions before_options;
  before_options.regular_nape = false;
  const NapeShape before = nape_shape(test::built_generic_head(before_options));
  const NapeShape now = nape_shape(asset());
  INFO("by shape: " << before.irregular << " of " << before.vertices << " vertices irregular; level-3 normal angle p99.9 "
                    << before.angle_p999 << " worst " << before.angle_max << " deg");
  INFO("regular nape (the asset): " << now.irregular << " of " << now.vertices
                                    << " vertices irregular; level-3 normal angle p99.9 " << now.angle_p999
                                    << " worst " << now.angle_max << " deg");
  CHECK(now.vertices == before.vertices);
  // By shape: 23 of 223 irregular, p99.9 4.05 deg, worst 5.78. Regular
  // nape: 6 (ear roots and the joining strip), p99.9 3.84, worst 6.04 (at
  // the back's midline under the strip, where the merge still gives one
  // ring vertex 8 neighbours).
  CHECK(before.irregular >= 15);
  CHECK(now.irregular <= 8);
  CHECK(now.angle_p999 < 3.95);
  CHECK(now.angle_max < 6.5);
  // The nape itself (above the strip, where the old split rippled most):
  // worst 5.78 deg by shape, 4.21 now.
  const TriMesh fine = smooth_level3(asset());
  const std::vector<double> nape = normal_angles(fine, [&](int f0, int) {
    const Vec3 c = centroid(fine, f0);
    return behind_ears_and_neck(c) && c.y() > -0.1;
  });
  REQUIRE(nape.size() > 5000);
  INFO("nape above the strip: worst " << nape.back() << " deg");
  CHECK(nape.back() < 4.8);
}

namespace {

// The builder's ring ear (GenericHeadBuildOptions::ring_ear), built once;
// not the asset's ear yet (docs/journal.md "A ring ear").
const GenericHead& ring_ear_head() {
  static const GenericHead head = [] {
    GenericHeadBuildOptions options;
    options.ring_ear = true;
    return test::built_generic_head(options);
  }();
  return head;
}

}  // namespace

TEST_CASE("generic head, ring ear: each ear is rings round the concha, its helix rim a regular loop", "[head]") {
  // The ear was the 2 x 6 root patch extruded into a plate whose bowl was a
  // vertical strip of quads (Butterfly made it a washboard). It is now rings
  // from the root to the helix rim and back in to the concha floor, joined
  // by strips whose vertices all have valence 5-7; only the floor (the
  // centre of the innermost ring) and corners of the root (where the head's
  // grid meets the ear) may be extraordinary.
  const GenericHead& h = ring_ear_head();
  const TriMesh& m = h.mesh;
  const HeadAnnotations& a = h.annotations;
  MeshTopology topo;
  REQUIRE(build_topology(m, topo).ok());
  for (const char* side : {"left", "right"}) {
    INFO(side);
    const std::vector<int>& ear = a.regions.at(std::string("ear_") + side);
    const std::vector<int>& rim = a.regions.at(std::string("ear_rim_") + side);
    const std::set<int> ear_set(ear.begin(), ear.end()), rim_set(rim.begin(), rim.end());
    // Enough control vertices for a round helix (jeong2002 Sec. 4), and a
    // closed loop: every rim vertex has exactly two rim neighbours, and the
    // rim edges form one cycle.
    CHECK(rim.size() >= 18);
    CHECK(rim.size() <= 24);
    int irregular_rim = 0, irregular = 0;
    for (int v : rim) {
      CHECK(ear_set.count(v) == 1);
      int rim_neighbours = 0;
      for (int w : topo.rings[v]) rim_neighbours += rim_set.count(w) ? 1 : 0;
      CHECK(rim_neighbours == 2);
      const int valence = static_cast<int>(topo.rings[v].size());
      irregular_rim += valence < 5 || valence > 7 ? 1 : 0;
    }
    CHECK(irregular_rim == 0);
    std::set<int> seen = {rim[0]};
    for (int v = rim[0], previous = -1;;) {
      int next = -1;
      for (int w : topo.rings[v])
        if (rim_set.count(w) && w != previous && (next < 0 || !seen.count(w))) next = w;
      if (next < 0 || seen.count(next)) break;
      seen.insert(next);
      previous = v;
      v = next;
    }
    CHECK(seen.size() == rim.size());
    int root = 0;
    for (int v : ear) {
      bool on_root = false;  // a neighbour on the head: where the grid meets the ear
      for (int w : topo.rings[v]) on_root = on_root || !ear_set.count(w);
      root += on_root ? 1 : 0;
      const int valence = static_cast<int>(topo.rings[v].size());
      if (!on_root) irregular += valence < 5 || valence > 8 ? 1 : 0;
    }
    INFO("ear vertices " << ear.size() << " (" << root << " on the root), valence outside 5-8 off the root: "
                         << irregular);
    CHECK(root == 16);
    CHECK(irregular == 0);
  }
}

TEST_CASE("generic head, ring ear: ear triangles are not slivers and mirror each other", "[head]") {
  // Measured on the ring ear (triangles with all corners in an ear):
  // longest / shortest edge median 1.73, p90 2.37, worst 3.61; smallest
  // angle 15.2 deg (the plate ear: p90 3.64, worst 4.44, 13.0 deg). Joining
  // the wall to the rim by place along the ring instead of by angle round
  // the concha left 5 deg slivers across the lobe.
  const GenericHead& h = ring_ear_head();
  const TriMesh& m = h.mesh;
  const std::vector<int>& ears = h.annotations.regions.at("ears");
  const std::vector<char> in_ear = vertex_mask(ears, m.num_vertices());
  std::vector<double> ratios;
  double smallest = 180;
  for (int f = 0; f < m.num_triangles(); ++f) {
    const Tri& t = m.triangles[f];
    if (!(in_ear[t[0]] && in_ear[t[1]] && in_ear[t[2]])) continue;
    ratios.push_back(edge_ratio(m, t));
    smallest = std::min(smallest, min_angle_degrees(m, f));
  }
  REQUIRE(ratios.size() > 200);
  std::sort(ratios.begin(), ratios.end());
  const double p90 = ratios[ratios.size() * 9 / 10];
  INFO("ear triangles " << ratios.size() << ", edge ratio p90 " << p90 << ", worst " << ratios.back()
                        << ", smallest angle " << smallest << " deg");
  CHECK(p90 < 2.8);
  CHECK(ratios.back() < 4.2);
  CHECK(smallest > 12.0);
  // Each ear triangle has its mirror image in the other ear (the strips
  // joining rings of different counts only stay symmetric if their merge is).
  CHECK(triangles_without_mirror(m, in_ear) == 0);
}

TEST_CASE("generic head, ring ear: ear landmarks sit on the rim, inside the ear's box, and binding edges mirror", "[head]") {
  const GenericHead& h = ring_ear_head();
  const TriMesh& m = h.mesh;
  const HeadAnnotations& a = h.annotations;
  MeshTopology topo;
  REQUIRE(build_topology(m, topo).ok());
  std::map<std::string, int> binding_per_side;
  for (const char* side : {"left", "right"}) {
    INFO(side);
    const FeatureBox& box = box_named(a, std::string("ear_") + side);
    const std::vector<int>& rim = a.regions.at(std::string("ear_rim_") + side);
    REQUIRE(box.landmarks.size() == 3);
    const int top = box.landmarks[0], back = box.landmarks[1], lobe = box.landmarks[2];
    for (int v : box.landmarks) {
      CHECK(std::count(rim.begin(), rim.end(), v) == 1);
      CHECK(box.contains(m.positions[v]));
    }
    // Top: the rim's highest vertex; lobe: its lowest; back: its rearmost.
    for (int v : rim) {
      CHECK(m.positions[v].y() <= m.positions[top].y());
      CHECK(m.positions[v].y() >= m.positions[lobe].y());
      CHECK(m.positions[v].z() >= m.positions[back].z());
    }
    // An ear is 55-75 mm tall (the generic head is 0.24 m chin to crown).
    const double height = m.positions[top].y() - m.positions[lobe].y();
    CHECK(height > 0.055);
    CHECK(height < 0.075);
  }
  // Binding edges behind both ears, each the mirror image of one on the other side.
  std::set<std::array<int, 2>> edges;
  for (const auto& e : a.binding_edges) edges.insert({std::min(e[0], e[1]), std::max(e[0], e[1])});
  auto mirror_of = [&](int v) {
    const Vec3 q(-m.positions[v].x(), m.positions[v].y(), m.positions[v].z());
    for (int w = 0; w < m.num_vertices(); ++w)
      if ((m.positions[w] - q).norm() < 1e-9) return w;
    return -1;
  };
  int left = 0, right = 0, unmatched = 0;
  for (const auto& e : a.binding_edges) {
    if (topo.find_edge(e[0], e[1]) < 0) continue;  // the lips' virtual edges
    (m.positions[e[0]].x() > 0 ? left : right) += 1;
    const int p = mirror_of(e[0]), q = mirror_of(e[1]);
    unmatched += edges.count({std::min(p, q), std::max(p, q)}) ? 0 : 1;
  }
  INFO("ear binding edges left " << left << ", right " << right);
  CHECK(left >= 10);
  CHECK(left == right);
  CHECK(unmatched == 0);
}

namespace {

struct EarSmoothness {
  std::vector<double> angles;  // between adjacent level-3 face normals (deg), sorted
  int crossing_pairs = 0;      // level-3 triangle pairs crossing, either refined from an ear face
  double at(double q) const { return angles[static_cast<size_t>(q * (angles.size() - 1))]; }
};

// The head's smooth level 3 (with the rim creases, as the fit refines it),
// on the triangles refined from its ears' control faces.
EarSmoothness ear_smoothness(const GenericHead& h) {
  EarSmoothness out;
  const TriMesh fine = smooth_level3(h);
  const std::vector<char> in_ear = vertex_mask(h.annotations.regions.at("ears"), h.mesh.num_vertices());
  std::vector<char> ear_face(h.mesh.num_triangles(), 0);
  for (int f = 0; f < h.mesh.num_triangles(); ++f) {
    const Tri& t = h.mesh.triangles[f];
    ear_face[f] = in_ear[t[0]] && in_ear[t[1]] && in_ear[t[2]];
  }
  REQUIRE(fine.num_triangles() == 64 * h.mesh.num_triangles());
  out.angles = normal_angles(fine, [&](int f0, int f1) { return ear_face[f0 / 64] && ear_face[f1 / 64]; });
  REQUIRE(out.angles.size() > 5000);
  std::vector<std::array<int, 2>> pairs;
  REQUIRE(find_self_intersections(fine, pairs).ok());
  for (const auto& p : pairs) out.crossing_pairs += ear_face[p[0] / 64] || ear_face[p[1] / 64] ? 1 : 0;
  return out;
}

}  // namespace

TEST_CASE("generic head, ring ear: the smooth level 3 of the ears has no washboard", "[head]") {
  // Angle between the normals of adjacent level-3 triangles refined from
  // the ears' control faces: the plate ear's bowl (a vertical strip of
  // quads) refines into horizontal ripples; the ring ear's rows run round
  // the concha. Neither ear's smooth level 3 may cross itself (every fit
  // starts from it).
  const EarSmoothness plate = ear_smoothness(asset()), ring = ear_smoothness(ring_ear_head());
  INFO("plate ear: " << plate.angles.size() << " edges, normal angle median " << plate.at(0.5) << ", p75 "
                     << plate.at(0.75) << ", p95 " << plate.at(0.95) << ", worst " << plate.angles.back()
                     << " deg; crossing pairs " << plate.crossing_pairs);
  INFO("ring ear: " << ring.angles.size() << " edges, normal angle median " << ring.at(0.5) << ", p75 "
                    << ring.at(0.75) << ", p95 " << ring.at(0.95) << ", worst " << ring.angles.back()
                    << " deg; crossing pairs " << ring.crossing_pairs);
  // Measured: plate median 3.6, p75 8.7, p95 23.9 deg; ring 1.7 / 4.1 /
  // 16.6 (the ring ear has 1.47x the edges, which alone would make its
  // angles ~0.8x, not 0.5x). Its worst, 124 deg, is the helix rim's edge.
  CHECK(ring.crossing_pairs == 0);
  CHECK(plate.crossing_pairs == 0);
  CHECK(ring.at(0.5) < 2.5);
  CHECK(ring.at(0.75) < 6.0);
  CHECK(ring.at(0.95) < 20.0);
}

TEST_CASE("generic head mirrors its connectivity and annotations too", "[head]") {
  // Issue 35: every vertex has its partner in x = 0 (exactly, the builder
  // copies one side onto the other), every triangle its mirrored triangle
  // (opposite winding), and the annotations map onto themselves: left
  // regions onto right ones, the others onto themselves, the boxes and
  // their landmarks, rims, creases and binding edges likewise.
  const GenericHead& h = asset();
  const TriMesh& m = h.mesh;
  const HeadAnnotations& a = h.annotations;
  const int n = m.num_vertices();
  std::vector<int> mirror(n, -1);
  std::map<std::array<long long, 3>, int> at;  // positions in 0.1 um steps
  auto key = [](const Vec3& p) {
    return std::array<long long, 3>{std::llround(p.x() * 1e7), std::llround(p.y() * 1e7), std::llround(p.z() * 1e7)};
  };
  for (int v = 0; v < n; ++v) at[key(m.positions[v])] = v;
  REQUIRE(at.size() == size_t(n));  // no two vertices at one place
  for (int v = 0; v < n; ++v) {
    const auto it = at.find(key(Vec3(-m.positions[v].x(), m.positions[v].y(), m.positions[v].z())));
    if (it != at.end()) mirror[v] = it->second;
  }
  int unpaired = 0;
  for (int v = 0; v < n; ++v) unpaired += mirror[v] < 0;
  REQUIRE(unpaired == 0);
  CHECK(triangles_without_mirror(m, std::vector<char>(n, 1)) == 0);
  {
    // Each side's quads split by their own shape: symmetric quads, whose
    // diagonals tie, split the same way on both sides (the asset before).
    GenericHeadBuildOptions by_side;
    by_side.mirror_diagonals = false;
    const GenericHead old = test::built_generic_head(by_side);
    CHECK(triangles_without_mirror(old.mesh, std::vector<char>(old.mesh.num_vertices(), 1)) > 0);
  }
  auto mirrored = [&](std::vector<int> ids) {
    for (int& v : ids) v = mirror[v];
    std::sort(ids.begin(), ids.end());
    return ids;
  };
  auto sorted = [](std::vector<int> ids) {
    std::sort(ids.begin(), ids.end());
    return ids;
  };
  auto other_side = [](const std::string& name) {
    for (auto [l, r] : {std::pair<std::string, std::string>{"_left", "_right"}, {"_right", "_left"}}) {
      const size_t k = name.rfind(l);
      if (k != std::string::npos && k + l.size() == name.size()) return name.substr(0, k) + r;
    }
    return name;
  };
  for (const auto& [name, ids] : a.regions) {
    INFO("region " << name);
    REQUIRE(a.regions.count(other_side(name)));
    CHECK(mirrored(ids) == sorted(a.regions.at(other_side(name))));
  }
  CHECK(mirrored(a.eye_left.rim) == sorted(a.eye_right.rim));
  CHECK(a.eye_left.center.isApprox(Vec3(-a.eye_right.center.x(), a.eye_right.center.y(), a.eye_right.center.z())));
  CHECK(mirrored(a.constrained_vertices) == sorted(a.constrained_vertices));
  for (const FeatureBox& b : a.boxes) {
    INFO("box " << b.name);
    const FeatureBox& o = box_named(a, other_side(b.name));
    CHECK(b.min.x() == Approx(-o.max.x()).margin(1e-9));
    CHECK(b.max.x() == Approx(-o.min.x()).margin(1e-9));
    CHECK(mirrored(b.landmarks) == sorted(o.landmarks));
  }
  for (const CreaseCurve& c : a.creases) {
    INFO("crease " << c.name);
    bool found = false;
    for (const CreaseCurve& o : a.creases)
      found = found || (o.closed == c.closed && mirrored(c.vertices) == sorted(o.vertices));
    CHECK(found);
  }
  std::set<std::array<int, 2>> binding;
  for (const auto& e : a.binding_edges) binding.insert({std::min(e[0], e[1]), std::max(e[0], e[1])});
  int binding_unmatched = 0;
  for (const auto& e : binding)
    binding_unmatched += binding.count({std::min(mirror[e[0]], mirror[e[1]]), std::max(mirror[e[0]], mirror[e[1]])}) ? 0 : 1;
  CHECK(binding_unmatched == 0);
}

TEST_CASE("generic head, faired skin or wide mouth ring: no smooth level from 0 to 3 crosses itself", "[head]") {
  // Issue 35 asks for 0 self-intersecting pairs at every level of the
  // smooth hierarchy (rim creases, as the fit refines). The asset (the skin
  // as cast) has 8 at level 2 and 24 at level 3, all at the outer mouth
  // corners, where the first ring round the mouth is cast 4.5 mm past the
  // lip line and lands 0.3 mm from the mouth bag. Neither 3 fairing passes
  // (GenericHeadBuildOptions::fair_iterations) nor the ring cast 8 mm past
  // the lip line (wide_mouth_ring) crosses at any level; neither is the
  // asset's (docs/design/generic_head.md).
  HeadSurfaceQuality asset_q, faired_q, wide_q;
  REQUIRE(measure_head_surface(asset(), 3, asset_q).ok());
  GenericHeadBuildOptions faired, wide;
  faired.fair_iterations = 3;
  wide.wide_mouth_ring = true;
  REQUIRE(measure_head_surface(test::built_generic_head(faired), 3, faired_q).ok());
  REQUIRE(measure_head_surface(test::built_generic_head(wide), 3, wide_q).ok());
  REQUIRE(faired_q.crossing_pairs.size() == 4u);
  REQUIRE(wide_q.crossing_pairs.size() == 4u);
  for (int l = 0; l <= 3; ++l) {
    INFO("level " << l << ": asset " << asset_q.crossing_pairs[l] << " pairs, faired " << faired_q.crossing_pairs[l]
                  << ", wide mouth ring " << wide_q.crossing_pairs[l]);
    CHECK(faired_q.crossing_pairs[l] == 0);
    CHECK(wide_q.crossing_pairs[l] == 0);
    CHECK(asset_q.crossing_pairs[l] <= (l == 3 ? 24 : l == 2 ? 8 : 0));
  }
  CHECK(asset_q.crossing_pairs[3] > 0);
}

TEST_CASE("generic head, faired skin: its smooth level 3 is less furrowed at the brows, cheeks and mouth", "[head]") {
  // The furrows over the brows, under the eyes and across the cheeks of the
  // smooth level 3 were the interpolating Butterfly's, on a grid bent round
  // the eye and mouth rings (the shape itself is smooth there); the
  // builder's fairing (fair_iterations 3, not the asset's) evens the skin's
  // control vertices on the shape. The dihedral roughness of the level 3
  // (head/surface_quality.h), the asset (the skin as cast) -> faired, measured (deg, p95 / p99 / max): cheeks 2.64 / 3.44 /
  // 8.04 -> 2.40 / 3.06 / 6.87, brow 8.79 / 15.23 / 26.49 -> 7.07 / 11.59 /
  // 21.89, mouth 9.66 / 17.91 / 38.05 -> 7.11 / 10.25 / 18.43. The bounds
  // sit between, so the asset fails each. (The eyes' figures are not
  // bounded: their region, skin within 22 mm of the eyeball, counts other
  // edges once the ring moves.)
  GenericHeadBuildOptions faired;
  faired.fair_iterations = 3;
  const GenericHead faired_head = test::built_generic_head(faired);
  HeadSurfaceQuality now, cast_q;
  REQUIRE(measure_head_surface(faired_head, 3, now).ok());
  REQUIRE(measure_head_surface(asset(), 3, cast_q).ok());
  auto region = [](const HeadSurfaceQuality& q, const std::string& name) {
    for (const RegionRoughness& r : q.regions)
      if (r.region == name) return r;
    FAIL("no region " << name);
    return RegionRoughness{};
  };
  struct Bound {
    const char* region;
    double p95, p99, max;  // deg
  };
  for (const Bound& b : {Bound{"cheeks", 2.55, 3.3, 7.5}, Bound{"brow", 8.0, 13.5, 24.0},
                         Bound{"mouth", 8.5, 13.0, 25.0}}) {
    const RegionRoughness r = region(now, b.region), before = region(cast_q, b.region);
    INFO(b.region << ": p95 / p99 / max " << r.p95_deg << " / " << r.p99_deg << " / " << r.max_deg
                  << " deg, the skin as cast " << before.p95_deg << " / " << before.p99_deg << " / "
                  << before.max_deg);
    CHECK(r.edges > 1000);
    CHECK(r.p95_deg < b.p95);
    CHECK(r.p99_deg < b.p99);
    CHECK(r.max_deg < b.max);
    CHECK((before.p95_deg >= b.p95 || before.p99_deg >= b.p99 || before.max_deg >= b.max));
  }
  // The fairing leaves the midline, the head's profile (nasion, bridge,
  // nose tip, lips, chin), where it was cast.
  const GenericHead& h = faired_head;
  const GenericHead& cast_head = asset();
  double most = 0;
  for (int v = 0; v < h.mesh.num_vertices(); ++v)
    if (std::abs(h.mesh.positions[v].x()) < 1e-9)
      most = std::max(most, (h.mesh.positions[v] - cast_head.mesh.positions[v]).norm());
  CHECK(most < 1e-9);  // the midline (the profile) does not move
}

TEST_CASE("generic head, faired skin with the rings round the rims kept: those rings stay as cast", "[head]") {
  // GenericHeadBuildOptions::fair_keep_rim_rings (session 50): the faired
  // fits depart where the fairing moved the vertices next to the eye rims
  // and lip lines (docs/design/generic_head.md); with 1 ring kept, every
  // neighbour of a crease vertex is where the skin was cast, and the
  // fairing still moves the skin farther out.
  GenericHeadBuildOptions kept;
  kept.fair_iterations = 3;
  kept.fair_keep_rim_rings = 1;
  const GenericHead head = test::built_generic_head(kept);
  REQUIRE(head.alignment_positions.size() == head.mesh.positions.size());
  const int nv = head.mesh.num_vertices();
  std::vector<char> crease(nv, 0), ring(nv, 0);
  for (const auto& curve : head.annotations.creases)
    for (int v : curve.vertices) crease[v] = 1;
  for (const Tri& t : head.mesh.triangles)
    for (int k = 0; k < 3; ++k)
      if (crease[t[k]]) ring[t[(k + 1) % 3]] = ring[t[(k + 2) % 3]] = 1;
  int ring_moved = 0, ring_count = 0, moved_elsewhere = 0;
  for (int v = 0; v < nv; ++v) {
    const bool moved = head.mesh.positions[v] != head.alignment_positions[v];
    if (ring[v] || crease[v]) ring_count += ring[v], ring_moved += moved;
    else moved_elsewhere += moved;
  }
  CHECK(ring_count > 0);
  CHECK(ring_moved == 0);
  CHECK(moved_elsewhere > 0);
}
