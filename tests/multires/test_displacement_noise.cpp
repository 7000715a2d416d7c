// Displacements against scanner noise (core/multires/displacement.h,
// DisplacementOptions::max_footprint_points): on dense noisy data the
// footprint widens until the height is certain to a fraction of the level's
// edge, but not across detail the narrower footprints agree on; on clean or
// sparse data it stays as it was.
//
// Ground truth: a flat 12 x 12 control patch (level-3 edges ~0.14) and the
// surface z = A exp(-r^2 / 2 s^2) around its centre (a bump ~3 level-3
// edges wide), sampled at random with Gaussian depth noise.
#include "multires/displacement.h"
#include "multires/multires.h"

#include "../subdiv/shapes.h"
#include "test_scan.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>

using namespace lk;
using namespace lk::test;

namespace {

constexpr double kBumpHeight = 0.3;  // A
// s: about three level-3 edges.
constexpr double bump_width = 0.4;
// On a vertex that level 3 introduces (odd eighths): its height is that
// level's own measurement, not a coarser level's.
const Vec3 kCentre(6.375, 6.625, 0);

double truth_height(double x, double y) {
  const double r2 = (x - kCentre.x()) * (x - kCentre.x()) + (y - kCentre.y()) * (y - kCentre.y());
  return kBumpHeight * std::exp(-r2 / (2 * bump_width * bump_width));
}

Vec3 truth_normal(double x, double y) {
  const double h = truth_height(x, y), k = 1.0 / (bump_width * bump_width);
  return Vec3(h * k * (x - kCentre.x()), h * k * (y - kCentre.y()), 1.0).normalized();
}

// `count` points uniformly over the patch, depth noise sigma.
PointCloud scan_bump(int count, double sigma, unsigned seed) {
  return test::scan_height_field(truth_height, 12, count, sigma, seed);
}

struct BumpResult {
  double flat_error = 0;   // mean |z - truth| over level-3 vertices away from the bump
  double flat_angle = 0;   // mean angle (deg) of level-3 face normals to the truth's there: the roughness
  double peak = 0;         // the highest level-3 vertex at the bump's centre (within 0.1)
  int widened = 0;         // level-3 vertices whose footprint the noise widened
};

BumpResult measure_bump(const PointCloud& cloud, const DisplacementOptions& options) {
  MultiresMesh mr;
  REQUIRE(build_multires(regular_grid(12, 12), 3, mr).ok());
  DisplacementStats stats;
  REQUIRE(measure_displacements(cloud, options, mr, &stats).ok());
  const TriMesh m = level_mesh(mr, 3);
  BumpResult r;
  r.widened = stats.widened[3];
  auto inside = [](const Vec3& p) { return p.x() > 2 && p.x() < 10 && p.y() > 2 && p.y() < 10; };
  auto flat = [&](const Vec3& p) { return inside(p) && (p - kCentre).head<2>().norm() > 2.0; };
  int n_flat = 0;
  for (const Vec3& p : m.positions) {
    if (flat(p)) r.flat_error += std::abs(p.z() - truth_height(p.x(), p.y())), ++n_flat;
    if ((p - kCentre).head<2>().norm() < 0.1) r.peak = std::max(r.peak, p.z());
  }
  r.flat_error /= std::max(1, n_flat);
  int n_faces = 0;
  for (const Tri& t : m.triangles) {
    const Vec3 c = (m.positions[t[0]] + m.positions[t[1]] + m.positions[t[2]]) / 3.0;
    if (!flat(c)) continue;
    const Vec3 n = (m.positions[t[1]] - m.positions[t[0]]).cross(m.positions[t[2]] - m.positions[t[0]]).normalized();
    r.flat_angle += std::acos(std::clamp(n.dot(truth_normal(c.x(), c.y())), -1.0, 1.0)) * 180.0 / 3.14159265358979323846;
    ++n_faces;
  }
  r.flat_angle /= std::max(1, n_faces);
  return r;
}

DisplacementOptions sixteen_points() {
  DisplacementOptions o;
  o.max_footprint_points = o.footprint_points;  // the footprint as it was: no widening
  o.smooth_finest_levels = 0;                   // and no smoothing over the mesh
  return o;
}

DisplacementOptions widened() {
  DisplacementOptions o = sixteen_points();
  o.max_footprint_points = 128;  // `likeness fit --widen-footprints` (off by default)
  return o;
}

}  // namespace

TEST_CASE("displacement noise: dense noisy data is averaged, the bump's peak kept", "[multires][displacement]") {
  // 37k points, 0.06 apart (half a level-3 edge), noise 0.02 (a seventh of
  // an edge: the synthetic heads' 0.2 mm on 1.3 mm edges).
  const double sigma = 0.02;
  const PointCloud cloud = scan_bump(36864, sigma, 11);
  const BumpResult fixed = measure_bump(cloud, sixteen_points());
  const BumpResult adaptive = measure_bump(cloud, widened());
  INFO("flat mean error: 16 points " << fixed.flat_error << ", adaptive " << adaptive.flat_error);
  INFO("flat roughness (deg): 16 points " << fixed.flat_angle << ", adaptive " << adaptive.flat_angle);
  INFO("peak (truth " << kBumpHeight << "): 16 points " << fixed.peak << ", adaptive " << adaptive.peak
                      << "; widened level-3 vertices " << adaptive.widened);
  CHECK(fixed.widened == 0);
  CHECK(adaptive.widened > 1000);
  // The noise averaged (level 3 only, the finest): 60 % of the error and
  // about half the roughness of the 16-point footprint (measured 0.0067 vs
  // 0.0115, 6.0 vs 11.3 deg).
  CHECK(adaptive.flat_error < 0.7 * fixed.flat_error);
  CHECK(adaptive.flat_angle < 0.6 * fixed.flat_angle);
  CHECK(adaptive.flat_error < 0.4 * sigma);
  // The detail kept: the peak within a fraction of the noise of the truth
  // (measured 0.3007; the 16-point footprint's 0.280 is off by the noise).
  CHECK(std::abs(adaptive.peak - kBumpHeight) < 0.25 * sigma);
}

TEST_CASE("displacement noise: nearly clean dense data is measured as before", "[multires][displacement]") {
  const double sigma = 0.0005;
  const PointCloud cloud = scan_bump(36864, sigma, 12);
  const BumpResult fixed = measure_bump(cloud, sixteen_points());
  const BumpResult adaptive = measure_bump(cloud, widened());
  INFO("flat mean error: 16 points " << fixed.flat_error << ", adaptive " << adaptive.flat_error << "; peak "
                                     << fixed.peak << " / " << adaptive.peak << "; widened " << adaptive.widened);
  CHECK(adaptive.flat_error < 1.2 * fixed.flat_error + 1e-4);
  CHECK(std::abs(adaptive.peak - kBumpHeight) < 0.01);
}

TEST_CASE("displacement noise: a sparse clean bump is reproduced, not smoothed", "[multires][displacement]") {
  // 2,304 points 0.25 apart (two level-3 edges, like the Cyberware face
  // patch): the level-3 footprint of 16 points is already wider than the
  // widening may go (coarser levels may widen where their fits agree).
  const PointCloud cloud = scan_bump(2304, 0.0, 13);
  const BumpResult fixed = measure_bump(cloud, sixteen_points());
  const BumpResult adaptive = measure_bump(cloud, widened());
  INFO("peak (truth " << kBumpHeight << "): 16 points " << fixed.peak << ", adaptive " << adaptive.peak
                      << "; widened " << adaptive.widened);
  CHECK(std::abs(adaptive.peak - kBumpHeight) < 0.02 * kBumpHeight);
  CHECK(std::abs(adaptive.peak - fixed.peak) < 0.02 * kBumpHeight);
  CHECK(adaptive.widened == 0);
}

TEST_CASE("displacement noise: bad options are refused", "[multires][displacement]") {
  MultiresMesh mr;
  REQUIRE(build_multires(regular_grid(4, 4), 1, mr).ok());
  const PointCloud cloud = scan_bump(200, 0.0, 1);
  DisplacementOptions o = widened();
  o.noise_edge_fraction = 0;
  CHECK(measure_displacements(cloud, o, mr).code == ErrorCode::InvalidInput);
  o = widened();
  o.noise_confidence = std::nan("");
  CHECK(measure_displacements(cloud, o, mr).code == ErrorCode::InvalidInput);
  o = widened();
  o.noise_max_radius_edges = -1;
  CHECK(measure_displacements(cloud, o, mr).code == ErrorCode::InvalidInput);
  o = widened();
  o.noise_finest_levels = -1;
  CHECK(measure_displacements(cloud, o, mr).code == ErrorCode::InvalidInput);
}
