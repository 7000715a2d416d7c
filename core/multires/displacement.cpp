#include "multires/displacement.h"

#include "multires/multires_detail.h"

#include <Eigen/Cholesky>
#include <nanoflann.hpp>

#include <algorithm>
#include <cmath>
#include <numeric>

namespace lk {

using namespace multires_detail;

namespace {

struct CloudAdaptor {
  const std::vector<Vec3>& pts;
  size_t kdtree_get_point_count() const { return pts.size(); }
  double kdtree_get_pt(size_t i, size_t dim) const { return pts[i][static_cast<int>(dim)]; }
  template <class BBOX>
  bool kdtree_get_bbox(BBOX&) const { return false; }
};
using CloudTree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, CloudAdaptor>,
                                                      CloudAdaptor, 3, size_t>;

// Median of a non-empty list (reordered).
double median(std::vector<double>& xs) {
  const size_t h = xs.size() / 2;
  std::nth_element(xs.begin(), xs.begin() + h, xs.end());
  const double upper = xs[h];
  if (xs.size() % 2) return upper;
  return 0.5 * (*std::max_element(xs.begin(), xs.begin() + h) + upper);
}

// Cylinder points in the vertex's frame: (u, v) across the normal line, t along it.
struct LinePoint {
  double u, v, t;
};

// Least-squares height field t = t0 + a u + b v + c u^2 + d uv + e v^2 over
// the points; its value t0 at the line is where the line meets the sampled
// surface. A quadric, not a plane or a median: a curved surface sags by
// rho^2 / 2R across the cylinder, which would otherwise bias the result.
using Quadric = Eigen::Matrix<double, 6, 1>;
inline Quadric quadric_row(const LinePoint& p, double scale) {
  const double u = p.u / scale, v = p.v / scale;  // O(1) for conditioning
  Quadric row;
  row << 1, u, v, u * u, u * v, v * v;
  return row;
}

bool fit_crossing(const std::vector<LinePoint>& pts, const std::vector<char>& use, double scale, Quadric& x) {
  Eigen::Matrix<double, 6, 6> A = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 1> rhs = Eigen::Matrix<double, 6, 1>::Zero();
  int n = 0;
  for (size_t i = 0; i < pts.size(); ++i) {
    if (!use[i]) continue;
    const Quadric row = quadric_row(pts[i], scale);
    A += row * row.transpose();
    rhs += row * pts[i].t;
    ++n;
  }
  if (n < 10) return false;
  Eigen::LDLT<Eigen::Matrix<double, 6, 6>> ldlt(A);
  if (ldlt.info() != Eigen::Success) return false;
  x = ldlt.solve(rhs);
  return x.allFinite() && ldlt.rcond() > 1e-10;
}

// Signed distance along n from p to the sampled surface, or false when the
// cylinder around the normal line holds too few points.
bool measure_one(const CloudTree& tree, const std::vector<Vec3>& pts, const std::vector<Vec3>* point_normals,
                 const Vec3& p, const Vec3& n, double radius,
                 double max_distance, const DisplacementOptions& opt,
                 std::vector<std::pair<size_t, double>>& matches, std::vector<LinePoint>& line_pts,
                 std::vector<double>& scratch, double& out) {
  if (n.squaredNorm() == 0) return false;  // no normal (isolated vertex)
  matches.clear();
  const double r2 = radius * radius;
  tree.radiusSearch(p.data(), max_distance * max_distance + r2, matches, nanoflann::SearchParams(32, 0, false));
  const Vec3 e1 = n.unitOrthogonal(), e2 = n.cross(e1);
  line_pts.clear();
  for (const auto& m : matches) {
    const Vec3 delta = pts[m.first] - p;
    const double t = delta.dot(n);
    if (std::abs(t) > max_distance) continue;
    if (delta.squaredNorm() - t * t > r2) continue;
    if (point_normals) {
      const Vec3& pn = (*point_normals)[m.first];
      if (!(pn.dot(n) > opt.min_normal_agreement * pn.norm())) continue;
    }
    line_pts.push_back({delta.dot(e1), delta.dot(e2), t});
  }
  const int min_points = std::max(1, opt.min_points);
  if (static_cast<int>(line_pts.size()) < min_points) return false;
  std::sort(line_pts.begin(), line_pts.end(),
            [](const LinePoint& a, const LinePoint& b) { return std::abs(a.t) < std::abs(b.t); });
  // The nearest crossing that enough points agree on; a lone stray point
  // near the vertex does not count as a crossing.
  const double width = opt.cluster_fraction * max_distance;
  std::vector<char> use(line_pts.size(), 0);
  for (const LinePoint& centre : line_pts) {
    scratch.clear();
    for (size_t i = 0; i < line_pts.size(); ++i) {
      use[i] = std::abs(line_pts[i].t - centre.t) <= width;
      if (use[i]) scratch.push_back(line_pts[i].t);
    }
    if (static_cast<int>(scratch.size()) < min_points) continue;
    const double fallback = median(scratch);
    double t0 = fallback;
    Quadric q;
    if (fit_crossing(line_pts, use, radius, q)) {
      t0 = q[0];
      // One robust pass: drop points far from the first fit (outliers,
      // the edge of another sheet), then refit.
      scratch.clear();
      for (size_t i = 0; i < line_pts.size(); ++i)
        if (use[i]) scratch.push_back(std::abs(line_pts[i].t - quadric_row(line_pts[i], radius).dot(q)));
      const double limit = 4.0 * median(scratch) + 1e-12 * max_distance;
      int dropped = 0;
      for (size_t i = 0; i < line_pts.size(); ++i)
        if (use[i] && std::abs(line_pts[i].t - quadric_row(line_pts[i], radius).dot(q)) > limit) use[i] = 0, ++dropped;
      // Nothing dropped: the refit would be the same fit.
      if (dropped > 0 && fit_crossing(line_pts, use, radius, q)) t0 = q[0];
    }
    out = std::abs(t0) <= max_distance ? t0 : fallback;
    return true;
  }
  return false;
}

}  // namespace

Status measure_displacements(const PointCloud& cloud, const DisplacementOptions& options, MultiresMesh& mesh,
                             DisplacementStats* stats, const ProgressFn& progress) {
  if (cloud.positions.empty()) return Status::error(ErrorCode::Empty, "multires: the point cloud is empty");
  for (const Vec3& p : cloud.positions)
    if (!p.allFinite()) return Status::error(ErrorCode::InvalidInput, "multires: a point of the cloud is not finite");
  if (options.radius < 0 || options.max_distance < 0 || !(options.cluster_fraction > 0))
    return Status::error(ErrorCode::InvalidInput, "multires: negative radius/max distance or non-positive cluster fraction");
  Status s = check_sizes(mesh);
  if (!s.ok()) return s;

  const bool use_normals = options.min_normal_agreement >= -1 && cloud.normals.size() == cloud.positions.size();
  const std::vector<Vec3>* point_normals = use_normals ? &cloud.normals : nullptr;
  CloudAdaptor adaptor{cloud.positions};
  CloudTree tree(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  tree.buildIndex();

  const int L = mesh.num_levels();
  for (auto& d : mesh.displacements) std::fill(d.begin(), d.end(), 0.0);
  resize_state(mesh);
  if (stats) *stats = DisplacementStats{std::vector<int>(L + 1, 0), std::vector<int>(L + 1, 0),
                                        std::vector<double>(L + 1, 0.0), std::vector<double>(L + 1, 0.0)};
  std::vector<std::pair<size_t, double>> matches;
  std::vector<LinePoint> line_pts;
  std::vector<double> scratch;
  mesh.state.base[0] = mesh.control;
  for (int l = 0; l <= L; ++l) {
    evaluate_level(mesh, l);  // normals N_l with d_l = 0
    const double edge = mean_edge(mesh.state.base[l], mesh.triangles(l));
    // Default footprint: half an edge, but never so small that the cloud's
    // sampling leaves the cylinder empty on fine levels (a disk of radius
    // 2 x spacing holds ~12 points where the scan covers the surface).
    double area = 0;
    for (int f = 0; f < static_cast<int>(mesh.triangles(l).size()); ++f)
      area += 0.5 * face_normal(mesh.triangles(l), mesh.state.base[l], f).norm();
    const double spacing = std::sqrt(area / cloud.size());
    const double radius = options.radius > 0 ? options.radius : std::max(0.5 * edge, 2.0 * spacing);
    double max_distance = options.max_distance > 0 ? options.max_distance : std::max(2.0 * edge, 2.0 * radius);
    if (l > 0 && options.fine_line_edges > 0)
      max_distance = std::min(max_distance, options.fine_line_edges * std::max(edge, radius));
    const int nv = mesh.num_vertices(l);
    const int first = (l == 0 || options.remeasure_coarse_vertices) ? 0 : mesh.num_vertices(l - 1);
    int measured = 0;
    double sum_abs = 0, max_abs = 0;
    for (int v = first; v < nv; ++v) {
      double d = 0;
      if (measure_one(tree, cloud.positions, point_normals, mesh.state.base[l][v], mesh.state.normals[l][v], radius,
                      max_distance,
                      options, matches, line_pts, scratch, d)) {
        mesh.displacements[l][v] = d;
        ++measured;
        sum_abs += std::abs(d);
        max_abs = std::max(max_abs, std::abs(d));
      }
    }
    if (stats) {
      stats->candidates[l] = nv - first;
      stats->measured[l] = measured;
      stats->mean_abs[l] = measured ? sum_abs / measured : 0.0;
      stats->max_abs[l] = max_abs;
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
