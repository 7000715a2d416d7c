#include "test_scan.h"

#include "head/generic_head.h"
#include "head/generic_head_builder.h"

#include <catch2/catch.hpp>
#include <random>

namespace lk::test {

const GenericHead& generic_head() {
  static const GenericHead generic = [] {
    GenericHead g;
    const Status st = load_generic_head(g);
    INFO(st.message);
    REQUIRE(st.ok());
    return g;
  }();
  return generic;
}

GenericHead built_generic_head(const GenericHeadBuildOptions& options) {
  GenericHead g;
  const Status st = build_generic_head(options, g);
  INFO(st.message);
  REQUIRE(st.ok());
  return g;
}

const GenericHead& back_rows_generic_head() {
  static const GenericHead generic = [] {
    GenericHeadBuildOptions options;
    options.regular_nape = false;
    options.mirror_diagonals = false;  // the asset's quads of then, split side by side
    options.fair_iterations = 0;       // and its skin as cast, not faired
    return built_generic_head(options);
  }();
  return generic;
}

const GenericHead& corner45_generic_head() {
  static const GenericHead generic = [] {
    GenericHeadBuildOptions options;
    options.even_eye_corners = false;
    options.even_back_rows = false;  // the asset's rows of then, too
    options.regular_nape = false;    // and its nape
    options.fair_iterations = 0;     // and its skin as cast, not faired
    options.mirror_diagonals = false;
    return built_generic_head(options);
  }();
  return generic;
}

GenericHead make_test_head(std::uint32_t seed, const SynthHeadOptions& options, const GenericHead& generic) {
  GenericHead head;
  const Status st = synthesize_head(generic, seed, options, head);
  INFO(st.message);
  REQUIRE(st.ok());
  return head;
}

TruthSurface make_test_truth(const GenericHead& head, std::uint32_t seed, const TruthOptions& options) {
  TruthSurface truth;
  const Status st = make_truth_surface(head, seed, options, truth);
  INFO(st.message);
  REQUIRE(st.ok());
  return truth;
}

PointCloud scan_test_truth(const TruthSurface& truth, std::uint32_t seed, int points, ScannerOptions options,
                           ScanStats* stats) {
  options.target_points = points;
  options.hair_triangles = truth.hair;
  PointCloud scan;
  const Status st = scan_virtual(truth.mesh, options, seed, scan, stats);
  INFO(st.message);
  REQUIRE(st.ok());
  return scan;
}

TestScan make_test_scan(std::uint32_t seed, int points, const TestScanOptions& options) {
  TestScan s;
  s.head = make_test_head(seed, options.head, options.generic ? *options.generic : generic_head());
  s.truth = make_test_truth(s.head, seed, options.truth);
  s.scanner = options.scanner;
  s.scanner.target_points = points;
  s.scanner.hair_triangles = s.truth.hair;
  s.scan = scan_test_truth(s.truth, seed, points, s.scanner, &s.stats);
  return s;
}

PointCloud scan_height_field(const std::function<double(double, double)>& surface, double size,
                             int count, double sigma, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, size);
  std::normal_distribution<double> g(0, 1);
  PointCloud c;
  for (int i = 0; i < count; ++i) {
    const double x = u(rng), y = u(rng);
    c.positions.push_back(Vec3(x, y, surface(x, y) + sigma * g(rng)));
  }
  return c;
}

Vec3 vertices_centroid(const TriMesh& mesh, const std::vector<int>& indices) {
  Vec3 c = Vec3::Zero();
  for (int v : indices) c += mesh.positions[static_cast<size_t>(v)];
  return c / static_cast<double>(indices.size());
}

}  // namespace lk::test
