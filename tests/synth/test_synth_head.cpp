// Synthetic heads: deterministic, plausible, smooth, valid, with annotations
// that follow the mesh; Loop subdivision and the truth surface.
#include "synth/analytic_head.h"
#include "synth/synth_head.h"

#include "mesh/geometry.h"
#include "mesh/primitives.h"
#include "mesh/topology.h"
#include "test_scan.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <cstring>

using namespace lk;
using lk::test::generic_head;

namespace {

const GenericHead& base_head() {
  static const GenericHead h = analytic_head();
  return h;
}

// Options with every range zero except those set by the caller.
SynthHeadOptions only() {
  SynthHeadOptions o;
  o.proportion_range = o.shape_range = o.jaw_width_range = o.chin_range_m = 0;
  o.nose_length_range = o.nose_width_range = o.nose_projection_range = 0;
  o.ear_shift_m = o.ear_size_range = o.lip_fullness_m = o.mouth_width_range = 0;
  o.brow_ridge_m = o.cheek_m = 0;
  return o;
}

// Largest |d(a) - d(b)| / |a - b| over mesh edges: a crease (a displacement
// that jumps between neighbours) makes this large.
double displacement_gradient(const TriMesh& before, const TriMesh& after) {
  double worst = 0;
  for (const Tri& t : before.triangles)
    for (int k = 0; k < 3; ++k) {
      const int a = t[k], b = t[(k + 1) % 3];
      const Vec3 da = after.positions[a] - before.positions[a];
      const Vec3 db = after.positions[b] - before.positions[b];
      worst = std::max(worst, (da - db).norm() / (before.positions[a] - before.positions[b]).norm());
    }
  return worst;
}

}  // namespace

TEST_CASE("the analytic head is a valid disk with annotated regions", "[synth]") {
  const GenericHead& h = base_head();
  MeshTopology topo;
  REQUIRE(build_topology(h.mesh, topo).ok());
  CHECK(euler_characteristic(topo, h.mesh.num_triangles()) == 1);
  CHECK(topo.boundary_loops.size() == 1);
  for (const char* r : {"nose", "ear_left", "ear_right", "scalp", "chin", "jaw", "lips", "upper_lip",
                        "lower_lip", "brow", "cheeks", "face"}) {
    INFO(r);
    CHECK(h.annotations.regions.count(r));
    CHECK(h.annotations.regions.at(r).size() >= 5);
  }
  CHECK(h.annotations.boxes.size() == 4);
  const BBox b = bounding_box(h.mesh.positions);
  CHECK(b.size().y() == Approx(0.23).margin(0.02));
}

TEST_CASE("synthesized heads are deterministic per seed and differ between seeds", "[synth]") {
  GenericHead a, b, c;
  REQUIRE(synthesize_head(base_head(), 7, {}, a).ok());
  REQUIRE(synthesize_head(base_head(), 7, {}, b).ok());
  REQUIRE(synthesize_head(base_head(), 8, {}, c).ok());
  REQUIRE(a.mesh.positions.size() == b.mesh.positions.size());
  CHECK(std::memcmp(a.mesh.positions.data(), b.mesh.positions.data(),
                    a.mesh.positions.size() * sizeof(Vec3)) == 0);
  double max_diff = 0;
  for (size_t v = 0; v < a.mesh.positions.size(); ++v)
    max_diff = std::max(max_diff, (a.mesh.positions[v] - c.mesh.positions[v]).norm());
  CHECK(max_diff > 0.002);
  // The parameter stream is fixed: seed 7's first draw never changes silently.
  CHECK(draw_synth_params(7).values.front().first == "width");
  CHECK(draw_synth_params(7).get("width") == draw_synth_params(7).get("width"));
  CHECK(draw_synth_params(7).get("width") != draw_synth_params(8).get("width"));
}

TEST_CASE("variation 0 reproduces the generic head", "[synth]") {
  SynthHeadOptions o;
  o.variation = 0;
  GenericHead h;
  REQUIRE(synthesize_head(base_head(), 3, o, h).ok());
  for (size_t v = 0; v < h.mesh.positions.size(); ++v)
    REQUIRE((h.mesh.positions[v] - base_head().mesh.positions[v]).norm() < 1e-12);
}

TEST_CASE("heads over many seeds stay valid, plausible and smooth", "[synth]") {
  const bool real = GENERATE(true, false);
  const GenericHead& g = real ? generic_head() : base_head();
  INFO((real ? "generic head" : "analytic head"));
  const std::vector<Vec3> n0 = face_normals(g.mesh);
  const BBox gb = bounding_box(g.mesh.positions);
  double widest = 0, narrowest = 10;
  for (std::uint32_t seed = 1; seed <= 30; ++seed) {
    INFO("seed " << seed);
    GenericHead h;
    SynthHeadParams p;
    REQUIRE(synthesize_head(g, seed, {}, h, &p).ok());
    REQUIRE(h.mesh.triangles == g.mesh.triangles);
    REQUIRE(is_valid(h.mesh));
    const std::vector<Vec3> n1 = face_normals(h.mesh);
    int flipped = 0;
    for (size_t f = 0; f < n0.size(); ++f) flipped += n0[f].dot(n1[f]) < 0.5;  // > 60 degree turn
    CHECK(flipped == 0);
    const BBox hb = bounding_box(h.mesh.positions);
    const Vec3 ratio = hb.size().cwiseQuotient(gb.size());
    CHECK(ratio.minCoeff() > 0.85);  // like adults: within about +-15%
    CHECK(ratio.maxCoeff() < 1.15);
    widest = std::max(widest, ratio.x());
    narrowest = std::min(narrowest, ratio.x());
    double max_disp = 0, mean_disp = 0;
    for (size_t v = 0; v < g.mesh.positions.size(); ++v) {
      const double d = (h.mesh.positions[v] - g.mesh.positions[v]).norm();
      max_disp = std::max(max_disp, d);
      mean_disp += d / g.mesh.positions.size();
    }
    CHECK(max_disp < 0.03);
    CHECK(mean_disp > 0.0005);
    // No creases: neighbouring vertices move alike (a crease shows as a jump).
    CHECK(displacement_gradient(g.mesh, h.mesh) < 0.6);
    for (double v : {p.get("width"), p.get("nose_length"), p.get("jaw_width")}) CHECK(std::abs(v) <= 0.15);
  }
  CHECK(widest - narrowest > 0.04);  // the seeds really spread
}

TEST_CASE("each deformation does what its name says", "[synth]") {
  const GenericHead& g = base_head();
  const auto& nose = g.annotations.regions.at("nose");
  SECTION("nose projection moves the tip forward by the drawn share of the nose depth") {
    SynthHeadOptions o = only();
    o.nose_projection_range = 0.18;
    for (std::uint32_t seed : {1u, 2u, 3u}) {
      GenericHead h;
      SynthHeadParams p;
      REQUIRE(synthesize_head(g, seed, o, h, &p).ok());
      int tip = nose.front();
      double base_z = 1e9;
      for (int v : nose) {
        if (g.mesh.positions[v].z() > g.mesh.positions[tip].z()) tip = v;
        base_z = std::min(base_z, g.mesh.positions[v].z());
      }
      const double want = p.get("nose_projection") * (g.mesh.positions[tip].z() - base_z);
      CHECK(h.mesh.positions[tip].z() - g.mesh.positions[tip].z() == Approx(want).margin(1e-9));
      CHECK(std::abs(want) > 1e-5);
    }
  }
  SECTION("proportions scale the bounding box exactly") {
    SynthHeadOptions o = only();
    o.proportion_range = 0.07;
    GenericHead h;
    SynthHeadParams p;
    REQUIRE(synthesize_head(g, 11, o, h, &p).ok());
    const Vec3 r = bounding_box(h.mesh.positions).size().cwiseQuotient(bounding_box(g.mesh.positions).size());
    CHECK(r.x() == Approx(1 + p.get("width")).epsilon(1e-9));
    CHECK(r.y() == Approx(1 + p.get("height")).epsilon(1e-9));
    CHECK(r.z() == Approx(1 + p.get("depth")).epsilon(1e-9));
  }
  SECTION("jaw width scales jaw vertices sideways, leaves the crown alone") {
    SynthHeadOptions o = only();
    o.jaw_width_range = 0.12;
    GenericHead h;
    SynthHeadParams p;
    REQUIRE(synthesize_head(g, 5, o, h, &p).ok());
    const Vec3 c = bounding_box(g.mesh.positions).center();
    for (int v : g.annotations.regions.at("jaw"))
      CHECK(h.mesh.positions[v].x() - c.x() ==
            Approx((1 + p.get("jaw_width")) * (g.mesh.positions[v].x() - c.x())).margin(1e-12));
    CHECK((h.mesh.positions[0] - g.mesh.positions[0]).norm() < 1e-12);  // vertex 0 is the crown
  }
  SECTION("ears move up by the drawn amount, one a bit more than the other") {
    SynthHeadOptions o = only();
    o.ear_shift_m = 0.006;
    GenericHead h;
    SynthHeadParams p;
    REQUIRE(synthesize_head(g, 9, o, h, &p).ok());
    const int l = g.annotations.regions.at("ear_left").front();
    const int r = g.annotations.regions.at("ear_right").front();
    const double k = p.get("ear_asymmetry");
    CHECK(h.mesh.positions[l].y() - g.mesh.positions[l].y() == Approx((1 + k) * p.get("ear_up_m")).margin(1e-12));
    CHECK(h.mesh.positions[r].y() - g.mesh.positions[r].y() == Approx((1 - k) * p.get("ear_up_m")).margin(1e-12));
  }
}

TEST_CASE("annotations follow the synthesized mesh", "[synth]") {
  const GenericHead& g = base_head();
  for (std::uint32_t seed : {4u, 5u, 6u}) {
    GenericHead h;
    SynthHeadParams p;
    REQUIRE(synthesize_head(g, seed, {}, h, &p).ok());
    for (size_t b = 0; b < h.annotations.boxes.size(); ++b) {
      const FeatureBox& gb = g.annotations.boxes[b];
      const FeatureBox& hb = h.annotations.boxes[b];
      for (int v = 0; v < g.mesh.num_vertices(); ++v)
        if (gb.contains(g.mesh.positions[v])) REQUIRE(hb.contains(h.mesh.positions[v]));
      for (int v : hb.landmarks) CHECK(hb.contains(h.mesh.positions[v]));
    }
    // The mouth gets wider exactly when both the mouth and the head do.
    if (p.get("mouth_width") > 0.02 && p.get("width") > 0)
      CHECK(h.annotations.mouth_width > g.annotations.mouth_width);
    if (p.get("mouth_width") < -0.02 && p.get("width") < 0)
      CHECK(h.annotations.mouth_width < g.annotations.mouth_width);
    // Eye centres move with the surrounding skin.
    const double moved = (h.annotations.eye_left.center - g.annotations.eye_left.center).norm();
    CHECK(moved > 0);
    CHECK(moved < 0.02);
  }
}

TEST_CASE("bad generic heads are refused", "[synth]") {
  GenericHead empty, out;
  CHECK(synthesize_head(empty, 1, {}, out).code == ErrorCode::Empty);
  CHECK(synthesize_head(empty, 1).mesh.positions.empty());
  GenericHead bad = base_head();
  bad.mesh.triangles[10][2] = 1 << 30;
  CHECK(synthesize_head(bad, 1, {}, out).code == ErrorCode::InvalidInput);
  SynthHeadOptions o;
  o.falloff_m = 0;
  CHECK(synthesize_head(base_head(), 1, o, out).code == ErrorCode::InvalidInput);
  o = SynthHeadOptions{};
  o.variation = std::nan("");
  CHECK(synthesize_head(base_head(), 1, o, out).code == ErrorCode::InvalidInput);
}

TEST_CASE("Loop subdivision: counts, affine invariance, smoothing", "[synth]") {
  // A flat grid on a tilted plane stays on that plane (weights sum to 1).
  const int n = 6;
  TriMesh grid = make_regular_grid(n, n);  // vertex (i, j) at (i, j, 0)
  for (Vec3& p : grid.positions) p.z() = 0.3 * p.x() - 0.2 * p.y();
  TriMesh fine;
  REQUIRE(loop_subdivide(grid, fine).ok());
  MeshTopology topo;
  REQUIRE(build_topology(grid, topo).ok());
  CHECK(fine.num_vertices() == grid.num_vertices() + static_cast<int>(topo.edges.size()));
  CHECK(fine.num_triangles() == 4 * grid.num_triangles());
  for (const Vec3& p : fine.positions) CHECK(p.z() == Approx(0.3 * p.x() - 0.2 * p.y()).margin(1e-12));
  // Boundary corners of a straight boundary stay on it; interior regular
  // vertices of a regular grid stay put (the plane is reproduced).
  CHECK((fine.positions[n + 2] - grid.positions[n + 2]).norm() < 1e-12);
  // On a closed, convex shape Loop shrinks: every old vertex moves inwards.
  const GenericHead& h = base_head();
  TriMesh sm;
  REQUIRE(loop_subdivide(h.mesh, sm).ok());
  const Vec3 c = bounding_box(h.mesh.positions).center();
  CHECK((sm.positions[0] - c).norm() < (h.mesh.positions[0] - c).norm());  // the crown
  // Non-manifold input is refused, not crashed on.
  TriMesh bad = grid;
  bad.triangles.push_back(bad.triangles.front());
  CHECK_FALSE(loop_subdivide(bad, fine).ok());
}

TEST_CASE("the truth surface refines the head, adds bounded detail, marks hair", "[synth]") {
  const GenericHead& h = base_head();
  TruthOptions smooth;
  smooth.detail_amplitude_m = 0;
  TruthSurface plain, detailed, again;
  REQUIRE(make_truth_surface(h, 5, smooth, plain).ok());
  REQUIRE(make_truth_surface(h, 5, {}, detailed).ok());
  REQUIRE(make_truth_surface(h, 5, {}, again).ok());
  CHECK(detailed.mesh.num_triangles() == 16 * h.mesh.num_triangles());
  CHECK(detailed.parent_triangle.size() == detailed.mesh.triangles.size());
  CHECK(detailed.parent_triangle[37] == 37 / 16);
  CHECK(std::memcmp(detailed.mesh.positions.data(), again.mesh.positions.data(),
                    again.mesh.positions.size() * sizeof(Vec3)) == 0);
  double max_d = 0, sum2 = 0;
  for (size_t v = 0; v < plain.mesh.positions.size(); ++v) {
    const double d = (detailed.mesh.positions[v] - plain.mesh.positions[v]).norm();
    max_d = std::max(max_d, d);
    sum2 += d * d;
  }
  const double rms = std::sqrt(sum2 / plain.mesh.positions.size());
  CHECK(max_d <= 0.0005 + 1e-12);
  CHECK(rms > 0.00005);  // the detail is really there ...
  CHECK(rms < 0.0004);   // ... and skin-sized
  // Hair triangles are exactly the children of scalp triangles.
  std::vector<char> scalp(h.mesh.positions.size(), 0);
  for (int v : h.annotations.regions.at("scalp")) scalp[v] = 1;
  int hair = 0;
  for (size_t f = 0; f < detailed.hair.size(); ++f) {
    const Tri& t = h.mesh.triangles[detailed.parent_triangle[f]];
    REQUIRE(detailed.hair[f] == ((scalp[t[0]] + scalp[t[1]] + scalp[t[2]]) >= 2));
    hair += detailed.hair[f];
  }
  CHECK(hair > 0);
  CHECK(hair < static_cast<int>(detailed.hair.size()) * 3 / 4);
  TruthOptions bad;
  bad.subdivision_levels = 9;
  CHECK(make_truth_surface(h, 5, bad, plain).code == ErrorCode::InvalidInput);
}
