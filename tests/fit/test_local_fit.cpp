#include "fit/closest_point.h"
#include "fit/local_fit.h"
#include "toy_shapes.h"

#include <catch2/catch.hpp>

using namespace lk;

namespace {

// The "nose": vertices of an ellipsoid with z > 0.07 (a cap at the front).
// The truth moves that cap rigidly (a shift and a small tilt); the local fit
// must recover the motion from points alone.
struct NoseCase {
  TriMesh mesh, truth;
  MeshTopology topo;
  FeatureBox box;
  Mat3 R;
  Vec3 shift;
};

NoseCase make_nose_case() {
  NoseCase c;
  c.mesh = test::bumpy_ellipsoid(test::icosphere(3), Vec3(0.08, 0.11, 0.10), Vec3(0, 0, 1), 0.02, 0.2);
  REQUIRE(build_topology(c.mesh, c.topo).ok());
  c.box.name = "nose";
  c.box.min = Vec3(-0.05, -0.05, 0.085);
  c.box.max = Vec3(0.05, 0.05, 0.2);
  c.R = Eigen::AngleAxisd(0.08, Vec3(1, 0, 0)).toRotationMatrix();
  c.shift = Vec3(0.002, -0.004, 0.001);
  c.truth = c.mesh;
  const Vec3 pivot(0, 0, 0.1);
  for (int v = 0; v < c.mesh.num_vertices(); ++v)
    if (c.box.contains(c.mesh.positions[v])) {
      c.truth.positions[v] = pivot + c.R * (c.mesh.positions[v] - pivot) + c.shift;
      if (c.box.landmarks.size() < 4) c.box.landmarks.push_back(v);
    }
  return c;
}

}  // namespace

TEST_CASE("local fit recovers a rigid motion of a feature, energy decreasing") {
  NoseCase c = make_nose_case();
  const auto pts = test::sample_surface(c.truth, 30000, 0.0001, 2);
  TriMesh out;
  LocalFitResult r;
  REQUIRE(fit_local(pts, c.mesh, c.topo, {c.box}, AffineMap{}, bounding_box(pts).diagonal(),
                    LocalFitOptions{}, out, r).ok());
  REQUIRE(r.boxes.size() == 1);
  const BoxFit& b = r.boxes[0];
  CHECK(!b.skipped);
  CHECK(b.points > 100);
  REQUIRE(b.energies.size() >= 3);
  for (size_t i = 1; i < b.energies.size(); ++i) CHECK(b.energies[i] <= b.energies[i - 1]);
  CHECK(b.energies.back() < 0.1 * b.energies.front());
  // Box vertices land where the truth put them.
  double err = 0, moved = 0;
  int n = 0;
  for (int v = 0; v < c.mesh.num_vertices(); ++v)
    if (c.box.contains(c.mesh.positions[v])) {
      err = std::max(err, (out.positions[v] - c.truth.positions[v]).norm());
      moved = std::max(moved, (c.mesh.positions[v] - c.truth.positions[v]).norm());
      ++n;
    }
  INFO("box vertices " << n << ": max error " << err << " of a motion up to " << moved);
  CHECK(err < 0.25 * moved);
  // Vertices outside the box follow smoothly: the nearest ones move, far ones do not.
  const Vec3 back(0, 0, -0.1);
  int far_vertex = 0;
  for (int v = 0; v < c.mesh.num_vertices(); ++v)
    if ((c.mesh.positions[v] - back).norm() < (c.mesh.positions[far_vertex] - back).norm()) far_vertex = v;
  CHECK((out.positions[far_vertex] - c.mesh.positions[far_vertex]).norm() < 1e-4);
}

TEST_CASE("local fit through an alignment: boxes are tested in the generic frame") {
  NoseCase c = make_nose_case();
  // The scan is the truth scaled by 1000 (millimetres) and shifted; the mesh
  // is the generic mapped by the same affine map.
  AffineMap g2m;
  g2m.A = Mat3::Identity() * 1000.0;
  g2m.t = Vec3(10, 200, -30);
  TriMesh mesh = c.mesh, truth = c.truth;
  for (Vec3& p : mesh.positions) p = g2m.apply(p);
  for (Vec3& p : truth.positions) p = g2m.apply(p);
  const auto pts = test::sample_surface(truth, 30000, 0.1, 2);
  TriMesh out;
  LocalFitResult r;
  REQUIRE(fit_local(pts, mesh, c.topo, {c.box}, g2m, bounding_box(pts).diagonal(), LocalFitOptions{},
                    out, r).ok());
  std::vector<Vec3> in_box;
  for (const Vec3& p : pts)
    if (c.box.contains(g2m.A.inverse() * (p - g2m.t))) in_box.push_back(p);
  REQUIRE(in_box.size() > 100);
  const double before = point_to_surface_stats(in_box, mesh, 1.0).mean;
  const double after = point_to_surface_stats(in_box, out, 1.0).mean;
  INFO("mean distance in the box (mm) before " << before << " after " << after);
  CHECK(after < 0.3 * before);
  CHECK(r.boxes[0].transform.A.isApprox(c.R, 0.01));
}

TEST_CASE("local fit leaves a box without data alone and rejects bad input") {
  NoseCase c = make_nose_case();
  std::vector<Vec3> pts = test::sample_surface(c.truth, 5000, 0.0, 3);
  std::vector<Vec3> no_nose;
  for (const Vec3& p : pts)
    if (!c.box.contains(p)) no_nose.push_back(p);
  TriMesh out;
  LocalFitResult r;
  REQUIRE(fit_local(no_nose, c.mesh, c.topo, {c.box}, AffineMap{}, 0.3, LocalFitOptions{}, out, r).ok());
  CHECK(r.boxes[0].skipped);
  for (int v = 0; v < c.mesh.num_vertices(); ++v) CHECK((out.positions[v] - c.mesh.positions[v]).norm() < 1e-12);
  AffineMap singular;
  singular.A.setZero();
  CHECK(fit_local(pts, c.mesh, c.topo, {c.box}, singular, 0.3, {}, out, r).code == ErrorCode::InvalidInput);
  CHECK(fit_local(pts, c.mesh, c.topo, {c.box}, AffineMap{}, 0.0, {}, out, r).code == ErrorCode::InvalidInput);
  FeatureBox bad = c.box;
  bad.landmarks = {-1};
  CHECK(fit_local(pts, c.mesh, c.topo, {bad}, AffineMap{}, 0.3, {}, out, r).code == ErrorCode::InvalidInput);
}
