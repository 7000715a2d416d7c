#include "fit/point_patch.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace lk {

namespace {
// Centroid and principal axes of the patch's points, and the vertex's
// place over their plane.
void principal_plane(const std::vector<Vec3>& points, const Vec3& q, PointPatch& out) {
  const int m = out.count;
  Vec3 c = Vec3::Zero();
  for (int i = 0; i < m; ++i) c += points[out.index[i]];
  c /= double(m);
  Mat3 cov = Mat3::Zero();
  for (int i = 0; i < m; ++i) {
    const Vec3 p = points[out.index[i]] - c;
    cov += p * p.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Mat3> es(cov);
  out.centroid = c;
  out.eigenvalues = es.eigenvalues();  // ascending
  out.axes = es.eigenvectors();
  out.plane_normal = out.axes.col(0);
  const Vec3 off = q - c;
  out.height = out.plane_normal.dot(off);
  out.tangential = (off - out.height * out.plane_normal).norm();
  out.spread = std::sqrt(out.eigenvalues[1] / double(m));
  const Vec3 foot = off - out.height * out.plane_normal;  // about the centroid
  out.extent = 0;
  out.foot_gap = 1e300;
  for (int i = 0; i < m; ++i) {
    Vec3 p = points[out.index[i]] - c;
    p -= out.plane_normal.dot(p) * out.plane_normal;
    out.extent = std::max(out.extent, p.norm());
    out.foot_gap = std::min(out.foot_gap, (p - foot).norm());
  }
}

// The median of |x| times `trim` x 1.4826 (a robust spread's multiple).
double robust_limit(std::vector<double> x, double trim) {
  for (double& v : x) v = std::abs(v);
  std::nth_element(x.begin(), x.begin() + x.size() / 2, x.end());
  return trim * 1.4826 * x[x.size() / 2];
}
}  // namespace

bool fit_patch_plane(const CloudTree& tree, const std::vector<Vec3>& points, const Vec3& q, int k, PointPatch& out,
                     double trim) {
  out.quadric_ok = false;
  out.count = 0;
  if (k < 1) return false;
  out.index.resize(k);
  std::vector<double> d2(k);
  const size_t got = tree.knnSearch(q.data(), k, out.index.data(), d2.data());
  if (static_cast<int>(got) < k) return false;
  out.count = k;
  out.radius = std::sqrt(d2[got - 1]);
  principal_plane(points, q, out);
  if (trim > 0) {
    // Points off the plane by more than `trim` robust spreads are outliers
    // (a stray return 2 mm out makes a 16-point patch look like two sheets).
    std::vector<double> h(k);
    for (int i = 0; i < k; ++i) h[i] = out.plane_normal.dot(points[out.index[i]] - out.centroid);
    const double limit = std::max(robust_limit(h, trim), 1e-6 * out.radius);  // exact data: keep all
    int kept = 0;
    for (int i = 0; i < k; ++i)
      if (std::abs(h[i]) <= limit) out.index[kept++] = out.index[i];
    if (kept < k && kept >= 6) {
      out.count = kept;
      out.index.resize(kept);
      principal_plane(points, q, out);
    }
  }
  return true;
}

namespace {
using Vec6 = Eigen::Matrix<double, 6, 1>;

Vec6 quadric_row(double u, double w) {
  Vec6 row;
  row << 1, u, w, u * u, u * w, w * w;
  return row;
}

double quadric_at(const Vec6& q, double u, double w) {
  return q[0] + q[1] * u + q[2] * w + q[3] * u * u + q[4] * u * w + q[5] * w * w;
}

// Least-squares height field h(u, w) = row(u, w) . quad over the patch's
// points not flagged in `dropped` (coordinates about the centroid, scaled).
Vec6 solve_quadric(const std::vector<Vec3>& local, const std::vector<char>& dropped) {
  Eigen::Matrix<double, 6, 6> A = Eigen::Matrix<double, 6, 6>::Zero();
  Vec6 b = Vec6::Zero();
  for (size_t i = 0; i < local.size(); ++i) {
    if (dropped[i]) continue;
    const Vec6 row = quadric_row(local[i].x(), local[i].y());
    A.noalias() += row * row.transpose();
    b += row * local[i].z();
  }
  A.diagonal().tail<3>().array() += 1e-3;  // a flat patch keeps a defined quadric
  return A.ldlt().solve(b);
}
}  // namespace

bool fit_patch_quadric(const std::vector<Vec3>& points, const Vec3& q, PointPatch& out, double trim) {
  out.quadric_ok = false;
  if (out.count < 6) return false;
  const Vec3& n = out.plane_normal;
  const Vec3 t1 = out.axes.col(2), t2 = out.axes.col(1);  // in the plane
  const Vec3& c = out.centroid;
  const double scale = 1.0 / std::max(out.radius, 1e-12);  // unit-free coordinates
  std::vector<Vec3> local(out.count);  // (u, w, height) of each point
  for (int i = 0; i < out.count; ++i) {
    const Vec3 p = (points[out.index[i]] - c) * scale;
    local[i] = Vec3(p.dot(t1), p.dot(t2), p.dot(n));
  }
  std::vector<char> dropped(out.count, 0);
  Vec6 quad = solve_quadric(local, dropped);
  if (!quad.allFinite()) return false;
  if (trim > 0) {
    // Points farther from the fit than `trim` robust spreads are outliers.
    std::vector<double> r(out.count);
    for (int i = 0; i < out.count; ++i) r[i] = std::abs(local[i].z() - quadric_at(quad, local[i].x(), local[i].y()));
    const double limit = std::max(robust_limit(r, trim), 1e-6);  // scaled units
    int kept = 0;
    for (int i = 0; i < out.count; ++i) kept += !(dropped[i] = r[i] > limit);
    if (kept < out.count && kept >= 6) {
      quad = solve_quadric(local, dropped);
      if (!quad.allFinite()) return false;
    }
  }
  const Vec3 off = q - c;
  const double u0 = off.dot(t1) * scale, w0 = off.dot(t2) * scale;
  const double height = quadric_at(quad, u0, w0) / scale;
  out.foot = c + off.dot(t1) * t1 + off.dot(t2) * t2 + height * n;
  // Slopes in the scaled frame equal the true ones (u and w scale alike).
  const double du = quad[1] + 2 * quad[3] * u0 + quad[4] * w0, dw = quad[2] + quad[4] * u0 + 2 * quad[5] * w0;
  out.normal = (n - du * t1 - dw * t2).normalized();
  out.quadric_ok = out.foot.allFinite() && out.normal.allFinite();
  return out.quadric_ok;
}

}  // namespace lk
