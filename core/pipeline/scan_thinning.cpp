#include "pipeline/scan_thinning.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>

namespace lk {

namespace {

// 0..5: the axis of the largest |component| and its sign (6 for no normal).
std::uint64_t normal_class(const Vec3& n) {
  int axis = 0;
  for (int a = 1; a < 3; ++a)
    if (std::abs(n[a]) > std::abs(n[axis])) axis = a;
  if (!(std::abs(n[axis]) > 0)) return 6;
  return static_cast<std::uint64_t>(2 * axis + (n[axis] < 0 ? 1 : 0));
}

}  // namespace

Status thin_scan(const PointCloud& scan, double cell, PointCloud& out, ScanThinning& stats,
                 const std::vector<char>& leave_out, bool grid_order) {
  stats = ScanThinning{};
  const size_t n = scan.positions.size();
  stats.points = static_cast<int>(n);
  stats.kept = static_cast<int>(n);
  if (!(cell > 0) || !std::isfinite(cell)) return Status::error(ErrorCode::InvalidInput, "thin_scan: the cell must be positive");
  const bool normals = scan.normals.size() == n, colors = scan.colors.size() == n;
  if (!leave_out.empty() && leave_out.size() != n)
    return Status::error(ErrorCode::InvalidInput, "thin_scan: leave_out must have one flag a point");
  out = PointCloud{};
  if (n == 0) return Status::success();
  Vec3 lo = scan.positions[0], hi = lo;
  for (const Vec3& p : scan.positions) {
    if (!p.allFinite()) return Status::error(ErrorCode::InvalidInput, "thin_scan: non-finite coordinates");
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  // 20 bits an axis and 3 for the normal class: one 64-bit key.
  constexpr double kMaxCells = 1048575.0;
  const double extent = (hi - lo).maxCoeff();
  if (extent / cell >= kMaxCells) cell = extent / (kMaxCells - 1);
  stats.cell = cell;
  std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed;
  keyed.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    if (!leave_out.empty() && leave_out[i]) continue;
    std::uint64_t key = 0;
    for (int a = 0; a < 3; ++a) {
      const double c = std::min(kMaxCells - 1, std::floor((scan.positions[i][a] - lo[a]) / cell));
      key = (key << 20) | static_cast<std::uint64_t>(std::max(0.0, c));
    }
    key = (key << 3) | (normals ? normal_class(scan.normals[i]) : 0);
    keyed.push_back({key, static_cast<std::uint32_t>(i)});
  }
  const size_t m_in = keyed.size();
  std::sort(keyed.begin(), keyed.end());
  // One group per key, placed where its first point was (or in the keys'
  // order, which is the grid's).
  std::vector<std::pair<std::uint32_t, std::uint32_t>> groups;  // (first point, start in keyed)
  for (size_t i = 0; i < m_in; ++i)
    if (i == 0 || keyed[i].first != keyed[i - 1].first) groups.push_back({keyed[i].second, static_cast<std::uint32_t>(i)});
  if (!grid_order) std::sort(groups.begin(), groups.end());
  const size_t m = groups.size();
  out.positions.resize(m);
  if (normals) out.normals.resize(m);
  if (colors) out.colors.resize(m);
  for (size_t g = 0; g < m; ++g) {
    const size_t begin = groups[g].second;
    size_t end = begin + 1;
    while (end < m_in && keyed[end].first == keyed[begin].first) ++end;
    Vec3 p = Vec3::Zero(), nn = Vec3::Zero(), c = Vec3::Zero();
    for (size_t k = begin; k < end; ++k) {
      const std::uint32_t i = keyed[k].second;
      p += scan.positions[i];
      if (normals) nn += scan.normals[i];
      if (colors) c += scan.colors[i];
    }
    const double count = static_cast<double>(end - begin);
    out.positions[g] = p / count;  // in the cell (up to rounding): it is convex
    if (normals) {
      const double len = nn.norm();
      out.normals[g] = len > 1e-12 ? Vec3(nn / len) : scan.normals[groups[g].first];
    }
    if (colors) out.colors[g] = c / count;
  }
  stats.kept = static_cast<int>(m);
  stats.thinned = true;
  return Status::success();
}

Status surface_cell_averages(const std::vector<Vec3>& positions, const std::vector<Tri>& faces, double cell,
                             PointCloud& out) {
  out = PointCloud{};
  if (!(cell > 0) || !std::isfinite(cell))
    return Status::error(ErrorCode::InvalidInput, "surface cells: the cell must be positive and finite");
  const int n = static_cast<int>(positions.size());
  PointCloud samples;
  const double h = cell / 4;
  for (const Tri& t : faces) {
    for (int v : t)
      if (v < 0 || v >= n) return Status::error(ErrorCode::InvalidInput, "surface cells: a triangle's index is out of range");
    const Vec3 &a = positions[t[0]], &b = positions[t[1]], &c = positions[t[2]];
    const double longest = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
    if (!std::isfinite(longest))
      return Status::error(ErrorCode::InvalidInput, "surface cells: a triangle has a non-finite corner");
    const int k = std::max(1, static_cast<int>(std::min(1e4, std::ceil(longest / h))));
    for (int i = 0; i < k; ++i)
      for (int j = 0; j < k - i; ++j)
        samples.positions.push_back(a + (i + 1.0 / 3) / k * (b - a) + (j + 1.0 / 3) / k * (c - a));
  }
  if (samples.positions.empty()) return Status::error(ErrorCode::Empty, "surface cells: no triangles");
  // In the grid's order, not the triangles' (which the first sample of each
  // cell would follow).
  ScanThinning stats;
  return thin_scan(samples, cell, out, stats, {}, true);
}

}  // namespace lk
