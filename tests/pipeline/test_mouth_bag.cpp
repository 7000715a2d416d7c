// The mouth bag follows its lips after global fitting (fit_head.h,
// carry_mouth_bag): lips pulled back past the held bag made the bag's wall
// come out through the skin (Fran's mouth corner: 35 crossing pairs on her
// smooth level 3), and a carried bag keeps its shape behind them.
#include "mesh/topology.h"
#include "pipeline/fit_head.h"
#include "smooth_pairs.h"
#include "test_scan.h"

#include <catch2/catch.hpp>

using namespace lk;

namespace {

std::vector<char> bag_flags(const GenericHead& head) {
  std::vector<char> bag(head.mesh.num_vertices(), 0);
  for (int v : head.annotations.constrained_vertices) bag[v] = 1;
  return bag;
}

// The skin around the mouth moved by `shift` (full within `inner` of the
// mouth centre, fading out by `outer`), the bag held where it was: what
// global fitting hands over when the scan's lips lie behind the template's.
TriMesh lips_moved(const GenericHead& head, const Vec3& shift, double inner, double outer) {
  TriMesh moved = head.mesh;
  const std::vector<char> bag = bag_flags(head);
  for (int v = 0; v < moved.num_vertices(); ++v) {
    if (bag[v]) continue;
    const double d = (moved.positions[v] - head.annotations.mouth_center).norm();
    const double u = std::clamp((d - inner) / (outer - inner), 0.0, 1.0);
    moved.positions[v] += (1 - u * u * (3 - 2 * u)) * shift;
  }
  return moved;
}

}  // namespace

TEST_CASE("carry_mouth_bag: lips moved as one carry the bag unchanged") {
  const GenericHead& head = test::generic_head();
  MeshTopology topo;
  REQUIRE(build_topology(head.mesh, topo).ok());
  const Vec3 shift(0.001, -0.002, -0.004);
  TriMesh moved = lips_moved(head, shift, 0.06, 0.08);  // everything near the mouth moves alike
  REQUIRE(carry_mouth_bag(bag_flags(head), topo, head.mesh, moved).ok());
  double worst = 0;
  for (int v : head.annotations.constrained_vertices)
    worst = std::max(worst, (moved.positions[v] - head.mesh.positions[v] - shift).norm());
  INFO("largest bag vertex error " << worst << " m");
  CHECK(worst < 1e-12);
}

TEST_CASE("carry_mouth_bag: lips pulled 4 mm back no longer cross the bag on the smooth level 3") {
  const GenericHead& head = test::generic_head();
  MeshTopology topo;
  REQUIRE(build_topology(head.mesh, topo).ok());
  // The generic head's own smooth level 3 has pairs at the mouth corners;
  // only new ones count.
  const int generic_pairs = test::smooth_region_pairs(head.mesh, head, 3, "lips");
  TriMesh held = lips_moved(head, Vec3(0, 0, -0.004), 0.02, 0.04);
  const int held_pairs = test::smooth_region_pairs(held, head, 3, "lips");
  TriMesh carried = held;
  REQUIRE(carry_mouth_bag(bag_flags(head), topo, head.mesh, carried).ok());
  const int carried_pairs = test::smooth_region_pairs(carried, head, 3, "lips");
  INFO("lip pairs on smooth level 3: generic " << generic_pairs << ", lips moved with the bag held " << held_pairs
                                                << ", bag carried " << carried_pairs);
  CHECK(held_pairs > generic_pairs + 20);
  CHECK(carried_pairs <= generic_pairs);
  // Skin vertices are not touched.
  const std::vector<char> bag = bag_flags(head);
  for (int v = 0; v < head.mesh.num_vertices(); ++v)
    if (!bag[v]) REQUIRE(carried.positions[v] == held.positions[v]);
}

TEST_CASE("carry_mouth_bag: inputs of different sizes are refused") {
  const GenericHead& head = test::generic_head();
  MeshTopology topo;
  REQUIRE(build_topology(head.mesh, topo).ok());
  TriMesh moved = head.mesh;
  std::vector<char> short_flags(10, 0);
  CHECK(carry_mouth_bag(short_flags, topo, head.mesh, moved).code == ErrorCode::InvalidInput);
  TriMesh fewer = head.mesh;
  fewer.positions.pop_back();
  CHECK(carry_mouth_bag(bag_flags(head), topo, fewer, moved).code == ErrorCode::InvalidInput);
}
