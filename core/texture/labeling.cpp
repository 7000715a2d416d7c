#include "texture/labeling.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <unordered_map>

namespace lk {
namespace {

struct Edge {
  int a, b;  // vertices
  int f, g;  // the two triangles (g = -1 on a border)
};

std::vector<Edge> triangle_edges(const TriMesh& mesh) {
  std::unordered_map<std::uint64_t, int> index;
  std::vector<Edge> edges;
  for (int f = 0; f < mesh.num_triangles(); ++f)
    for (int k = 0; k < 3; ++k) {
      int a = mesh.triangles[f][k], b = mesh.triangles[f][(k + 1) % 3];
      if (a > b) std::swap(a, b);
      const std::uint64_t key = (static_cast<std::uint64_t>(a) << 32) | static_cast<std::uint32_t>(b);
      auto it = index.find(key);
      if (it == index.end()) {
        index.emplace(key, static_cast<int>(edges.size()));
        edges.push_back({a, b, f, -1});
      } else if (edges[it->second].g < 0) {
        edges[it->second].g = f;
      }
    }
  return edges;
}

// Dinic's maximum flow; after max_flow, on_source_side(v) tells the minimum cut.
class MaxFlow {
 public:
  explicit MaxFlow(int n) : head_(n, -1), level_(n), it_(n) {}
  void add_edge(int u, int v, double cap, double rev_cap = 0) {
    arcs_.push_back({v, head_[u], cap});
    head_[u] = static_cast<int>(arcs_.size()) - 1;
    arcs_.push_back({u, head_[v], rev_cap});
    head_[v] = static_cast<int>(arcs_.size()) - 1;
  }
  double max_flow(int s, int t) {
    double flow = 0;
    while (bfs(s, t)) {
      it_ = head_;
      while (true) {
        const double f = push(s, t);
        if (f <= 0) break;
        flow += f;
      }
    }
    return flow;
  }
  bool on_source_side(int v) const { return level_[v] >= 0; }

 private:
  struct Arc {
    int to, next;
    double cap;
  };
  bool bfs(int s, int t) {
    std::fill(level_.begin(), level_.end(), -1);
    std::vector<int> queue{s};
    level_[s] = 0;
    for (size_t q = 0; q < queue.size(); ++q)
      for (int a = head_[queue[q]]; a >= 0; a = arcs_[a].next)
        if (arcs_[a].cap > kEps && level_[arcs_[a].to] < 0) {
          level_[arcs_[a].to] = level_[queue[q]] + 1;
          queue.push_back(arcs_[a].to);
        }
    return level_[t] >= 0;
  }
  // One augmenting path in the level graph (iterative, no deep recursion).
  double push(int s, int t) {
    std::vector<int> path;  // arcs
    int u = s;
    while (true) {
      if (u == t) {
        double f = std::numeric_limits<double>::infinity();
        for (int a : path) f = std::min(f, arcs_[a].cap);
        for (int a : path) {
          arcs_[a].cap -= f;
          arcs_[a ^ 1].cap += f;
        }
        return f;
      }
      int& a = it_[u];
      while (a >= 0 && !(arcs_[a].cap > kEps && level_[arcs_[a].to] == level_[u] + 1)) a = arcs_[a].next;
      if (a >= 0) {
        path.push_back(a);
        u = arcs_[a].to;
      } else {  // dead end: retreat
        if (path.empty()) return 0;
        level_[u] = -2;  // not reachable in this phase any more (still "source side" is recomputed by bfs)
        u = arcs_[path.back() ^ 1].to;
        path.pop_back();
        it_[u] = arcs_[it_[u]].next;
      }
    }
  }
  static constexpr double kEps = 1e-12;
  std::vector<Arc> arcs_;
  std::vector<int> head_, level_, it_;
};

}  // namespace

Status label_regions(const TriMesh& mesh, const VertexBinding& binding, const std::vector<TexturePhoto>& photos,
                     const std::vector<TriangleCase>& cases, const LabelingOptions& options,
                     std::vector<int>& region, LabelingReport& report) {
  const int nf = mesh.num_triangles(), np = binding.num_photos;
  if (static_cast<int>(cases.size()) != nf || static_cast<int>(region.size()) != nf ||
      static_cast<int>(photos.size()) != np || static_cast<int>(binding.valid.size()) != mesh.num_vertices())
    return Status::error(ErrorCode::InvalidInput, "label_regions: inconsistent sizes");
  report = LabelingReport();

  auto common = [&](int f) {
    const Tri& t = mesh.triangles[f];
    return binding.valid[t[0]] & binding.valid[t[1]] & binding.valid[t[2]];
  };
  auto data = [&](int f, int i) {
    const Tri& t = mesh.triangles[f];
    double s = 0;
    for (int k = 0; k < 3; ++k) s += binding.facing[static_cast<size_t>(t[k]) * np + i];
    return 1.0 - s / 3.0;
  };

  const std::vector<Edge> edges = triangle_edges(mesh);
  const int ns = std::max(2, options.edge_samples);
  // Photo i's colours at ns points along edge e, cached.
  std::vector<std::vector<std::vector<float>>> samples(edges.size());
  auto edge_colors = [&](int e, int i) -> const std::vector<float>& {
    auto& per = samples[e];
    if (per.empty()) per.resize(np);
    std::vector<float>& c = per[i];
    if (c.empty()) {
      c.assign(static_cast<size_t>(ns) * 3, 0.f);
      const Vec3& A = mesh.positions[edges[e].a];
      const Vec3& B = mesh.positions[edges[e].b];
      for (int s = 0; s < ns; ++s) {
        const double t = static_cast<double>(s) / (ns - 1);
        Vec2 px;
        if (photos[i].camera.project((1 - t) * A + t * B, px)) sample_bilinear(photos[i].image, px.x(), px.y(), &c[s * 3]);
      }
    }
    return c;
  };
  // Disagreement of photos i and j on edge e alone (-1: not both valid there).
  auto local = [&](int e, int i, int j) {
    const Edge& E = edges[e];
    if (!binding.is_valid(E.a, i) || !binding.is_valid(E.b, i) || !binding.is_valid(E.a, j) || !binding.is_valid(E.b, j))
      return -1.0;
    const std::vector<float>& ci = edge_colors(e, i);
    const std::vector<float>& cj = edge_colors(e, j);
    double d = 0;
    for (size_t k = 0; k < ci.size(); ++k) d += std::abs(ci[k] - cj[k]);
    return d / ci.size();
  };
  // Edges whose midpoints lie within seam_radius of edge e's (through edges
  // sharing vertices), computed once per edge that can be a boundary.
  std::vector<std::vector<int>> vertex_edges(mesh.num_vertices());
  for (int e = 0; e < static_cast<int>(edges.size()); ++e) {
    vertex_edges[edges[e].a].push_back(e);
    vertex_edges[edges[e].b].push_back(e);
  }
  auto midpoint = [&](int e) { return Vec3(0.5 * (mesh.positions[edges[e].a] + mesh.positions[edges[e].b])); };
  std::vector<std::vector<int>> near(edges.size());
  auto neighbourhood = [&](int e) -> const std::vector<int>& {
    std::vector<int>& out = near[e];
    if (!out.empty()) return out;
    const Vec3 m = midpoint(e);
    out.push_back(e);
    for (size_t q = 0; q < out.size(); ++q)
      for (int v : {edges[out[q]].a, edges[out[q]].b})
        for (int e2 : vertex_edges[v])
          if (std::find(out.begin(), out.end(), e2) == out.end() && (midpoint(e2) - m).norm() <= options.seam_radius)
            out.push_back(e2);
    return out;
  };
  // Seam cost: the largest disagreement within seam_radius, so a boundary
  // keeps that far from any feature the two photos show at different
  // places (between two copies the photos agree on the edge itself).
  // A max of per-edge L1 differences still obeys the triangle inequality.
  std::vector<float> seam_cache(edges.size() * np * np, -1.f);
  auto seam = [&](int e, int i, int j) {
    if (i == j) return 0.0;
    if (i > j) std::swap(i, j);
    float& c = seam_cache[(static_cast<size_t>(e) * np + i) * np + j];
    if (c < 0) {
      double d = 0;
      for (int e2 : neighbourhood(e)) d = std::max(d, local(e2, i, j));
      c = static_cast<float>(d);
    }
    return options.smoothness * (options.seam_floor + c);
  };
  auto energy = [&](int& boundary) {
    double E = 0;
    boundary = 0;
    for (int f = 0; f < nf; ++f)
      if (cases[f] == TriangleCase::CommonPhoto) E += data(f, region[f]);
    for (int e = 0; e < static_cast<int>(edges.size()); ++e) {
      const Edge& ed = edges[e];
      if (ed.g < 0 || cases[ed.f] != TriangleCase::CommonPhoto || cases[ed.g] != TriangleCase::CommonPhoto) continue;
      if (region[ed.f] != region[ed.g]) {
        ++boundary;
        E += seam(e, region[ed.f], region[ed.g]);
      }
    }
    return E;
  };

  report.energy_before = energy(report.boundary_edges_before);
  const std::vector<int> initial = region;
  // Alpha-expansion (Boykov, Veksler & Zabih 2001): for each photo alpha,
  // one minimum cut decides which triangles switch to alpha. The seam cost
  // is a metric (a mean absolute difference over fixed samples plus a
  // constant), so each move is exact and the energy never rises.
  std::vector<int> node(nf, -1), tris;
  for (int f = 0; f < nf; ++f)
    if (cases[f] == TriangleCase::CommonPhoto) {
      node[f] = static_cast<int>(tris.size());
      tris.push_back(f);
    }
  const int n = static_cast<int>(tris.size());
  const double kBig = 1e9;  // alpha not valid for all three corners
  for (int cycle = 0; cycle < options.max_passes; ++cycle) {
    int changed = 0;
    for (int alpha = 0; alpha < np; ++alpha) {
      // Node x = 0 (source side): keep the label; x = 1 (sink side): alpha.
      std::vector<double> delta(n, 0.0);  // cost(x = 1) - cost(x = 0)
      MaxFlow graph(n + 2);
      const int S = n, T = n + 1;
      for (int k = 0; k < n; ++k) {
        const int f = tris[k];
        const double keep = data(f, region[f]);
        const double take = ((common(f) >> alpha) & 1u) ? data(f, alpha) : kBig;
        delta[k] += region[f] == alpha ? 0.0 : take - keep;
      }
      for (int e = 0; e < static_cast<int>(edges.size()); ++e) {
        const Edge& ed = edges[e];
        if (ed.g < 0 || node[ed.f] < 0 || node[ed.g] < 0) continue;
        const int a = region[ed.f], b = region[ed.g];
        const double A = seam(e, a, b), B = seam(e, a, alpha), C = seam(e, alpha, b);
        // E(x_f, x_g) = A + (C - A) x_f + (0 - C) x_g + (B + C - A)(1 - x_f) x_g
        delta[node[ed.f]] += C - A;
        delta[node[ed.g]] += -C;
        const double w = std::max(0.0, B + C - A);
        if (w > 0) graph.add_edge(node[ed.f], node[ed.g], w);
      }
      for (int k = 0; k < n; ++k) {
        if (region[tris[k]] == alpha) {
          graph.add_edge(S, k, kBig * 4);  // already alpha: x = 0 and x = 1 are the same label
        } else if (delta[k] > 0) {
          graph.add_edge(S, k, delta[k]);
        } else if (delta[k] < 0) {
          graph.add_edge(k, T, -delta[k]);
        }
      }
      graph.max_flow(S, T);
      for (int k = 0; k < n; ++k)
        if (!graph.on_source_side(k) && region[tris[k]] != alpha) {
          region[tris[k]] = alpha;
          ++changed;
        }
    }
    report.passes = cycle + 1;
    if (changed == 0) break;
  }
  report.energy_after = energy(report.boundary_edges_after);
  for (int f = 0; f < nf; ++f) report.triangles_changed += region[f] != initial[f];
  return Status::success();
}

}  // namespace lk
