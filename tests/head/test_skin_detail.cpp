// The generic head's skin detail (head/skin_detail.h): the displacements
// that put its smooth Butterfly levels back on the shape it was cast from,
// on the skin only. Would fail if the detail were measured on the wrong side
// of the normal, left the cast shape's nose tip or the pockets in, left the
// lips, the bridge or the nose's base out, or raised a crossing.
#include "head/generic_head.h"
#include "head/head_creases.h"
#include "head/head_pockets.h"
#include "head/head_shape.h"
#include "head/skin_detail.h"
#include "head/surface_quality.h"
#include "mesh/topology.h"
#include "multires/multires.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>

using namespace lk;

namespace {

const GenericHead& asset() {
  static const GenericHead head = [] {
    GenericHead h;
    REQUIRE(load_generic_head(h));
    return h;
  }();
  return head;
}

const RegionRoughness& roughness(const HeadSurfaceQuality& q, const std::string& region) {
  for (const RegionRoughness& r : q.regions)
    if (r.region == region) return r;
  FAIL("no region " << region);
  return q.regions.front();
}

double roughness_p95(const HeadSurfaceQuality& q, const std::string& region) { return roughness(q, region).p95_deg; }

}  // namespace

TEST_CASE("skin detail: the generic head's levels back on its cast shape, on the skin only") {
  const GenericHead& head = asset();
  std::vector<std::vector<double>> detail;
  REQUIRE(generic_skin_detail(head, 3, SkinDetailOptions{}, detail));
  REQUIRE(detail.size() == 4);
  for (double d : detail[0]) CHECK(d == 0.0);

  MeshTopology topo;
  REQUIRE(build_topology(head.mesh, topo));
  MultiresMesh plain, displaced;
  const ButterflyCreases creases = head_creases(head.mesh, topo, head.annotations);
  REQUIRE(build_multires(head.mesh, creases, 3, plain));
  REQUIRE(build_multires(head.mesh, creases, 3, displaced));
  REQUIRE(apply_skin_detail(detail, displaced));

  // Control vertices keep their index on every level: the ears, the lip
  // lines, the mouth corners with their one-rings, the pockets and the
  // nose's lower half above its base (tip and wings) take no detail; the
  // nose's upper half (the bridge), its base on the upper lip and the lips
  // off their lines are skin.
  std::vector<char> off = pocket_vertices(topo, head.annotations);
  for (int v : head.annotations.regions.at("ears")) off[size_t(v)] = 1;
  for (const CreaseCurve& c : head.annotations.creases)
    if (c.name.find("lip_line") != std::string::npos) {
      for (int v : c.vertices) off[size_t(v)] = 1;
      for (int corner : {c.vertices.front(), c.vertices.back()})
        for (int w : topo.rings[size_t(corner)]) off[size_t(w)] = 1;
    }
  int lips_detailed = 0;
  for (int v : head.annotations.regions.at("lips"))
    if (!off[size_t(v)] && std::abs(detail[1][size_t(v)]) > 1e-5) ++lips_detailed;
  CHECK(lips_detailed > 0);
  const std::vector<int>& nose = head.annotations.regions.at("nose");
  double low = 1e9, high = -1e9;
  for (int v : nose) {
    low = std::min(low, head.mesh.positions[size_t(v)].y());
    high = std::max(high, head.mesh.positions[size_t(v)].y());
  }
  std::vector<char> bridge(size_t(topo.num_vertices), 0), base(size_t(topo.num_vertices), 0);
  for (int v : nose) {
    const double y = head.mesh.positions[size_t(v)].y();
    if (y > 0.5 * (low + high)) bridge[size_t(v)] = 1;
    else if (y <= low + 0.1 * (high - low)) base[size_t(v)] = 1;
    else off[size_t(v)] = 1;
  }
  for (int l = 1; l <= 3; ++l)
    for (int v = 0; v < topo.num_vertices; ++v)
      if (off[size_t(v)]) CHECK(detail[size_t(l)][size_t(v)] == 0.0);

  // Where it is set, level 3 lies on the shape: at least 4 times closer.
  const HeadShape shape;
  double before = 0, after = 0, largest = 0;
  int n = 0;
  for (size_t v = 0; v < detail[3].size(); ++v) {
    if (detail[3][v] == 0.0) continue;
    before += std::abs(shape.distance(plain.state.displaced[3][v]));
    after += std::abs(shape.distance(displaced.state.displaced[3][v]));
    largest = std::max(largest, std::abs(detail[3][v]));
    ++n;
  }
  REQUIRE(n > 20000);  // most of the face, scalp and neck
  INFO("mean |distance| to the shape, level 3: " << 1e3 * before / n << " -> " << 1e3 * after / n << " mm over " << n
                                                 << " vertices; largest detail " << 1e3 * largest << " mm");
  CHECK(after * 4 < before);
  CHECK(largest <= 0.5 * SkinDetailOptions{}.max_distance);  // the taper peaks at half of it

  // The refined vertices of the nose's bridge and of its base on the upper
  // lip come onto the shape too (left out, they kept the levels' furrows up
  // to the glabella and over the philtrum).
  const auto closer = [&](const std::vector<char>& control, const char* name, int at_least) {
    const std::vector<char> mask3 = propagate_vertex_mask(plain, control)[3];
    double before_m = 0, after_m = 0;
    int count = 0;
    for (size_t v = size_t(topo.num_vertices); v < mask3.size(); ++v) {
      if (!mask3[v]) continue;
      before_m += std::abs(shape.distance(plain.state.displaced[3][v]));
      after_m += std::abs(shape.distance(displaced.state.displaced[3][v]));
      ++count;
    }
    INFO(name << "'s level 3: mean |distance| " << 1e3 * before_m / std::max(count, 1) << " -> "
              << 1e3 * after_m / std::max(count, 1) << " mm over " << count << " vertices");
    REQUIRE(count > at_least);
    CHECK(after_m * 2 < before_m);
  };
  closer(bridge, "the bridge", 50);
  closer(base, "the nose's base", 20);

  // The furrows go: rougher cheeks and brow without it; no new crossing.
  HeadSurfaceQuality q_plain, q_detail;
  REQUIRE(measure_head_surface(head, creases, 3, q_plain));
  REQUIRE(measure_head_surface(head, creases, 3, q_detail, &detail));
  // The cheeks' furrows go (p95 2.64 -> 2.35 deg); the brow's p95 rises
  // (8.8 -> 9.5 deg): the shape's own lid fold under the brow, sharper
  // than the levels' (docs/design/generic_head.md, "The skin detail"). Its
  // p99 stays (15.2): with the detail cut off hard at 2 mm, the pleats at
  // the outer eye corners raised it to 21.9.
  INFO("cheeks p95 " << roughness_p95(q_plain, "cheeks") << " -> " << roughness_p95(q_detail, "cheeks")
                     << " deg, brow p95 " << roughness_p95(q_plain, "brow") << " -> "
                     << roughness_p95(q_detail, "brow") << ", p99 " << roughness(q_plain, "brow").p99_deg << " -> "
                     << roughness(q_detail, "brow").p99_deg);
  CHECK(roughness_p95(q_detail, "cheeks") < 0.92 * roughness_p95(q_plain, "cheeks"));
  CHECK(roughness_p95(q_detail, "brow") < 1.15 * roughness_p95(q_plain, "brow"));
  CHECK(roughness(q_detail, "brow").p99_deg < 1.1 * roughness(q_plain, "brow").p99_deg);
  for (int l = 0; l <= 3; ++l) {
    INFO("level " << l);
    CHECK(q_detail.crossing_pairs[size_t(l)] <= q_plain.crossing_pairs[size_t(l)]);
  }
}

TEST_CASE("skin detail: a head of another topology is refused, the options are checked") {
  const GenericHead& head = asset();
  std::vector<std::vector<double>> detail;
  REQUIRE(generic_skin_detail(head, 2, SkinDetailOptions{}, detail));
  TriMesh tetra;
  tetra.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  tetra.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  MultiresMesh other;
  REQUIRE(build_multires(tetra, 2, other));
  const Status s = apply_skin_detail(detail, other);
  CHECK(s.code == ErrorCode::InvalidInput);
  SkinDetailOptions bad;
  bad.max_distance = 0;
  CHECK(generic_skin_detail(head, 2, bad, detail).code == ErrorCode::InvalidInput);
}
