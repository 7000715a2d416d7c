#include "multires/displacement.h"

#include "common/cloud_tree.h"
#include "common/parallel.h"
#include "multires/multires_detail.h"

#include <Eigen/Cholesky>

#include <algorithm>
#include <unordered_map>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <queue>

namespace lk {

using namespace multires_detail;

namespace {

// Not M_PI: it is not standard C++ (the wasm build's libc hides it).
constexpr double kPi = 3.14159265358979323846;

inline double sqr(double x) { return x * x; }


// Median of a non-empty list (reordered).
double median(std::vector<double>& xs) {
  const size_t h = xs.size() / 2;
  std::nth_element(xs.begin(), xs.begin() + h, xs.end());
  const double upper = xs[h];
  if (xs.size() % 2) return upper;
  return 0.5 * (*std::max_element(xs.begin(), xs.begin() + h) + upper);
}

// A point in the vertex's frame: (u, v) across the normal line, t along it,
// rho2 = u^2 + v^2; h = t minus the base surface's height at (u, v).
struct LinePoint {
  double u, v, t, rho2, h;
};

// Compactly supported smooth kernel (Wendland-like): 1 on the line, 0 with
// zero slope at the footprint's rim, so a point entering or leaving the
// footprint as the vertex moves changes the fit continuously.
inline double kernel(double rho2, double radius2) {
  const double s = 1.0 - rho2 / radius2;
  return s > 0 ? s * s : 0.0;
}

// Height field h = c0 + c1 u + c2 v + c3 u^2 + c4 uv + c5 v^2, (u, v) scaled
// by the footprint radius for conditioning. A quadric, not a plane or a
// median: a curved surface sags by rho^2 / 2R across the footprint.
using Quadric = Eigen::Matrix<double, 6, 1>;

// The shape of the level's undisplaced surface around a vertex, as heights
// above its tangent plane: t = b0 u + b1 v + b2 u^2 + b3 uv + b4 v^2 (no
// constant: the vertex lies on it), fitted to the level's vertices within
// the footprint with the same kernel as the points.
struct BaseShape {
  double b[5] = {0, 0, 0, 0, 0};
  double height(double u, double v) const { return b[0] * u + b[1] * v + b[2] * u * u + b[3] * u * v + b[4] * v * v; }
};

// Per-level scratch of the base-shape search (a breadth-first walk over the
// level's one-rings, kept within the footprint).
struct RingWalk {
  std::vector<std::uint32_t> mark;
  std::uint32_t stamp = 0;
  std::vector<int> queue;
};

BaseShape base_shape(const MultiresMesh& mesh, int level, int vertex, const Vec3& e1, const Vec3& e2, const Vec3& n,
                     double radius, RingWalk& walk) {
  BaseShape shape;
  const std::vector<Vec3>& P = mesh.state.base[level];
  const IndexRows& ring = mesh.links[level].normal_reach;  // itself + one-ring
  const Vec3& p = P[vertex];
  const double r2 = radius * radius;
  if (++walk.stamp == 0) {
    std::fill(walk.mark.begin(), walk.mark.end(), 0);
    walk.stamp = 1;
  }
  // At most this many vertices (about four rings): a footprint many edges
  // wide needs no more to show the base surface's curvature. (Fran, level-3
  // footprints ~7 edges wide: 256 vertices cost 0.4 s more for the same
  // held-out distance and a slightly rougher face.)
  constexpr size_t kMaxVertices = 64;
  walk.queue.clear();
  walk.queue.push_back(vertex);
  walk.mark[vertex] = walk.stamp;
  Eigen::Matrix<double, 5, 5> A = Eigen::Matrix<double, 5, 5>::Zero();
  Eigen::Matrix<double, 5, 1> rhs = Eigen::Matrix<double, 5, 1>::Zero();
  double sum_w = 0;
  int used = 0;
  size_t one_ring_end = 1;  // queue[1 .. one_ring_end) is the one-ring
  for (size_t head = 0; head < walk.queue.size(); ++head) {
    const int q = walk.queue[head];
    const Vec3 delta = P[q] - p;
    if (q != vertex) {
      const double t = delta.dot(n);
      const double u = delta.dot(e1) / radius, v = delta.dot(e2) / radius;
      // A one-ring vertex always counts (even beyond a small footprint):
      // the curvature needs neighbours on every side.
      const double w = std::max(kernel(delta.squaredNorm() - t * t, r2), head < one_ring_end ? 0.05 : 0.0);
      if (w > 0) {
        Eigen::Matrix<double, 5, 1> row;
        row << u, v, u * u, u * v, v * v;
        A.noalias() += w * row * row.transpose();
        rhs += w * row * t;
        sum_w += w;
        ++used;
      }
    }
    if (q != vertex && delta.squaredNorm() > r2) continue;  // do not walk beyond the footprint
    for (int i = ring.offsets[q]; i < ring.offsets[q + 1] && walk.queue.size() < kMaxVertices; ++i) {
      const int next = ring.items[i];
      if (walk.mark[next] == walk.stamp) continue;
      walk.mark[next] = walk.stamp;
      walk.queue.push_back(next);
    }
    if (head == 0) one_ring_end = walk.queue.size();
  }
  if (used < 3 || !(sum_w > 0)) return shape;
  // A light ridge: a valence-3 vertex or a mesh boundary leaves some of the
  // five coefficients undetermined; those stay 0 (the tangent plane).
  for (int k = 0; k < 5; ++k) A(k, k) += 1e-3 * sum_w;
  Eigen::LDLT<Eigen::Matrix<double, 5, 5>> ldlt(A);
  if (ldlt.info() != Eigen::Success) return shape;
  const Eigen::Matrix<double, 5, 1> c = ldlt.solve(rhs);
  if (!c.allFinite()) return shape;
  shape.b[0] = c[0] / radius;
  shape.b[1] = c[1] / radius;
  shape.b[2] = c[2] / (radius * radius);
  shape.b[3] = c[3] / (radius * radius);
  shape.b[4] = c[4] / (radius * radius);
  return shape;
}

// Per-level constants of the measurement.
// One footprint's estimate of the height of the sampled surface above the
// vertex (before the support taper), with what its noise costs.
struct FootprintFit {
  double height = 0;
  double taper = 1;
  double radius = 0;
  // var(height) = noise variance x variance_factor: the weighted least
  // squares' (A^-1 B A^-1)_00, A = sum w x x^T (+ ridge), B = sum w^2 x x^T.
  double variance_factor = 0;
  // The noise variance from the residuals, sum w r^2 / (sum w - tr(A^-1 B))
  // (the expectation of the numerator is sigma^2 times the denominator);
  // -1 when the quadric leaves too few degrees of freedom to tell.
  double noise_variance = -1;
  int points = 0;  // in the footprint's disk (all sheets)
  int sheets = 0;  // sheets the normal line crosses within the footprint
};

// Data support: the kernel-weighted centroid of the points `offset` (a
// fraction of the radius) off the line gives the full displacement up to
// support_full_offset, none from support_zero_offset on.
double support_taper(double offset, const DisplacementOptions& opt) {
  if (offset <= opt.support_full_offset) return 1.0;
  const double x = std::clamp((opt.support_zero_offset - offset) /
                                  std::max(opt.support_zero_offset - opt.support_full_offset, 1e-12),
                              0.0, 1.0);
  return x * x * (3 - 2 * x);  // smoothstep: no kink where the taper starts or ends
}

struct LevelGeometry {
  double min_radius;     // half the level's mean edge (or the fixed radius)
  double max_radius;     // no data beyond this
  double first_radius;   // first search: where footprint_points are expected
  double max_distance;   // half-length of the normal line
  double edge;           // the level's mean edge length
  bool adaptive;
  bool widen;            // footprints may widen against the noise on this level
  bool smooth;           // the level's heights are smoothed over the mesh (denoising)
  bool noise_figures;    // fits estimate their height's standard error (widen or smooth)
};

struct Scratch {
  std::vector<std::pair<size_t, double>> matches;
  std::vector<LinePoint> line_pts, pool;
  std::vector<FootprintFit> fits;  // the footprints tried at one vertex, narrowest first
  std::vector<double> weights, values, residuals;
  std::vector<std::pair<double, std::pair<size_t, size_t>>> sheets;
  std::vector<std::pair<double, double>> buckets;  // (lowest, highest) height
  RingWalk walk;
};

// Gathers the points in the cylinder of radius `radius` around the line, as
// far along it as the search ball sqrt(radius^2 + max_distance^2) reaches.
// The line's length is applied later to the heights above the base surface
// (a tangent-plane slab would cut a curved surface off near the rim).
void gather(const CloudTree& tree, const std::vector<Vec3>& pts, const std::vector<Vec3>* point_normals,
            const Vec3& p, const Vec3& n, const Vec3& e1, const Vec3& e2, double radius, double max_distance,
            double min_normal_agreement, Scratch& s) {
  s.matches.clear();
  s.line_pts.clear();
  const double r2 = radius * radius;
  tree.radiusSearch(p.data(), max_distance * max_distance + r2, s.matches, nanoflann::SearchParams(32, 0, false));
  for (const auto& m : s.matches) {
    const Vec3 delta = pts[m.first] - p;
    const double t = delta.dot(n);
    const double rho2 = delta.squaredNorm() - t * t;
    if (rho2 > r2) continue;
    if (point_normals) {
      const Vec3& pn = (*point_normals)[m.first];
      // (No square root for the default agreement of 0: the sign suffices.)
      const double needed = min_normal_agreement == 0 ? 0.0 : min_normal_agreement * pn.norm();
      if (!(pn.dot(n) > needed)) continue;
    }
    s.line_pts.push_back({delta.dot(e1), delta.dot(e2), t, rho2, t});
  }
}

// Heights above the base surface (h = t - base) for the gathered points;
// keeps those within the line's reach of it.
void heights_above(const BaseShape& base, double max_distance, std::vector<LinePoint>& line_pts) {
  for (LinePoint& q : line_pts) q.h = q.t - base.height(q.u, q.v);
  line_pts.erase(std::remove_if(line_pts.begin(), line_pts.end(),
                                [max_distance](const LinePoint& q) { return !(std::abs(q.h) <= max_distance); }),
                 line_pts.end());
}

// Weighted least squares of the heights above the base surface, with a
// ridge on every coefficient but c0: sum w_i (h_i - row_i . c)^2 + ridge *
// sum(w) * |c_1..5|^2. The ridge pulls slope and curvature towards 0 where
// the points cannot determine them.
//
// The normal equations as sums over the points: the products row_a row_b of
// the monomials (1, u, v, u^2, uv, v^2) are the 15 monomials u^i v^j of
// degree <= 4, so each point adds to 15 sums (and 15 more with w^2 for the
// noise figures), not to the 21 + 21 entries of two lower triangles. This
// is the innermost loop of the measurement. Sums also let a robust pass
// take its few outliers out instead of summing the rest again.
struct QuadricSums {
  double a[15] = {};   // sum w u^i v^j: A's entries
  double b[15] = {};   // sum w^2 u^i v^j: B's entries (the noise figures)
  double rhs[6] = {};  // sum w h row
  // (u, v) already scaled by the footprint radius; sign -1 takes a point out.
  void add(double u, double v, double h, double w, bool with_b, double sign = 1.0) {
    const double uu = u * u, uv = u * v, vv = v * v;
    const double m[15] = {1, u, v, uu, uv, vv, uu * u, uu * v, vv * u, vv * v, uu * uu, uu * uv, uu * vv, uv * vv, vv * vv};
    const double sw = sign * w;
    for (int k = 0; k < 15; ++k) a[k] += sw * m[k];
    if (with_b) {
      const double sw2 = sw * w;
      for (int k = 0; k < 15; ++k) b[k] += sw2 * m[k];
    }
    const double swh = sw * h;
    for (int k = 0; k < 6; ++k) rhs[k] += swh * m[k];
  }
  double sum_w() const { return a[0]; }
};

// The monomial of row_a row_b (index into QuadricSums::a, b).
constexpr int kProduct[6][6] = {{0, 1, 2, 3, 4, 5},      {1, 3, 4, 6, 7, 8},      {2, 4, 5, 7, 8, 9},
                                {3, 6, 7, 10, 11, 12},   {4, 7, 8, 11, 12, 13},   {5, 8, 9, 12, 13, 14}};

inline double quadric_at(const Quadric& c, double u, double v) {
  return c[0] + c[1] * u + c[2] * v + c[3] * u * u + c[4] * u * v + c[5] * v * v;
}

// Solves the sums' normal equations for c.
bool solve_quadric(const QuadricSums& sums, double ridge, Quadric& c) {
  const double sum_w = sums.sum_w();
  if (!(sum_w > 0)) return false;
  Eigen::Matrix<double, 6, 6> A = Eigen::Matrix<double, 6, 6>::Zero();  // LDLT reads the lower triangle
  for (int b = 0; b < 6; ++b)
    for (int a = b; a < 6; ++a) A(a, b) = sums.a[kProduct[a][b]];
  for (int k = 1; k < 6; ++k) A(k, k) += std::max(ridge, 1e-9) * sum_w;
  Eigen::LDLT<Eigen::Matrix<double, 6, 6>> ldlt(A);  // reads the lower triangle
  if (ldlt.info() != Eigen::Success) return false;
  c = ldlt.solve(Eigen::Map<const Quadric>(sums.rhs));
  return c.allFinite();
}

// c0's variance factor, (A^-1 B A^-1)_00 (see FootprintFit), and with
// `dof` the denominator of the noise estimate, sum w - tr(A^-1 B); the
// numerator, sum w r^2, needs the points. Sums with B (with_b).
bool variance_figures(const QuadricSums& sums, double ridge, double& variance_factor, double* dof) {
  const double sum_w = sums.sum_w();
  if (!(sum_w > 0)) return false;
  Eigen::Matrix<double, 6, 6> A, B;
  for (int b = 0; b < 6; ++b)
    for (int a = 0; a < 6; ++a) {
      A(a, b) = sums.a[kProduct[a][b]];
      B(a, b) = sums.b[kProduct[a][b]];
    }
  for (int k = 1; k < 6; ++k) A(k, k) += std::max(ridge, 1e-9) * sum_w;
  Eigen::LDLT<Eigen::Matrix<double, 6, 6>> ldlt(A);
  if (ldlt.info() != Eigen::Success) return false;
  const Quadric z = ldlt.solve(Quadric::Unit(0));  // A^-1 e0 (A is symmetric)
  variance_factor = z.dot(B * z);
  if (dof) *dof = sum_w - ldlt.solve(B).trace();
  return std::isfinite(variance_factor);
}

// The noise variance from the residuals: sum w r^2 / dof. Fewer than about
// one weighted point beyond the six coefficients: the residuals say nothing
// about the noise (-1).
double noise_variance(double sum_wr2, double dof, double sum_w) {
  return dof > 0.1 * sum_w && std::isfinite(dof) ? sum_wr2 / dof : -1.0;
}

// Whether points sorted by height would hold a gap wider than `gap`
// between neighbours, without sorting: in buckets `gap` tall, a bucket's
// points are closer than that; a wider gap lies across an empty bucket or
// between one bucket's highest and the next one's lowest point. Unknown
// when the heights span too many buckets to be worth it.
enum class SheetCount { One, More, Unknown };
SheetCount count_sheets(const std::vector<LinePoint>& pts, double gap, std::vector<std::pair<double, double>>& buckets) {
  if (pts.empty() || !(gap > 0)) return SheetCount::Unknown;
  double lo = pts[0].h, hi = pts[0].h;
  for (const LinePoint& q : pts) lo = std::min(lo, q.h), hi = std::max(hi, q.h);
  if (hi - lo <= gap) return SheetCount::One;
  const double span = (hi - lo) / gap;
  if (!(span < static_cast<double>(pts.size()))) return SheetCount::Unknown;
  const size_t n = static_cast<size_t>(span) + 1;
  buckets.assign(n, {std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()});
  for (const LinePoint& q : pts) {
    auto& b = buckets[std::min(n - 1, static_cast<size_t>((q.h - lo) / gap))];
    b.first = std::min(b.first, q.h);
    b.second = std::max(b.second, q.h);
  }
  double previous_highest = buckets[0].second;
  for (size_t i = 1; i < n; ++i) {
    if (buckets[i].first > buckets[i].second) return SheetCount::More;  // empty
    if (buckets[i].first - previous_highest > gap) return SheetCount::More;
    previous_highest = buckets[i].second;
  }
  return SheetCount::One;
}

// The footprint of k points within the pool (the points gathered within
// pool_radius of the line, heights above `base` fitted over pool_radius):
// the disk holding the k nearest (at least min_radius), its nearest sheet,
// a robust quadric fit. False when the footprint holds no sheet of enough
// points, or more than one sheet and one_sheet_only (nothing is fitted).
bool fit_footprint(const MultiresMesh& mesh, int level, int vertex, const Vec3& e1, const Vec3& e2, const Vec3& n,
                   const LevelGeometry& g, const DisplacementOptions& opt, size_t k, double pool_radius,
                   bool one_sheet_only, Scratch& s, FootprintFit& out) {
  const int min_points = std::max(1, opt.min_points);
  double radius = pool_radius;
  if (g.adaptive && s.line_pts.size() >= k) {
    // (The k-th distance from a copy: moving doubles, not whole points.)
    s.values.clear();
    for (const LinePoint& q : s.line_pts) s.values.push_back(q.rho2);
    std::nth_element(s.values.begin(), s.values.begin() + (k - 1), s.values.end());
    // The kernel is 0 at the rim: keep the k-th point just inside it.
    const double footprint = std::max(g.min_radius, std::sqrt(s.values[k - 1]) * (1.0 + 1e-9));
    if (footprint < radius) {
      // The base shape over the footprint itself when it is much smaller
      // than the search (sparse data searched at max_radius); within a
      // factor of 1.5 the two shapes are the same to well below the noise.
      const bool reshape = footprint * 1.5 < radius;
      radius = footprint;
      const double footprint2 = radius * radius;
      s.line_pts.erase(std::remove_if(s.line_pts.begin(), s.line_pts.end(),
                                      [footprint2](const LinePoint& q) { return !(q.rho2 < footprint2); }),
                       s.line_pts.end());
      if (reshape) {
        const BaseShape base = base_shape(mesh, level, vertex, e1, e2, n, radius, s.walk);
        heights_above(base, g.max_distance, s.line_pts);
      }
    }
  }
  const double r2 = radius * radius;
  out.points = static_cast<int>(s.line_pts.size());
  if (out.points < min_points) return false;
  // Sheets: the line may cross the scan more than once (lips, ear rims,
  // lids). Sorted by height above the base surface, the points of one sheet
  // follow each other closely however much the sheet departs from the base
  // shape over the footprint: neighbours a point spacing apart differ by
  // the noise plus the sheet's slope against the base over that spacing. A
  // wider gap (cluster_fraction x the line's half-length, plus half the
  // local spacing for a slope of up to 1:2) separates two sheets. The
  // nearest sheet that enough points agree on is measured; a lone stray
  // point does not count as a crossing.
  const size_t count = s.line_pts.size();
  const double local_spacing = radius * std::sqrt(kPi / static_cast<double>(count));
  const double gap = opt.cluster_fraction * g.max_distance + 0.5 * local_spacing;
  s.sheets.clear();  // [begin, end) ranges, then ordered by their height nearest to 0
  if (one_sheet_only) {
    // Whether the points form one sheet needs no sorting (the widest
    // footprints: the most points, and more than one sheet is no use).
    switch (count_sheets(s.line_pts, gap, s.buckets)) {
      case SheetCount::One:
        s.sheets.push_back({0.0, {0, count}});
        break;
      case SheetCount::More:
        out.sheets = 2;  // at least
        return false;
      case SheetCount::Unknown:
        break;
    }
  }
  if (s.sheets.empty()) {
    std::sort(s.line_pts.begin(), s.line_pts.end(), [](const LinePoint& a, const LinePoint& b) { return a.h < b.h; });
    for (size_t i = 0; i < count;) {
      size_t j = i + 1;
      while (j < count && s.line_pts[j].h - s.line_pts[j - 1].h <= gap) ++j;
      double nearest = std::abs(s.line_pts[i].h);
      for (size_t k2 = i; k2 < j; ++k2) nearest = std::min(nearest, std::abs(s.line_pts[k2].h));
      s.sheets.push_back({nearest, {i, j}});
      i = j;
    }
  }
  out.sheets = static_cast<int>(s.sheets.size());
  std::sort(s.sheets.begin(), s.sheets.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  if (one_sheet_only && s.sheets.size() > 1) return false;
  s.weights.assign(count, 0.0);
  const bool noise_figures = g.noise_figures;
  const double inv_radius = 1.0 / radius;
  for (const auto& sheet : s.sheets) {
    // Not a structured binding: C++17 lambdas (the fallback below) cannot
    // capture those, and Emscripten's clang refuses it.
    const size_t first_point = sheet.second.first, end_point = sheet.second.second;
    if (static_cast<int>(end_point - first_point) < min_points) continue;
    QuadricSums sums;
    double cu = 0, cv = 0;
    for (size_t i = first_point; i < end_point; ++i) {
      const LinePoint& q = s.line_pts[i];
      const double w = kernel(q.rho2, r2);
      s.weights[i] = w;
      if (!(w > 0)) continue;
      sums.add(q.u * inv_radius, q.v * inv_radius, q.h, w, noise_figures);
      cu += w * q.u;
      cv += w * q.v;
    }
    const double sum_w = sums.sum_w();
    if (!(sum_w > 0)) continue;
    // Where the quadric fails: the sheet's median height.
    auto fallback = [&] {
      s.values.clear();
      for (size_t i = first_point; i < end_point; ++i) s.values.push_back(s.line_pts[i].h);
      return median(s.values);
    };
    // Data support: how far off the line the points' weighted centroid lies.
    const double offset = std::sqrt(cu * cu + cv * cv) / (sum_w * radius);
    const double taper = support_taper(offset, opt);
    Quadric c;
    out.variance_factor = 0;
    out.noise_variance = -1;
    double h0 = 0;
    if (solve_quadric(sums, opt.ridge, c)) {
      // One robust pass: drop points far from the first fit (outliers, the
      // edge of another sheet), then refit: their sums taken out.
      s.values.clear();
      s.residuals.assign(count, 0.0);
      double sum_wr2 = 0;  // the first fit's, should the refit fail
      for (size_t i = first_point; i < end_point; ++i)
        if (s.weights[i] > 0) {
          const LinePoint& q = s.line_pts[i];
          const double r = q.h - quadric_at(c, q.u * inv_radius, q.v * inv_radius);
          s.residuals[i] = std::abs(r);
          s.values.push_back(s.residuals[i]);
          sum_wr2 += s.weights[i] * r * r;
        }
      const double limit = 4.0 * median(s.values) + 1e-12 * g.max_distance;
      QuadricSums kept = sums;
      int dropped = 0;
      for (size_t i = first_point; i < end_point; ++i)
        if (s.weights[i] > 0 && s.residuals[i] > limit) {
          const LinePoint& q = s.line_pts[i];
          kept.add(q.u * inv_radius, q.v * inv_radius, q.h, s.weights[i], noise_figures, -1.0);
          s.weights[i] = 0, ++dropped;
        }
      const QuadricSums* final_sums = &sums;
      // Nothing dropped: the refit would be the same fit.
      Quadric refit;
      if (dropped > 0 && solve_quadric(kept, opt.ridge, refit)) {
        c = refit;
        final_sums = &kept;
        sum_wr2 = 0;
        for (size_t i = first_point; i < end_point; ++i)
          if (s.weights[i] > 0) {
            const LinePoint& q = s.line_pts[i];
            sum_wr2 += s.weights[i] * sqr(q.h - quadric_at(c, q.u * inv_radius, q.v * inv_radius));
          }
      }
      h0 = c[0];
      // The noise figures only where a wider footprint may be tried.
      double dof = 0;
      if (noise_figures && variance_figures(*final_sums, opt.ridge, out.variance_factor, &dof))
        out.noise_variance = noise_variance(sum_wr2, dof, final_sums->sum_w());
      if (!(std::abs(h0) <= g.max_distance)) h0 = fallback(), out.noise_variance = -1;
    } else {
      h0 = fallback();
    }
    out.height = h0;
    out.taper = taper;
    out.radius = radius;
    return true;
  }
  return false;
}

// A footprint between the first and the widest: the kernel-weighted quadric
// of the widest footprint's inliers (weights > 0: its sheet, its robust
// pass) within `radius`; the noise variance only `with_noise`.
bool fit_between(const std::vector<LinePoint>& pts, const std::vector<double>& inliers, double radius,
                 const LevelGeometry& g, const DisplacementOptions& opt, bool with_noise, FootprintFit& out) {
  const double r2 = radius * radius, inv_radius = 1.0 / radius;
  QuadricSums sums;
  double cu = 0, cv = 0;
  int points = 0;
  for (size_t i = 0; i < pts.size(); ++i) {
    const LinePoint& q = pts[i];
    if (!(q.rho2 < r2)) continue;
    ++points;
    if (!(inliers[i] > 0)) continue;
    const double w = kernel(q.rho2, r2);
    sums.add(q.u * inv_radius, q.v * inv_radius, q.h, w, true);
    cu += w * q.u;
    cv += w * q.v;
  }
  const double sum_w = sums.sum_w();
  if (points < std::max(1, opt.min_points) || !(sum_w > 0)) return false;
  Quadric c;
  double dof = 0;
  if (!solve_quadric(sums, opt.ridge, c) || !(std::abs(c[0]) <= g.max_distance) ||
      !variance_figures(sums, opt.ridge, out.variance_factor, with_noise ? &dof : nullptr))
    return false;
  out.noise_variance = -1;
  if (with_noise) {
    double sum_wr2 = 0;
    for (size_t i = 0; i < pts.size(); ++i) {
      const LinePoint& q = pts[i];
      if (q.rho2 < r2 && inliers[i] > 0)
        sum_wr2 += kernel(q.rho2, r2) * sqr(q.h - quadric_at(c, q.u * inv_radius, q.v * inv_radius));
    }
    out.noise_variance = noise_variance(sum_wr2, dof, sum_w);
  }
  const double offset = std::sqrt(cu * cu + cv * cv) / (sum_w * radius);
  out.height = c[0];
  out.taper = support_taper(offset, opt);
  out.radius = radius;
  out.points = points;
  return true;
}

// Measures one vertex: the signed distance along n from p to the sampled
// surface (already multiplied by the support taper), or false when the
// footprint holds too few points. radius_out/taper_out/widened_out: what
// was used.
bool measure_one(const CloudTree& tree, const std::vector<Vec3>& pts, const std::vector<Vec3>* point_normals,
                 const MultiresMesh& mesh, int level, int vertex, const LevelGeometry& g,
                 const DisplacementOptions& opt, Scratch& s, double& out, double& radius_out, double& taper_out,
                 char& widened_out, double& noise_out, double& variance_factor_out) {
  const Vec3& p = mesh.state.base[level][vertex];
  const Vec3& n = mesh.state.normals[level][vertex];
  if (n.squaredNorm() == 0) return false;  // no normal (isolated vertex)
  const Vec3 e1 = n.unitOrthogonal(), e2 = n.cross(e1);

  // Footprint: the disk holding footprint_points points within the line's
  // reach of the base surface (at least half an edge, at most max_radius).
  // The first search usually holds them; a sparser neighbourhood is
  // searched again at the largest radius. Each step depends continuously on
  // the vertex's position (the k-th nearest point, a kernel that vanishes at
  // the rim), so neighbouring vertices get nearly the same footprint.
  const size_t k = static_cast<size_t>(std::max(opt.footprint_points, 1));
  double pool_radius = g.first_radius;
  gather(tree, pts, point_normals, p, n, e1, e2, pool_radius, g.max_distance, opt.min_normal_agreement, s);
  BaseShape base = base_shape(mesh, level, vertex, e1, e2, n, pool_radius, s.walk);
  heights_above(base, g.max_distance, s.line_pts);
  // A first search without any point is a hole or off the data: the wider
  // search could only find its edge, where the support taper gives ~0.
  if (g.adaptive && s.line_pts.size() < k && !s.line_pts.empty() && pool_radius < g.max_radius) {
    pool_radius = g.max_radius;
    gather(tree, pts, point_normals, p, n, e1, e2, pool_radius, g.max_distance, opt.min_normal_agreement, s);
    base = base_shape(mesh, level, vertex, e1, e2, n, pool_radius, s.walk);
    heights_above(base, g.max_distance, s.line_pts);
  }
  const bool may_widen = g.adaptive && g.widen && opt.max_footprint_points > opt.footprint_points;
  if (may_widen) s.pool = s.line_pts;
  s.fits.clear();
  s.fits.emplace_back();
  if (!fit_footprint(mesh, level, vertex, e1, e2, n, g, opt, k, pool_radius, false, s, s.fits[0])) return false;
  size_t chosen = 0;

  // Noise: where the first footprint's height is less certain than
  // noise_edge_fraction of the level's edge (dense noisy scans: neighbouring
  // vertices a level-3 edge apart with independent errors tilt the faces,
  // the orange-peel), footprints of 2, 4, ... times the points are fitted as
  // well, and the widest one whose height agrees with every narrower one
  // within noise_confidence standard errors is kept (Katkovnik's
  // intersection of confidence intervals, the adaptive bandwidth choice of
  // local polynomial regression): a wider footprint that bends away from
  // the narrow ones is smoothing away real detail, not noise. The noise is
  // the smaller of the two narrowest fits' residual estimates (the wider
  // one has more degrees of freedom, the narrower less unfitted detail).
  const double first_noise = s.fits[0].noise_variance;
  const size_t first_points = static_cast<size_t>(s.fits[0].points);
  // Only on one sheet: near thin features (lips, lids, ear rims) a wider
  // footprint reaches the other sheet's edge.
  if (may_widen && first_noise > 0 && s.fits[0].sheets == 1 && s.fits[0].radius > g.min_radius &&
      2 * first_points <= static_cast<size_t>(opt.max_footprint_points) &&
      first_noise * s.fits[0].variance_factor > sqr(opt.noise_edge_fraction * g.edge)) {
    const double widest = std::max(s.fits[0].radius, opt.noise_max_radius_edges * g.edge);
    // One search for the widest footprint: by the first one's density, with
    // margin, within the widest radius.
    size_t most = first_points;
    while (2 * most <= static_cast<size_t>(opt.max_footprint_points)) most *= 2;
    const double wanted = s.fits[0].radius * std::sqrt(static_cast<double>(most) / first_points) * 1.15;
    if (s.pool.size() < most && pool_radius < widest) {
      pool_radius = std::min(widest, wanted);
      gather(tree, pts, point_normals, p, n, e1, e2, pool_radius, g.max_distance, opt.min_normal_agreement, s);
      base = base_shape(mesh, level, vertex, e1, e2, n, pool_radius, s.walk);
      heights_above(base, g.max_distance, s.line_pts);
    } else {
      s.line_pts = s.pool;
    }
    while (most > first_points && s.line_pts.size() < most) most /= 2;
    // The widest footprint is fitted in full (its sheet, its robust pass);
    // the ones between reuse its points and outliers (a kernel-weighted
    // quadric each, no search, no sorting).
    FootprintFit wide;
    if (most > first_points &&
        fit_footprint(mesh, level, vertex, e1, e2, n, g, opt, most, pool_radius, true, s, wide) &&
        wide.radius > s.fits[0].radius && wide.radius <= widest * (1 + 1e-9) && wide.noise_variance > 0) {
      s.values.clear();
      for (const LinePoint& q : s.line_pts) s.values.push_back(q.rho2);
      // The footprints in order, each fitted only when the intervals of the
      // narrower ones still intersect (the choice is the same as with all
      // of them fitted first): 2, 4, ... times the first one's points, then
      // the widest.
      size_t kj = 2 * first_points, selected = 0;
      bool between_left = kj < most, wide_left = true;
      auto next_fit = [&]() {
        while (between_left) {
          // values[selected..] are no nearer than the previous k-th.
          std::nth_element(s.values.begin() + selected, s.values.begin() + (kj - 1), s.values.end());
          selected = kj;
          const double radius = std::max(g.min_radius, std::sqrt(s.values[kj - 1]) * (1.0 + 1e-9));
          FootprintFit between;
          // Only the first one after the narrowest needs its noise (below).
          const bool with_noise = s.fits.size() == 1;
          if (!(radius > s.fits.back().radius) || !(radius < wide.radius) ||
              !fit_between(s.line_pts, s.weights, radius, g, opt, with_noise, between)) {
            between_left = false;
            break;
          }
          kj *= 2;
          between_left = kj < most;
          s.fits.push_back(between);
          return true;
        }
        if (!wide_left) return false;
        wide_left = false;
        s.fits.push_back(wide);
        return true;
      };
      next_fit();
      // Intersection of the confidence intervals, narrowest first, with one
      // noise level for all: the smaller of the two narrowest estimates.
      const double noise = std::min(first_noise, s.fits[1].noise_variance > 0 ? s.fits[1].noise_variance : first_noise);
      double lo = -std::numeric_limits<double>::infinity(), hi = std::numeric_limits<double>::infinity();
      for (size_t j = 0; j < s.fits.size() || next_fit(); ++j) {
        const FootprintFit& f = s.fits[j];
        const double half = opt.noise_confidence * std::sqrt(noise * f.variance_factor);
        lo = std::max(lo, f.height - half);
        hi = std::min(hi, f.height + half);
        if (lo > hi) break;
        chosen = j;
        if (noise * f.variance_factor <= sqr(opt.noise_edge_fraction * g.edge)) break;  // certain enough
      }
    }
  }
  const FootprintFit& fit = s.fits[chosen];
  out = fit.taper * fit.height;
  radius_out = fit.radius;
  taper_out = fit.taper;
  widened_out = chosen > 0;
  // The first fit's noise (a widened footprint's interval used the smaller
  // of the two narrowest; close enough for weighting neighbours).
  noise_out = s.fits[0].noise_variance;
  variance_factor_out = fit.variance_factor * fit.taper * fit.taper;
  return true;
}

// Denoising of one level's heights by smoothing over the mesh (see
// DisplacementOptions::smooth_*). heights (#V_l): h_v above the level's
// base surface, smoothed in place; noise, variance_factor (#V_l): the
// noise variance the vertex's fit estimated from its residuals and its
// height's variance per unit noise (var h_v = noise x factor); noise <= 0
// where unknown: such a vertex neither moves nor counts as a neighbour.
// Vertices below first_free (a coarser level's, which jeong2002 does not
// measure again) count as neighbours but do not move. moved / sum_change:
// how many heights changed and by how much in all.
void smooth_heights(const MultiresMesh& mesh, int level, const DisplacementOptions& opt, double edge,
                    const std::vector<double>& noise, const std::vector<double>& variance_factor,
                    const std::vector<double>& radius, int first_free, std::vector<double>& heights, int& moved,
                    double& sum_change) {
  moved = 0;
  sum_change = 0;
  const IndexRows& ring = mesh.links[level].normal_reach;  // itself + one-ring
  const int nv = mesh.num_vertices(level);
  // Each height's variance: the noise pooled over the one-ring (a 16-point
  // fit's own estimate rests on about three degrees of freedom: alone it
  // would make the weights as noisy as the heights) times its own factor.
  std::vector<double> variance(nv, -1.0), pooled(nv, -1.0), known;
  // In edges of the finest level: a coarser level's footprints are as wide
  // in millimetres where the scan is dense (both hold footprint_points), and
  // a sparse scan's (James's level 2) are wider than that.
  const double widest = opt.smooth_max_radius_edges * std::ldexp(edge, level - mesh.num_levels());
  for (int v = 0; v < nv; ++v) {
    if (!(noise[v] > 0) || !(variance_factor[v] > 0) || !(radius[v] <= widest)) continue;
    double sum = 0;
    int count = 0;
    for (int i = ring.offsets[v]; i < ring.offsets[v + 1]; ++i) {
      const int u = ring.items[i];
      if (noise[u] > 0) sum += noise[u], ++count;
    }
    pooled[v] = sum / count;
    known.push_back(pooled[v]);
  }
  if (known.empty()) return;
  // Residuals above the scanner's noise are mostly the quadric's misfit of
  // real detail (lip edges, nostrils, ear rims), not noise: taken at face
  // value they would make such a vertex's own measurement the least
  // trusted, and smooth detail hardest. The pooled noise is capped at
  // smooth_noise_cap^2 times the level's median.
  const double noise_limit = opt.smooth_noise_cap > 0 ? sqr(opt.smooth_noise_cap) * median(known)
                                                    : std::numeric_limits<double>::infinity();
  known.clear();
  for (int v = 0; v < nv; ++v) {
    if (!(pooled[v] > 0)) continue;
    variance[v] = std::min(pooled[v], noise_limit) * variance_factor[v];
    known.push_back(variance[v]);
  }
  const double typical = median(known);
  if (!(typical > 0) || !std::isfinite(typical)) return;
  // A height many typical errors above the base surface is detail the
  // coarser levels missed (an ear's fold, a nostril), not noise: it takes
  // no part (see DisplacementOptions::smooth_max_height_errors).
  if (opt.smooth_max_height_errors > 0) {
    const double tallest = opt.smooth_max_height_errors * std::sqrt(typical);
    for (int v = 0; v < nv; ++v)
      if (variance[v] > 0 && !(std::abs(heights[v]) <= tallest)) variance[v] = -1.0;
  }
  // A neighbour's pull per unit weight, against a vertex's own 1 / s_v^2.
  const double coupling = opt.smooth_strength / typical;
  const double c = opt.smooth_agreement;
  // How far a height may move and how far two may differ and still be
  // averaged: its standard error, but at most smooth_move_cap times the
  // level's typical one (an uncertain fit at a data edge or a thin
  // feature is trusted less, yet not moved farther than a typical one).
  std::vector<double> bound(nv, 0.0);
  const double typical_error = std::sqrt(typical);
  for (int v = 0; v < nv; ++v)
    if (variance[v] > 0)
      bound[v] = opt.smooth_move_cap > 0 ? std::min(std::sqrt(variance[v]), opt.smooth_move_cap * typical_error)
                                         : std::sqrt(variance[v]);
  // Heights are along each vertex's own normal: they compare only where
  // the two normals nearly agree (not across an ear rim, a lid, a lip's
  // edge): full weight up to smooth_normal_degrees apart, none from twice
  // that.
  const double cos_full = std::cos(opt.smooth_normal_degrees * kPi / 180.0);
  const double cos_zero = std::cos(std::min(2.0 * opt.smooth_normal_degrees, 90.0) * kPi / 180.0);
  const std::vector<Vec3>& normals = mesh.state.normals[level];
  // Neighbour weights from the measured heights (fixed, so the iteration
  // solves one linear system): 1 while the two agree within c combined
  // standard errors, smoothly 0 at 2c.
  std::vector<double> weight(ring.items.size(), 0.0);
  for (int v = 0; v < nv; ++v) {
    if (!(variance[v] > 0)) continue;
    for (int i = ring.offsets[v]; i < ring.offsets[v + 1]; ++i) {
      const int u = ring.items[i];
      if (u == v || !(variance[u] > 0)) continue;
      const double t = std::abs(heights[u] - heights[v]) / (c * std::hypot(bound[u], bound[v]));
      const double x = std::clamp(2.0 - t, 0.0, 1.0);
      weight[i] = x * x * (3 - 2 * x);
      if (opt.smooth_normal_degrees > 0) {
        const double agree = normals[u].dot(normals[v]);
        const double y = cos_full > cos_zero ? std::clamp((agree - cos_zero) / (cos_full - cos_zero), 0.0, 1.0)
                                             : (agree >= cos_full ? 1.0 : 0.0);  // 90 degrees: a step
        weight[i] *= y * y * (3 - 2 * y);
      }
    }
  }
  // Jacobi steps, each height kept within c standard errors of its own
  // measurement (its confidence interval).
  std::vector<double> x = heights, next(nv);
  for (int iteration = 0; iteration < opt.smooth_iterations; ++iteration) {
    for (int v = 0; v < nv; ++v) {
      if (!(variance[v] > 0) || v < first_free) {
        next[v] = x[v];
        continue;
      }
      double num = heights[v] / variance[v], den = 1.0 / variance[v];
      for (int i = ring.offsets[v]; i < ring.offsets[v + 1]; ++i) {
        if (!(weight[i] > 0)) continue;
        num += coupling * weight[i] * x[ring.items[i]];
        den += coupling * weight[i];
      }
      const double limit = c * bound[v];
      next[v] = std::clamp(num / den, heights[v] - limit, heights[v] + limit);
    }
    x.swap(next);
  }
  for (int v = 0; v < nv; ++v) {
    if (x[v] == heights[v]) continue;
    ++moved;
    sum_change += std::abs(x[v] - heights[v]);
    heights[v] = x[v];
  }
}

// The fade across the data's edge (DisplacementOptions::
// edge_fade_control_edges) on level l. support (#V_L; level l's vertices
// set): 1 = full data support; d (#V_l): the level's displacements, of
// which those of the vertices from `first` on (the level's own) may change.
// Returns how many changed.
int fade_across_data_edge(const MultiresMesh& mesh, int level, int first, const std::vector<double>& support,
                          double width, std::vector<double>& d) {
  const IndexRows& ring = mesh.links[level].normal_reach;  // itself + one-ring
  const std::vector<Vec3>& P = mesh.state.base[level];
  const std::vector<Vec3>& N = mesh.state.normals[level];
  const int nv = mesh.num_vertices(level);
  auto full = [&support](int v) { return support[v] >= 1.0; };
  // The band does not turn round a rim (an ear's, a lip's, a lid's): a
  // displacement measured on one side means nothing on the other, and
  // carried there it pushed the two sheets into each other. Neighbours
  // whose normals are more than ~15 degrees apart are not joined.
  const double min_agreement = std::cos(15.0 * kPi / 180.0);
  // The band: vertices without full support within `width` of a supported
  // one, by the shortest path over the level's edges (Dijkstra from the
  // supported vertices that have an unsupported neighbour).
  std::vector<double> dist(nv, std::numeric_limits<double>::infinity());
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> heap;
  for (int v = 0; v < nv; ++v) {
    if (!full(v)) continue;
    for (int i = ring.offsets[v]; i < ring.offsets[v + 1]; ++i)
      if (!full(ring.items[i])) {
        dist[v] = 0;
        heap.push({0.0, v});
        break;
      }
  }
  std::vector<int> band;  // nearest first
  while (!heap.empty()) {
    const Item top = heap.top();
    heap.pop();
    const int v = top.second;
    if (top.first > dist[v]) continue;
    if (!full(v)) band.push_back(v);
    for (int i = ring.offsets[v]; i < ring.offsets[v + 1]; ++i) {
      const int u = ring.items[i];
      if (full(u) || !(N[u].dot(N[v]) >= min_agreement)) continue;
      const double next = top.first + (P[u] - P[v]).norm();
      if (next < width && next < dist[u]) {
        dist[u] = next;
        heap.push({next, u});
      }
    }
  }
  if (band.empty()) return 0;
  // The value carried into the band: the level's own supported vertices
  // hold their displacement (a coarser level's vertices hold 0 here, they
  // lie on the data already: they carry nothing); each band vertex takes the
  // mean over its neighbours that hold a value. The first sweep, nearest
  // first, reaches across the band; the further ones average along the
  // edge too (one vertex's noise is not carried out alone).
  constexpr int kSweeps = 8;
  std::vector<double> carried(nv, 0.0);
  std::vector<char> holds(nv, 0);
  for (int v = first; v < nv; ++v)
    if (full(v)) carried[v] = d[v], holds[v] = 1;
  for (int sweep = 0; sweep < kSweeps; ++sweep)
    for (int v : band) {
      double sum = 0;
      int count = 0;
      for (int i = ring.offsets[v]; i < ring.offsets[v + 1]; ++i) {
        const int u = ring.items[i];
        if (u != v && holds[u] && N[u].dot(N[v]) >= min_agreement) sum += carried[u], ++count;
      }
      if (count == 0) continue;
      carried[v] = sum / count;
      holds[v] = 1;
    }
  // A partly supported vertex takes a share only at the data's edge
  // (within a few rings of a vertex without data): inside the data a
  // footprint's centroid can lie off the line by chance (sparse or noisy
  // points), and such a vertex keeps its measurement as before.
  constexpr int kEdgeRings = 3;
  std::vector<int> rings_to_void(nv, kEdgeRings + 1);
  std::vector<int> queue;
  for (int v : band)
    if (support[v] <= 0) rings_to_void[v] = 0, queue.push_back(v);
  for (size_t head = 0; head < queue.size(); ++head) {
    const int v = queue[head];
    if (rings_to_void[v] >= kEdgeRings) continue;
    for (int i = ring.offsets[v]; i < ring.offsets[v + 1]; ++i) {
      const int u = ring.items[i];
      if (rings_to_void[u] > rings_to_void[v] + 1) rings_to_void[u] = rings_to_void[v] + 1, queue.push_back(u);
    }
  }
  int changed = 0;
  for (int v : band) {
    if (v < first || !holds[v] || rings_to_void[v] > kEdgeRings) continue;
    const double x = std::clamp(1.0 - dist[v] / width, 0.0, 1.0);
    const double share = (1.0 - std::clamp(support[v], 0.0, 1.0)) * x * x * (3 - 2 * x);
    if (!(share > 0) || carried[v] == 0) continue;
    d[v] += share * carried[v];
    ++changed;
  }
  return changed;
}

// Points grouped by a cell key (of_point[i] = key_of(i)'s cell): cells get
// dense ids in the order their first point comes, with their point count
// and that first point.
struct Cells {
  std::unordered_map<std::int64_t, int> id_of;
  std::vector<int> count, of_point;
  std::vector<size_t> first_point;
};
template <class KeyOf>
Cells group_into_cells(size_t n, size_t expected_cells, const KeyOf& key_of) {
  Cells c;
  c.id_of.reserve(expected_cells);
  c.of_point.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const auto [it, fresh] = c.id_of.try_emplace(key_of(i), static_cast<int>(c.count.size()));
    if (fresh) c.count.push_back(0), c.first_point.push_back(i);
    ++c.count[it->second];
    c.of_point[i] = it->second;
  }
  return c;
}

// The median over every step-th point of the distance to its nearest other
// point (a point with a copy at the same place is left out, as a kd-tree's
// two nearest neighbours leave it out); 0 when no sampled point has one.
// Exact, over a grid: a point's cell and the 26 around it hold every point
// within one cell of it, so a neighbour found that close is the nearest,
// and rings of cells further out widen the search. A point with no
// neighbour within kRings cells (a stray return) only needs to be known to
// lie above every distance found: the median is then the same as long as
// fewer than half the samples are such. The cells are sized so that a
// scanned surface puts tens of points in one (a kd-tree over the whole
// cloud cost ~40 ms for 4096 queries); clouds that defeat the grid go to
// the kd-tree.
double median_nearest_distance(const std::vector<Vec3>& points, size_t step) {
  const size_t n = points.size();
  constexpr int kRings = 2;
  std::vector<double> nearest;
  auto with_kd_tree = [&] {
    nearest.clear();
    CloudAdaptor adaptor{points};
    const CloudTree tree(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16));  // (built here)
    for (size_t i = 0; i < n; i += step) {
      size_t idx[2];
      double d2[2];
      if (tree.knnSearch(points[i].data(), 2, idx, d2) == 2 && d2[1] > 0) nearest.push_back(std::sqrt(d2[1]));
    }
    return nearest.empty() ? 0.0 : median(nearest);
  };
  BBox box;
  for (const Vec3& p : points) box.extend(p);
  const Vec3 size = box.size();
  const double volume = std::max(size.x(), 1e-300) * std::max(size.y(), 1e-300) * std::max(size.z(), 1e-300);
  const double h = std::cbrt(volume / static_cast<double>(n));
  if (!(h > 0) || !std::isfinite(h) || !(size.maxCoeff() / h < (1 << 20))) return with_kd_tree();
  // The cells as runs of one array (counted, then filled: no list per cell).
  auto index = [&](double v, double lo) { return static_cast<std::int64_t>(std::floor((v - lo) / h)); };
  auto key = [](std::int64_t x, std::int64_t y, std::int64_t z) { return (x << 42) | (y << 21) | z; };
  Cells cells = group_into_cells(n, n / 8, [&](size_t i) {
    const Vec3& p = points[i];
    return key(index(p.x(), box.min.x()), index(p.y(), box.min.y()), index(p.z(), box.min.z()));
  });
  if (*std::max_element(cells.count.begin(), cells.count.end()) > 4096)
    return with_kd_tree();  // points piled into few cells
  // Counts -> one past each cell's end, then filled backwards to its start.
  std::vector<int> cell_start = std::move(cells.count), cell_points(n);
  int sum = 0;
  for (int& c : cell_start) sum += c, c = sum;
  cell_start.push_back(sum);
  for (size_t i = n; i-- > 0;) cell_points[--cell_start[cells.of_point[i]]] = static_cast<int>(i);
  const auto& cell_of = cells.id_of;
  int far = 0;  // samples with no neighbour within kRings cells
  for (size_t i = 0; i < n; i += step) {
    const Vec3& p = points[i];
    const std::int64_t c[3] = {index(p.x(), box.min.x()), index(p.y(), box.min.y()), index(p.z(), box.min.z())};
    double best2 = std::numeric_limits<double>::infinity();
    bool duplicate = false, known = false;
    // Ring r: the cells at Chebyshev distance r; every point beyond it lies
    // more than r cells away.
    for (int r = 0; r <= kRings && !known; ++r) {
      for (int dx = -r; dx <= r; ++dx)
        for (int dy = -r; dy <= r; ++dy)
          for (int dz = -r; dz <= r; ++dz) {
            if (std::max({std::abs(dx), std::abs(dy), std::abs(dz)}) != r) continue;
            const auto it = cell_of.find(key(c[0] + dx, c[1] + dy, c[2] + dz));
            if (it == cell_of.end()) continue;
            for (int k = cell_start[it->second]; k < cell_start[it->second + 1]; ++k) {
              const int j = cell_points[k];
              // (summed as the kd-tree's metric sums: the same last bit)
              const double ex = points[j].x() - p.x(), ey = points[j].y() - p.y(), ez = points[j].z() - p.z();
              const double d2 = ex * ex + ey * ey + ez * ez;
              if (d2 > 0 && d2 < best2) best2 = d2;
              duplicate = duplicate || (d2 == 0 && j != static_cast<int>(i));
            }
          }
      known = best2 <= sqr(r * h);
    }
    if (duplicate) continue;
    if (known) nearest.push_back(std::sqrt(best2));
    else ++far;
  }
  // The far samples sort above every distance found; the median's one or
  // two middle elements must be found ones.
  const size_t total = nearest.size() + far;
  if (total == 0) return 0.0;
  if (static_cast<size_t>(far) >= total - total / 2) return with_kd_tree();
  nearest.resize(total, std::numeric_limits<double>::infinity());
  return median(nearest);
}

}  // namespace

std::vector<char> isolated_scan_points(const std::vector<Vec3>& points, double density_ratio) {
  const size_t n = points.size();
  std::vector<char> isolated(n, 0);
  if (n < 16 || !(density_ratio > 0)) return isolated;
  // Typical spacing: median nearest-neighbour distance of a spread sample.
  const double spacing = median_nearest_distance(points, std::max<size_t>(1, n / 4096));
  if (!(spacing > 0)) return isolated;
  const double cell = 4.0 * spacing;
  // A surface through the 3x3x3 cells holds about (3 cell / spacing)^2 points.
  const double expected = (3.0 * cell / spacing) * (3.0 * cell / spacing);
  const double needed = expected / density_ratio;
  auto key = [&](const Vec3& p, int dx, int dy, int dz) {
    const auto c = [&](double v, int d) { return static_cast<std::int64_t>(std::floor(v / cell)) + d + (1 << 20); };
    return (c(p.x(), dx) << 42) ^ (c(p.y(), dy) << 21) ^ c(p.z(), dz);
  };
  // Counted per occupied cell, then each cell's 3x3x3 block summed once
  // (not once per point: a cell holds ~9 points), then looked up per point.
  std::vector<std::int64_t> point_key(n);
  parallel_for(0, static_cast<int>(n), 8192, [&](int i, int) { point_key[i] = key(points[i], 0, 0, 0); });
  const Cells cells = group_into_cells(n, n / 4, [&](size_t i) { return point_key[i]; });
  std::vector<char> cell_isolated(cells.count.size(), 0);
  parallel_for(0, static_cast<int>(cells.count.size()), 1024, [&](int c, int) {
    const Vec3& p = points[cells.first_point[c]];
    int around = 0;
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const auto it = cells.id_of.find(key(p, dx, dy, dz));
          if (it != cells.id_of.end()) around += cells.count[it->second];
        }
    cell_isolated[c] = around < needed;
  });
  for (size_t i = 0; i < n; ++i) isolated[i] = cell_isolated[cells.of_point[i]];
  return isolated;
}

Status measure_displacements(const PointCloud& cloud, const DisplacementOptions& options, MultiresMesh& mesh,
                             DisplacementStats* stats, const ProgressFn& progress) {
  if (cloud.positions.empty()) return Status::error(ErrorCode::Empty, "multires: the point cloud is empty");
  for (const Vec3& p : cloud.positions)
    if (!p.allFinite()) return Status::error(ErrorCode::InvalidInput, "multires: a point of the cloud is not finite");
  if (!(options.radius >= 0) || !(options.max_distance >= 0) || !(options.max_radius >= 0) ||
      !(options.cluster_fraction > 0))
    return Status::error(ErrorCode::InvalidInput,
                         "multires: negative radius/max radius/max distance or non-positive cluster fraction");
  if (!(options.isolated_density_ratio >= 0))
    return Status::error(ErrorCode::InvalidInput, "multires: isolated_density_ratio must be >= 0");
  if (!(options.noise_edge_fraction > 0) || !(options.noise_max_radius_edges >= 0) ||
      !(options.noise_confidence > 0) || options.max_footprint_points > (1 << 16) || options.noise_finest_levels < 0)
    return Status::error(ErrorCode::InvalidInput,
                         "multires: noise_edge_fraction and noise_confidence must be > 0, noise_max_radius_edges and "
                         "noise_finest_levels >= 0, max_footprint_points <= 65536");
  if (options.smooth_finest_levels < 0 || options.smooth_iterations < 0 || options.smooth_iterations > 1000 ||
      !(options.smooth_strength >= 0) || !(options.smooth_strength < 1e6) || !(options.smooth_agreement > 0) ||
      !(options.smooth_agreement < 1e6) || !(options.smooth_max_radius_edges >= 0) || !(options.smooth_noise_cap >= 0) ||
      !(options.smooth_move_cap >= 0) || !(options.smooth_normal_degrees >= 0) || !(options.smooth_normal_degrees <= 90) ||
      !(options.smooth_max_height_errors >= 0))
    return Status::error(ErrorCode::InvalidInput,
                         "multires: smooth_finest_levels >= 0, 0 <= smooth_iterations <= 1000, 0 <= smooth_strength "
                         "< 1e6, 0 < smooth_agreement < 1e6, smooth_max_radius_edges, smooth_noise_cap, smooth_move_cap, "
                         "smooth_max_height_errors >= 0 and 0 <= smooth_normal_degrees <= 90 required");
  if (!(options.edge_fade_control_edges >= 0) || !(options.edge_fade_control_edges < 1e6))
    return Status::error(ErrorCode::InvalidInput, "multires: edge_fade_control_edges must be >= 0 and finite");
  if (options.footprint_points < 1 || !(options.ridge >= 0) || !(options.support_full_offset >= 0) ||
      !(options.support_zero_offset > options.support_full_offset))
    return Status::error(ErrorCode::InvalidInput,
                         "multires: footprint_points must be >= 1, ridge >= 0, and 0 <= support_full_offset < "
                         "support_zero_offset");
  Status s = check_sizes(mesh);
  if (!s.ok()) return s;

  const bool use_normals = options.min_normal_agreement >= -1 && cloud.normals.size() == cloud.positions.size();
  // The points measured from: without the isolated ones (hair returns).
  std::vector<Vec3> kept_positions, kept_normals;
  const std::vector<Vec3>* positions = &cloud.positions;
  const std::vector<Vec3>* point_normals = use_normals ? &cloud.normals : nullptr;
  if (options.isolated_density_ratio > 0) {
    const std::vector<char> isolated = isolated_scan_points(cloud.positions, options.isolated_density_ratio);
    const size_t n_isolated = static_cast<size_t>(std::count(isolated.begin(), isolated.end(), 1));
    if (n_isolated > 0 && n_isolated < cloud.positions.size()) {
      for (size_t i = 0; i < cloud.positions.size(); ++i) {
        if (isolated[i]) continue;
        kept_positions.push_back(cloud.positions[i]);
        if (use_normals) kept_normals.push_back(cloud.normals[i]);
      }
      positions = &kept_positions;
      if (use_normals) point_normals = &kept_normals;
    }
  }
  CloudAdaptor adaptor{*positions};
  // (nanoflann 1.4's constructor builds the index; a buildIndex() after it
  // built the same tree a second time, ~25 ms on 225k points.)
  const CloudTree tree(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16));

  const int L = mesh.num_levels();
  for (auto& d : mesh.displacements) std::fill(d.begin(), d.end(), 0.0);
  resize_state(mesh);
  if (stats)
    *stats = DisplacementStats{std::vector<int>(L + 1, 0),    std::vector<int>(L + 1, 0),
                               std::vector<double>(L + 1, 0), std::vector<double>(L + 1, 0),
                               std::vector<int>(L + 1, 0),    std::vector<double>(L + 1, 0),
                               std::vector<int>(L + 1, 0),    std::vector<int>(L + 1, 0),
                               std::vector<double>(L + 1, 0), std::vector<int>(L + 1, 0), 0.0};
  std::vector<Scratch> scratch(parallel_workers());  // one per worker
  // Per vertex of the finest level (a coarser level's vertices keep their
  // indices): the noise figures of the fit that measured it, for the
  // smoothing over the mesh.
  std::vector<double> vertex_noise(mesh.num_vertices(L), -1.0), vertex_variance_factor(mesh.num_vertices(L), 0.0),
      vertex_radius(mesh.num_vertices(L), 0.0);
  mesh.state.base[0] = mesh.control;
  // Data support of every vertex on the level that introduced it, and the
  // width of the fade across the data's edge.
  mesh.data_support.assign(mesh.num_vertices(L), 0.0);
  const double fade_width = options.edge_fade_control_edges * mean_edge(mesh.control, mesh.control_triangles);
  if (stats) stats->edge_fade_width = fade_width;
  for (int l = 0; l <= L; ++l) {
    evaluate_level(mesh, l);  // normals N_l with d_l = 0
    const double edge = mean_edge(mesh.state.base[l], mesh.triangles(l));
    double area = 0;
    for (int f = 0; f < static_cast<int>(mesh.triangles(l).size()); ++f)
      area += 0.5 * face_normal(mesh.triangles(l), mesh.state.base[l], f).norm();
    // Mean spacing if the cloud covered the whole level: a lower bound on
    // its density where it has data (it covers part of the head).
    const double spacing = std::sqrt(area / positions->size());
    LevelGeometry g;
    g.adaptive = options.radius <= 0;
    if (g.adaptive) {
      g.min_radius = 0.5 * edge;
      g.max_radius = options.max_radius > 0 ? options.max_radius : std::max(g.min_radius, 2.0 * spacing);
      // Where footprint_points points are expected at the mean spacing,
      // with margin so the first search usually suffices.
      const double expected = spacing * std::sqrt(options.footprint_points / kPi);
      g.first_radius = std::clamp(1.1 * expected, g.min_radius, std::max(g.min_radius, g.max_radius));
    } else {
      g.min_radius = g.max_radius = g.first_radius = options.radius;
    }
    const double typical_radius =
        g.adaptive ? std::clamp(spacing * std::sqrt(options.footprint_points / kPi), g.min_radius, g.max_radius)
                   : options.radius;
    g.edge = edge;
    g.widen = l > L - options.noise_finest_levels;
    g.smooth = l > L - options.smooth_finest_levels && options.smooth_iterations > 0 && options.smooth_strength > 0;
    // The fits' standard errors: for the smoothing on its levels and the
    // level before (its vertices are part of the next level's heights).
    g.noise_figures = g.adaptive && ((g.widen && options.max_footprint_points > options.footprint_points) ||
                                     l >= L - options.smooth_finest_levels);
    g.max_distance = options.max_distance > 0 ? options.max_distance : 2.0 * std::max(edge, typical_radius);
    if (l > 0 && options.fine_line_edges > 0)
      g.max_distance = std::min(g.max_distance, options.fine_line_edges * std::max(edge, typical_radius));
    for (Scratch& sc : scratch) {
      sc.walk.mark.assign(mesh.num_vertices(l), 0);
      sc.walk.stamp = 0;
    }

    const int nv = mesh.num_vertices(l);
    const int first = (l == 0 || options.remeasure_coarse_vertices) ? 0 : mesh.num_vertices(l - 1);
    // Each vertex is measured on its own (the mesh is read, not written):
    // in parallel, then summed in vertex order.
    std::vector<char> found(nv - first, 0);
    std::vector<double> found_d(nv - first, 0.0), found_radius(nv - first, 0.0), found_taper(nv - first, 1.0);
    std::vector<char> found_widened(nv - first, 0);
    parallel_for(first, nv, 256, [&](int v, int worker) {
      const int k = v - first;
      found[k] = measure_one(tree, *positions, point_normals, mesh, l, v, g, options, scratch[worker], found_d[k],
                             found_radius[k], found_taper[k], found_widened[k], vertex_noise[v],
                             vertex_variance_factor[v]);
      if (!found[k]) vertex_noise[v] = -1.0;
      vertex_radius[v] = found_radius[k];
    });
    int measured = 0, tapered = 0, widened = 0;
    double sum_abs = 0, max_abs = 0, sum_radius = 0;
    for (int v = first; v < nv; ++v) {
      const int k = v - first;
      if (!found[k]) continue;
      const double d = found_d[k];
      mesh.displacements[l][v] = d;
      ++measured;
      tapered += found_taper[k] < 1;
      sum_abs += std::abs(d);
      max_abs = std::max(max_abs, std::abs(d));
      sum_radius += found_radius[k];
      widened += found_widened[k];
    }
    int smoothed = 0;
    double sum_smoothing = 0;
    if (g.smooth) {
      // Heights above this level's base: the coarser vertices lie where
      // their own level measured them (0 here, with that level's error);
      // they steady their neighbours but keep their place (one
      // displacement per vertex, on the level that introduced it).
      std::vector<double> heights(nv, 0.0);
      for (int v = first; v < nv; ++v) heights[v] = mesh.displacements[l][v];
      smooth_heights(mesh, l, options, edge, vertex_noise, vertex_variance_factor, vertex_radius, first, heights, smoothed,
                     sum_smoothing);
      for (int v = first; v < nv; ++v) mesh.displacements[l][v] = heights[v];
    }
    for (int v = first; v < nv; ++v) mesh.data_support[v] = found[v - first] ? found_taper[v - first] : 0.0;
    int faded = 0;
    if (fade_width > 0) faded = fade_across_data_edge(mesh, l, first, mesh.data_support, fade_width, mesh.displacements[l]);
    if (stats) {
      stats->candidates[l] = nv - first;
      stats->measured[l] = measured;
      stats->mean_abs[l] = measured ? sum_abs / measured : 0.0;
      stats->max_abs[l] = max_abs;
      stats->tapered[l] = tapered;
      stats->mean_radius[l] = measured ? sum_radius / measured : 0.0;
      stats->widened[l] = widened;
      stats->smoothed[l] = smoothed;
      stats->mean_smoothing[l] = smoothed ? sum_smoothing / smoothed : 0.0;
      stats->faded[l] = faded;
    }
    evaluate_level(mesh, l);  // now with d_l
    if (l < L) {
      s = apply(mesh.levels[l], mesh.state.displaced[l], mesh.state.base[l + 1]);
      if (!s.ok()) return s;
    }
    if (!report(progress, "multires displacements", static_cast<double>(l + 1) / (L + 1))) {
      for (auto& d : mesh.displacements) std::fill(d.begin(), d.end(), 0.0);
      evaluate(mesh);
      return Status::error(ErrorCode::Cancelled, "multires: displacement measurement cancelled");
    }
  }
  return Status::success();
}

}  // namespace lk
