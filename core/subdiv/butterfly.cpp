#include "subdiv/butterfly.h"

#include "mesh/topology.h"

#include <cmath>
#include <utility>

namespace lk {
namespace {

using Term = std::pair<int, double>;  // (coarse vertex, weight)

// Extraordinary-vertex weights s_0..s_{K-1} and the centre weight (last).
// The centre takes 1 - sum(s) so that every stencil is affine to rounding.
std::vector<double> extraordinary_weights(int K) {
  std::vector<double> s(K + 1, 0.0);
  if (K == 3) {
    s = {5.0 / 12, -1.0 / 12, -1.0 / 12, 0.0};
  } else if (K == 4) {
    s = {3.0 / 8, 0.0, -1.0 / 8, 0.0, 0.0};
  } else {
    const double pi = std::acos(-1.0);
    for (int j = 0; j < K; ++j)
      s[j] = (0.25 + std::cos(2 * pi * j / K) + 0.5 * std::cos(4 * pi * j / K)) / K;
  }
  double sum = 0;
  for (int j = 0; j < K; ++j) sum += s[j];
  s[K] = 1.0 - sum;
  return s;
}

struct StencilBuilder {
  const TriMesh& mesh;
  const MeshTopology& topo;
  std::vector<std::vector<double>> weight_table;  // by valence

  const std::vector<double>& weights_for(int K) {
    if (static_cast<int>(weight_table.size()) <= K) weight_table.resize(K + 1);
    if (weight_table[K].empty()) weight_table[K] = extraordinary_weights(K);
    return weight_table[K];
  }

  bool irregular_interior(int v) const { return !topo.is_boundary(v) && topo.valence(v) != 6; }

  // The other boundary neighbour of boundary vertex v (not `not_this`).
  int boundary_neighbour(int v, int not_this) const {
    const auto& r = topo.rings[v];
    return r.front() == not_this ? r.back() : r.front();
  }

  // Wing across edge x-apex, seen from triangle `face` = (x, y, apex); when
  // that edge is on the boundary the wing is the reflection x + apex - y.
  void add_wing(int x, int y, int apex, int face, double w, std::vector<Term>& terms) const {
    const int e = topo.find_edge(x, apex);
    const Edge& edge = topo.edges[e];
    if (edge.boundary()) {
      terms.push_back({x, w});
      terms.push_back({apex, w});
      terms.push_back({y, -w});
      return;
    }
    const int other = edge.f0 == face ? edge.f1 : edge.f0;
    terms.push_back({topo.opposite_vertex(mesh, other, e), w});
  }

  void add_extraordinary(int center, int other_end, double scale, std::vector<Term>& terms) {
    const auto& ring = topo.rings[center];
    const int K = static_cast<int>(ring.size());
    const auto& s = weights_for(K);
    int j0 = 0;
    while (ring[j0] != other_end) ++j0;
    // The weights are symmetric (s_j = s_{K-j}), so the ring's direction does not matter.
    for (int j = 0; j < K; ++j) terms.push_back({ring[(j0 + j) % K], scale * s[j]});
    terms.push_back({center, scale * s[K]});
  }

  void edge_stencil(int e, std::vector<Term>& terms) {
    terms.clear();
    const Edge& edge = topo.edges[e];
    const int a = edge.v0, b = edge.v1;
    if (edge.boundary()) {
      terms.push_back({a, 9.0 / 16});
      terms.push_back({b, 9.0 / 16});
      terms.push_back({boundary_neighbour(a, b), -1.0 / 16});
      terms.push_back({boundary_neighbour(b, a), -1.0 / 16});
      return;
    }
    const bool irr_a = irregular_interior(a), irr_b = irregular_interior(b);
    if (irr_a || irr_b) {
      const double scale = (irr_a && irr_b) ? 0.5 : 1.0;
      if (irr_a) add_extraordinary(a, b, scale, terms);
      if (irr_b) add_extraordinary(b, a, scale, terms);
      return;
    }
    const int c = topo.opposite_vertex(mesh, edge.f0, e);
    const int d = topo.opposite_vertex(mesh, edge.f1, e);
    terms.push_back({a, 0.5});
    terms.push_back({b, 0.5});
    terms.push_back({c, 0.125});
    terms.push_back({d, 0.125});
    add_wing(a, b, c, edge.f0, -1.0 / 16, terms);
    add_wing(b, a, c, edge.f0, -1.0 / 16, terms);
    add_wing(a, b, d, edge.f1, -1.0 / 16, terms);
    add_wing(b, a, d, edge.f1, -1.0 / 16, terms);
  }
};

// Sorts by vertex, merges repeated vertices (reflected wings, tiny meshes
// where wings coincide) and drops exact zeros (K = 4).
void compact(std::vector<Term>& terms) {
  std::sort(terms.begin(), terms.end(), [](const Term& x, const Term& y) { return x.first < y.first; });
  size_t out = 0;
  for (size_t i = 0; i < terms.size();) {
    Term t = terms[i++];
    while (i < terms.size() && terms[i].first == t.first) t.second += terms[i++].second;
    if (t.second != 0.0) terms[out++] = t;
  }
  terms.resize(out);
}

Status build_one_level(const std::vector<Tri>& triangles, int num_vertices, ButterflyLevel& level) {
  TriMesh mesh;  // connectivity only; build_topology takes #V from positions
  mesh.positions.assign(num_vertices, Vec3::Zero());
  mesh.triangles = triangles;
  MeshTopology topo;
  Status s = build_topology(mesh, topo);
  if (!s.ok()) return s;
  for (int v = 0; v < num_vertices; ++v)
    if (!topo.rings[v].empty() && !topo.is_boundary(v) && topo.valence(v) < 3)
      return Status::error(ErrorCode::InvalidInput,
                           "vertex " + std::to_string(v) + " is interior with valence " +
                               std::to_string(topo.valence(v)) + " (< 3): the mesh folds onto itself");

  const int nc = num_vertices;
  const int ne = static_cast<int>(topo.edges.size());
  level = ButterflyLevel{};
  level.num_coarse_vertices = nc;
  level.num_fine_vertices = nc + ne;
  level.coarse_triangles = triangles;
  level.edge_endpoints.resize(ne);
  level.stencil_offsets.resize(ne + 1);
  level.stencil_offsets[0] = 0;
  level.stencil_indices.reserve(static_cast<size_t>(ne) * 8);
  level.stencil_weights.reserve(static_cast<size_t>(ne) * 8);

  StencilBuilder builder{mesh, topo, {}};
  std::vector<Term> terms;
  for (int e = 0; e < ne; ++e) {
    level.edge_endpoints[e] = {topo.edges[e].v0, topo.edges[e].v1};
    builder.edge_stencil(e, terms);
    compact(terms);
    for (const Term& t : terms) {
      level.stencil_indices.push_back(t.first);
      level.stencil_weights.push_back(t.second);
    }
    level.stencil_offsets[e + 1] = static_cast<int>(level.stencil_indices.size());
  }

  // 1 -> 4 split; face_edges[f][k] joins corners k and k+1, so the children
  // keep the parent's counter-clockwise orientation.
  level.fine_triangles.resize(4 * triangles.size());
  for (size_t f = 0; f < triangles.size(); ++f) {
    const Tri& t = triangles[f];
    const auto& fe = topo.face_edges[f];
    const int m01 = nc + fe[0], m12 = nc + fe[1], m20 = nc + fe[2];
    level.fine_triangles[4 * f + 0] = {t[0], m01, m20};
    level.fine_triangles[4 * f + 1] = {t[1], m12, m01};
    level.fine_triangles[4 * f + 2] = {t[2], m20, m12};
    level.fine_triangles[4 * f + 3] = {m01, m12, m20};
  }
  return Status::success();
}

}  // namespace

Status build_butterfly_levels(const TriMesh& control, int levels, std::vector<ButterflyLevel>& out,
                              int max_fine_triangles) {
  out.clear();
  if (levels < 0) return Status::error(ErrorCode::InvalidInput, "butterfly: negative number of levels");
  if (control.triangles.empty()) return Status::error(ErrorCode::Empty, "butterfly: the control mesh has no triangles");
  double fine = static_cast<double>(control.triangles.size());
  for (int l = 0; l < levels; ++l) fine *= 4;
  if (fine > max_fine_triangles)
    return Status::error(ErrorCode::TooLarge, "butterfly: " + std::to_string(levels) + " levels of " +
                                                  std::to_string(control.triangles.size()) +
                                                  " triangles exceed the limit of " +
                                                  std::to_string(max_fine_triangles) + " fine triangles");
  out.resize(levels);
  for (int l = 0; l < levels; ++l) {
    const std::vector<Tri>& tris = l == 0 ? control.triangles : out[l - 1].fine_triangles;
    const int nv = l == 0 ? control.num_vertices() : out[l - 1].num_fine_vertices;
    Status s = build_one_level(tris, nv, out[l]);
    if (!s.ok()) {
      out.clear();
      return with_context(s, "butterfly level " + std::to_string(l));
    }
  }
  return Status::success();
}

}  // namespace lk
