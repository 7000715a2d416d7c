// isolated_scan_points: sparse returns (hair junk) above a densely sampled
// surface are flagged, the surface is not; a scan that is sparse everywhere
// keeps every point (the test is relative to the scan's own spacing).
#include "multires/displacement.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <unordered_map>

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

// The definition, written out plainly: the spacing is the median over every
// max(1, n / 4096)-th point of the distance to its nearest other point
// (brute force; a point with a copy elsewhere is left out), and a point is
// isolated when the 3x3x3 cells of 4 spacings around it hold fewer than
// (12 spacings / spacing)^2 / ratio points.
std::vector<char> isolated_reference(const std::vector<Vec3>& pts, double ratio) {
  const size_t n = pts.size();
  std::vector<char> out(n, 0);
  if (n < 16) return out;
  std::vector<double> nearest;
  for (size_t i = 0; i < n; i += std::max<size_t>(1, n / 4096)) {
    double best = std::numeric_limits<double>::infinity();
    bool copy = false;
    for (size_t j = 0; j < n; ++j) {
      if (j == i) continue;
      const double ex = pts[j].x() - pts[i].x(), ey = pts[j].y() - pts[i].y(), ez = pts[j].z() - pts[i].z();
      const double d2 = ex * ex + ey * ey + ez * ez;
      copy = copy || d2 == 0;
      best = std::min(best, d2);
    }
    if (!copy && std::isfinite(best)) nearest.push_back(std::sqrt(best));
  }
  if (nearest.empty()) return out;
  std::sort(nearest.begin(), nearest.end());
  const size_t h = nearest.size() / 2;
  const double spacing = nearest.size() % 2 ? nearest[h] : 0.5 * (nearest[h - 1] + nearest[h]);
  const double cell = 4 * spacing, needed = (3 * cell / spacing) * (3 * cell / spacing) / ratio;
  auto key = [&](const Vec3& p, int dx, int dy, int dz) {
    auto c = [&](double v, int d) { return static_cast<std::int64_t>(std::floor(v / cell)) + d + (1 << 20); };
    return (c(p.x(), dx) << 42) ^ (c(p.y(), dy) << 21) ^ c(p.z(), dz);
  };
  std::unordered_map<std::int64_t, int> count;
  for (const Vec3& p : pts) ++count[key(p, 0, 0, 0)];
  for (size_t i = 0; i < n; ++i) {
    int around = 0;
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const auto it = count.find(key(pts[i], dx, dy, dz));
          if (it != count.end()) around += it->second;
        }
    out[i] = around < needed;
  }
  return out;
}

}  // namespace

TEST_CASE("multires: isolated scan points are exactly those of the plain definition", "[multires]") {
  // The implementation finds the spacing over a grid (stray points only
  // known to lie far) and sums cells once per cell: the flags must be the
  // brute-force definition's, on a noisy sphere with junk, stray points far
  // off and exact copies, on a flat patch (no volume: another path), and on
  // a cloud that is mostly strays.
  std::mt19937 rng(11);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  auto sphere = [&](int count, double radius, double noise) {
    std::vector<Vec3> pts;
    for (int i = 0; i < count; ++i) {
      const Vec3 d = Vec3(gauss(rng), gauss(rng), gauss(rng)).normalized();
      pts.push_back(d * (radius + noise * gauss(rng)));
    }
    return pts;
  };
  for (double scale : {0.001, 1.0, 250.0}) {
    INFO("scale " << scale);
    std::vector<Vec3> pts = sphere(9000, 100 * scale, 0.2 * scale);
    for (int i = 0; i < 200; ++i) pts.push_back(Vec3(unit(rng), unit(rng), unit(rng)) * 130 * scale);  // junk
    for (int i = 0; i < 30; ++i) pts.push_back(Vec3(unit(rng), unit(rng), unit(rng)) * 900 * scale);   // far strays
    for (int i = 0; i < 40; ++i) pts.push_back(pts[static_cast<size_t>(i) * 97]);                    // copies
    std::shuffle(pts.begin(), pts.end(), rng);
    const std::vector<char> got = isolated_scan_points(pts, 30.0), want = isolated_reference(pts, 30.0);
    CHECK(got == want);
    CHECK(std::count(want.begin(), want.end(), 1) > 150);  // the junk and strays are found
  }
  SECTION("a flat patch") {
    std::vector<Vec3> pts = plane(0.5, 40, rng);
    for (int i = 0; i < 20; ++i) pts.push_back(Vec3(40 + 30 * unit(rng), 40 * unit(rng), 0.0));
    CHECK(isolated_scan_points(pts, 30.0) == isolated_reference(pts, 30.0));
  }
  SECTION("a nearly flat scatter: the grid's cells are as thin as the cloud, most points far apart") {
    // A dense patch and a sparse rest, 1e-7 thick: cells of cbrt(volume /
    // points) put most points more than two cells from any other.
    std::vector<Vec3> pts;
    std::uniform_real_distribution<double> u01(0.0, 1.0);
    for (int i = 0; i < 5000; ++i) pts.push_back(Vec3(0.2 * u01(rng), 0.2 * u01(rng), 1e-7 * u01(rng)));
    for (int i = 0; i < 1000; ++i) pts.push_back(Vec3(0.2 + 0.8 * u01(rng), u01(rng), 1e-7 * u01(rng)));
    const std::vector<char> want = isolated_reference(pts, 30.0);
    CHECK(isolated_scan_points(pts, 30.0) == want);
    CHECK(std::count(want.begin(), want.end(), 1) > 500);  // the sparse rest
  }
  SECTION("a tight cluster in a wide box of strays") {
    std::vector<Vec3> pts = sphere(3000, 1.0, 0.01);
    for (int i = 0; i < 5000; ++i) pts.push_back(Vec3(unit(rng), unit(rng), unit(rng)) * 1000.0);
    std::shuffle(pts.begin(), pts.end(), rng);
    CHECK(isolated_scan_points(pts, 30.0) == isolated_reference(pts, 30.0));
  }
}

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
