// The step where the data ends (DisplacementOptions::edge_fade_control_edges,
// core/multires/displacement.h): a scan patch that stops above a control
// surface lying a known height below it. Without the fade, the level-3
// surface drops from the data to the control surface across about one
// level-3 edge (a ledge); with it, the drop is spread over the fade's width
// (one control edge here) and the surface inside the patch still meets the
// data.
#include "multires/displacement.h"
#include "multires/multires.h"

#include "../subdiv/shapes.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>

using namespace lk;
using namespace lk::test;

namespace {

constexpr double kHeight = 0.1;  // the data's plane above the control plane z = 0
constexpr double kDataEnd = 8;   // by default the data covers x < kDataEnd

// Noise-free samples 0.05 apart of the plane z = kHeight over
// [0, end) x [0, 8].
PointCloud plane_patch(double end = kDataEnd) {
  PointCloud c;
  for (double x = 0.025; x < end; x += 0.05)
    for (double y = 0.025; y < 8; y += 0.05) c.positions.push_back(Vec3(x, y, kHeight));
  return c;
}

struct EdgeProfile {
  double max_slope = 0;       // steepest level-3 face (|dz| per unit across), away from the y borders
  double inside_error = 0;    // max |z - kHeight| of level-3 vertices well inside the data
  double far_max = 0;         // max |z| of level-3 vertices far beyond the edge
  int inside = 0, far = 0;
};

EdgeProfile profile(const MultiresMesh& mr, double end) {
  const TriMesh m = level_mesh(mr, mr.num_levels());
  EdgeProfile p;
  for (const Tri& t : m.triangles) {
    const Vec3 c = (m.positions[t[0]] + m.positions[t[1]] + m.positions[t[2]]) / 3.0;
    if (c.y() < 2 || c.y() > 6 || c.x() < 1 || c.x() > 15) continue;  // away from the grid's own border
    const Vec3 n = (m.positions[t[1]] - m.positions[t[0]]).cross(m.positions[t[2]] - m.positions[t[0]]);
    p.max_slope = std::max(p.max_slope, std::hypot(n.x(), n.y()) / std::abs(n.z()));
  }
  for (const Vec3& v : m.positions) {
    if (v.y() < 2 || v.y() > 6) continue;
    if (v.x() > 1.5 && v.x() < end - 1.5) p.inside_error = std::max(p.inside_error, std::abs(v.z() - kHeight)), ++p.inside;
    if (v.x() > end + 4.5) p.far_max = std::max(p.far_max, std::abs(v.z())), ++p.far;
  }
  return p;
}

}  // namespace

TEST_CASE("edge fade: the drop from the data to the control surface is a slope, not a ledge",
          "[multires][displacement]") {
  // A flat 16 x 8 control grid (edges 1, level-3 edges 1/8); the data is
  // the plane z = 0.1 over x < end only, the edge on a control vertex
  // column and between two. Without the fade, the finer levels pull their
  // vertices up to the data's edge and the coarser surface beyond it drops
  // 0.05 over a level-3 edge: a slope of ~0.4 (measured 0.40 / 0.42). The
  // fade (two control edges of ~1.14) spreads the drop: a smoothstep over
  // that width peaks at 1.5 x 0.1 / 2.28 = 0.066; measured 0.18 / 0.16,
  // the carried values being the levels' own, each faded on its own.
  for (double end : {8.0, 8.45}) {
    const PointCloud cloud = plane_patch(end);
    MultiresMesh faded, ledge;
    REQUIRE(build_multires(regular_grid(16, 8), 3, faded).ok());
    REQUIRE(build_multires(regular_grid(16, 8), 3, ledge).ok());
    DisplacementStats stats;
    REQUIRE(measure_displacements(cloud, DisplacementOptions{}, faded, &stats).ok());
    DisplacementOptions off;
    off.edge_fade_control_edges = 0;
    REQUIRE(measure_displacements(cloud, off, ledge).ok());
    const EdgeProfile f = profile(faded, end), s = profile(ledge, end);
    INFO("data end " << end << ": faded: max slope " << f.max_slope << ", inside error " << f.inside_error << ", far "
                     << f.far_max << "; without the fade: max slope " << s.max_slope << ", inside error "
                     << s.inside_error << "; fade width " << stats.edge_fade_width);
    REQUIRE(f.inside > 100);
    REQUIRE(f.far > 50);
    CHECK(s.max_slope > 0.35);                // the ledge this guards against
    CHECK(f.max_slope < 0.25);                // spread over the fade's width
    CHECK(f.max_slope < 0.5 * s.max_slope);
    CHECK(f.inside_error < 0.05 * kHeight);   // the data's interior still meets the data
    CHECK(s.inside_error < 0.05 * kHeight);
    CHECK(f.far_max < 1e-3 * kHeight);        // beyond the fade: the control surface
    CHECK(stats.faded[3] > 0);
  }
}

TEST_CASE("edge fade: supported vertices keep their measurement, the fade only adds beyond the data",
          "[multires][displacement]") {
  const PointCloud cloud = plane_patch();
  MultiresMesh faded, ledge;
  REQUIRE(build_multires(regular_grid(16, 8), 3, faded).ok());
  REQUIRE(build_multires(regular_grid(16, 8), 3, ledge).ok());
  // Two control edges wide: the control vertex on the data's edge (one
  // edge from the last fully supported one) gets half the carried value.
  DisplacementOptions wide;
  wide.edge_fade_control_edges = 2;
  REQUIRE(measure_displacements(cloud, wide, faded).ok());
  DisplacementOptions off;
  off.edge_fade_control_edges = 0;
  REQUIRE(measure_displacements(cloud, off, ledge).ok());
  // Level 0 is measured on the same base in both: a fully supported
  // control vertex keeps its displacement exactly, one without full
  // support only gains (the data lies above), and within the fade's reach.
  REQUIRE(faded.data_support.size() == static_cast<size_t>(faded.num_vertices(3)));
  int kept = 0, gained = 0;
  for (int v = 0; v < faded.num_vertices(0); ++v) {
    const double x = faded.control[v].x(), y = faded.control[v].y();
    if (x < 1 || y < 1 || y > 7) continue;  // the grid's border is a data edge too
    if (faded.data_support[v] >= 1) {
      CHECK(faded.displacements[0][v] == ledge.displacements[0][v]);
      ++kept;
    } else if (faded.displacements[0][v] != ledge.displacements[0][v]) {
      CHECK(faded.displacements[0][v] > ledge.displacements[0][v]);
      CHECK(x >= kDataEnd - 1);
      CHECK(x < kDataEnd + 2);
      ++gained;
    }
  }
  CHECK(kept > 30);
  CHECK(gained > 0);
}

TEST_CASE("edge fade: local update still equals a full recompute", "[multires][displacement]") {
  MultiresMesh mr;
  REQUIRE(build_multires(regular_grid(16, 8), 3, mr).ok());
  REQUIRE(measure_displacements(plane_patch(), DisplacementOptions{}, mr).ok());
  // A control vertex at the data's edge, where the fade acts.
  int moved = -1;
  for (int v = 0; v < mr.num_vertices(0); ++v)
    if (mr.control[v].x() == kDataEnd && mr.control[v].y() == 4) moved = v;
  REQUIRE(moved >= 0);
  const Vec3 to = mr.control[moved] + Vec3(0.05, -0.03, 0.2);
  REQUIRE(update_control_vertices(mr, {moved}, {to}).ok());
  MultiresMesh full = mr;
  REQUIRE(evaluate(full).ok());
  for (int l = 0; l <= 3; ++l) CHECK(full.state.displaced[l] == mr.state.displaced[l]);
}

TEST_CASE("edge fade: bad widths are refused", "[multires][displacement]") {
  MultiresMesh mr;
  REQUIRE(build_multires(regular_grid(4, 4), 1, mr).ok());
  DisplacementOptions o;
  o.edge_fade_control_edges = -1;
  CHECK(measure_displacements(plane_patch(), o, mr).code == ErrorCode::InvalidInput);
  o.edge_fade_control_edges = std::nan("");
  CHECK(measure_displacements(plane_patch(), o, mr).code == ErrorCode::InvalidInput);
}
