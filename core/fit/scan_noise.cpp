#include "fit/scan_noise.h"

#include "common/cloud_tree.h"
#include "common/parallel.h"
#include "fit/point_patch.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace lk {

Status estimate_scan_noise(const std::vector<Vec3>& points, const std::vector<char>& measured, int k,
                           ScanNoise& out) {
  out = ScanNoise{};
  if (k < 7) return Status::error(ErrorCode::InvalidInput, "the noise floor needs k >= 7 (a quadric has 6 unknowns)");
  if (!measured.empty() && measured.size() != points.size())
    return Status::error(ErrorCode::InvalidInput, "the noise floor's mask and points differ in size");
  for (const Vec3& p : points)
    if (!p.allFinite()) return Status::error(ErrorCode::InvalidInput, "the scan has non-finite coordinates");
  if (static_cast<int>(points.size()) < k) return Status::error(ErrorCode::Empty, "too few points for a noise floor");
  const CloudAdaptor adaptor{points};
  CloudTree tree(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  tree.buildIndex();
  const int n = static_cast<int>(points.size());
  std::vector<double> sigma(n, -1);
  parallel_for(0, n, 512, [&](int i, int) {
    if (!measured.empty() && !measured[i]) return;
    PointPatch patch;
    if (!fit_patch_plane(tree, points, points[i], k, patch)) return;
    // Height field h = c0 + c1 u + c2 w + c3 u^2 + c4 uw + c5 w^2 in the
    // patch's frame (coordinates over its radius, so the system is scaled).
    const Vec3 n0 = patch.plane_normal, t1 = patch.axes.col(2), t2 = patch.axes.col(1);
    const double scale = 1.0 / std::max(patch.radius, 1e-300);
    Eigen::Matrix<double, Eigen::Dynamic, 6> A(patch.count, 6);
    Eigen::VectorXd h(patch.count);
    for (int j = 0; j < patch.count; ++j) {
      const Vec3 d = (points[patch.index[j]] - patch.centroid) * scale;
      const double u = d.dot(t1), w = d.dot(t2);
      A.row(j) << 1, u, w, u * u, u * w, w * w;
      h[j] = d.dot(n0);
    }
    const Eigen::Matrix<double, 6, 1> c = A.colPivHouseholderQr().solve(h);
    const double rss = (A * c - h).squaredNorm();
    if (std::isfinite(rss)) sigma[i] = std::sqrt(rss / (patch.count - 6)) / scale;
  });
  std::vector<double> kept;
  for (double s : sigma)
    if (s >= 0) kept.push_back(s);
  if (kept.empty()) return Status::error(ErrorCode::Empty, "no point measured for the noise floor");
  double sum = 0;
  for (double s : kept) sum += s;  // in point order: the same on any thread count
  out.points = static_cast<int>(kept.size());
  out.sigma_mean = sum / kept.size();
  std::nth_element(kept.begin(), kept.begin() + kept.size() / 2, kept.end());
  out.sigma_median = kept[kept.size() / 2];
  out.floor = std::sqrt(2.0 / 3.14159265358979323846) * out.sigma_mean;
  return Status::success();
}

}  // namespace lk
