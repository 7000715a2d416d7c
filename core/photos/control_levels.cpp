#include "photos/control_levels.h"

#include "photos/shape_fit.h"

#include <algorithm>
#include <limits>
#include <map>
#include <queue>
#include <set>

namespace lk {

namespace {

struct Neighbour {
  int v;
  double length;
};

std::vector<std::vector<Neighbour>> edge_graph(const TriMesh& mesh) {
  std::vector<std::set<int>> nbr(size_t(mesh.num_vertices()));
  for (const Tri& t : mesh.triangles)
    for (size_t k = 0; k < 3; ++k) {
      nbr[size_t(t[k])].insert(t[(k + 1) % 3]);
      nbr[size_t(t[(k + 1) % 3])].insert(t[k]);
    }
  std::vector<std::vector<Neighbour>> g(nbr.size());
  for (size_t i = 0; i < nbr.size(); ++i)
    for (int j : nbr[i]) g[i].push_back({j, (mesh.positions[i] - mesh.positions[size_t(j)]).norm()});
  return g;
}

// Lowers dist (and sets owner) over the graph from one new source.
void dijkstra_from(const std::vector<std::vector<Neighbour>>& g, int source, int owner_id, std::vector<double>& dist,
                   std::vector<int>& owner) {
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> q;
  dist[size_t(source)] = 0;
  owner[size_t(source)] = owner_id;
  q.push({0.0, source});
  while (!q.empty()) {
    const auto [d, v] = q.top();
    q.pop();
    if (d > dist[size_t(v)]) continue;
    for (const Neighbour& n : g[size_t(v)]) {
      const double nd = d + n.length;
      if (nd < dist[size_t(n.v)]) {
        dist[size_t(n.v)] = nd;
        owner[size_t(n.v)] = owner_id;
        q.push({nd, n.v});
      }
    }
  }
}

// Barycentric coordinates of p projected into the plane of (a, b, c).
Vec3 plane_barycentric(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 e0 = b - a, e1 = c - a, d = p - a;
  const double d00 = e0.dot(e0), d01 = e0.dot(e1), d11 = e1.dot(e1), d20 = d.dot(e0), d21 = d.dot(e1);
  const double den = d00 * d11 - d01 * d01;
  if (!(std::abs(den) > 1e-30)) return Vec3(1, 0, 0);
  const double v = (d11 * d20 - d01 * d21) / den, w = (d00 * d21 - d01 * d20) / den;
  return Vec3(1 - v - w, v, w);
}

}  // namespace

Status build_control_level(const TriMesh& control, int num_nodes, ControlLevel& out) {
  out = {};
  const int V = control.num_vertices();
  if (V == 0) return Status::error(ErrorCode::InvalidInput, "control level: empty control mesh");
  if (num_nodes < 4) return Status::error(ErrorCode::InvalidInput, "control level: at least 4 nodes needed");
  if (num_nodes >= V) {
    out.identity = true;
    out.nodes.resize(size_t(V));
    out.cell.resize(size_t(V));
    for (int v = 0; v < V; ++v) out.nodes[size_t(v)] = out.cell[size_t(v)] = v;
    out.triangles = control.triangles;
    out.attachment.resize(V, V);
    out.attachment.setIdentity();
    out.laplacian = uniform_laplacian(control);
    return Status::success();
  }
  const auto g = edge_graph(control);
  // Farthest-point sampling: the first node is the vertex farthest from vertex 0.
  std::vector<double> dist(size_t(V), std::numeric_limits<double>::infinity());
  std::vector<int> owner(size_t(V), -1);
  {
    std::vector<double> d0(size_t(V), std::numeric_limits<double>::infinity());
    std::vector<int> o0(size_t(V), -1);
    dijkstra_from(g, 0, 0, d0, o0);
    int far = 0;
    for (int v = 0; v < V; ++v)
      if (std::isfinite(d0[size_t(v)]) && d0[size_t(v)] > d0[size_t(far)]) far = v;
    out.nodes.push_back(far);
    dijkstra_from(g, far, 0, dist, owner);
  }
  while (int(out.nodes.size()) < num_nodes) {
    // The farthest vertex from every node so far; an unreached component counts as farthest.
    int far = -1;
    for (int v = 0; v < V; ++v)
      if (far < 0 || dist[size_t(v)] > dist[size_t(far)]) far = v;
    if (dist[size_t(far)] <= 0) break;  // every vertex is a node
    dijkstra_from(g, far, int(out.nodes.size()), dist, owner);
    out.nodes.push_back(far);
  }
  out.cell = owner;
  const int K = out.num_nodes();
  // The level's graph: cells sharing a mesh edge.
  std::vector<std::set<int>> adj(static_cast<size_t>(K));
  for (int v = 0; v < V; ++v)
    for (const Neighbour& n : g[size_t(v)]) {
      const int a = out.cell[size_t(v)], b = out.cell[size_t(n.v)];
      if (a != b) adj[size_t(a)].insert(b);
    }
  std::vector<Eigen::Triplet<double>> lt;
  for (int i = 0; i < K; ++i) {
    if (adj[size_t(i)].empty()) continue;
    lt.emplace_back(i, i, 1.0);
    for (int j : adj[size_t(i)]) lt.emplace_back(i, j, -1.0 / double(adj[size_t(i)].size()));
  }
  out.laplacian.resize(K, K);
  out.laplacian.setFromTriplets(lt.begin(), lt.end());
  // Coarse triangles: the dual of the cells, oriented as the mesh triangle that makes each.
  std::set<std::array<int, 3>> seen;
  std::vector<std::vector<int>> fan(static_cast<size_t>(K));  // coarse triangles round each node
  for (const Tri& t : control.triangles) {
    const Tri c = {out.cell[size_t(t[0])], out.cell[size_t(t[1])], out.cell[size_t(t[2])]};
    if (c[0] == c[1] || c[1] == c[2] || c[0] == c[2]) continue;
    std::array<int, 3> key = {c[0], c[1], c[2]};
    std::sort(key.begin(), key.end());
    if (!seen.insert(key).second) continue;
    for (int n : c) fan[size_t(n)].push_back(int(out.triangles.size()));
    out.triangles.push_back(c);
  }
  // eq. 3: each vertex on the best triangle round its own node.
  const std::vector<Vec3>& P = control.positions;
  std::vector<Eigen::Triplet<double>> at;
  for (int v = 0; v < V; ++v) {
    const int c = out.cell[size_t(v)];
    if (out.nodes[size_t(c)] == v || fan[size_t(c)].empty()) {
      at.emplace_back(v, c, 1.0);
      continue;
    }
    double best_score = -std::numeric_limits<double>::infinity();
    Vec3 best_b = Vec3::Zero();
    int best_t = -1;
    for (int ti : fan[size_t(c)]) {
      const Tri& t = out.triangles[size_t(ti)];
      const Vec3 b = plane_barycentric(P[size_t(v)], P[size_t(out.nodes[size_t(t[0])])],
                                       P[size_t(out.nodes[size_t(t[1])])], P[size_t(out.nodes[size_t(t[2])])]);
      if (b.minCoeff() > best_score) {
        best_score = b.minCoeff();
        best_b = b;
        best_t = ti;
      }
    }
    Vec3 b = best_b.cwiseMax(0.0);
    if (!(b.sum() > 1e-12)) {
      at.emplace_back(v, c, 1.0);
      continue;
    }
    b /= b.sum();
    const Tri& t = out.triangles[size_t(best_t)];
    for (size_t k = 0; k < 3; ++k)
      if (b[long(k)] > 0) at.emplace_back(v, t[k], b[long(k)]);
  }
  out.attachment.resize(V, K);
  out.attachment.setFromTriplets(at.begin(), at.end());
  return Status::success();
}

std::vector<Vec3> attached_positions(const ControlLevel& level, const std::vector<Vec3>& base,
                                     const Eigen::VectorXd& delta) {
  std::vector<Vec3> p = base;
  const SparseMat& A = level.attachment;
  for (int k = 0; k < A.outerSize(); ++k)
    for (SparseMat::InnerIterator it(A, k); it; ++it)
      p[size_t(it.row())] += it.value() * delta.segment<3>(3 * long(it.col()));
  return p;
}

SparseMat attach_jacobian(const ControlLevel& level, const SparseMat& J) {
  if (level.identity) return J;
  const SparseMat& A = level.attachment;
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(size_t(3 * A.nonZeros()));
  for (int k = 0; k < A.outerSize(); ++k)
    for (SparseMat::InnerIterator it(A, k); it; ++it)
      for (int j = 0; j < 3; ++j) trip.emplace_back(3 * int(it.row()) + j, 3 * int(it.col()) + j, it.value());
  SparseMat A3(3 * A.rows(), 3 * A.cols());
  A3.setFromTriplets(trip.begin(), trip.end());
  return SparseMat(J * A3);
}

}  // namespace lk
