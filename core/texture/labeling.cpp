#include "texture/labeling.h"

#include "mesh/geometry.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <unordered_map>

// GCC 12 warns of a maybe-uninitialized boost::optional inside Boost.Graph's
// edge iterator (a known false positive of its headers).
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#include <boost/graph/adjacency_list.hpp>
#include <boost/graph/boykov_kolmogorov_max_flow.hpp>
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif

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

// Boost.Graph's graph for one expansion move's minimum cut (Boykov &
// Kolmogorov 2004): every arc has its reverse, as the algorithm needs.
using Traits = boost::adjacency_list_traits<boost::vecS, boost::vecS, boost::directedS>;
struct CutNode {
  boost::default_color_type color = boost::white_color;
  long distance = 0;
  Traits::edge_descriptor predecessor;
};
struct CutArc {
  double capacity = 0, residual = 0;
  Traits::edge_descriptor reverse;
};
using CutGraph = boost::adjacency_list<boost::vecS, boost::vecS, boost::directedS, CutNode, CutArc>;

void add_arc(CutGraph& g, int u, int v, double cap, double rev_cap = 0) {
  const auto uv = boost::add_edge(u, v, g).first;
  const auto vu = boost::add_edge(v, u, g).first;
  g[uv].capacity = cap;
  g[vu].capacity = rev_cap;
  g[uv].reverse = vu;
  g[vu].reverse = uv;
}

// Minimum cut: true for the nodes left on the source side (the source's
// tree, black, after the flow).
std::vector<char> source_side(CutGraph& g, int s, int t) {
  boost::boykov_kolmogorov_max_flow(g, boost::get(&CutArc::capacity, g), boost::get(&CutArc::residual, g),
                                    boost::get(&CutArc::reverse, g), boost::get(&CutNode::predecessor, g),
                                    boost::get(&CutNode::color, g), boost::get(&CutNode::distance, g),
                                    boost::get(boost::vertex_index, g), s, t);
  std::vector<char> out(boost::num_vertices(g));
  for (size_t v = 0; v < out.size(); ++v) out[v] = g[v].color == boost::black_color;
  return out;
}

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
  const std::vector<Edge> edges = triangle_edges(mesh);
  // The surface's direction at the scale of the face: the area-weighted
  // normals Gaussian-averaged (sigma = face_radius) around each triangle.
  // Cheaply: normals summed into cells of sigma / 2, the average taken at
  // the cells' corners over the cells within 3 sigma, and trilinearly
  // interpolated at each triangle's centroid.
  std::vector<Vec3> broad(nf, Vec3::Zero()), centroid(nf);
  for (int f = 0; f < nf; ++f) {
    const Tri& t = mesh.triangles[f];
    centroid[f] = (mesh.positions[t[0]] + mesh.positions[t[1]] + mesh.positions[t[2]]) / 3.0;
  }
  if (options.face_weight > 0 && options.face_radius > 0 && nf > 0) {
    const double sigma = options.face_radius, cell = std::max(0.5 * sigma, mean_edge_length(mesh));
    auto key = [](long x, long y, long z) {
      return (static_cast<std::uint64_t>(x + (1 << 20)) << 42) | (static_cast<std::uint64_t>(y + (1 << 20)) << 21) |
             static_cast<std::uint64_t>(z + (1 << 20));
    };
    struct Cell {
      Vec3 normal = Vec3::Zero(), at = Vec3::Zero();
      double area = 0;
    };
    std::unordered_map<std::uint64_t, Cell> cells;
    auto index = [&](const Vec3& p, int k) { return static_cast<long>(std::floor(p[k] / cell)); };
    for (int f = 0; f < nf; ++f) {
      const Vec3 n = face_normal_area(mesh, f);
      Cell& c = cells[key(index(centroid[f], 0), index(centroid[f], 1), index(centroid[f], 2))];
      c.normal += n;
      c.at += n.norm() * centroid[f];
      c.area += n.norm();
    }
    for (auto& kv : cells)
      if (kv.second.area > 0) kv.second.at /= kv.second.area;
    const long reach = static_cast<long>(std::ceil(3 * sigma / cell));
    std::unordered_map<std::uint64_t, Vec3> corner;
    auto corner_normal = [&](long x, long y, long z) -> const Vec3& {
      auto it = corner.find(key(x, y, z));
      if (it != corner.end()) return it->second;
      const Vec3 at(x * cell, y * cell, z * cell);
      Vec3 sum = Vec3::Zero();
      for (long i = x - reach; i <= x + reach; ++i)
        for (long j = y - reach; j <= y + reach; ++j)
          for (long k = z - reach; k <= z + reach; ++k) {
            auto c = cells.find(key(i, j, k));
            if (c == cells.end()) continue;
            sum += std::exp(-(c->second.at - at).squaredNorm() / (2 * sigma * sigma)) * c->second.normal;
          }
      return corner.emplace(key(x, y, z), sum).first->second;
    };
    for (int f = 0; f < nf; ++f) {
      const Vec3 q = centroid[f] / cell;
      const long x = static_cast<long>(std::floor(q.x())), y = static_cast<long>(std::floor(q.y())),
                 z = static_cast<long>(std::floor(q.z()));
      const double u = q.x() - x, v = q.y() - y, w = q.z() - z;
      Vec3 n = Vec3::Zero();
      for (int c = 0; c < 8; ++c)
        n += ((c & 1) ? u : 1 - u) * ((c & 2) ? v : 1 - v) * ((c & 4) ? w : 1 - w) *
             corner_normal(x + (c & 1), y + ((c >> 1) & 1), z + ((c >> 2) & 1));
      broad[f] = n.norm() > 0 ? Vec3(n.normalized()) : Vec3::Zero();
    }
  }
  std::vector<Vec3> centres(np);
  for (int i = 0; i < np; ++i) centres[i] = photos[i].camera.center();
  const double w = options.face_weight;
  auto data = [&](int f, int i) {
    const Tri& t = mesh.triangles[f];
    double s = 0;
    for (int k = 0; k < 3; ++k) s += binding.facing[static_cast<size_t>(t[k]) * np + i];
    double face = 0;
    if (w > 0) face = broad[f].dot((centres[i] - centroid[f]).normalized());
    return 1.0 - ((1 - w) * s / 3.0 + w * face);
  };

  const int ns = std::max(2, options.edge_samples);
  // Pair index of photos i < j, and per-edge caches over all pairs.
  const int pairs = np * (np - 1) / 2;
  auto pair_index = [&](int i, int j) { return i * np - i * (i + 1) / 2 + (j - i - 1); };
  // Disagreement of photos i < j on edge e alone: the mean absolute
  // difference (linear RGB) at ns points along it, -1 where not both valid.
  std::vector<float> local(edges.size() * pairs);
  std::vector<char> local_done(edges.size(), 0);
  std::vector<float> colors(static_cast<size_t>(np) * ns * 3);
  auto fill_local = [&](int e) {
    if (local_done[e]) return;
    local_done[e] = 1;
    const Edge& E = edges[e];
    const std::uint64_t both = binding.valid[E.a] & binding.valid[E.b];
    for (int i = 0; i < np; ++i) {
      if (!((both >> i) & 1u)) continue;
      float* c = &colors[static_cast<size_t>(i) * ns * 3];
      std::fill_n(c, ns * 3, 0.f);
      for (int k = 0; k < ns; ++k) {
        const double t = static_cast<double>(k) / (ns - 1);
        Vec2 px;
        if (photos[i].camera.project((1 - t) * mesh.positions[E.a] + t * mesh.positions[E.b], px))
          sample_bilinear(photos[i].image, px.x(), px.y(), c + k * 3);
      }
    }
    for (int i = 0; i < np; ++i)
      for (int j = i + 1; j < np; ++j) {
        float& out = local[static_cast<size_t>(e) * pairs + pair_index(i, j)];
        if (!((both >> i) & (both >> j) & 1u)) {
          out = -1.f;
          continue;
        }
        const float* ci = &colors[static_cast<size_t>(i) * ns * 3];
        const float* cj = &colors[static_cast<size_t>(j) * ns * 3];
        double d = 0;
        for (int k = 0; k < ns * 3; ++k) d += std::abs(ci[k] - cj[k]);
        out = static_cast<float>(d / (ns * 3));
      }
  };
  std::vector<std::vector<int>> vertex_edges(mesh.num_vertices());
  for (int e = 0; e < static_cast<int>(edges.size()); ++e) {
    vertex_edges[edges[e].a].push_back(e);
    vertex_edges[edges[e].b].push_back(e);
  }
  auto midpoint = [&](int e) { return Vec3(0.5 * (mesh.positions[edges[e].a] + mesh.positions[edges[e].b])); };
  // Seam cost: the largest disagreement over the edges whose midpoints lie
  // within seam_radius of the shared edge's (reached through shared
  // vertices), so a boundary keeps that far from any feature the two photos
  // show at different places (between two copies the photos agree on the
  // edge itself). A max of per-edge L1 differences still obeys the triangle
  // inequality. All pairs of an edge at once, on first use.
  std::vector<float> seam_cache(edges.size() * pairs, 0.f);
  std::vector<char> seam_done(edges.size(), 0);
  std::vector<int> stamp(edges.size(), -1), near;
  auto seam = [&](int e, int i, int j) {
    if (i == j) return 0.0;
    if (i > j) std::swap(i, j);
    float* c = &seam_cache[static_cast<size_t>(e) * pairs];
    if (!seam_done[e]) {
      seam_done[e] = 1;
      const Vec3 m = midpoint(e);
      near.assign(1, e);
      stamp[e] = e;
      for (size_t q = 0; q < near.size(); ++q)
        for (int v : {edges[near[q]].a, edges[near[q]].b})
          for (int e2 : vertex_edges[v])
            if (stamp[e2] != e && (midpoint(e2) - m).norm() <= options.seam_radius) {
              stamp[e2] = e;
              near.push_back(e2);
            }
      for (int e2 : near) {
        fill_local(e2);
        const float* l = &local[static_cast<size_t>(e2) * pairs];
        for (int k = 0; k < pairs; ++k) c[k] = std::max(c[k], l[k]);
      }
    }
    return options.smoothness * (options.seam_floor + c[pair_index(i, j)]);
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
  std::vector<int> node(nf, -1), tris;
  for (int f = 0; f < nf; ++f)
    if (cases[f] == TriangleCase::CommonPhoto) {
      node[f] = static_cast<int>(tris.size());
      tris.push_back(f);
    }
  const int n = static_cast<int>(tris.size());
  const double kBig = 1e9;  // alpha not valid for all three corners
  std::vector<std::vector<int>> around(options.icm ? nf : 0);  // ICM: each triangle's case-1 edges
  if (options.icm)
    for (int e = 0; e < static_cast<int>(edges.size()); ++e)
      if (edges[e].g >= 0 && node[edges[e].f] >= 0 && node[edges[e].g] >= 0) {
        around[edges[e].f].push_back(e);
        around[edges[e].g].push_back(e);
      }
  for (int cycle = 0; cycle < options.max_passes; ++cycle) {
    int changed = 0;
    if (options.icm) {
      // Iterated conditional modes (the baseline): each triangle in turn
      // takes the label that is cheapest given its neighbours' labels.
      for (int f : tris) {
        int best = region[f];
        double best_cost = std::numeric_limits<double>::infinity();
        for (int l = 0; l < np; ++l) {
          if (!((common(f) >> l) & 1u)) continue;
          double c = data(f, l);
          for (int e : around[f]) c += seam(e, l, region[edges[e].f == f ? edges[e].g : edges[e].f]);
          if (c < best_cost - 1e-12) {
            best_cost = c;
            best = l;
          }
        }
        changed += best != region[f];
        region[f] = best;
      }
    } else {
      // Alpha-expansion (Boykov, Veksler & Zabih 2001): for each photo
      // alpha, one minimum cut decides which triangles switch to alpha.
      for (int alpha = 0; alpha < np; ++alpha) {
        // Node x = 0 (source side): keep the label; x = 1 (sink side): alpha.
        std::vector<double> delta(n, 0.0);  // cost(x = 1) - cost(x = 0)
        CutGraph graph(n + 2);
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
          const double wfg = std::max(0.0, B + C - A);
          if (wfg > 0) add_arc(graph, node[ed.f], node[ed.g], wfg);
        }
        for (int k = 0; k < n; ++k) {
          if (region[tris[k]] == alpha) {
            add_arc(graph, S, k, kBig * 4);  // already alpha: x = 0 and x = 1 are the same label
          } else if (delta[k] > 0) {
            add_arc(graph, S, k, delta[k]);
          } else if (delta[k] < 0) {
            add_arc(graph, k, T, -delta[k]);
          }
        }
        const std::vector<char> keep = source_side(graph, S, T);
        for (int k = 0; k < n; ++k)
          if (!keep[k] && region[tris[k]] != alpha) {
            region[tris[k]] = alpha;
            ++changed;
          }
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
