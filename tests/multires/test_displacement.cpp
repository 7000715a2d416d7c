// Displacements measured from sparse, noisy and partial data
// (core/multires/displacement.h): the footprint follows the local point
// spacing, the height field is fitted above the base surface, and the
// displacement tapers to 0 at the data's edge.
#include "multires/displacement.h"
#include "multires/multires.h"

#include "head/generic_head.h"
#include "io/io.h"
#include "pipeline/fit_head.h"
#include "../subdiv/shapes.h"
#include "test_data.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>

using namespace lk;
using namespace lk::test;

namespace {

// n points uniformly on the unit sphere, radial Gaussian noise sigma.
PointCloud sphere_points(int n, double sigma, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0, 1);
  PointCloud c;
  for (int i = 0; i < n; ++i) {
    Vec3 d(g(rng), g(rng), g(rng));
    d.normalize();
    c.positions.push_back(d * (1.0 + sigma * g(rng)));
  }
  return c;
}

// Level-L surface of the unit sphere's control mesh shrunk by `shrink` (so
// the data lies outside it and there is something to measure).
struct SphereResult {
  double mean_radial_error = 0;  // mean | |p| - 1 | over level-L vertices
  double mean_normal_angle = 0;  // degrees between the displaced surface's normals and the true (radial) ones
};

SphereResult measure_sphere(const PointCloud& cloud, const DisplacementOptions& options, bool displace) {
  TriMesh control = icosphere(2);
  for (Vec3& p : control.positions) p *= 0.97;
  MultiresMesh mr;
  REQUIRE(build_multires(control, 3, mr).ok());
  if (displace) REQUIRE(measure_displacements(cloud, options, mr).ok());
  const TriMesh m = level_mesh(mr, 3);
  SphereResult r;
  for (int v = 0; v < m.num_vertices(); ++v) {
    r.mean_radial_error += std::abs(m.positions[v].norm() - 1.0);
    const double c = std::clamp(m.normals[v].dot(m.positions[v].normalized()), -1.0, 1.0);
    r.mean_normal_angle += std::acos(c) * 180.0 / 3.14159265358979323846;
  }
  r.mean_radial_error /= m.num_vertices();
  r.mean_normal_angle /= m.num_vertices();
  return r;
}

}  // namespace

TEST_CASE("displacement: a sparse noisy sphere is recovered without becoming rougher than the truth",
          "[multires][displacement]") {
  // 1,500 points: spacing 0.09, over twice the level-3 edge (0.04), like
  // the Cyberware face patch (3.4 mm points, 1.2 mm level-3 edges).
  const double sigma = 0.003;
  const PointCloud cloud = sphere_points(1500, sigma, 7);
  // The footprints alone: without the fade across the data's edge, which
  // fills the level-3 vertices these sparse points leave without data from
  // their neighbours (test_edge_fade.cpp).
  DisplacementOptions adaptive_options;
  adaptive_options.edge_fade_control_edges = 0;
  const SphereResult smooth = measure_sphere(cloud, adaptive_options, false);
  const SphereResult adaptive = measure_sphere(cloud, adaptive_options, true);
  // A footprint of 4 points: detail finer than the data carries.
  DisplacementOptions tiny = adaptive_options;
  tiny.footprint_points = 4;
  tiny.max_footprint_points = 4;  // and not widened against the noise
  const SphereResult naive = measure_sphere(cloud, tiny, true);
  INFO("mean radial error: smooth " << smooth.mean_radial_error << ", adaptive " << adaptive.mean_radial_error
                                    << ", 4-point footprint " << naive.mean_radial_error);
  INFO("mean normal angle (deg): smooth " << smooth.mean_normal_angle << ", adaptive " << adaptive.mean_normal_angle
                                          << ", 4-point footprint " << naive.mean_normal_angle);
  // The analytic sphere is the held-out truth: the surface lies on it to
  // within the noise of a single point (measured 0.75 sigma) and its
  // normals are a third closer to the true ones than with footprints too
  // small for the data (measured 2.8 vs 4.1 degrees). Still weak: the
  // undisplaced Butterfly sphere's normals are off by only 0.66 degrees; a
  // free quadric over ~16 points keeps some of their noise (pinning the
  // curvature to the base surface's raised a ridge at data edges).
  CHECK(smooth.mean_radial_error > 0.02);
  CHECK(adaptive.mean_radial_error < 0.85 * sigma);
  CHECK(naive.mean_radial_error > 1.1 * sigma);
  CHECK(adaptive.mean_normal_angle < 0.75 * naive.mean_normal_angle);
}

TEST_CASE("displacement: no ridge where the data stops", "[multires][displacement]") {
  // A flat 12 x 12 control patch; the truth is the tilted plane
  // z = 0.3 + 0.1 x, sampled (0.5 apart, noise 0.01) only for x < 6. A
  // height field fitted to one side of the line extrapolates the slope past
  // the edge (a ridge up to ~1.0); the displacement must taper instead.
  const double sigma = 0.01;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> ux(0, 6), uy(0, 12);
  std::normal_distribution<double> g(0, sigma);
  PointCloud cloud;
  for (int i = 0; i < 288; ++i) {
    const double x = ux(rng), y = uy(rng);
    cloud.positions.push_back(Vec3(x, y, 0.3 + 0.1 * x + g(rng)));
  }
  MultiresMesh mr;
  REQUIRE(build_multires(regular_grid(12, 12), 3, mr).ok());
  DisplacementStats stats;
  REQUIRE(measure_displacements(cloud, {}, mr, &stats).ok());
  const TriMesh m = level_mesh(mr, 3);
  const double edge_height = 0.3 + 0.1 * 6;
  double inside_error = 0, highest = -1e9, highest_x = 0, highest_beyond = -1e9;
  int inside = 0, beyond = 0, far_nonzero = 0;
  for (const Vec3& p : m.positions) {
    if (p.y() < 3 || p.y() > 9) continue;  // away from the patch's own boundary
    if (p.z() > highest) highest = p.z(), highest_x = p.x();
    if (p.x() > 1.5 && p.x() < 4.5) inside_error += std::abs(p.z() - (0.3 + 0.1 * p.x())), ++inside;
    if (p.x() > 6) highest_beyond = std::max(highest_beyond, p.z()), ++beyond;
    // Beyond the fade across the data's edge (two control edges of ~1.1
    // past the last supported vertex) and the Butterfly stencils' reach.
    if (p.x() > 10.5) far_nonzero += p.z() != 0.0;
  }
  inside_error /= inside;
  INFO("inside mean error " << inside_error << ", highest " << highest << " (data edge " << edge_height
                            << ") at x = " << highest_x << ", highest beyond the edge " << highest_beyond << "; tapered per level "
                            << stats.tapered[0] << " " << stats.tapered[1] << " " << stats.tapered[2] << " "
                            << stats.tapered[3]);
  CHECK(inside > 100);
  CHECK(beyond > 100);
  CHECK(inside_error < sigma);                  // the data's interior is fitted
  CHECK(highest < edge_height + 3 * sigma);     // no ridge above the data
  CHECK(highest_beyond < edge_height);          // nothing extrapolated upward past the edge
  CHECK(far_nonzero == 0);                      // no data within reach: the control patch itself
  CHECK(stats.tapered[3] > 0);
}

TEST_CASE("displacement: bad options are refused", "[multires][displacement]") {
  MultiresMesh mr;
  REQUIRE(build_multires(icosphere(1), 1, mr).ok());
  const PointCloud cloud = sphere_points(200, 0.0, 1);
  DisplacementOptions o;
  o.footprint_points = 0;
  CHECK(measure_displacements(cloud, o, mr).code == ErrorCode::InvalidInput);
  o = {};
  o.support_zero_offset = o.support_full_offset;
  CHECK(measure_displacements(cloud, o, mr).code == ErrorCode::InvalidInput);
  o = {};
  o.ridge = -1;
  CHECK(measure_displacements(cloud, o, mr).code == ErrorCode::InvalidInput);
  o = {};
  o.max_radius = std::nan("");
  CHECK(measure_displacements(cloud, o, mr).code == ErrorCode::InvalidInput);
}

namespace {

// Fits a real scan and returns its stage reports (global fitting, level 3).
void fit_real(const std::string& rel, DistanceStats& control, DistanceStats& finest) {
  PointCloud scan;
  REQUIRE(load_point_cloud_file(shared_data_dir() + "/" + rel, scan).ok());
  GenericHead generic;
  REQUIRE(load_generic_head(generic).ok());
  FitHeadResult r;
  REQUIRE(fit_head(scan, generic, FitHeadOptions{}, r).ok());
  for (const FitStageReport& s : r.stages) {
    if (s.name == "global_fitting") control = s.distance;
    if (s.name == "subdivision") finest = s.distance;
  }
  REQUIRE(control.count > 0);
  REQUIRE(finest.count > 0);
}

}  // namespace

TEST_CASE("displacement: the sparse Cyberware face patch (fran_cut) gains from level 3",
          "[multires][displacement][shared]") {
  LK_REQUIRE_SHARED("head_scans/fran_cyberware/fran_cut.vtk");
  DistanceStats control, finest;
  fit_real("head_scans/fran_cyberware/fran_cut.vtk", control, finest);
  INFO("mean distance, % of the diagonal: control " << control.mean_pct << ", level 3 " << finest.mean_pct);
  // Points 3.4 mm apart: the old measurement made level 3 worse than the
  // control mesh (0.127 vs 0.112 %); measured 0.072 % now.
  CHECK(finest.mean_pct < 0.8 * control.mean_pct);
}

TEST_CASE("displacement: the menpo3d face capture (james) gains from level 3", "[multires][displacement][shared]") {
  LK_REQUIRE_SHARED("head_scans/james_menpo3d/james.obj");
  DistanceStats control, finest;
  fit_real("head_scans/james_menpo3d/james.obj", control, finest);
  INFO("mean distance, % of the diagonal: control " << control.mean_pct << ", level 3 " << finest.mean_pct);
  CHECK(finest.mean_pct < 0.8 * control.mean_pct);
}
