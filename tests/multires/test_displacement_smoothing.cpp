// Denoising by smoothing over the mesh (core/multires/displacement.h,
// DisplacementOptions::smooth_*, on by default): the finest level's heights
// are averaged over one-rings where neighbours agree within their standard
// errors, never farther than smooth_agreement errors from a vertex's own
// measurement.
//
// Ground truth on a flat 12 x 12 control patch (level-3 edges ~0.14):
// a Gaussian bump about three level-3 edges wide, and a cliff (a step of
// 0.3, two level-3 edges tall, along x = 6.3), sampled at random with
// Gaussian depth noise of a seventh of an edge (the synthetic heads' 0.2 mm
// on 1.3 mm edges).
#include "height_field_cases.h"
#include "test_scan.h"

#include <catch2/catch.hpp>

#include <functional>

using namespace lk;
using namespace lk::test;

namespace {

PointCloud scan(const std::function<double(double, double)>& surface, int count, double sigma, unsigned seed) {
  return test::scan_height_field(surface, 12, count, sigma, seed);
}

// The finest level's smoothing alone (see height_field_cases.h; the current
// defaults are tested in test_displacement_grain.cpp).
DisplacementOptions finest_level() { return finest_level_smoothing(); }

DisplacementOptions raw() {
  DisplacementOptions o;
  o.smooth_finest_levels = 0;
  return o;
}

double flat_roughness(const Measured& m) { return roughness(m, away_from_bump); }

}  // namespace

TEST_CASE("displacement smoothing: noise averaged over the mesh, the bump's peak kept", "[multires][displacement]") {
  const double sigma = 0.02;
  const PointCloud cloud = scan(bump, 36864, sigma, 11);
  const Measured before = measure(cloud, raw());
  const Measured after = measure(cloud, finest_level());
  auto flat = away_from_bump;
  const double e0 = mean_error(before, bump, flat), e1 = mean_error(after, bump, flat);
  const double r0 = flat_roughness(before), r1 = flat_roughness(after);
  INFO("flat error " << e0 << " -> " << e1 << ", roughness " << r0 << " -> " << r1 << " deg, peak " << peak(before)
                     << " -> " << peak(after) << " (truth " << kHeight << "), moved " << after.stats.smoothed[3]);
  CHECK(before.stats.smoothed[3] == 0);
  CHECK(after.stats.smoothed[3] > 1000);
  CHECK(after.stats.smoothed[2] == 0);  // the finest level only
  CHECK(e1 < 0.8 * e0);
  CHECK(r1 < 0.7 * r0);
  // The peak as measured (the 16-point fit's own bias at the top, 0.280,
  // is detail the neighbours disagree with: it is not averaged away).
  CHECK(std::abs(peak(after) - peak(before)) < 0.25 * sigma);
}

TEST_CASE("displacement smoothing: a cliff is not smoothed across", "[multires][displacement]") {
  // Neighbours on either side of the cliff disagree by far more than their
  // errors: they do not average. Without that rule (agreement 1e5: every
  // neighbour counts, and a vertex may move anywhere) a strong smoothing
  // (strength 3, ten times the default) blurs the cliff's band; with it,
  // it does not.
  const double sigma = 0.02;
  const PointCloud cloud = scan(cliff, 36864, sigma, 21);
  DisplacementOptions strong = finest_level();
  strong.smooth_strength = 3;
  DisplacementOptions blind = strong;
  blind.smooth_agreement = 1e5;
  const Measured before = measure(cloud, raw());
  const Measured after = measure(cloud, finest_level());
  const Measured kept = measure(cloud, strong);
  const Measured blurred = measure(cloud, blind);
  auto band = [](const Vec3& p) { return std::abs(p.x() - kStepX) > 0.1 && std::abs(p.x() - kStepX) < 0.5; };
  auto away = [](const Vec3& p) { return std::abs(p.x() - kStepX) > 1.5; };
  const double b0 = mean_error(before, cliff, band), b1 = mean_error(after, cliff, band),
               b2 = mean_error(kept, cliff, band), b3 = mean_error(blurred, cliff, band);
  const double a0 = mean_error(before, cliff, away), a1 = mean_error(after, cliff, away);
  INFO("band beside the cliff: raw " << b0 << ", smoothed " << b1 << ", strongly smoothed " << b2
                                     << ", the same without the agreement rule " << b3 << "; away from it: " << a0
                                     << " -> " << a1);
  CHECK(a1 < 0.8 * a0);           // the noise is averaged away from the cliff
  CHECK(b1 < b0 + 0.1 * sigma);   // and the cliff is kept as sharp as measured
  CHECK(b2 < b0 + 0.1 * sigma);   // even by a strong smoothing
  CHECK(b3 > 1.15 * b2);          // which the agreement rule is for (measured 1.28x)
}

TEST_CASE("displacement smoothing: clean data is left as measured", "[multires][displacement]") {
  const PointCloud cloud = scan(bump, 36864, 0.0, 12);
  const Measured before = measure(cloud, raw());
  const Measured after = measure(cloud, finest_level());
  auto all = [](const Vec3&) { return true; };
  const double e0 = mean_error(before, bump, all), e1 = mean_error(after, bump, all);
  INFO("error " << e0 << " -> " << e1 << ", peak " << peak(before) << " -> " << peak(after));
  CHECK(e1 < 1.1 * e0 + 1e-5);
  CHECK(std::abs(peak(after) - peak(before)) < 1e-3);
}

TEST_CASE("displacement smoothing: local update still equals a full recompute", "[multires][displacement]") {
  const PointCloud cloud = scan(bump, 9216, 0.02, 31);
  Measured m = measure(cloud, finest_level());
  REQUIRE(m.stats.smoothed[3] > 0);
  check_local_update_equals_recompute(m);
}

TEST_CASE("displacement smoothing: bad options are refused", "[multires][displacement]") {
  MultiresMesh mr;
  REQUIRE(build_multires(regular_grid(4, 4), 1, mr).ok());
  const PointCloud cloud = scan(bump, 200, 0.0, 1);
  DisplacementOptions o;
  o.smooth_finest_levels = -1;
  CHECK(measure_displacements(cloud, o, mr).code == ErrorCode::InvalidInput);
  o = DisplacementOptions{};
  o.smooth_strength = std::nan("");
  CHECK(measure_displacements(cloud, o, mr).code == ErrorCode::InvalidInput);
  o = DisplacementOptions{};
  o.smooth_agreement = 0;
  CHECK(measure_displacements(cloud, o, mr).code == ErrorCode::InvalidInput);
  o = DisplacementOptions{};
  o.smooth_iterations = -2;
  CHECK(measure_displacements(cloud, o, mr).code == ErrorCode::InvalidInput);
}
