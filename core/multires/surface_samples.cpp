#include "multires/surface_samples.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace lk {

namespace {
// Boubekeur & Alexa's alpha. They suggest 3/4 for looks; 1/2 is exact to
// second order on a quadric (an edge's midpoint: the chord lies k h^2 / 2
// above a parabola of curvature k, the corners' tangent lines k h^2 / 2
// below it), so the samples lie on the scan's surface, not above it.
constexpr double kPhongShape = 0.5;
}  // namespace

Status sample_scan_surface(const std::vector<Vec3>& positions, const std::vector<Vec3>& normals,
                           const std::vector<Tri>& faces, const std::vector<char>& keep, double spacing,
                           double max_edge_ratio, int max_samples, PointCloud& out, SurfaceSampleStats& stats) {
  stats = {};
  const int np = static_cast<int>(positions.size());
  if (keep.size() != positions.size())
    return Status::error(ErrorCode::InvalidInput, "surface samples: keep flags do not match the points");
  if (!(spacing > 0) || !std::isfinite(spacing))
    return Status::error(ErrorCode::InvalidInput, "surface samples: spacing must be positive");
  const bool with_normals = normals.size() == positions.size() && out.normals.size() == out.positions.size();
  std::vector<int> kept;
  std::vector<double> longest;  // per kept triangle
  std::vector<double> edges;
  for (int f = 0; f < static_cast<int>(faces.size()); ++f) {
    const Tri& t = faces[f];
    bool ok = true;
    for (int k = 0; k < 3; ++k) {
      if (t[k] < 0 || t[k] >= np)
        return Status::error(ErrorCode::InvalidInput, "surface samples: triangle " + std::to_string(f) +
                                                          " has a corner index out of range");
      ok = ok && keep[t[k]];
    }
    if (!ok || t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;
    kept.push_back(f);
    double l = 0;
    for (int k = 0; k < 3; ++k) {
      edges.push_back((positions[t[k]] - positions[t[(k + 1) % 3]]).norm());
      l = std::max(l, edges.back());
    }
    longest.push_back(l);
  }
  if (kept.empty()) return Status::success();
  std::nth_element(edges.begin(), edges.begin() + edges.size() / 2, edges.end());
  const double cap = max_edge_ratio * edges[edges.size() / 2];

  // Count first, so a spacing far below the scan's own fails before any work.
  std::vector<int> cuts(kept.size(), 0);
  long long total = 0;
  for (size_t i = 0; i < kept.size(); ++i) {
    if (!(longest[i] <= cap)) {
      ++stats.triangles_skipped_long;
      continue;
    }
    const double n = std::ceil(longest[i] / spacing);
    if (n > 1e4) return Status::error(ErrorCode::InvalidInput, "surface samples: spacing far below the scan's edges");
    if (n < 2) {  // the scan's own points are as dense as asked here
      ++stats.triangles_dense;
      continue;
    }
    cuts[i] = static_cast<int>(n);
    total += static_cast<long long>(cuts[i]) * cuts[i];
  }
  if (total > max_samples)
    return Status::error(ErrorCode::TooLarge, "surface samples: " + std::to_string(total) +
                                                  " samples would exceed the limit of " + std::to_string(max_samples));
  // Vertex normals for the Phong tessellation: area-weighted over the kept
  // triangles, each triangle's normal signed to agree with the sum so far
  // (the projection below does not depend on the sign, so a scan with
  // inconsistently wound triangles still gets its tangent planes).
  std::vector<Vec3> vn(positions.size(), Vec3::Zero());
  for (size_t i = 0; i < kept.size(); ++i) {
    if (cuts[i] == 0) continue;
    const Tri& t = faces[kept[i]];
    const Vec3 fn = (positions[t[1]] - positions[t[0]]).cross(positions[t[2]] - positions[t[0]]);
    for (int k = 0; k < 3; ++k) vn[t[k]] += vn[t[k]].dot(fn) < 0 ? Vec3(-fn) : fn;
  }
  for (Vec3& v : vn) {
    const double len = v.norm();
    v = len > 0 ? Vec3(v / len) : Vec3::Zero();
  }
  out.positions.reserve(out.positions.size() + static_cast<size_t>(total));
  if (with_normals) out.normals.reserve(out.positions.capacity());
  for (size_t i = 0; i < kept.size(); ++i) {
    const int n = cuts[i];
    if (n == 0) continue;
    const Tri& t = faces[kept[i]];
    const Vec3 &a = positions[t[0]], &b = positions[t[1]], &c = positions[t[2]];
    // Sub-triangles of the n x n split in barycentric steps of 1/n: the
    // upright ones have corners (i,j), (i+1,j), (i,j+1) and centroid
    // (i+1/3, j+1/3); the inverted ones (i+1,j), (i+1,j+1), (i,j+1) with
    // centroid (i+2/3, j+2/3), for i + j <= n - 2.
    auto emit = [&](double u, double v) {  // weights of b and c
      const double w = 1.0 - u - v;
      const Vec3 q = w * a + u * b + v * c;
      // Phong tessellation (Boubekeur & Alexa 2008): the flat point
      // blended with its projections on the corners' tangent planes.
      auto onto = [&](int k) { return Vec3(q - (q - positions[t[k]]).dot(vn[t[k]]) * vn[t[k]]); };
      const Vec3 curved = w * onto(0) + u * onto(1) + v * onto(2);
      out.positions.push_back((1 - kPhongShape) * q + kPhongShape * curved);
      if (with_normals) {
        Vec3 nn = w * normals[t[0]] + u * normals[t[1]] + v * normals[t[2]];
        const double len = nn.norm();
        out.normals.push_back(len > 0 ? Vec3(nn / len) : Vec3::Zero());
      }
    };
    for (int ii = 0; ii < n; ++ii)
      for (int jj = 0; ii + jj < n; ++jj) {
        emit((ii + 1.0 / 3) / n, (jj + 1.0 / 3) / n);
        if (ii + jj <= n - 2) emit((ii + 2.0 / 3) / n, (jj + 2.0 / 3) / n);
      }
    ++stats.triangles_sampled;
  }
  stats.samples = static_cast<int>(total);
  return Status::success();
}

}  // namespace lk
