#include "fit/closest_point.h"

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

SurfacePoint ClosestPointTree::closest(const Vec3& p, double max_squared_distance) const {
  SurfacePoint best;
  best.squared_distance = max_squared_distance;
  const ClosestPoint c = closest_point(bvh_, p, std::sqrt(max_squared_distance));
  if (!c.found()) return best;
  best.face = c.triangle;
  best.point = c.point;
  best.barycentric = c.barycentric;
  best.squared_distance = (c.point - p).squaredNorm();
  return best;
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
  std::vector<double> d;
  if (tree.empty()) return DistanceStats{};
  stride = std::max(1, stride);
  d.reserve(points.size() / stride + 1);
  for (size_t i = 0; i < points.size(); i += stride)
    d.push_back(std::sqrt(tree.closest(points[i]).squared_distance));
  return summarize_distances(d, reference_diagonal);
}

}  // namespace lk
