#include "raycast/self_intersection.h"

#include "common/parallel.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <string>
#include <utility>

namespace lk {

double orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const Vec3 u = b - a, v = c - a, w = d - a;
  const double m0 = u.y() * v.z(), m1 = u.z() * v.y();
  const double m2 = u.z() * v.x(), m3 = u.x() * v.z();
  const double m4 = u.x() * v.y(), m5 = u.y() * v.x();
  const double det = w.x() * (m0 - m1) + w.y() * (m2 - m3) + w.z() * (m4 - m5);
  const double permanent = std::abs(w.x()) * (std::abs(m0) + std::abs(m1)) +
                           std::abs(w.y()) * (std::abs(m2) + std::abs(m3)) +
                           std::abs(w.z()) * (std::abs(m4) + std::abs(m5));
  return std::abs(det) > 1e-15 * permanent ? det : 0.0;
}

namespace {

// Twice the signed area of (a, b, c), > 0 counter-clockwise; 0 when within
// Shewchuk's bound (3 + 16 eps) eps times the permanent (here 5e-16).
inline double orient2d(const Vec2& a, const Vec2& b, const Vec2& c) {
  const double left = (b.x() - a.x()) * (c.y() - a.y()), right = (b.y() - a.y()) * (c.x() - a.x());
  const double det = left - right;
  return std::abs(det) > 5e-16 * (std::abs(left) + std::abs(right)) ? det : 0.0;
}

inline bool opposite_or_zero(double s, double t) { return (s <= 0 && t >= 0) || (s >= 0 && t <= 0); }

bool segments_intersect_2d(const Vec2& p, const Vec2& q, const Vec2& a, const Vec2& b) {
  const double d1 = orient2d(a, b, p), d2 = orient2d(a, b, q);
  const double d3 = orient2d(p, q, a), d4 = orient2d(p, q, b);
  if (d1 == 0 && d2 == 0 && d3 == 0 && d4 == 0) {
    // Collinear: overlapping extents along the line, measured along the
    // longer segment (along a zero-length one every point has extent 0:
    // a point p = q on the line through a and b but beyond b was taken as
    // meeting it).
    if ((q - p).squaredNorm() < (b - a).squaredNorm()) return segments_intersect_2d(a, b, p, q);
    const Vec2 dir = q - p;
    const double len2 = dir.squaredNorm();
    if (len2 == 0) return p == a;  // both are points
    const double ta = (a - p).dot(dir), tb = (b - p).dot(dir);
    return std::max(std::min(ta, tb), 0.0) <= std::min(std::max(ta, tb), len2);
  }
  return opposite_or_zero(d1, d2) && opposite_or_zero(d3, d4);
}

bool point_in_triangle_2d(const Vec2& p, const Vec2& a, const Vec2& b, const Vec2& c) {
  const double s1 = orient2d(a, b, p), s2 = orient2d(b, c, p), s3 = orient2d(c, a, p);
  return (s1 >= 0 && s2 >= 0 && s3 >= 0) || (s1 <= 0 && s2 <= 0 && s3 <= 0);
}

// The projection onto the plane with normal n that drops n's largest axis
// (areas keep their sign up to the flip of that axis, and none vanishes).
struct PlaneProjection {
  int i = 1, j = 2;
  explicit PlaneProjection(const Vec3& n) {
    int drop = 0;
    n.cwiseAbs().maxCoeff(&drop);
    i = (drop + 1) % 3;
    j = (drop + 2) % 3;
  }
  Vec2 operator()(const Vec3& x) const { return Vec2(x[i], x[j]); }
};

// A point in the plane of triangle (a, b, c) with normal n: inside or on
// its edges, in that projection.
bool coplanar_point_in_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& n) {
  const PlaneProjection flat(n);
  return point_in_triangle_2d(flat(p), flat(a), flat(b), flat(c));
}

// A computed crossing point x (rounded, so off the plane and off an edge
// by a few ulps of `scale`, the segment's largest coordinate) in triangle
// (a, b, c): inside or within 1e-13 scale of an edge, in that projection.
bool crossing_in_triangle(const Vec3& x, const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& n, double scale) {
  const PlaneProjection flat(n);
  const Vec2 P = flat(x), A = flat(a), B = flat(b), C = flat(c);
  const double tol = 1e-13 * std::max(scale, a.cwiseAbs().cwiseMax(b.cwiseAbs()).cwiseMax(c.cwiseAbs()).maxCoeff());
  // Signed distances of P from the edges' lines (> 0 on the triangle's side
  // when it is counter-clockwise in the projection).
  auto side = [&](const Vec2& u, const Vec2& v) {
    const double len = (v - u).norm();
    return len > 0 ? ((v.x() - u.x()) * (P.y() - u.y()) - (v.y() - u.y()) * (P.x() - u.x())) / len : 0.0;
  };
  const double d1 = side(A, B), d2 = side(B, C), d3 = side(C, A);
  return (d1 >= -tol && d2 >= -tol && d3 >= -tol) || (d1 <= tol && d2 <= tol && d3 <= tol);
}

// Segment and triangle in one plane with normal n, in that projection.
bool coplanar_segment_triangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c,
                               const Vec3& n) {
  const PlaneProjection flat(n);
  const Vec2 P = flat(p), Q = flat(q), A = flat(a), B = flat(b), C = flat(c);
  if (point_in_triangle_2d(P, A, B, C) || point_in_triangle_2d(Q, A, B, C)) return true;
  return segments_intersect_2d(P, Q, A, B) || segments_intersect_2d(P, Q, B, C) ||
         segments_intersect_2d(P, Q, C, A);
}

inline bool boxes_overlap(const BvhNode& x, const BvhNode& y) {
  return (x.box_min.array() <= y.box_max.array()).all() && (y.box_min.array() <= x.box_max.array()).all();
}

struct PairTester {
  const MeshBvh& bvh;
  std::vector<std::array<int, 2>>& pairs;
  int max_pairs;

  bool full() const { return max_pairs > 0 && static_cast<int>(pairs.size()) >= max_pairs; }

  void test(int fa, int fb) {
    if (mesh_triangles_cross(bvh.positions, bvh.triangles[fa], bvh.triangles[fb]))
      pairs.push_back({std::min(fa, fb), std::max(fa, fb)});
  }

  void leaf_pairs(const BvhNode& x, const BvhNode& y, bool same) {
    for (int i = 0; i < x.count && !full(); ++i) {
      const int fa = bvh.triangle_order[x.first + i];
      for (int j = same ? i + 1 : 0; j < y.count && !full(); ++j) test(fa, bvh.triangle_order[y.first + j]);
    }
  }

  // One step of the self-traversal: node pair (i, j) is tested (leaves) or
  // split into the node pairs that may still hold crossings (pushed).
  template <class Stack>
  void step(int i, int j, Stack& stack) {
    auto left = [](int n) { return n + 1; };
    auto right = [&](int n) { return bvh.nodes[n].first; };
    const BvhNode& x = bvh.nodes[i];
    const BvhNode& y = bvh.nodes[j];
    if (i == j) {
      if (x.leaf()) {
        leaf_pairs(x, x, true);
      } else {
        stack.push_back({left(i), left(i)});
        stack.push_back({right(i), right(i)});
        stack.push_back({left(i), right(i)});
      }
      return;
    }
    if (!boxes_overlap(x, y)) return;
    if (x.leaf() && y.leaf()) {
      leaf_pairs(x, y, false);
    } else if (y.leaf() || (!x.leaf() && (x.box_max - x.box_min).squaredNorm() >=
                                              (y.box_max - y.box_min).squaredNorm())) {
      stack.push_back({left(i), j});
      stack.push_back({right(i), j});
    } else {
      stack.push_back({i, left(j)});
      stack.push_back({i, right(j)});
    }
  }

  // Depth first from the node pairs on the stack.
  void run(std::vector<std::pair<int, int>>& stack) {
    if (bvh.empty()) return;
    while (!stack.empty() && !full()) {
      const auto [i, j] = stack.back();
      stack.pop_back();
      step(i, j, stack);
    }
  }
};

}  // namespace

bool mesh_triangles_cross(const std::vector<Vec3>& P, const Tri& ta, const Tri& tb) {
  int shared = 0, ia = -1, ib = -1;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (ta[i] == tb[j]) {
        ++shared;
        ia = i;
        ib = j;
      }
  if (shared == 0) return triangles_intersect(P[ta[0]], P[ta[1]], P[ta[2]], P[tb[0]], P[tb[1]], P[tb[2]]);
  if (shared > 1) return false;
  // They meet at the shared corner; they cross only if their common
  // segment leaves it, i.e. reaches the edge opposite it in one of them.
  return segment_intersects_triangle(P[ta[(ia + 1) % 3]], P[ta[(ia + 2) % 3]], P[tb[0]], P[tb[1]], P[tb[2]]) ||
         segment_intersects_triangle(P[tb[(ib + 1) % 3]], P[tb[(ib + 2) % 3]], P[ta[0]], P[ta[1]], P[ta[2]]);
}

namespace {

// segment_intersects_triangle with dp, dq = orient3d(a, b, c, p), orient3d(a,
// b, c, q) already known (triangles_intersect has them from its rejection
// tests: the same expressions, so the same bits). Sides whose signs already
// decide are not computed.
inline bool segment_meets_triangle(const Vec3& p, const Vec3& q, double dp, double dq, const Vec3& a, const Vec3& b,
                                   const Vec3& c) {
  if ((dp > 0 && dq > 0) || (dp < 0 && dq < 0)) return false;
  if (dp == 0 || dq == 0) {
    const Vec3 n = (b - a).cross(c - a);
    if (n.squaredNorm() == 0) return false;  // a degenerate triangle has no plane to meet
    if (dp == 0 && dq == 0) return coplanar_segment_triangle(p, q, a, b, c, n);
    // One end on the plane (the other strictly off it): that end, in the plane.
    return coplanar_point_in_triangle(dp == 0 ? p : q, a, b, c, n);
  }
  // The segment spans the plane: it meets the triangle iff its line passes
  // on the same side of all three edges. A side too close to call (the
  // line nearly in the plane, or through an edge) is decided by the
  // crossing point itself, in the plane.
  const double s1 = orient3d(p, q, a, b), s2 = orient3d(p, q, b, c);
  if ((s1 > 0 && s2 < 0) || (s1 < 0 && s2 > 0)) return false;
  const double s3 = orient3d(p, q, c, a);
  if ((s1 > 0 && s3 < 0) || (s1 < 0 && s3 > 0) || (s2 > 0 && s3 < 0) || (s2 < 0 && s3 > 0)) return false;
  if (s1 != 0 && s2 != 0 && s3 != 0) return true;
  const Vec3 n = (b - a).cross(c - a);
  if (n.squaredNorm() == 0) return false;
  return crossing_in_triangle(p + (dp / (dp - dq)) * (q - p), a, b, c, n,
                              p.cwiseAbs().cwiseMax(q.cwiseAbs()).maxCoeff());
}

}  // namespace

bool segment_intersects_triangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c) {
  return segment_meets_triangle(p, q, orient3d(a, b, c, p), orient3d(a, b, c, q), a, b, c);
}

bool triangles_intersect(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& b0, const Vec3& b1,
                         const Vec3& b2) {
  // Cheap rejections: boxes apart, or all of one triangle strictly on one
  // side of the other's plane.
  const Vec3 alo = a0.cwiseMin(a1).cwiseMin(a2), ahi = a0.cwiseMax(a1).cwiseMax(a2);
  const Vec3 blo = b0.cwiseMin(b1).cwiseMin(b2), bhi = b0.cwiseMax(b1).cwiseMax(b2);
  if ((alo.array() > bhi.array()).any() || (blo.array() > ahi.array()).any()) return false;
  const double s0 = orient3d(b0, b1, b2, a0), s1 = orient3d(b0, b1, b2, a1), s2 = orient3d(b0, b1, b2, a2);
  if ((s0 > 0 && s1 > 0 && s2 > 0) || (s0 < 0 && s1 < 0 && s2 < 0)) return false;
  const double t0 = orient3d(a0, a1, a2, b0), t1 = orient3d(a0, a1, a2, b1), t2 = orient3d(a0, a1, a2, b2);
  if ((t0 > 0 && t1 > 0 && t2 > 0) || (t0 < 0 && t1 < 0 && t2 < 0)) return false;
  return segment_meets_triangle(a0, a1, s0, s1, b0, b1, b2) || segment_meets_triangle(a1, a2, s1, s2, b0, b1, b2) ||
         segment_meets_triangle(a2, a0, s2, s0, b0, b1, b2) || segment_meets_triangle(b0, b1, t0, t1, a0, a1, a2) ||
         segment_meets_triangle(b1, b2, t1, t2, a0, a1, a2) || segment_meets_triangle(b2, b0, t2, t0, a0, a1, a2);
}

void find_self_intersections(const MeshBvh& bvh, std::vector<std::array<int, 2>>& pairs,
                             const SelfIntersectionOptions& options) {
  pairs.clear();
  PairTester tester{bvh, pairs, std::max(0, options.max_pairs)};
  // Natively the traversal is split breadth first into independent node
  // pairs searched on all cores; the result is sorted and deduplicated, so
  // it is the same set on any number of threads. (A capped search stays
  // serial: which pairs a cap keeps would depend on the order.)
  constexpr size_t kTasks = 256;
  constexpr int kMinTrianglesToSplit = 4096;
  if (options.max_pairs <= 0 && parallel_workers() > 1 && bvh.num_triangles() >= kMinTrianglesToSplit) {
    std::deque<std::pair<int, int>> tasks = {{0, 0}};
    while (!tasks.empty() && tasks.size() < kTasks) {
      const auto [i, j] = tasks.front();
      tasks.pop_front();
      tester.step(i, j, tasks);
    }
    std::vector<std::vector<std::array<int, 2>>> found(tasks.size());
    parallel_for(0, static_cast<int>(tasks.size()), 1, [&](int task, int) {
      std::vector<std::pair<int, int>> own = {tasks[task]};
      PairTester part{bvh, found[task], 0};
      part.run(own);
    });
    for (const auto& f : found) pairs.insert(pairs.end(), f.begin(), f.end());
  } else if (!bvh.empty()) {
    std::vector<std::pair<int, int>> stack = {{0, 0}};
    tester.run(stack);
  }
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
}

void find_intersections_with(const MeshBvh& bvh, const std::vector<int>& triangles,
                             std::vector<std::array<int, 2>>& pairs) {
  pairs.clear();
  if (bvh.empty()) return;
  // Each listed triangle is searched on its own: natively in runs of
  // kRun on parallel_for's threads, each run into its own list (the fold
  // limiter's re-checks list hundreds to thousands of triangles), then
  // merged, sorted and deduplicated: the same set on any number of threads.
  // A pair of two listed triangles is tested once, from its larger id
  // (mesh_triangles_cross gives the same answer either way round): the
  // re-checks list regions, whose triangles are mostly each other's
  // candidates.
  constexpr int kRun = 128;
  const int n = static_cast<int>(triangles.size());
  const int runs = (n + kRun - 1) / kRun;
  std::vector<char> listed(bvh.num_triangles(), 0);
  for (int t : triangles)
    if (t >= 0 && t < bvh.num_triangles()) listed[t] = 1;
  std::vector<std::vector<std::array<int, 2>>> found(runs);
  parallel_for(0, runs, 1, [&](int run, int) {
    PairTester tester{bvh, found[run], 0};
    std::vector<int> stack;
    for (int k = run * kRun; k < std::min(n, (run + 1) * kRun); ++k) {
      const int t = triangles[k];
      if (t < 0 || t >= bvh.num_triangles()) continue;
      Vec3 lo = Vec3::Constant(1e300), hi = Vec3::Constant(-1e300);
      for (int v : bvh.triangles[t]) {
        lo = lo.cwiseMin(bvh.positions[v]);
        hi = hi.cwiseMax(bvh.positions[v]);
      }
      stack.assign(1, 0);
      while (!stack.empty()) {
        const BvhNode& node = bvh.nodes[stack.back()];
        const int id = stack.back();
        stack.pop_back();
        if (!(node.box_min.array() <= hi.array()).all() || !(lo.array() <= node.box_max.array()).all()) continue;
        if (node.leaf()) {
          for (int i = 0; i < node.count; ++i) {
            const int other = bvh.triangle_order[node.first + i];
            if (other != t && !(other > t && listed[other])) tester.test(t, other);
          }
        } else {
          stack.push_back(id + 1);
          stack.push_back(node.first);
        }
      }
    }
  });
  for (const auto& f : found) pairs.insert(pairs.end(), f.begin(), f.end());
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
}

Status find_new_self_intersections(const MeshBvh& bvh, const std::vector<Vec3>& reference,
                                   std::vector<std::array<int, 2>>& pairs, const std::vector<int>* from_triangles) {
  pairs.clear();
  if (reference.size() != bvh.positions.size())
    return Status::error(ErrorCode::InvalidInput, "new self-intersections: the reference has " +
                                                      std::to_string(reference.size()) + " vertices, the mesh " +
                                                      std::to_string(bvh.positions.size()));
  for (const Vec3& p : reference)
    if (!p.allFinite())
      return Status::error(ErrorCode::InvalidInput, "new self-intersections: non-finite reference position");
  if (from_triangles)
    find_intersections_with(bvh, *from_triangles, pairs);
  else
    find_self_intersections(bvh, pairs);
  size_t kept = 0;
  for (const auto& p : pairs)
    if (!mesh_triangles_cross(reference, bvh.triangles[p[0]], bvh.triangles[p[1]])) pairs[kept++] = p;
  pairs.resize(kept);
  return Status::success();
}

std::vector<std::array<int, 2>> pairs_after_change(const std::vector<std::array<int, 2>>& before,
                                                   const std::vector<char>& changed,
                                                   const std::vector<std::array<int, 2>>& found) {
  std::vector<std::array<int, 2>> pairs = found;
  for (const auto& p : before)
    if (!changed[p[0]] && !changed[p[1]]) pairs.push_back(p);
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

void moved_triangles(const std::vector<Tri>& triangles, const std::vector<Vec3>& before,
                     const std::vector<Vec3>& after, std::vector<char>& changed, std::vector<int>& list) {
  changed.assign(triangles.size(), 0);
  list.clear();
  for (size_t f = 0; f < triangles.size(); ++f)
    for (int v : triangles[f])
      if (after[v] != before[v]) {
        changed[f] = 1;
        list.push_back(static_cast<int>(f));
        break;
      }
}

Status find_self_intersections(const TriMesh& mesh, std::vector<std::array<int, 2>>& pairs,
                               const SelfIntersectionOptions& options) {
  pairs.clear();
  MeshBvh bvh;
  const Status st = build_bvh(mesh, bvh);
  if (!st) return st;
  find_self_intersections(bvh, pairs, options);
  return Status::success();
}

}  // namespace lk
