#include "fit/closest_point.h"

#include <algorithm>
#include <cmath>

namespace lk {

// Ericson, "Real-Time Collision Detection", Sec. 5.1.5: Voronoi regions of
// the triangle's vertices, edges and face, in that order.
SurfacePoint closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  SurfacePoint r;
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  auto done = [&](double u, double v, double w) {
    r.barycentric = Vec3(u, v, w);
    r.point = u * a + v * b + w * c;
    r.squared_distance = (r.point - p).squaredNorm();
    return r;
  };
  if (d1 <= 0 && d2 <= 0) return done(1, 0, 0);
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return done(0, 1, 0);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    return done(1 - v, v, 0);
  }
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return done(0, 0, 1);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double w = d2 / (d2 - d6);
    return done(1 - w, 0, w);
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return done(0, 1 - w, w);
  }
  const double denom = va + vb + vc;
  if (!(std::abs(denom) > 0)) {
    // Degenerate (zero-area) triangle: the nearest of its three edges.
    SurfacePoint best;
    const Vec3* q[3] = {&a, &b, &c};
    for (int k = 0; k < 3; ++k) {
      const Vec3& s = *q[k];
      const Vec3& e = *q[(k + 1) % 3];
      const Vec3 d = e - s;
      const double len2 = d.squaredNorm();
      const double t = len2 > 0 ? std::clamp((p - s).dot(d) / len2, 0.0, 1.0) : 0.0;
      const Vec3 x = s + t * d;
      const double dist2 = (x - p).squaredNorm();
      if (dist2 < best.squared_distance) {
        best.squared_distance = dist2;
        best.point = x;
        best.barycentric = Vec3::Zero();
        best.barycentric[k] = 1 - t;
        best.barycentric[(k + 1) % 3] = t;
      }
    }
    return best;
  }
  const double v = vb / denom, w = vc / denom;
  return done(1 - v - w, v, w);
}

void ClosestPointTree::build(const TriMesh& mesh) {
  positions_ = mesh.positions;
  triangles_ = mesh.triangles;
  nodes_.clear();
  order_.resize(triangles_.size());
  std::vector<Vec3> centroids(triangles_.size());
  for (size_t f = 0; f < triangles_.size(); ++f) {
    order_[f] = static_cast<int>(f);
    const Tri& t = triangles_[f];
    centroids[f] = (positions_[t[0]] + positions_[t[1]] + positions_[t[2]]) / 3.0;
  }
  if (!triangles_.empty()) {
    nodes_.reserve(2 * triangles_.size() / 2 + 1);
    build_node(0, static_cast<int>(triangles_.size()), centroids);
  }
}

int ClosestPointTree::build_node(int first, int count, std::vector<Vec3>& centroids) {
  const int id = static_cast<int>(nodes_.size());
  nodes_.push_back(Node{});
  Vec3 lo = Vec3::Constant(1e300), hi = Vec3::Constant(-1e300);
  Vec3 clo = lo, chi = hi;
  for (int i = first; i < first + count; ++i) {
    const Tri& t = triangles_[order_[i]];
    for (int k = 0; k < 3; ++k) {
      lo = lo.cwiseMin(positions_[t[k]]);
      hi = hi.cwiseMax(positions_[t[k]]);
    }
    clo = clo.cwiseMin(centroids[order_[i]]);
    chi = chi.cwiseMax(centroids[order_[i]]);
  }
  nodes_[id].min = lo;
  nodes_[id].max = hi;
  constexpr int kLeafSize = 4;
  if (count <= kLeafSize) {
    nodes_[id].first = first;
    nodes_[id].count = count;
    return id;
  }
  // Median split on the longest axis of the centroids' box: balanced trees
  // whatever the triangle size distribution.
  int axis = 0;
  (chi - clo).maxCoeff(&axis);
  const int mid = first + count / 2;
  std::nth_element(order_.begin() + first, order_.begin() + mid, order_.begin() + first + count,
                   [&](int a, int b) { return centroids[a][axis] < centroids[b][axis]; });
  const int left = build_node(first, mid - first, centroids);
  const int right = build_node(mid, first + count - mid, centroids);
  nodes_[id].left = left;
  nodes_[id].right = right;
  nodes_[id].count = 0;
  return id;
}

static inline double box_squared_distance(const Vec3& p, const Vec3& lo, const Vec3& hi) {
  double d = 0;
  for (int k = 0; k < 3; ++k) {
    const double e = p[k] < lo[k] ? lo[k] - p[k] : (p[k] > hi[k] ? p[k] - hi[k] : 0.0);
    d += e * e;
  }
  return d;
}

SurfacePoint ClosestPointTree::closest(const Vec3& p, double max_squared_distance) const {
  SurfacePoint best;
  best.squared_distance = max_squared_distance;
  if (nodes_.empty()) return best;
  int stack[128];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& n = nodes_[stack[--top]];
    if (box_squared_distance(p, n.min, n.max) >= best.squared_distance) continue;
    if (n.count > 0) {
      for (int i = n.first; i < n.first + n.count; ++i) {
        const Tri& t = triangles_[order_[i]];
        SurfacePoint s = closest_point_on_triangle(p, positions_[t[0]], positions_[t[1]], positions_[t[2]]);
        if (s.squared_distance < best.squared_distance) {
          s.face = order_[i];
          best = s;
        }
      }
      continue;
    }
    // Visit the nearer child first so the bound tightens early.
    const Node& l = nodes_[n.left];
    const Node& r = nodes_[n.right];
    const double dl = box_squared_distance(p, l.min, l.max);
    const double dr = box_squared_distance(p, r.min, r.max);
    if (top + 2 > 128) continue;  // depth is ~log2(#F): never happens
    if (dl < dr) {
      stack[top++] = n.right;
      stack[top++] = n.left;
    } else {
      stack[top++] = n.left;
      stack[top++] = n.right;
    }
  }
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
