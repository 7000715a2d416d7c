#include "multires/multires.h"

#include "mesh/geometry.h"
#include "raycast/bvh.h"
#include "raycast/self_intersection.h"

#include <Eigen/Cholesky>
#include <nanoflann.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numeric>
#include <set>

namespace lk {
namespace {

// The per-vertex kernels below are the ONLY place where normals and
// displaced positions are computed, by evaluate() and by local updates alike:
// same operands in the same order give bit-identical results.
inline Vec3 face_normal(const std::vector<Tri>& tris, const std::vector<Vec3>& P, int f) {
  const Tri& t = tris[f];
  const Vec3& a = P[t[0]];
  return (P[t[1]] - a).cross(P[t[2]] - a);  // length = 2 area: area-weighted sums
}

inline Vec3 vertex_normal(const IndexRows& vertex_faces, const std::vector<Vec3>& face_normals, int v) {
  Vec3 n = Vec3::Zero();
  for (int i = vertex_faces.offsets[v]; i < vertex_faces.offsets[v + 1]; ++i) n += face_normals[vertex_faces.items[i]];
  const double len = n.norm();
  if (len > 0) n /= len;
  return n;
}

inline bool same_bits(const Vec3& a, const Vec3& b) { return std::memcmp(a.data(), b.data(), sizeof(double) * 3) == 0; }

inline Vec3 displace(const Vec3& p, double d, const Vec3& n) { return p + d * n; }

// Counting-sort construction of compressed rows, O(#items): count(emit)
// calls emit(row, item) for every pair, twice (count, then fill), in the
// same order, so rows keep the emission order.
template <class Emit>
IndexRows rows_by_counting(int rows, const Emit& emit_all) {
  IndexRows r;
  r.offsets.assign(rows + 1, 0);
  emit_all([&](int row, int) { ++r.offsets[row + 1]; });
  for (int i = 0; i < rows; ++i) r.offsets[i + 1] += r.offsets[i];
  r.items.resize(r.offsets[rows]);
  std::vector<int> fill(r.offsets.begin(), r.offsets.end() - 1);
  emit_all([&](int row, int item) { r.items[fill[row]++] = item; });
  return r;
}

MultiresLevelLinks build_links(int num_vertices, const std::vector<Tri>& tris, const ButterflyLevel* next) {
  MultiresLevelLinks L;
  const int nf = static_cast<int>(tris.size());
  // Faces in ascending order per vertex: the normal's summation order.
  L.vertex_faces = rows_by_counting(num_vertices, [&](auto&& emit) {
    for (int f = 0; f < nf; ++f)
      for (int v : tris[f]) emit(v, f);
  });

  // A vertex's normal reads every corner of its triangles, so moving u
  // changes the normals of u and of every vertex sharing a triangle with u.
  std::vector<int> seen(num_vertices, -1);
  L.normal_reach = rows_by_counting(num_vertices, [&](auto&& emit) {
    std::fill(seen.begin(), seen.end(), -1);
    for (int u = 0; u < num_vertices; ++u) {
      seen[u] = u;
      emit(u, u);
      for (int i = L.vertex_faces.offsets[u]; i < L.vertex_faces.offsets[u + 1]; ++i)
        for (int v : tris[L.vertex_faces.items[i]])
          if (seen[v] != u) {
            seen[v] = u;
            emit(u, v);
          }
    }
  });

  if (next) {
    // Coarse vertex u feeds fine vertex u (a copy) and every stencil naming it.
    L.refine_reach = rows_by_counting(num_vertices, [&](auto&& emit) {
      for (int v = 0; v < num_vertices; ++v) emit(v, v);
      for (int k = 0; k < next->num_new_vertices(); ++k)
        for (int i = next->stencil_offsets[k]; i < next->stencil_offsets[k + 1]; ++i)
          emit(next->stencil_indices[i], num_vertices + k);
    });
  }
  return L;
}

// Normals and displaced positions of level l from its base positions.
void evaluate_level(MultiresMesh& m, int l) {
  MultiresState& s = m.state;
  const int nv = m.num_vertices(l);
  const auto& tris = m.triangles(l);
  s.normals[l].resize(nv);
  s.displaced[l].resize(nv);
  s.face_normals[l].resize(tris.size());
  for (int f = 0; f < static_cast<int>(tris.size()); ++f) s.face_normals[l][f] = face_normal(tris, s.base[l], f);
  for (int v = 0; v < nv; ++v) {
    s.normals[l][v] = vertex_normal(m.links[l].vertex_faces, s.face_normals[l], v);
    s.displaced[l][v] = displace(s.base[l][v], m.displacements[l][v], s.normals[l][v]);
  }
}

void resize_state(MultiresMesh& m) {
  const int L = m.num_levels();
  m.state.base.resize(L + 1);
  m.state.normals.resize(L + 1);
  m.state.displaced.resize(L + 1);
  m.state.face_normals.resize(L + 1);
}

Status check_sizes(const MultiresMesh& m) {
  const int L = m.num_levels();
  if (static_cast<int>(m.displacements.size()) != L + 1 || static_cast<int>(m.links.size()) != L + 1)
    return Status::error(ErrorCode::InvalidInput, "multires: displacement or link arrays do not match the levels");
  for (int l = 0; l <= L; ++l)
    if (static_cast<int>(m.displacements[l].size()) != m.num_vertices(l))
      return Status::error(ErrorCode::InvalidInput, "multires: level " + std::to_string(l) + " has " +
                                                        std::to_string(m.displacements[l].size()) +
                                                        " displacements for " + std::to_string(m.num_vertices(l)) +
                                                        " vertices");
  return Status::success();
}

double mean_edge(const std::vector<Vec3>& P, const std::vector<Tri>& tris) {
  if (tris.empty()) return 0;
  double sum = 0;
  for (const Tri& t : tris)
    for (int k = 0; k < 3; ++k) sum += (P[t[k]] - P[t[(k + 1) % 3]]).norm();
  return sum / (3.0 * tris.size());
}

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

Status build_multires(const TriMesh& control, int levels, MultiresMesh& out) {
  out = MultiresMesh{};
  for (const Vec3& p : control.positions)
    if (!p.allFinite()) return Status::error(ErrorCode::InvalidInput, "multires: a control position is not finite");
  Status s = build_butterfly_levels(control, levels, out.levels);
  if (!s.ok()) {
    out = MultiresMesh{};
    return s;
  }
  out.control = control.positions;
  out.control_triangles = control.triangles;
  const int L = out.num_levels();
  out.displacements.resize(L + 1);
  out.links.resize(L + 1);
  for (int l = 0; l <= L; ++l) {
    out.displacements[l].assign(out.num_vertices(l), 0.0);
    out.links[l] = build_links(out.num_vertices(l), out.triangles(l), l < L ? &out.levels[l] : nullptr);
  }
  return evaluate(out);
}

Status evaluate(MultiresMesh& mesh) {
  Status s = check_sizes(mesh);
  if (!s.ok()) return s;
  resize_state(mesh);
  mesh.state.base[0] = mesh.control;
  for (int l = 0; l <= mesh.num_levels(); ++l) {
    evaluate_level(mesh, l);
    if (l < mesh.num_levels()) {
      s = apply(mesh.levels[l], mesh.state.displaced[l], mesh.state.base[l + 1]);
      if (!s.ok()) return s;
    }
  }
  return Status::success();
}

TriMesh level_mesh(const MultiresMesh& mesh, int level) {
  TriMesh m;
  if (level < 0 || level > mesh.num_levels() || static_cast<int>(mesh.state.displaced.size()) <= level) return m;
  m.positions = mesh.state.displaced[level];
  m.triangles = mesh.triangles(level);
  m.normals = vertex_normals(m);  // of the displaced surface, for shading
  return m;
}

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

namespace {

// Bad against the smooth triangle: turned over or collapsed. Arguments are
// unnormalised (2 x area) normals. A smooth triangle of zero area gives no
// reference and is never bad.
inline bool bad_triangle(const Vec3& displaced, const Vec3& smooth, const FoldLimitOptions& o) {
  const double ls = smooth.norm();
  if (ls == 0) return false;
  const double ld = displaced.norm();
  if (!(ld > o.min_area_ratio * ls)) return true;
  return displaced.dot(smooth) <= o.min_normal_cos * ld * ls;
}

}  // namespace

Status smooth_positions(const MultiresMesh& mesh, std::vector<std::vector<Vec3>>& out) {
  return apply_all(mesh.levels, mesh.control, out);
}

void count_bad_triangles(const MultiresMesh& mesh, int level, const std::vector<Vec3>& smooth,
                         const FoldLimitOptions& options, int& flipped, int& collapsed) {
  flipped = collapsed = 0;
  if (level < 0 || level > mesh.num_levels() || static_cast<int>(mesh.state.displaced.size()) <= level) return;
  const auto& tris = mesh.triangles(level);
  const auto& P = mesh.state.displaced[level];
  if (P.size() != smooth.size()) return;
  for (int f = 0; f < static_cast<int>(tris.size()); ++f) {
    const Vec3 nd = face_normal(tris, P, f), ns = face_normal(tris, smooth, f);
    const double ls = ns.norm(), ld = nd.norm();
    if (ls == 0) continue;
    if (!(ld > options.min_area_ratio * ls)) ++collapsed;
    if (nd.dot(ns) <= options.min_normal_cos * ld * ls) ++flipped;
  }
}

std::vector<std::vector<char>> propagate_vertex_mask(const MultiresMesh& mesh, const std::vector<char>& control_mask) {
  const int L = mesh.num_levels();
  std::vector<std::vector<char>> out(L + 1);
  out[0] = control_mask;
  out[0].resize(mesh.num_vertices(0), 0);
  for (int l = 0; l < L; ++l) {
    const ButterflyLevel& lv = mesh.levels[l];
    out[l + 1].assign(lv.num_fine_vertices, 0);
    std::copy(out[l].begin(), out[l].end(), out[l + 1].begin());
    for (int k = 0; k < lv.num_new_vertices(); ++k)
      out[l + 1][lv.num_coarse_vertices + k] = out[l][lv.edge_endpoints[k][0]] && out[l][lv.edge_endpoints[k][1]];
  }
  return out;
}

Status limit_folds(MultiresMesh& mesh, const FoldLimitOptions& options, FoldLimitStats* stats) {
  if (!(options.shrink >= 0 && options.shrink < 1) || options.min_area_ratio < 0 || options.max_shrinks < 0 ||
      options.max_rounds < 0 || options.max_intersection_rounds < 0 || options.max_intersection_restarts < 0 ||
      !(std::abs(options.min_normal_cos) <= 1))
    return Status::error(ErrorCode::InvalidInput,
                         "multires fold limit: shrink must be in [0, 1), the cosine in [-1, 1], ratios and counts >= 0");
  Status s = check_sizes(mesh);
  if (!s.ok()) return s;
  const int L = mesh.num_levels();
  std::vector<std::vector<Vec3>> smooth;
  s = smooth_positions(mesh, smooth);
  if (!s.ok()) return s;
  s = evaluate(mesh);
  if (!s.ok()) return s;
  MultiresState& state = mesh.state;

  FoldLimitStats st;
  st.bad_found.assign(L + 1, 0);
  st.shrunk.assign(L + 1, 0);
  st.zeroed.assign(L + 1, 0);
  std::vector<std::vector<Vec3>> smooth_normals(L + 1);
  std::vector<std::vector<std::uint8_t>> shrinks(L + 1);
  std::vector<std::vector<int>> shrunk_in_round(L + 1), face_checked(L + 1);
  std::vector<char> checked(L + 1, 0);
  for (int l = 0; l <= L; ++l) {
    const auto& tris = mesh.triangles(l);
    smooth_normals[l].resize(tris.size());
    for (int f = 0; f < static_cast<int>(tris.size()); ++f) smooth_normals[l][f] = face_normal(tris, smooth[l], f);
    shrinks[l].assign(mesh.num_vertices(l), 0);
    shrunk_in_round[l].assign(mesh.num_vertices(l), -1);
    face_checked[l].assign(tris.size(), -1);
  }
  auto is_bad = [&](int l, int f) {
    return bad_triangle(face_normal(mesh.triangles(l), state.displaced[l], f), smooth_normals[l][f], options);
  };
  // Scales d_k[v] once per round; true when v carries a displacement.
  auto shrink_one = [&](int k, int v, bool to_zero = false) {
    double& d = mesh.displacements[k][v];
    if (d == 0) return false;
    if (shrunk_in_round[k][v] == st.rounds) return true;
    shrunk_in_round[k][v] = st.rounds;
    if (shrinks[k][v]++ == 0) ++st.shrunk[k];
    if (to_zero || shrinks[k][v] >= options.max_shrinks) {
      d = 0;
      ++st.zeroed[k];
    } else {
      d *= options.shrink;
    }
    return true;
  };
  // A triangle's own corners on its level; the changed ones are re-displaced
  // at once (N_l does not depend on d_l, so nothing else on level l moves).
  std::vector<int> changed;
  auto shrink_corners = [&](int l, int f) {
    bool any = false;
    for (int v : mesh.triangles(l)[f])
      if (shrink_one(l, v)) {
        any = true;
        changed.push_back(v);
        state.displaced[l][v] = displace(state.base[l][v], mesh.displacements[l][v], state.normals[l][v]);
      }
    return any;
  };
  // Corners without displacement (pockets, holes): the coarser levels bent
  // the triangle. First their displacement is set to reach the smooth
  // surface along the normal (what the smooth levels would have there);
  // shrinking coarser levels (below) is the last resort.
  std::vector<std::vector<char>> corrected(L + 1);
  for (int k = 0; k <= L; ++k) corrected[k].assign(mesh.num_vertices(k), 0);
  auto correct_corners = [&](int l, int f) {
    bool any = false;
    for (int v : mesh.triangles(l)[f]) {
      if (corrected[l][v] || mesh.displacements[l][v] != 0) continue;
      corrected[l][v] = 1;
      const double d = (smooth[l][v] - state.base[l][v]).dot(state.normals[l][v]);
      if (d == 0) continue;
      mesh.displacements[l][v] = d;
      shrunk_in_round[l][v] = st.rounds;  // not shrunk again in this round
      ++st.corrected;
      any = true;
      changed.push_back(v);
      state.displaced[l][v] = displace(state.base[l][v], d, state.normals[l][v]);
    }
    return any;
  };
  // Corners without displacement: the coarser levels bent the triangle.
  // Shrinks the neighbourhood of its parent (the Butterfly stencils of the
  // parent's edges) on the first level above that has displacement there;
  // returns that level, or -1.
  auto shrink_above = [&](int l, int f) {
    for (int k = l, g = f; k > 0;) {
      g /= 4;  // child c of coarse triangle g is 4 g + c
      --k;
      // The parent's own corners first; their neighbourhood only when they
      // carry nothing (less detail lost for the same effect).
      // Zeroed at once: each step up costs a re-evaluation of the levels below.
      bool any = false;
      for (int c : mesh.triangles(k)[g]) any |= shrink_one(k, c, true);
      const MultiresLevelLinks& links = mesh.links[k];
      if (!any)
        for (int c : mesh.triangles(k)[g])
          for (int i = links.vertex_faces.offsets[c]; i < links.vertex_faces.offsets[c + 1]; ++i)
            for (int v : mesh.triangles(k)[links.vertex_faces.items[i]]) any |= shrink_one(k, v, true);
      if (any) return k;
    }
    return -1;
  };
  // Triangles of level l around the changed vertices, each once per round.
  auto around_changed = [&](int l, std::vector<int>& out) {
    out.clear();
    const IndexRows& vf = mesh.links[l].vertex_faces;
    for (int v : changed)
      for (int i = vf.offsets[v]; i < vf.offsets[v + 1]; ++i) {
        const int f = vf.items[i];
        if (face_checked[l][f] == st.rounds) continue;
        face_checked[l][f] = st.rounds;
        out.push_back(f);
      }
  };
  // 1. Folds, level by level (again after step 2 if that turned any over).
  std::vector<int> bad, stuck, around;
  auto fold_pass = [&](int round_limit) -> Status {
    int l = 0;
    while (l <= L) {
      evaluate_level(mesh, l);
      const int nf = static_cast<int>(mesh.triangles(l).size());
      bad.clear();
      for (int f = 0; f < nf; ++f)
        if (is_bad(l, f)) bad.push_back(f);
      if (!checked[l]) {
        checked[l] = 1;
        st.bad_found[l] = static_cast<int>(bad.size());
      }
      int restart = -1;
      while (!bad.empty() && st.rounds < round_limit) {
        ++st.rounds;
        changed.clear();
        stuck.clear();
        for (int f : bad)
          if (!shrink_corners(l, f) && !correct_corners(l, f)) stuck.push_back(f);
        if (!options.shrink_coarser_levels) stuck.clear();
        for (int f : stuck) {
          const int k = shrink_above(l, f);
          if (k >= 0) restart = restart < 0 ? k : std::min(restart, k);
        }
        if (restart >= 0) break;  // the coarser levels changed: evaluate again from there
        around_changed(l, around);
        bad.clear();
        for (int f : around)
          if (is_bad(l, f)) bad.push_back(f);
      }
      if (restart >= 0) {
        ++st.restarts;
        l = restart;  // levels above it are unchanged, so its base P is current
        continue;
      }
      if (l < L) {
        s = apply(mesh.levels[l], state.displaced[l], state.base[l + 1]);
        if (!s.ok()) return s;
      }
      ++l;
    }
    return Status::success();
  };
  s = fold_pass(options.max_rounds);
  if (!s.ok()) return s;

  // 2. Self-intersections of the finest level: the triangles of each
  // crossing pair are shrunk towards the smooth surface like bad ones.
  if (options.max_intersection_rounds > 0) {
    TriMesh finest;
    finest.positions = state.displaced[L];
    finest.triangles = mesh.triangles(L);
    MeshBvh bvh;
    s = build_bvh(finest, bvh);
    if (!s.ok()) return s;
    std::vector<std::array<int, 2>> pairs;
    find_self_intersections(bvh, pairs);
    st.intersections_found = static_cast<int>(pairs.size());
    std::vector<int> tris, next_bad;
    std::vector<char> in_set(finest.triangles.size(), 0);
    int rounds = 0, full_searches = 0;
    std::set<std::array<int, 2>> unfixable;
    while ((!pairs.empty() || !next_bad.empty()) && rounds < options.max_intersection_rounds) {
      ++rounds;
      ++st.rounds;
      // A pair that crosses on the smooth surface too is not the
      // displacements' doing: shrinking would only lose detail. Counted.
      {
        size_t kept = 0;
        for (const auto& p : pairs) {
          if (mesh_triangles_cross(smooth[L], mesh.triangles(L)[p[0]], mesh.triangles(L)[p[1]])) {
            unfixable.insert(p);
            continue;
          }
          pairs[kept++] = p;
        }
        pairs.resize(kept);
      }
      tris.clear();
      for (const auto& p : pairs)
        for (int f : p)
          if (!in_set[f]) in_set[f] = 1, tris.push_back(f);
      for (int f : next_bad)
        if (!in_set[f]) in_set[f] = 1, tris.push_back(f);
      for (int f : tris) in_set[f] = 0;
      changed.clear();
      for (int f : tris) shrink_corners(L, f);
      // A pair whose triangles carry no displacement on this level was
      // crossed by the coarser levels: their parents' displacements are
      // zeroed and everything is evaluated and searched again (a few times
      // at most: each costs a full search). What still crosses then is the
      // smooth Butterfly surface's own doing (a control mesh with sheets
      // ~0.3 mm apart crosses itself at eye and mouth corners): counted.
      int restart = -1;
      for (const auto& p : pairs) {
        bool movable = false;
        for (int f : p)
          for (int v : mesh.triangles(L)[f]) movable |= shrunk_in_round[L][v] == st.rounds;
        if (movable) continue;
        if (full_searches < options.max_intersection_restarts)
          for (int f : p) {
            const int k = shrink_above(L, f);
            if (k >= 0) restart = restart < 0 ? k : std::min(restart, k);
          }
        if (restart < 0) unfixable.insert(p);
      }
      if (restart >= 0) {
        ++st.restarts;
        ++full_searches;
        for (int k = restart; k <= L; ++k) {
          evaluate_level(mesh, k);
          if (k < L) {
            s = apply(mesh.levels[k], state.displaced[k], state.base[k + 1]);
            if (!s.ok()) return s;
          }
        }
        finest.positions = state.displaced[L];
        s = refit_bvh(finest, bvh);
        if (!s.ok()) return s;
        find_self_intersections(bvh, pairs);
        unfixable.clear();
        next_bad.clear();
        for (int f = 0; f < static_cast<int>(finest.triangles.size()); ++f)
          if (is_bad(L, f)) next_bad.push_back(f);
        continue;
      }
      for (int v : changed) finest.positions[v] = state.displaced[L][v];
      s = refit_bvh(finest, bvh);
      if (!s.ok()) return s;
      around_changed(L, around);
      find_intersections_with(bvh, around, pairs);
      next_bad.clear();
      for (int f : around)
        if (is_bad(L, f)) next_bad.push_back(f);
    }
    for (const auto& p : pairs) unfixable.insert(p);
    st.intersections_left = static_cast<int>(unfixable.size());
    // Shrinking towards the smooth surface can turn a triangle over
    // against its neighbours: one more fold pass.
    bool any_bad = false;
    for (int f = 0; f < static_cast<int>(mesh.triangles(L).size()) && !any_bad; ++f) any_bad = is_bad(L, f);
    if (any_bad) {
      std::fill(checked.begin(), checked.end(), 1);  // keep the first pass's counts
      s = fold_pass(st.rounds + options.max_rounds);
      if (!s.ok()) return s;
    }
  }
  for (int f = 0; f < static_cast<int>(mesh.triangles(L).size()); ++f) st.remaining_bad += is_bad(L, f);
  if (stats) *stats = st;
  return Status::success();
}

Status update_control_vertices(MultiresMesh& mesh, const std::vector<int>& moved,
                               const std::vector<Vec3>& new_positions, UpdateFootprint* footprint) {
  const int L = mesh.num_levels();
  if (moved.size() != new_positions.size())
    return Status::error(ErrorCode::InvalidInput, "multires update: " + std::to_string(moved.size()) +
                                                      " indices but " + std::to_string(new_positions.size()) +
                                                      " positions");
  for (size_t i = 0; i < moved.size(); ++i) {
    if (moved[i] < 0 || moved[i] >= static_cast<int>(mesh.control.size()))
      return Status::error(ErrorCode::InvalidInput, "multires update: control vertex " + std::to_string(moved[i]) +
                                                        " does not exist");
    if (!new_positions[i].allFinite())
      return Status::error(ErrorCode::InvalidInput, "multires update: position of control vertex " +
                                                        std::to_string(moved[i]) + " is not finite");
  }
  MultiresState& st = mesh.state;
  if (static_cast<int>(st.displaced.size()) != L + 1 || static_cast<int>(mesh.links.size()) != L + 1 ||
      static_cast<int>(st.displaced[L].size()) != mesh.num_vertices(L) ||
      st.face_normals.size() != st.displaced.size())
    return Status::error(ErrorCode::InvalidInput, "multires update: the mesh has not been built and evaluated");

  auto& sc = mesh.scratch;
  if (static_cast<int>(sc.base_mark.size()) != L + 1) {
    sc.base_mark.assign(L + 1, {});
    sc.displaced_mark.assign(L + 1, {});
    sc.face_mark.assign(L + 1, {});
    for (int l = 0; l <= L; ++l) {
      sc.base_mark[l].assign(mesh.num_vertices(l), 0);
      sc.displaced_mark[l].assign(mesh.num_vertices(l), 0);
      sc.face_mark[l].assign(mesh.triangles(l).size(), 0);
    }
    sc.stamp = 0;
  }
  if (++sc.stamp == 0) {  // wrapped: clear the marks once every 2^32 updates
    for (int l = 0; l <= L; ++l) {
      std::fill(sc.base_mark[l].begin(), sc.base_mark[l].end(), 0);
      std::fill(sc.displaced_mark[l].begin(), sc.displaced_mark[l].end(), 0);
      std::fill(sc.face_mark[l].begin(), sc.face_mark[l].end(), 0);
    }
    sc.stamp = 1;
  }
  const std::uint32_t stamp = sc.stamp;
  if (footprint) {
    footprint->base_changed.assign(L + 1, 0);
    footprint->displaced_changed.assign(L + 1, 0);
  }

  // changed: P_l differs; reached: N_l and P'_l recomputed; spread: P'_l
  // differs bit-wise, so the next level must look at its dependents. A value
  // that comes out bit-identical (e.g. P' = P + 0 * N where d = 0 and P did
  // not move) stops the spread without changing the result.
  std::vector<int> changed, reached, spread, targets;
  changed.reserve(moved.size());
  for (size_t i = 0; i < moved.size(); ++i) {
    const int v = moved[i];
    mesh.control[v] = new_positions[i];
    st.base[0][v] = new_positions[i];
    if (sc.base_mark[0][v] != stamp) {
      sc.base_mark[0][v] = stamp;
      changed.push_back(v);
    }
  }
  for (int l = 0; l <= L; ++l) {
    const MultiresLevelLinks& links = mesh.links[l];
    auto& mark = sc.displaced_mark[l];
    reached.clear();
    for (int u : changed)
      for (int i = links.normal_reach.offsets[u]; i < links.normal_reach.offsets[u + 1]; ++i) {
        const int v = links.normal_reach.items[i];
        if (mark[v] != stamp) {
          mark[v] = stamp;
          reached.push_back(v);
        }
      }
    // Triangles with a moved corner get new face normals first.
    const auto& tris = mesh.triangles(l);
    auto& face_mark = sc.face_mark[l];
    for (int u : changed)
      for (int i = links.vertex_faces.offsets[u]; i < links.vertex_faces.offsets[u + 1]; ++i) {
        const int f = links.vertex_faces.items[i];
        if (face_mark[f] != stamp) {
          face_mark[f] = stamp;
          st.face_normals[l][f] = face_normal(tris, st.base[l], f);
        }
      }
    // Ascending order turns scattered reads into mostly forward sweeps.
    std::sort(reached.begin(), reached.end());
    spread.clear();
    for (int v : reached) {
      st.normals[l][v] = vertex_normal(links.vertex_faces, st.face_normals[l], v);
      const Vec3 p = displace(st.base[l][v], mesh.displacements[l][v], st.normals[l][v]);
      if (!same_bits(p, st.displaced[l][v])) {
        st.displaced[l][v] = p;
        spread.push_back(v);
      }
    }
    if (footprint) {
      footprint->base_changed[l] = static_cast<int>(changed.size());
      footprint->displaced_changed[l] = static_cast<int>(reached.size());
    }
    if (l == L) break;

    const ButterflyLevel& next = mesh.levels[l];
    const int nc = next.num_coarse_vertices;
    auto& next_mark = sc.base_mark[l + 1];
    auto& fine = st.base[l + 1];
    targets.clear();
    for (int u : spread)
      for (int i = links.refine_reach.offsets[u]; i < links.refine_reach.offsets[u + 1]; ++i) {
        const int f = links.refine_reach.items[i];
        if (next_mark[f] != stamp) {
          next_mark[f] = stamp;
          targets.push_back(f);
        }
      }
    std::sort(targets.begin(), targets.end());
    changed.clear();
    for (int f : targets) {
      const Vec3 p = f < nc ? st.displaced[l][f] : butterfly_new_vertex(next, f - nc, st.displaced[l]);
      if (!same_bits(p, fine[f])) {
        fine[f] = p;
        changed.push_back(f);
      }
    }
  }
  return Status::success();
}

}  // namespace lk
