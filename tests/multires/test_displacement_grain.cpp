// The orange peel of the finest levels (core/multires/displacement.h,
// DisplacementOptions::smooth_*): the heights of the two finest levels are
// smoothed over the mesh, a coarser level's noise is what the finer one is
// measured against and is never measured again (jeong2002 Sec. 5: one
// displacement per vertex, on the level that introduced it), so smoothing
// the finest level alone leaves the level before's noise in a quarter of
// its vertices. Heights many errors tall (detail the coarser levels
// missed) and neighbours whose normals disagree take no part.
//
// Ground truth on a flat 12 x 12 control patch (level-3 edges ~0.14), as in
// test_displacement_smoothing.cpp: a Gaussian bump, a cliff and a roof
// ridge, sampled at random with Gaussian depth noise of a seventh of a
// level-3 edge (the synthetic heads' 0.2 mm on 1.3 mm edges).
#include "height_field_cases.h"
#include "test_scan.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <functional>

using namespace lk;
using namespace lk::test;

namespace {

constexpr double kSigma = 0.02;

// A ridge along x = 6.3, slopes of 1:2 on either side: the level-2
// normals across it differ by ~50 degrees.
double roof(double x, double) { return 0.5 * (3.0 - std::min(3.0, std::abs(x - kStepX))); }

// The defaults before the two finest levels were smoothed together.
DisplacementOptions finest_only() { return finest_level_smoothing(); }

}  // namespace

TEST_CASE("grain: smoothing the two finest levels takes the orange peel off, the bump kept",
          "[multires][displacement]") {
  const PointCloud cloud = test::scan_height_field(bump, 12, 36864, kSigma, 41);
  const Measured before = measure(cloud, finest_only());
  const Measured after = measure(cloud, DisplacementOptions{});
  auto flat = away_from_bump;
  auto on_bump = [](const Vec3& p) { return (p - kCentre).head<2>().norm() < 1.0; };
  const double e0 = mean_error(before, bump, flat), e1 = mean_error(after, bump, flat);
  const double r0 = roughness(before, flat), r1 = roughness(after, flat);
  const double b0 = mean_error(before, bump, on_bump), b1 = mean_error(after, bump, on_bump);
  INFO("flat error " << e0 << " -> " << e1 << ", roughness " << r0 << " -> " << r1 << " deg, bump error " << b0
                     << " -> " << b1 << ", peak " << peak(before) << " -> " << peak(after) << " (truth 0.3); level 2 "
                     << after.stats.smoothed[2] << " moved, level 3 " << after.stats.smoothed[3]);
  CHECK(before.stats.smoothed[2] == 0);
  CHECK(after.stats.smoothed[2] > 500);
  CHECK(after.stats.smoothed[3] > 1000);
  CHECK(after.stats.smoothed[1] == 0);  // the two finest levels only
  CHECK(e1 < 0.8 * e0);
  CHECK(r1 < 0.75 * r0);
  // The bump is detail, not noise: not flattened.
  CHECK(b1 < b0 + 0.1 * kSigma);
  CHECK(std::abs(peak(after) - peak(before)) < 0.25 * kSigma);
}

TEST_CASE("grain: a cliff and a ridge are not smoothed across on either level", "[multires][displacement]") {
  for (int shape = 0; shape < 2; ++shape) {
    const std::function<double(double, double)> surface = shape == 0 ? cliff : roof;
    const PointCloud cloud = test::scan_height_field(surface, 12, 36864, kSigma, 51 + shape);
    DisplacementOptions raw;
    raw.smooth_finest_levels = 0;
    const Measured measured = measure(cloud, raw);
    const Measured before = measure(cloud, finest_only());
    const Measured after = measure(cloud, DisplacementOptions{});
    auto band = [](const Vec3& p) { return std::abs(p.x() - 6.3) > 0.1 && std::abs(p.x() - 6.3) < 0.5; };
    auto away = [](const Vec3& p) { return std::abs(p.x() - 6.3) > 1.5 && std::abs(p.x() - 6.3) < 2.8; };
    const double bm = mean_error(measured, surface, band), b0 = mean_error(before, surface, band),
                 b1 = mean_error(after, surface, band);
    const double a0 = mean_error(before, surface, away), a1 = mean_error(after, surface, away);
    INFO((shape == 0 ? "cliff" : "roof") << ": band beside it: as measured " << bm << ", finest level smoothed " << b0
                                         << ", two levels " << b1 << "; away from it " << a0 << " -> " << a1);
    CHECK(b1 < bm + 0.1 * kSigma);  // as sharp as measured
    CHECK(a1 < 0.9 * a0);           // the noise beside it averaged more
  }
}

TEST_CASE("grain: clean data is left as measured", "[multires][displacement]") {
  const PointCloud cloud = test::scan_height_field(bump, 12, 36864, 0.0, 42);
  DisplacementOptions raw;
  raw.smooth_finest_levels = 0;
  const Measured before = measure(cloud, raw);
  const Measured after = measure(cloud, DisplacementOptions{});
  auto all = [](const Vec3&) { return true; };
  const double e0 = mean_error(before, bump, all), e1 = mean_error(after, bump, all);
  INFO("error " << e0 << " -> " << e1 << ", peak " << peak(before) << " -> " << peak(after));
  CHECK(e1 < 1.1 * e0 + 1e-5);
  CHECK(std::abs(peak(after) - peak(before)) < 1e-3);
}

TEST_CASE("grain: local update still equals a full recompute", "[multires][displacement]") {
  const PointCloud cloud = test::scan_height_field(bump, 12, 9216, kSigma, 61);
  Measured m = measure(cloud, DisplacementOptions{});
  REQUIRE(m.stats.smoothed[2] > 0);
  check_local_update_equals_recompute(m);
}

TEST_CASE("grain: bad options are refused", "[multires][displacement]") {
  MultiresMesh mr;
  REQUIRE(build_multires(regular_grid(4, 4), 1, mr).ok());
  const PointCloud cloud = test::scan_height_field(bump, 12, 200, 0.0, 1);
  DisplacementOptions o;
  o.smooth_normal_degrees = -1;
  CHECK(measure_displacements(cloud, o, mr).code == ErrorCode::InvalidInput);
  o = DisplacementOptions{};
  o.smooth_normal_degrees = 91;
  CHECK(measure_displacements(cloud, o, mr).code == ErrorCode::InvalidInput);
  o = DisplacementOptions{};
  o.smooth_max_height_errors = std::nan("");
  CHECK(measure_displacements(cloud, o, mr).code == ErrorCode::InvalidInput);
  o = DisplacementOptions{};
  o.smooth_max_height_errors = -3;
  CHECK(measure_displacements(cloud, o, mr).code == ErrorCode::InvalidInput);
}
