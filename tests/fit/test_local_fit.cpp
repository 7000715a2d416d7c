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

namespace {

// Two "eyes": Gaussian dents in the front of an ellipsoid (a head-sized
// 0.08 x 0.11 x 0.10 m), under a ridge (the "brow") above them. The truth
// has the same features centred `drop` metres lower; the surface between
// them and around is the same ellipsoid.
TriMesh eye_ellipsoid(double drop) {
  TriMesh m = test::icosphere(4);
  const Vec3 r(0.08, 0.11, 0.10);
  for (Vec3& p : m.positions) {
    const Vec3 u = p.normalized();
    Vec3 q(u.x() * r.x(), u.y() * r.y(), u.z() * r.z());
    double h = 0;
    if (q.z() > 0) {
      for (double side : {-1.0, 1.0}) {
        const double dx = q.x() - side * 0.032, dy = q.y() - (0.02 - drop);
        h -= 0.008 * std::exp(-(dx * dx + dy * dy) / (2 * 0.010 * 0.010));
      }
      const double by = q.y() - (0.038 - drop);
      h += 0.006 * std::exp(-(by * by) / (2 * 0.006 * 0.006)) * std::exp(-(q.x() * q.x()) / (2 * 0.05 * 0.05));
    }
    p = q + h * u;
  }
  return m;
}

SoftRegion eye_ellipsoid_region(RegionMotion motion) {
  SoftRegion region;
  region.name = "eyes";
  region.center = Vec3(0, 0.025, 0.09);
  region.radii = Vec3(0.055, 0.025, 0.04);
  region.motion = motion;
  return region;
}

// Mean distance (m) from the mesh's front-feature vertices (the dents and
// the ridge, |x| < 0.05, 0 < y < 0.05 before the move) to the truth surface.
double feature_error(const TriMesh& fitted, const TriMesh& original, const TriMesh& truth) {
  ClosestPointTree tree(truth);
  double sum = 0;
  int n = 0;
  for (int v = 0; v < original.num_vertices(); ++v) {
    const Vec3& p = original.positions[v];
    if (p.z() > 0.05 && std::abs(p.x()) < 0.05 && p.y() > 0 && p.y() < 0.05) {
      sum += std::sqrt(tree.closest(fitted.positions[v]).squared_distance);
      ++n;
    }
  }
  return sum / std::max(1, n);
}

}  // namespace

TEST_CASE("soft region: eyes 8 mm lower than the template are found by translation and scale") {
  const TriMesh mesh = eye_ellipsoid(0.0), truth = eye_ellipsoid(0.008);
  MeshTopology topo;
  REQUIRE(build_topology(mesh, topo).ok());
  const auto pts = test::sample_surface(truth, 40000, 0.0002, 5);
  for (RegionMotion motion : {RegionMotion::TranslationScale, RegionMotion::Translation}) {
    TriMesh out;
    BoxFit fit;
    REQUIRE(fit_soft_region(pts, mesh, topo, eye_ellipsoid_region(motion), AffineMap{}, LocalFitOptions{}, out,
                            fit).ok());
    CHECK_FALSE(fit.skipped);
    CHECK(fit.points > 300);
    REQUIRE(fit.energies.size() >= 3);
    for (size_t i = 1; i < fit.energies.size(); ++i) CHECK(fit.energies[i] <= fit.energies[i - 1]);
    // The transform is what the motion allows: A = s I (s = 1 for a translation).
    const double s = fit.transform.A(0, 0);
    CHECK((fit.transform.A - s * Mat3::Identity()).norm() < 1e-12);
    if (motion == RegionMotion::Translation) CHECK(s == 1.0);
    const double before = feature_error(mesh, mesh, truth), after = feature_error(out, mesh, truth);
    INFO("motion " << int(motion) << ": shift (" << 1000 * fit.transform.t.transpose() << ") mm, scale " << s
                   << "; features to truth " << 1000 * before << " -> " << 1000 * after << " mm");
    // The dents moved down by about the 8 mm, the features sit on the truth.
    CHECK(fit.transform.t.y() < -0.006);
    CHECK(fit.transform.t.y() > -0.010);
    CHECK(before > 0.0015);
    CHECK(after < 0.35 * before);
    // The back of the ellipsoid (weight 0) does not move at all.
    for (int v = 0; v < mesh.num_vertices(); ++v)
      if (mesh.positions[v].z() < 0) REQUIRE(out.positions[v] == mesh.positions[v]);
  }
}

TEST_CASE("soft region: weights fall smoothly to zero, no data leaves the mesh alone, bad input is refused") {
  SoftRegion region = eye_ellipsoid_region(RegionMotion::TranslationScale);
  CHECK(region.weight(region.center) == 1.0);
  CHECK(region.weight(region.center + Vec3(0, 0.025, 0)) == 1.0);  // on the core ellipsoid
  const double mid = region.weight(region.center + Vec3(0, 0.0375, 0));
  CHECK(mid == Approx(0.5));
  CHECK(region.weight(region.center + Vec3(0.11, 0, 0)) == 0.0);  // at falloff x radius
  double previous = 1;
  for (double y = 0.025; y <= 0.05; y += 0.001) {
    const double w = region.weight(region.center + Vec3(0, y, 0));
    CHECK(w <= previous);
    previous = w;
  }

  const TriMesh mesh = eye_ellipsoid(0.0);
  MeshTopology topo;
  REQUIRE(build_topology(mesh, topo).ok());
  std::vector<Vec3> behind = test::sample_surface(mesh, 2000, 0.0, 6);
  behind.erase(std::remove_if(behind.begin(), behind.end(), [](const Vec3& p) { return p.z() > -0.02; }),
               behind.end());
  TriMesh out;
  BoxFit fit;
  REQUIRE(fit_soft_region(behind, mesh, topo, region, AffineMap{}, LocalFitOptions{}, out, fit).ok());
  CHECK(fit.skipped);
  for (int v = 0; v < mesh.num_vertices(); ++v) REQUIRE(out.positions[v] == mesh.positions[v]);

  const auto pts = test::sample_surface(mesh, 2000, 0.0, 7);
  SoftRegion bad = region;
  bad.falloff = 1.0;
  CHECK(fit_soft_region(pts, mesh, topo, bad, AffineMap{}, {}, out, fit).code == ErrorCode::InvalidInput);
  bad = region;
  bad.radii.y() = 0;
  CHECK(fit_soft_region(pts, mesh, topo, bad, AffineMap{}, {}, out, fit).code == ErrorCode::InvalidInput);
  AffineMap singular;
  singular.A.setZero();
  CHECK(fit_soft_region(pts, mesh, topo, region, singular, {}, out, fit).code == ErrorCode::InvalidInput);
  std::vector<Vec3> nan_pts = pts;
  nan_pts[5].x() = std::nan("");
  CHECK(fit_soft_region(nan_pts, mesh, topo, region, AffineMap{}, {}, out, fit).code == ErrorCode::InvalidInput);
}

TEST_CASE("eye region: centred between the eye rims, sized by their distance") {
  TriMesh mesh;
  mesh.positions = {Vec3(0.03, 0.02, 0.08), Vec3(0.034, 0.02, 0.08), Vec3(-0.03, 0.02, 0.08),
                    Vec3(-0.034, 0.02, 0.08)};
  mesh.triangles = {{0, 1, 2}, {1, 3, 2}};
  HeadAnnotations ann;
  ann.eye_left.rim = {0, 1};
  ann.eye_right.rim = {2, 3};
  SoftRegion region;
  REQUIRE(eye_region(mesh, ann, EyeRegionOptions{}, region).ok());
  CHECK(region.center.isApprox(Vec3(0, 0.02, 0.08)));
  CHECK(region.radii.x() == Approx(0.064 * EyeRegionOptions{}.radii_per_eye_distance.x()));
  ann.eye_right.rim.clear();
  CHECK(eye_region(mesh, ann, EyeRegionOptions{}, region).code == ErrorCode::InvalidInput);
  ann.eye_right.rim = {7};
  CHECK(eye_region(mesh, ann, EyeRegionOptions{}, region).code == ErrorCode::InvalidInput);
}
