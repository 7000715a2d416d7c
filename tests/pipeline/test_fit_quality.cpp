// The fit's quality checks (pipeline/fit_quality.h): crossing pairs by head
// region, turned-over and degenerate triangles.
#include "multires/multires.h"
#include "pipeline/fit_head.h"
#include "pipeline/fit_quality.h"
#include "head/head_creases.h"
#include "head/head_pockets.h"
#include "head/generic_head.h"
#include "head/generic_head_builder.h"

#include <algorithm>
#include <map>
#include "mesh/topology.h"
#include "raycast/self_intersection.h"

#include <catch2/catch.hpp>

using namespace lk;

namespace {

// Two unit squares crossing at right angles along the x axis: sheet A
// (vertices 0-3) in the plane z = 0, sheet B (4-7) in the plane y = 0.
TriMesh crossing_sheets() {
  TriMesh m;
  m.positions = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0},
                 {-1, 0, -1}, {1, 0, -1}, {1, 0, 1}, {-1, 0, 1}};
  m.triangles = {{0, 1, 2}, {0, 2, 3}, {4, 5, 6}, {4, 6, 7}};
  return m;
}

// m refined twice into mr, and the crossing pairs of its level 2 (some).
std::vector<std::array<int, 2>> level2_pairs(const TriMesh& m, MultiresMesh& mr) {
  REQUIRE(build_multires(m, 2, mr).ok());
  std::vector<std::array<int, 2>> pairs;
  REQUIRE(find_self_intersections(level_mesh(mr, 2), pairs).ok());
  REQUIRE(pairs.size() > 0);
  return pairs;
}

}  // namespace

TEST_CASE("crossing pairs are counted by the region they touch, lips before ears before rest", "[fit_quality]") {
  MultiresMesh mr;
  const std::vector<std::array<int, 2>> pairs = level2_pairs(crossing_sheets(), mr);
  const int n = static_cast<int>(pairs.size());

  HeadAnnotations ann;
  CrossingCounts c = count_crossings_by_region(mr, 2, pairs, ann);
  CHECK(c.total == n);
  CHECK(c.rest == n);
  CHECK(c.lips + c.ears == 0);

  // Sheet A is the ears, sheet B the nose: every pair has one triangle on
  // each sheet, so every pair is an ear pair.
  ann.regions["ears"] = {0, 1, 2, 3};
  ann.regions["nose"] = {4, 5, 6, 7};
  c = count_crossings_by_region(mr, 2, pairs, ann);
  CHECK(c.ears == n);
  CHECK(c.rest == 0);

  // Lips win over ears.
  ann.regions["lips"] = {4, 5, 6, 7};
  c = count_crossings_by_region(mr, 2, pairs, ann);
  CHECK(c.lips == n);
  CHECK(c.ears == 0);

  // Neither lips nor ears: rest, listed under the regions they touch.
  ann.regions.erase("lips");
  ann.regions.erase("ears");
  c = count_crossings_by_region(mr, 2, pairs, ann);
  CHECK(c.rest == n);
  CHECK(c.rest_by_region["nose"] == n);

  // Regions are carried down from the control mesh: the corners of sheet
  // B's triangle (4, 5, 6) hold the level-2 vertices inside it, which meet
  // sheet A on part of the crossing line only; the corners of its edge
  // (4, 5), far from the line, hold none that cross.
  ann.regions["lips"] = {4, 5};
  c = count_crossings_by_region(mr, 2, pairs, ann);
  CHECK(c.lips == 0);
  ann.regions["lips"] = {4, 5, 6};
  c = count_crossings_by_region(mr, 2, pairs, ann);
  CHECK(c.lips > 0);
  CHECK(c.lips < n);
  CHECK(count_pairs_touching(mr, 2, pairs, {4, 5, 6}) == c.lips);
  CHECK(count_pairs_touching(mr, 2, pairs, {4, 5}) == 0);
  CHECK(count_pairs_touching(mr, 2, pairs, {0, 1, 2, 3}) == n);
}

TEST_CASE("crossing pairs in an eye socket count as eye sockets, after lips and ears", "[fit_quality]") {
  // The crossing sheets and a small triangle far off (8, 9, 10). A rim loop
  // of vertex 8 alone cuts the mesh into sheet A, sheet B and (9, 10); all
  // but the largest (A, the first of equals) are the socket
  // (head/head_pockets.h), so every pair touches it.
  TriMesh m = crossing_sheets();
  m.positions.push_back({5, 5, 5});
  m.positions.push_back({6, 5, 5});
  m.positions.push_back({5, 6, 5});
  m.triangles.push_back({8, 9, 10});
  MultiresMesh mr;
  const std::vector<std::array<int, 2>> pairs = level2_pairs(m, mr);
  const int n = static_cast<int>(pairs.size());
  HeadAnnotations ann;
  ann.eye_left.rim = {8};
  MeshTopology topo;
  REQUIRE(build_topology(m, topo).ok());
  const std::vector<char> socket = eye_socket_vertices(topo, ann);
  CHECK(std::vector<char>(socket.begin(), socket.begin() + 4) == std::vector<char>(4, 0));  // A
  CHECK(std::vector<char>(socket.begin() + 4, socket.begin() + 8) == std::vector<char>(4, 1));  // B
  CHECK(socket[8] == 0);  // the rim is not inside
  CHECK(socket[9] == 1);
  CrossingCounts c = count_crossings_by_region(mr, 2, pairs, ann);
  CHECK(c.eye_sockets == n);
  CHECK(c.rest == 0);
  // Ears (and lips) are named first.
  ann.regions["ears"] = {0, 1, 2, 3};
  c = count_crossings_by_region(mr, 2, pairs, ann);
  CHECK(c.ears == n);
  CHECK(c.eye_sockets == 0);
  // No rim: no socket.
  ann.regions.clear();
  ann.eye_left.rim.clear();
  c = count_crossings_by_region(mr, 2, pairs, ann);
  CHECK(c.eye_sockets == 0);
  CHECK(c.rest == n);
}

TEST_CASE("the pockets: eye sockets, mouth bag and, on a head with nostrils, the nostrils' pockets but not their rims", "[fit_quality]") {
  GenericHeadBuildOptions options;
  options.nostrils = true;
  GenericHead h;
  REQUIRE(build_generic_head(options, h).ok());
  MeshTopology topo;
  REQUIRE(build_topology(h.mesh, topo).ok());
  const std::vector<char> pocket = pocket_vertices(topo, h.annotations);
  const std::vector<char> sockets = eye_socket_vertices(topo, h.annotations);
  int nostril_vertices = 0;
  for (const char* name : {"nostril_left", "nostril_right"})
    for (int v : h.annotations.regions.at(name)) {
      CHECK(pocket[v] == 1);
      CHECK(sockets[v] == 0);
      ++nostril_vertices;
    }
  CHECK(nostril_vertices > 0);
  for (const CreaseCurve& c : h.annotations.creases)
    if (c.name.rfind("nostril_rim", 0) == 0)
      for (int v : c.vertices) CHECK(pocket[v] == 0);
  // Nothing else: the rest are the sockets and the mouth bag.
  std::vector<char> expected = sockets;
  for (int v : h.annotations.constrained_vertices) expected[v] = 1;
  for (const char* name : {"nostril_left", "nostril_right"})
    for (int v : h.annotations.regions.at(name)) expected[v] = 1;
  CHECK(pocket == expected);
}

TEST_CASE("turned-over and degenerate triangles are counted against a reference", "[fit_quality]") {
  const TriMesh ref = crossing_sheets();
  int flipped = -1, degenerate = -1;
  count_turned_and_degenerate(ref, ref, flipped, degenerate);
  CHECK(flipped == 0);
  CHECK(degenerate == 0);

  TriMesh m = ref;
  m.positions[6] = {1, 0, -1.5};  // triangle 2 (4, 5, 6) now faces the other way; (4, 6, 7) keeps facing +y
  count_turned_and_degenerate(m, ref, flipped, degenerate);
  CHECK(flipped == 1);
  CHECK(degenerate == 0);

  m = ref;
  m.positions[2] = m.positions[0];  // triangles (0, 1, 2) and (0, 2, 3) get a repeated corner: zero area
  count_turned_and_degenerate(m, ref, flipped, degenerate);
  CHECK(degenerate == 2);
}

TEST_CASE("fit quality of a fit result: crossings of the displaced and the smooth level, control mesh", "[fit_quality]") {
  FitHeadResult fit;
  FitQuality q;
  CHECK(measure_fit_quality(fit, HeadAnnotations(), q).code == ErrorCode::InvalidInput);

  fit.control = crossing_sheets();
  REQUIRE(build_multires(fit.control, 2, fit.multires).ok());
  REQUIRE(measure_fit_quality(fit, HeadAnnotations(), q).ok());
  CHECK(q.level == 2);
  CHECK(q.triangles == 4 * 16);
  CHECK(q.flipped == 0);
  CHECK(q.degenerate == 0);
  CHECK(q.control_crossings > 0);
  CHECK(q.crossings.total > 0);
  CHECK(q.crossings.total == q.smooth_crossings.total);  // no displacements: the same surface
}

TEST_CASE("head creases: the curves as tagged edges, and the eye openings' corners as crease corners", "[fit_quality]") {
  GenericHead head;
  REQUIRE(load_generic_head(head).ok());
  const HeadAnnotations& ann = head.annotations;
  ButterflyCreases plain;
  for (const CreaseCurve& c : ann.creases) add_crease_polyline(c.vertices, c.closed, plain);
  const ButterflyCreases creases = head_creases(head.mesh, ann);
  // The curves first, then each eye's socket ring: edges between two
  // vertices next to its rim, not on it, forming one closed loop per eye
  // (every ring vertex on two ring edges, so no new corner).
  REQUIRE(creases.edges.size() > plain.edges.size());
  CHECK(std::equal(plain.edges.begin(), plain.edges.end(), creases.edges.begin()));
  std::map<int, int> ring_edges_at;
  for (std::size_t i = plain.edges.size(); i < creases.edges.size(); ++i)
    for (int v : creases.edges[i]) ++ring_edges_at[v];
  for (const EyeSocket* eye : {&ann.eye_left, &ann.eye_right}) {
    int ring_vertices = 0;
    for (const auto& [v, count] : ring_edges_at) {
      if (std::find(eye->rim.begin(), eye->rim.end(), v) != eye->rim.end()) FAIL("a ring vertex on the rim");
      bool next_to_rim = false;
      for (const Tri& t : head.mesh.triangles)
        if (std::find(t.begin(), t.end(), v) != t.end())
          for (int w : t) next_to_rim = next_to_rim || std::find(eye->rim.begin(), eye->rim.end(), w) != eye->rim.end();
      if (!next_to_rim) continue;  // the other eye's ring
      ++ring_vertices;
      CHECK(count == 2);
    }
    CHECK(ring_vertices >= static_cast<int>(eye->rim.size()) / 2);
  }
  // Each rim's corners: the vertices furthest along -x and +x (the inner and
  // outer canthus), and nothing else new.
  for (const EyeSocket* eye : {&ann.eye_left, &ann.eye_right}) {
    REQUIRE(eye->rim.size() >= 6);
    auto by_x = [&](int a, int b) { return head.mesh.positions[a].x() < head.mesh.positions[b].x(); };
    const int lo = *std::min_element(eye->rim.begin(), eye->rim.end(), by_x);
    const int hi = *std::max_element(eye->rim.begin(), eye->rim.end(), by_x);
    CHECK(std::count(creases.corners.begin(), creases.corners.end(), lo) == 1);
    CHECK(std::count(creases.corners.begin(), creases.corners.end(), hi) == 1);
    // An eye is ~25-30 mm wide between its corners.
    const double width = head.mesh.positions[hi].x() - head.mesh.positions[lo].x();
    CHECK(width > 0.02);
    CHECK(width < 0.035);
  }
  std::vector<int> plain_corners = plain.corners;  // the lip lines' ends (the mouth corners, each twice)
  std::sort(plain_corners.begin(), plain_corners.end());
  plain_corners.erase(std::unique(plain_corners.begin(), plain_corners.end()), plain_corners.end());
  CHECK(creases.corners.size() == plain_corners.size() + 4);
  // The levels refine with them: the 4-point rule does not reach past a
  // corner, so the rim's new vertices next to the corners move.
  std::vector<ButterflyLevel> with, without;
  REQUIRE(build_butterfly_levels(head.mesh, creases, 1, with).ok());
  REQUIRE(build_butterfly_levels(head.mesh, plain, 1, without).ok());
  std::vector<std::vector<Vec3>> a, b;
  REQUIRE(apply_all(with, head.mesh.positions, a).ok());
  REQUIRE(apply_all(without, head.mesh.positions, b).ok());
  CHECK(a.back() != b.back());
}

TEST_CASE("distance colours: near white to 0.25 mm, yellow at 1 mm, red from 3 mm, another colour where unmeasured",
          "[fit_quality]") {
  const std::vector<Vec3> c = distance_colors({0.0, 0.0002, 0.001, 0.002, 0.003, 0.01, -1.0});
  REQUIRE(c.size() == 7);
  CHECK(c[0].isApprox(c[1]));                         // within 0.25 mm: one colour
  CHECK(c[2].x() > c[2].z() + 0.5);                   // yellow: red and green, no blue
  CHECK(c[2].y() > c[2].z() + 0.5);
  CHECK(c[4].isApprox(c[5]));                         // 3 mm and beyond: the same red
  CHECK(c[4].x() > 0.5);
  CHECK(c[4].y() < 0.1);
  CHECK(c[3].y() < c[2].y());                         // 2 mm between yellow and red
  CHECK(c[3].y() > c[4].y());
  CHECK((c[6] - c[0]).norm() > 0.3);                  // unmeasured stands apart from "close"
  CHECK(c[6].z() > c[6].x());
}
