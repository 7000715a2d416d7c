#include "fit/closest_point.h"

#include "common/parallel.h"

#include <algorithm>
#include <cmath>

namespace lk {

SurfacePoint closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  SurfacePoint r;
  r.point = lk::closest_point_on_triangle(p, a, b, c, r.barycentric);
  r.squared_distance = (r.point - p).squaredNorm();
  return r;
}

void ClosestPointTree::build(const TriMesh& mesh) {
  // A mesh with out-of-range indices or non-finite positions leaves the tree
  // empty: queries then find nothing, and callers validate meshes first.
  if (!build_bvh(mesh, bvh_).ok()) bvh_ = MeshBvh{};
}

namespace {
SurfacePoint to_surface_point(const ClosestPoint& c, const Vec3& p) {
  SurfacePoint s;
  s.face = c.triangle;
  s.point = c.point;
  s.barycentric = c.barycentric;
  s.squared_distance = (c.point - p).squaredNorm();
  return s;
}
}  // namespace

SurfacePoint ClosestPointTree::closest(const Vec3& p, double max_squared_distance) const {
  const ClosestPoint c = closest_point(bvh_, p, std::sqrt(max_squared_distance));
  if (c.found()) return to_surface_point(c, p);
  SurfacePoint none;
  none.squared_distance = max_squared_distance;
  return none;
}

SurfacePoint ClosestPointTree::closest_near(const Vec3& p, int guess) const {
  const ClosestPoint c = closest_point_near(bvh_, p, guess);
  if (c.found()) return to_surface_point(c, p);
  return SurfacePoint{};  // (an empty tree)
}

DistanceStats summarize_distances(std::vector<double>& d, double reference_diagonal) {
  DistanceStats s;
  s.count = static_cast<int>(d.size());
  if (d.empty()) return s;
  double sum = 0, sum2 = 0, mx = 0;
  for (double x : d) {
    sum += x;
    sum2 += x * x;
    mx = std::max(mx, x);
  }
  s.mean = sum / d.size();
  s.rms = std::sqrt(sum2 / d.size());
  s.max = mx;
  const size_t k = std::min(d.size() - 1, static_cast<size_t>(0.95 * d.size()));
  std::nth_element(d.begin(), d.begin() + k, d.end());
  s.p95 = d[k];
  if (reference_diagonal > 0) {
    s.mean_pct = 100.0 * s.mean / reference_diagonal;
    s.max_pct = 100.0 * s.max / reference_diagonal;
  }
  return s;
}

DistanceStats point_to_surface_stats(const std::vector<Vec3>& points, const TriMesh& mesh,
                                     double reference_diagonal, int stride) {
  ClosestPointTree tree(mesh);
  if (tree.empty()) return DistanceStats{};
  stride = std::max(1, stride);
  const int n = static_cast<int>((points.size() + stride - 1) / stride);
  std::vector<double> d(n);
  constexpr int kRun = 512;  // points per run (one guess chain)
  parallel_for(0, (n + kRun - 1) / kRun, 1, [&](int run, int) {
    int face = -1;
    for (int k = run * kRun; k < std::min(n, (run + 1) * kRun); ++k) {
      const SurfacePoint c = tree.closest_near(points[size_t(k) * stride], face);
      face = c.face;
      d[k] = std::sqrt(c.squared_distance);
    }
  });
  return summarize_distances(d, reference_diagonal);
}

}  // namespace lk
