// Thinning a dense scan into cell averages (pipeline/scan_thinning.h): no
// region emptied, every point near a kept one, the noise averaged, the two
// sides of a fold kept apart; and fit_head on a thinned dense scan against
// the same scan fitted whole.
#include "head/generic_head.h"
#include "mesh/geometry.h"
#include "pipeline/fit_head.h"
#include "pipeline/fit_quality.h"
#include "pipeline/scan_thinning.h"
#include "raycast/self_intersection.h"
#include "test_scan.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <tuple>

using namespace lk;

namespace {

using Cell = std::tuple<long, long, long>;

Cell cell_of(const Vec3& p, const Vec3& lo, double cell) {
  return {static_cast<long>(std::floor((p.x() - lo.x()) / cell)), static_cast<long>(std::floor((p.y() - lo.y()) / cell)),
          static_cast<long>(std::floor((p.z() - lo.z()) / cell))};
}

// n points on a sphere of radius r, with radial depth noise sigma and
// outward normals; a tenth of them packed into one small cap (a region the
// scanner covered many times).
PointCloud noisy_sphere(int n, double r, double sigma, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  PointCloud c;
  for (int i = 0; i < n; ++i) {
    Vec3 d(g(rng), g(rng), g(rng));
    if (i % 10 == 0) d = Vec3(0.05 * g(rng), 0.05 * g(rng), 1.0);
    d.normalize();
    c.positions.push_back((r + sigma * g(rng)) * d);
    c.normals.push_back(d);
  }
  return c;
}

}  // namespace

TEST_CASE("thin_scan: one average per occupied cell, inside it, every point near a kept one") {
  const PointCloud scan = noisy_sphere(60000, 0.1, 0.0002, 3);
  const double cell = 0.004;
  PointCloud out;
  ScanThinning stats;
  REQUIRE(thin_scan(scan, cell, out, stats).ok());
  REQUIRE(stats.thinned);
  CHECK(stats.points == 60000);
  CHECK(stats.cell == cell);
  Vec3 lo = scan.positions[0];
  for (const Vec3& p : scan.positions) lo = lo.cwiseMin(p);
  // Occupied cells, counted here independently (the normals all point out,
  // so on a sphere a cell may still hold two classes at its edges).
  std::set<Cell> occupied;
  for (const Vec3& p : scan.positions) occupied.insert(cell_of(p, lo, cell));
  std::map<Cell, int> kept_per_cell;
  for (const Vec3& q : out.positions) {
    // Inside its cell, up to rounding: the cell of a point nudged towards
    // the cell's centre.
    ++kept_per_cell[cell_of(q, lo, cell)];
  }
  CHECK(static_cast<int>(out.positions.size()) == stats.kept);
  CHECK(stats.kept < 0.5 * stats.points);  // the sphere is dense at this cell
  // No region emptied: every occupied cell holds a kept point, and only
  // occupied cells do.
  int missing = 0, stray = 0;
  for (const Cell& c : occupied) missing += kept_per_cell.count(c) == 0;
  for (const auto& kv : kept_per_cell) stray += occupied.count(kv.first) == 0;
  CHECK(missing == 0);
  CHECK(stray == 0);
  // At most 6 normal classes share a cell; on a sphere's small cell, at most 3.
  for (const auto& kv : kept_per_cell) CHECK(kv.second <= 3);
  // Every scan point lies within the cell's diagonal of a kept point of its cell.
  std::map<Cell, std::vector<Vec3>> kept_at;
  for (const Vec3& q : out.positions) kept_at[cell_of(q, lo, cell)].push_back(q);
  double worst = 0;
  for (const Vec3& p : scan.positions) {
    double best = 1e300;
    for (const Vec3& q : kept_at[cell_of(p, lo, cell)]) best = std::min(best, (p - q).norm());
    worst = std::max(worst, best);
  }
  CHECK(worst <= std::sqrt(3.0) * cell);
  // Normals stay unit and outward.
  for (size_t i = 0; i < out.positions.size(); ++i) {
    CHECK(std::abs(out.normals[i].norm() - 1) < 1e-9);
    CHECK(out.normals[i].dot(out.positions[i].normalized()) > 0.9);
  }
}

TEST_CASE("thin_scan: averages, so the scanner's noise drops with the points of a cell") {
  // A flat patch z = 0 seen from above with 1 mm noise, 100 points a cell.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 0.1);
  std::normal_distribution<double> g(0.0, 0.001);
  PointCloud scan;
  for (int i = 0; i < 100000; ++i) scan.positions.push_back(Vec3(u(rng), u(rng), g(rng)));
  PointCloud out;
  ScanThinning stats;
  REQUIRE(thin_scan(scan, 0.01, out, stats).ok());
  REQUIRE(stats.kept == 100);  // 10 x 10 cells; one class with no normals
  double sum2 = 0;
  for (const Vec3& q : out.positions) sum2 += q.z() * q.z();
  const double rms = std::sqrt(sum2 / out.positions.size());
  INFO("rms height of the averages " << rms << " m, of the points 0.001 m");
  // 1 mm / sqrt(1000 points a cell) = 0.03 mm; one picked point would keep 1 mm.
  CHECK(rms < 0.0001);
}

TEST_CASE("thin_scan: two sheets facing apart in the same cells stay two") {
  // An ear's back against the scalp: points 0.2 mm apart, normals opposite.
  PointCloud scan;
  for (int i = 0; i < 50; ++i)
    for (int j = 0; j < 50; ++j) {
      scan.positions.push_back(Vec3(i * 0.0002, j * 0.0002, 0.0));
      scan.normals.push_back(Vec3(0, 0, 1));
      scan.positions.push_back(Vec3(i * 0.0002, j * 0.0002, 0.0002));
      scan.normals.push_back(Vec3(0, 0, -1));
    }
  PointCloud out;
  ScanThinning stats;
  REQUIRE(thin_scan(scan, 0.002, out, stats).ok());
  int up = 0, down = 0;
  for (size_t i = 0; i < out.positions.size(); ++i) {
    if (out.normals[i].z() > 0) {
      ++up;
      CHECK(out.positions[i].z() == 0.0);
    } else {
      ++down;
      CHECK(std::abs(out.positions[i].z() - 0.0002) < 1e-12);
    }
  }
  CHECK(up == 25);  // 5 x 5 cells (the last row and column share the fifth)
  CHECK(down == 25);
}

TEST_CASE("thin_scan: bad input is refused, an empty scan stays empty") {
  PointCloud scan, out;
  ScanThinning stats;
  CHECK(thin_scan(scan, 0.001, out, stats).ok());
  CHECK(out.positions.empty());
  scan.positions = {Vec3(0, 0, 0), Vec3(1, 1, 1)};
  CHECK(thin_scan(scan, 0.0, out, stats).code == ErrorCode::InvalidInput);
  CHECK(thin_scan(scan, std::nan(""), out, stats).code == ErrorCode::InvalidInput);
  scan.positions.push_back(Vec3(std::nan(""), 0, 0));
  CHECK(thin_scan(scan, 0.1, out, stats).code == ErrorCode::InvalidInput);
  // A cell far below the extent's 2^20 cells gets larger, not a wrapped key.
  scan.positions = {Vec3(0, 0, 0), Vec3(100, 0, 0), Vec3(100, 1e-9, 0)};
  REQUIRE(thin_scan(scan, 1e-9, out, stats).ok());
  CHECK(stats.cell > 100.0 / 1048576);
  CHECK(stats.kept == 2);
}

TEST_CASE("fit_head: a dense scan is fitted on cell averages, as close to its truth and its points as whole") {
  // A 300k-point scan at level 2: the cells (a level-2 edge / 4) hold about
  // two points each, so the scan is thinned.
  const test::TestScan person = test::make_test_scan(4, 300000);
  const GenericHead& generic = test::generic_head();
  FitHeadOptions thin;
  thin.levels = 2;
  thin.thin_cells_per_edge = 4;
  FitHeadOptions whole = thin;
  whole.thin_cells_per_edge = 0;
  FitHeadResult a, b;
  REQUIRE(fit_head(person.scan, generic, thin, a).ok());
  REQUIRE(fit_head(person.scan, generic, whole, b).ok());
  REQUIRE(a.thinning.thinned);
  CHECK(!b.thinning.thinned);
  CHECK(a.points == 300000);
  // Measured at the full scan's size (its hair returns left out of the
  // averages would shrink the box).
  CHECK(a.bbox_diagonal == b.bbox_diagonal);
  CHECK(a.thinning.kept < 0.6 * a.thinning.points);
  // The user is told, in the page's numbers.
  bool told = false;
  for (const std::string& n : a.notes) told = told || n.rfind("300,000 points, fitted on ", 0) == 0;
  CHECK(told);
  // Against the FULL scan (its points above the neck cut) and the truth.
  auto against = [&](const FitHeadResult& r, double& table1, double& truth_mm, double& face_mm, int& pairs) {
    const TriMesh& finest = r.level_meshes.back();
    ClipPlane neck;
    neck.point = r.generic_to_head.apply(generic.annotations.neck_clip.point);
    neck.normal = (r.generic_to_head.A.inverse().transpose() * generic.annotations.neck_clip.normal).normalized();
    std::vector<Vec3> above;
    for (const Vec3& p : person.scan.positions)
      if (neck.keeps(r.scan_to_head.apply(p))) above.push_back(r.scan_to_head.apply(p));
    table1 = point_to_surface_stats(above, finest, r.bbox_diagonal * r.unit_to_metres).mean_pct;
    truth_mm = 1e3 * point_to_surface_stats(person.truth.mesh.positions, finest, 1.0).mean;
    CoveredDistances face;
    REQUIRE(measure_fit_to_scan(r, person.scan, generic, face).ok());
    face_mm = 1e3 * face.mean;
    std::vector<std::array<int, 2>> crossing;
    REQUIRE(find_self_intersections(finest, crossing).ok());
    pairs = static_cast<int>(crossing.size());
  };
  double t_a, t_b, truth_a, truth_b, face_a, face_b;
  int pairs_a, pairs_b;
  against(a, t_a, truth_a, face_a, pairs_a);
  against(b, t_b, truth_b, face_b, pairs_b);
  INFO("thinned to " << a.thinning.kept << " (cell " << 1e3 * a.thinning.cell << " mm): Table 1 over the full scan "
                     << t_a << " % vs " << t_b << " %; truth -> surface " << truth_a << " vs " << truth_b
                     << " mm; face -> scan " << face_a << " vs " << face_b << " mm; crossing pairs " << pairs_a
                     << " vs " << pairs_b);
  // Measured (29 Nov): Table 1 0.0556 vs 0.0515 %, truth 0.523 vs 0.700 mm,
  // face 0.089 vs 0.084 mm, 0 pairs each: close, not equal (thinning is off
  // by default). Averaging the hair returns in with the skin (they then
  // looked like skin and were fitted) gave truth 0.92 mm here.
  CHECK(t_a <= 1.15 * t_b);
  CHECK(truth_a <= 1.15 * truth_b);
  CHECK(face_a <= 1.10 * face_b);
  CHECK(pairs_a <= pairs_b);
}
