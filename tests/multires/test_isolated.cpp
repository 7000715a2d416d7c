// isolated_scan_points: sparse returns (hair junk) above a densely sampled
// surface are flagged, the surface is not; a scan that is sparse everywhere
// keeps every point (the test is relative to the scan's own spacing).
#include "multires/displacement.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <random>

using namespace lk;

namespace {

// A jittered grid on the plane z = 0 with the given spacing, side x side.
std::vector<Vec3> plane(double spacing, double side, std::mt19937& rng) {
  std::uniform_real_distribution<double> jitter(-0.3 * spacing, 0.3 * spacing);
  std::vector<Vec3> pts;
  for (double x = 0; x < side; x += spacing)
    for (double y = 0; y < side; y += spacing) pts.emplace_back(x + jitter(rng), y + jitter(rng), 0.0);
  return pts;
}

}  // namespace

TEST_CASE("multires: isolated scan points are the sparse returns, not the surface", "[multires]") {
  std::mt19937 rng(3);
  for (double scale : {0.001, 1.0}) {  // metres or millimetres: scale-free
    INFO("scale " << scale);
    // The scanned skin: the left half (x < 50); the "scalp" on the right
    // returns no surface, only junk up to 10 units above it, at 1/80 of
    // the skin's point count (as a scanner's hair returns).
    std::vector<Vec3> pts = plane(0.5 * scale, 100 * scale, rng);
    pts.erase(std::remove_if(pts.begin(), pts.end(), [&](const Vec3& p) { return p.x() >= 50 * scale; }),
              pts.end());
    const size_t surface = pts.size();
    std::uniform_real_distribution<double> ux(55 * scale, 100 * scale), uy(0, 100 * scale), h(0, 10 * scale);
    const size_t junk = surface / 80;
    for (size_t i = 0; i < junk; ++i) pts.emplace_back(ux(rng), uy(rng), h(rng));
    const std::vector<char> isolated = isolated_scan_points(pts, 30.0);
    REQUIRE(isolated.size() == pts.size());
    size_t surface_flagged = 0, junk_flagged = 0;
    for (size_t i = 0; i < pts.size(); ++i) (i < surface ? surface_flagged : junk_flagged) += isolated[i];
    CHECK(surface_flagged == 0);
    CHECK(junk_flagged > 0.9 * junk);
  }
  SECTION("a scan sparse everywhere keeps all its points") {
    std::vector<Vec3> pts = plane(3.4, 300, rng);
    const std::vector<char> isolated = isolated_scan_points(pts, 30.0);
    CHECK(std::count(isolated.begin(), isolated.end(), 1) == 0);
  }
  SECTION("ratio 0 or tiny input flags nothing") {
    std::vector<Vec3> pts = plane(1.0, 10, rng);
    const std::vector<char> off = isolated_scan_points(pts, 0.0);
    CHECK(std::count(off.begin(), off.end(), 1) == 0);
    CHECK(isolated_scan_points({Vec3::Zero()}, 30.0) == std::vector<char>{0});
  }
}
