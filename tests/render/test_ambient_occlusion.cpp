// Ambient occlusion against analytic cases: an open plane sees the whole
// hemisphere; between two parallel planes at gap g with rays of length R,
// a cosine-weighted ray escapes iff cos(theta) < g / R, i.e. with
// probability (g / R)^2.
#include <catch2/catch.hpp>

#include "render/ambient_occlusion.h"

#include <cmath>

using namespace lk;

namespace {

// An n x n grid of quads in the plane z = height, facing +z or -z.
void append_plane(TriMesh& m, double half, double height, bool up, int n) {
  const int base = m.num_vertices();
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i)
      m.positions.emplace_back(-half + 2 * half * i / n, -half + 2 * half * j / n, height);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = base + j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
      if (up) {
        m.triangles.push_back({a, b, d});
        m.triangles.push_back({a, d, c});
      } else {
        m.triangles.push_back({a, d, b});
        m.triangles.push_back({a, c, d});
      }
    }
}

}  // namespace

TEST_CASE("an open plane is unoccluded", "[render][ao]") {
  TriMesh plane;
  append_plane(plane, 1.0, 0.0, true, 10);
  std::vector<float> ao;
  REQUIRE(vertex_ambient_occlusion(plane, OcclusionOptions{}, ao).ok());
  REQUIRE(ao.size() == plane.positions.size());
  for (float a : ao) CHECK(a == 1.0f);
}

TEST_CASE("between parallel planes the open share is (gap / reach)^2", "[render][ao]") {
  const double half = 1.0, gap = 0.1;
  TriMesh sandwich;
  append_plane(sandwich, half, 0.0, true, 10);   // floor, facing up
  append_plane(sandwich, half, gap, false, 10);  // ceiling, facing down
  const double diagonal = std::sqrt(8 * half * half + gap * gap);
  const int centre = 5 * 11 + 5;  // the floor's middle vertex, far from the edges
  for (const double ratio : {0.5, 0.25}) {
    OcclusionOptions o;
    o.rays = 256;
    o.max_distance_fraction = gap / ratio / diagonal;  // reach R = gap / ratio
    std::vector<float> ao;
    REQUIRE(vertex_ambient_occlusion(sandwich, o, ao).ok());
    INFO("g/R = " << ratio << ": open share " << ao[centre]);
    CHECK(ao[centre] == Approx(ratio * ratio).margin(0.02));
  }
  // With rays shorter than the gap nothing is hit.
  OcclusionOptions short_rays;
  short_rays.max_distance_fraction = 0.5 * gap / diagonal;
  std::vector<float> ao;
  REQUIRE(vertex_ambient_occlusion(sandwich, short_rays, ao).ok());
  CHECK(ao[centre] == 1.0f);
}

TEST_CASE("ambient occlusion rejects bad input and can be cancelled", "[render][ao]") {
  std::vector<float> ao;
  CHECK(vertex_ambient_occlusion(TriMesh{}, OcclusionOptions{}, ao).code == ErrorCode::Empty);
  TriMesh plane;
  append_plane(plane, 1.0, 0.0, true, 4);
  OcclusionOptions bad;
  bad.rays = 0;
  CHECK(vertex_ambient_occlusion(plane, bad, ao).code == ErrorCode::InvalidInput);
  OcclusionOptions small;
  small.max_vertices = 3;
  CHECK(vertex_ambient_occlusion(plane, small, ao).code == ErrorCode::TooLarge);
  TriMesh broken = plane;
  broken.triangles.push_back({0, 1, 999});
  CHECK(vertex_ambient_occlusion(broken, OcclusionOptions{}, ao).code == ErrorCode::InvalidInput);
  const Status cancelled =
      vertex_ambient_occlusion(plane, OcclusionOptions{}, ao, [](const char*, double) { return false; });
  CHECK(cancelled.code == ErrorCode::Cancelled);
}
