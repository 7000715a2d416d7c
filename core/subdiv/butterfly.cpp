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

// Connectivity of one level as the stencils need it. Level 0 comes from
// MeshTopology (which also validates the input); finer levels are derived
// from the coarser one in O(#F) without hashing: every coarse edge e splits
// into fine edges 2e (at edges[e].v0) and 2e+1 (at v1), every coarse face f
// adds three inner edges 2 #E + 3 f + {0, 1, 2}.
struct LevelTopo {
  int num_vertices = 0;
  const std::vector<Tri>* triangles = nullptr;
  std::vector<Edge> edges;                      // v0 < v1; f1 = -1 on the boundary
  std::vector<std::array<int, 3>> face_edges;   // edge k joins corners k and k+1
  std::vector<int> valence;                     // #V
  std::vector<char> boundary;                   // #V
  std::vector<std::array<int, 2>> boundary_edges;  // #V: the two boundary edges at a boundary vertex
  std::vector<std::vector<int>> ring_edges;     // #V: ordered edges around interior extraordinary vertices
  // Creases (all empty/zero without them).
  std::vector<char> crease;                     // #E: tagged (never a boundary edge)
  std::vector<char> corner;                     // #V: curves do not continue through it
  std::vector<int> crease_count;                // #V: tagged edges at the vertex
  std::vector<std::array<int, 2>> crease_pair;  // #V: the two tagged edges where there are exactly two

  int other_end(int e, int v) const { return edges[e].v0 == v ? edges[e].v1 : edges[e].v0; }
  int opposite(int f, int e) const {
    const Tri& t = (*triangles)[f];
    for (int v : t)
      if (v != edges[e].v0 && v != edges[e].v1) return v;
    return -1;
  }
  // A crease vertex is not interior: the mesh is cut there.
  bool irregular_interior(int v) const { return !boundary[v] && crease_count[v] == 0 && valence[v] != 6; }
  bool cut(int e) const { return edges[e].boundary() || crease[e]; }
};

Status topo_from_mesh(const std::vector<Tri>& triangles, int num_vertices, const ButterflyCreases& creases,
                      LevelTopo& out) {
  TriMesh mesh;  // connectivity only; build_topology takes #V from positions
  mesh.positions.assign(num_vertices, Vec3::Zero());
  mesh.triangles = triangles;
  MeshTopology topo;
  Status s = build_topology(mesh, topo);
  if (!s.ok()) return s;
  out.crease.assign(topo.edges.size(), 0);
  out.corner.assign(num_vertices, 0);
  out.crease_count.assign(num_vertices, 0);
  out.crease_pair.assign(num_vertices, {-1, -1});
  auto in_range = [&](int v) { return v >= 0 && v < num_vertices; };
  for (const auto& ce : creases.edges) {
    const std::string name = "crease edge (" + std::to_string(ce[0]) + ", " + std::to_string(ce[1]) + ")";
    if (!in_range(ce[0]) || !in_range(ce[1]))
      return Status::error(ErrorCode::InvalidInput, name + ": vertex out of range [0, " +
                                                        std::to_string(num_vertices) + ")");
    const int e = ce[0] == ce[1] ? -1 : topo.find_edge(ce[0], ce[1]);
    if (e < 0) return Status::error(ErrorCode::InvalidInput, name + " is not an edge of the mesh");
    if (topo.edges[e].boundary() || out.crease[e]) continue;
    out.crease[e] = 1;
    for (int v : {ce[0], ce[1]}) {
      if (out.crease_count[v] < 2) out.crease_pair[v][out.crease_count[v]] = e;
      ++out.crease_count[v];
    }
  }
  for (int v = 0; v < num_vertices; ++v)
    if (out.crease_count[v] != 2) out.crease_pair[v] = {-1, -1};
  for (int v : creases.corners) {
    if (!in_range(v))
      return Status::error(ErrorCode::InvalidInput, "crease corner " + std::to_string(v) + " out of range [0, " +
                                                        std::to_string(num_vertices) + ")");
    out.corner[v] = 1;
  }
  out.num_vertices = num_vertices;
  out.triangles = &triangles;
  out.edges = std::move(topo.edges);
  out.face_edges = std::move(topo.face_edges);
  out.valence.resize(num_vertices);
  out.boundary.assign(topo.boundary_vertex.begin(), topo.boundary_vertex.end());
  out.boundary_edges.assign(num_vertices, {-1, -1});
  out.ring_edges.assign(num_vertices, {});
  for (int v = 0; v < num_vertices; ++v) {
    const auto& ring = topo.rings[v];
    out.valence[v] = static_cast<int>(ring.size());
    if (ring.empty()) continue;  // isolated vertex: in no stencil
    if (out.boundary[v]) {
      out.boundary_edges[v] = {topo.find_edge(v, ring.front()), topo.find_edge(v, ring.back())};
    } else if (ring.size() < 3) {
      return Status::error(ErrorCode::InvalidInput,
                           "vertex " + std::to_string(v) + " is interior with valence " +
                               std::to_string(ring.size()) + " (< 3): the mesh folds onto itself");
    } else if (ring.size() != 6) {
      for (int n : ring) out.ring_edges[v].push_back(topo.find_edge(v, n));
    }
  }
  return Status::success();
}

// The connectivity of the 1 -> 4 split of `coarse` (fine triangles as built
// by build_one_level).
void topo_refined(const LevelTopo& c, const std::vector<Tri>& fine_triangles, LevelTopo& f) {
  const int nc = c.num_vertices;
  const int ne = static_cast<int>(c.edges.size());
  const int nf = static_cast<int>(c.triangles->size());
  const auto& tris = *c.triangles;
  f.num_vertices = nc + ne;
  f.triangles = &fine_triangles;
  auto corner_child = [&](int face, int v) {
    const Tri& t = tris[face];
    return 4 * face + (t[0] == v ? 0 : t[1] == v ? 1 : 2);
  };
  auto half = [&](int e, int v) { return 2 * e + (c.edges[e].v0 == v ? 0 : 1); };

  f.edges.resize(2 * ne + 3 * nf);
  for (int e = 0; e < ne; ++e) {
    const Edge& ce = c.edges[e];
    for (int side = 0; side < 2; ++side) {
      const int v = side == 0 ? ce.v0 : ce.v1;
      Edge& fe = f.edges[2 * e + side];
      fe.v0 = v;  // coarse indices come before every edge vertex
      fe.v1 = nc + e;
      fe.f0 = corner_child(ce.f0, v);
      fe.f1 = ce.f1 >= 0 ? corner_child(ce.f1, v) : -1;
    }
  }
  f.face_edges.resize(4 * static_cast<size_t>(nf));
  for (int face = 0; face < nf; ++face) {
    const Tri& t = tris[face];
    const auto& ce = c.face_edges[face];
    const int m0 = nc + ce[0], m1 = nc + ce[1], m2 = nc + ce[2];
    const int i0 = 2 * ne + 3 * face, i1 = i0 + 1, i2 = i0 + 2;
    f.edges[i0] = Edge{std::min(m0, m1), std::max(m0, m1), 4 * face + 1, 4 * face + 3};
    f.edges[i1] = Edge{std::min(m1, m2), std::max(m1, m2), 4 * face + 2, 4 * face + 3};
    f.edges[i2] = Edge{std::min(m2, m0), std::max(m2, m0), 4 * face + 0, 4 * face + 3};
    f.face_edges[4 * face + 0] = {half(ce[0], t[0]), i2, half(ce[2], t[0])};
    f.face_edges[4 * face + 1] = {half(ce[1], t[1]), i0, half(ce[0], t[1])};
    f.face_edges[4 * face + 2] = {half(ce[2], t[2]), i1, half(ce[1], t[2])};
    f.face_edges[4 * face + 3] = {i0, i1, i2};
  }
  f.valence.resize(f.num_vertices);
  f.boundary.resize(f.num_vertices);
  f.boundary_edges.assign(f.num_vertices, {-1, -1});
  f.ring_edges.assign(f.num_vertices, {});
  f.crease.assign(f.edges.size(), 0);
  f.corner.assign(f.num_vertices, 0);
  f.crease_count.assign(f.num_vertices, 0);
  f.crease_pair.assign(f.num_vertices, {-1, -1});
  for (int v = 0; v < nc; ++v) {
    f.valence[v] = c.valence[v];
    f.boundary[v] = c.boundary[v];
    if (c.boundary[v]) f.boundary_edges[v] = {half(c.boundary_edges[v][0], v), half(c.boundary_edges[v][1], v)};
    for (int e : c.ring_edges[v]) f.ring_edges[v].push_back(half(e, v));
    f.corner[v] = c.corner[v];
    f.crease_count[v] = c.crease_count[v];
    if (c.crease_pair[v][0] >= 0) f.crease_pair[v] = {half(c.crease_pair[v][0], v), half(c.crease_pair[v][1], v)};
  }
  for (int e = 0; e < ne; ++e) {
    const bool b = c.edges[e].boundary();
    f.valence[nc + e] = b ? 4 : 6;
    f.boundary[nc + e] = b;
    if (b) f.boundary_edges[nc + e] = {2 * e, 2 * e + 1};
    if (c.crease[e]) {  // children of a tagged edge are tagged
      f.crease[2 * e] = f.crease[2 * e + 1] = 1;
      f.crease_count[nc + e] = 2;
      f.crease_pair[nc + e] = {2 * e, 2 * e + 1};
    }
  }
}

struct StencilBuilder {
  const LevelTopo& topo;
  std::vector<std::vector<double>> weight_table;  // by valence

  const std::vector<double>& weights_for(int K) {
    if (static_cast<int>(weight_table.size()) <= K) weight_table.resize(K + 1);
    if (weight_table[K].empty()) weight_table[K] = extraordinary_weights(K);
    return weight_table[K];
  }

  // The next vertex beyond v on the curve (boundary or crease) of edge
  // `along`, or -1 where the curve does not continue through v (a corner,
  // an open crease end, a crease junction).
  int curve_neighbour(int v, int along) const {
    if (topo.corner[v]) return -1;
    const auto& pair = topo.crease[along] ? topo.crease_pair[v] : topo.boundary_edges[v];
    if (pair[0] < 0) return -1;
    return topo.other_end(pair[0] == along ? pair[1] : pair[0], v);
  }

  // The 4-point rule's outer term at end v (the other end w): the next
  // curve vertex, or the reflection 2 v - w where there is none.
  void add_curve_outer(int v, int w, int along, std::vector<Term>& terms) const {
    const int next = curve_neighbour(v, along);
    if (next >= 0) {
      terms.push_back({next, -1.0 / 16});
    } else {
      terms.push_back({v, -2.0 / 16});
      terms.push_back({w, 1.0 / 16});
    }
  }

  // Wing across edge x-apex, seen from triangle `face` = (x, y, apex); when
  // that edge is on the boundary the wing is the reflection x + apex - y.
  void add_wing(int x, int y, int apex, int face, double w, std::vector<Term>& terms) const {
    int e = -1;
    for (int k = 0; k < 3; ++k) {
      const Edge& cand = topo.edges[topo.face_edges[face][k]];
      if ((cand.v0 == x && cand.v1 == apex) || (cand.v0 == apex && cand.v1 == x)) e = topo.face_edges[face][k];
    }
    const Edge& edge = topo.edges[e];
    if (topo.cut(e)) {
      terms.push_back({x, w});
      terms.push_back({apex, w});
      terms.push_back({y, -w});
      return;
    }
    terms.push_back({topo.opposite(edge.f0 == face ? edge.f1 : edge.f0, e), w});
  }

  void add_extraordinary(int center, int other_end, double scale, std::vector<Term>& terms) {
    const auto& ring = topo.ring_edges[center];
    const int K = static_cast<int>(ring.size());
    const auto& s = weights_for(K);
    int j0 = 0;
    while (topo.other_end(ring[j0], center) != other_end) ++j0;
    // The weights are symmetric (s_j = s_{K-j}), so the ring's direction does not matter.
    for (int j = 0; j < K; ++j) terms.push_back({topo.other_end(ring[(j0 + j) % K], center), scale * s[j]});
    terms.push_back({center, scale * s[K]});
  }

  void edge_stencil(int e, std::vector<Term>& terms) {
    terms.clear();
    const Edge& edge = topo.edges[e];
    const int a = edge.v0, b = edge.v1;
    if (topo.cut(e)) {  // boundary or crease: the 4-point rule along the curve
      terms.push_back({a, 9.0 / 16});
      terms.push_back({b, 9.0 / 16});
      add_curve_outer(a, b, e, terms);
      add_curve_outer(b, a, e, terms);
      return;
    }
    const bool irr_a = topo.irregular_interior(a), irr_b = topo.irregular_interior(b);
    if (irr_a || irr_b) {
      const double scale = (irr_a && irr_b) ? 0.5 : 1.0;
      if (irr_a) add_extraordinary(a, b, scale, terms);
      if (irr_b) add_extraordinary(b, a, scale, terms);
      return;
    }
    const int c = topo.opposite(edge.f0, e);
    const int d = topo.opposite(edge.f1, e);
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

void build_one_level(const LevelTopo& topo, ButterflyLevel& level) {
  const int nc = topo.num_vertices;
  const int ne = static_cast<int>(topo.edges.size());
  const std::vector<Tri>& triangles = *topo.triangles;
  level.num_coarse_vertices = nc;
  level.num_fine_vertices = nc + ne;
  level.edge_endpoints.resize(ne);
  level.stencil_offsets.resize(ne + 1);
  level.stencil_offsets[0] = 0;
  level.stencil_indices.clear();
  level.stencil_weights.clear();
  level.stencil_indices.reserve(static_cast<size_t>(ne) * 8);
  level.stencil_weights.reserve(static_cast<size_t>(ne) * 8);
  level.crease_edges = topo.crease;

  StencilBuilder builder{topo, {}};
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
  // keep the parent's counter-clockwise orientation (topo_refined relies on
  // this numbering).
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
}

}  // namespace

void add_crease_polyline(const std::vector<int>& vertices, bool closed, ButterflyCreases& creases) {
  const size_t n = vertices.size();
  if (n < 2) return;
  for (size_t k = 0; k + 1 < n; ++k) creases.edges.push_back({vertices[k], vertices[k + 1]});
  if (closed && n > 2) {
    creases.edges.push_back({vertices[n - 1], vertices[0]});
  } else {
    creases.corners.push_back(vertices.front());
    creases.corners.push_back(vertices.back());
  }
}

void close_crease_ends(ButterflyCreases& creases) {
  std::vector<std::array<int, 2>> ends;  // (vertex, tagged edges)
  for (const auto& e : creases.edges)
    if (e[0] != e[1]) ends.push_back({e[0], 1}), ends.push_back({e[1], 1});
  std::sort(ends.begin(), ends.end());
  for (size_t i = 0; i < ends.size();) {
    size_t j = i;
    while (j < ends.size() && ends[j][0] == ends[i][0]) ++j;
    if (j - i != 2) creases.corners.push_back(ends[i][0]);
    i = j;
  }
  std::sort(creases.corners.begin(), creases.corners.end());
  creases.corners.erase(std::unique(creases.corners.begin(), creases.corners.end()), creases.corners.end());
}

Status build_butterfly_levels(const TriMesh& control, int levels, std::vector<ButterflyLevel>& out,
                              int max_fine_triangles) {
  return build_butterfly_levels(control, ButterflyCreases{}, levels, out, max_fine_triangles);
}

Status build_butterfly_levels(const TriMesh& control, const ButterflyCreases& creases, int levels,
                              std::vector<ButterflyLevel>& out, int max_fine_triangles) {
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
  if (levels == 0) return Status::success();
  out[0].coarse_triangles = control.triangles;
  LevelTopo topo, next;
  Status s = topo_from_mesh(out[0].coarse_triangles, control.num_vertices(), creases, topo);
  if (!s.ok()) {
    out.clear();
    return with_context(s, "butterfly level 0");
  }
  for (int l = 0; l < levels; ++l) {
    build_one_level(topo, out[l]);
    if (l + 1 < levels) {
      out[l + 1].coarse_triangles = out[l].fine_triangles;
      topo_refined(topo, out[l + 1].coarse_triangles, next);
      std::swap(topo, next);
    }
  }
  return Status::success();
}

}  // namespace lk
