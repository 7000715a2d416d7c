// fit/scan_noise.h: a scan's noise floor, from quadric fits to its own points.
#include "fit/scan_noise.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <random>

using namespace lk;

namespace {

// n points spread evenly over a sphere of radius r, each moved along its
// radius by Gaussian noise of standard deviation sigma.
std::vector<Vec3> noisy_sphere(int n, double r, double sigma, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<Vec3> p;
  const double golden = 3.14159265358979323846 * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double y = 1.0 - 2.0 * (i + 0.5) / n, ring = std::sqrt(1.0 - y * y), a = golden * i;
    const Vec3 dir(ring * std::cos(a), y, ring * std::sin(a));
    p.push_back((r + sigma * noise(rng)) * dir);
  }
  return p;
}

}  // namespace

TEST_CASE("estimate_scan_noise: the floor of a noisy sphere is the mean |noise| it was given", "[fit][scan_noise]") {
  // A head-sized sphere (10 cm) sampled every ~1.8 mm: a quadric over 16
  // points follows it to well under a micrometre, so what is left is noise.
  const double mean_abs = std::sqrt(2.0 / 3.14159265358979323846);  // E|N(0, 1)|
  for (double sigma : {0.05e-3, 0.2e-3, 0.5e-3}) {
    ScanNoise noise;
    REQUIRE(estimate_scan_noise(noisy_sphere(40000, 0.1, sigma, 7), {}, 16, noise).ok());
    INFO("sigma " << sigma << ": estimated " << noise.sigma_mean << " (median " << noise.sigma_median
                  << "), floor " << noise.floor);
    CHECK(noise.points == 40000);
    CHECK(noise.sigma_mean == Approx(sigma).epsilon(0.1));
    CHECK(noise.floor == Approx(mean_abs * sigma).epsilon(0.1));
  }
  // Without noise the curvature alone leaves next to nothing.
  ScanNoise clean;
  REQUIRE(estimate_scan_noise(noisy_sphere(40000, 0.1, 0.0, 7), {}, 16, clean).ok());
  CHECK(clean.floor < 1e-6);
}

TEST_CASE("estimate_scan_noise: only the masked points are averaged", "[fit][scan_noise]") {
  // The upper half noisy, the lower half clean: each half's own floor.
  std::vector<Vec3> pts = noisy_sphere(40000, 0.1, 0.3e-3, 3);
  const std::vector<Vec3> clean = noisy_sphere(40000, 0.1, 0.0, 3);
  std::vector<char> upper(pts.size()), lower(pts.size());
  for (size_t i = 0; i < pts.size(); ++i) {
    if (clean[i].y() < 0) pts[i] = clean[i];
    upper[i] = clean[i].y() > 0.02;  // away from the seam, where patches mix both
    lower[i] = clean[i].y() < -0.02;
  }
  ScanNoise top, bottom;
  REQUIRE(estimate_scan_noise(pts, upper, 16, top).ok());
  REQUIRE(estimate_scan_noise(pts, lower, 16, bottom).ok());
  CHECK(top.sigma_mean == Approx(0.3e-3).epsilon(0.1));
  CHECK(bottom.sigma_mean < 1e-6);
  CHECK(top.points < 20000);
}

TEST_CASE("estimate_scan_noise: bad input is refused with a message", "[fit][scan_noise]") {
  ScanNoise noise;
  CHECK(estimate_scan_noise(noisy_sphere(100, 0.1, 0, 1), {}, 6, noise).code == ErrorCode::InvalidInput);
  CHECK(estimate_scan_noise(noisy_sphere(10, 0.1, 0, 1), {}, 16, noise).code == ErrorCode::Empty);
  CHECK(estimate_scan_noise(noisy_sphere(100, 0.1, 0, 1), std::vector<char>(5, 1), 16, noise).code ==
        ErrorCode::InvalidInput);
  std::vector<Vec3> bad = noisy_sphere(100, 0.1, 0, 1);
  bad[3].x() = std::nan("");
  CHECK(estimate_scan_noise(bad, {}, 16, noise).code == ErrorCode::InvalidInput);
}
