#include "mesh/topology.h"

#include <algorithm>
#include <sstream>

namespace lk {
namespace {

std::uint64_t edge_key(int a, int b) {
  if (a > b) std::swap(a, b);
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) | static_cast<std::uint32_t>(b);
}

Status bad(const std::string& s) { return Status::error(ErrorCode::InvalidInput, s); }

}  // namespace

int MeshTopology::find_edge(int a, int b) const {
  auto it = edge_index.find(edge_key(a, b));
  return it == edge_index.end() ? -1 : it->second;
}

int MeshTopology::opposite_vertex(const TriMesh& mesh, int f, int e) const {
  const Tri& t = mesh.triangles[f];
  for (int k = 0; k < 3; ++k)
    if (t[k] != edges[e].v0 && t[k] != edges[e].v1) return t[k];
  return -1;
}

Status build_topology(const TriMesh& mesh, MeshTopology& out) {
  out = MeshTopology{};
  const int nv = mesh.num_vertices();
  const int nf = mesh.num_triangles();
  out.num_vertices = nv;
  out.face_edges.resize(nf);
  out.edge_index.reserve(static_cast<size_t>(nf) * 2);
  // Directed half-edge a->b must be unique for a consistently oriented manifold.
  std::unordered_map<std::uint64_t, int> directed;
  directed.reserve(static_cast<size_t>(nf) * 3);

  for (int f = 0; f < nf; ++f) {
    const Tri& t = mesh.triangles[f];
    for (int k = 0; k < 3; ++k) {
      if (t[k] < 0 || t[k] >= nv) {
        std::ostringstream s;
        s << "triangle " << f << " has vertex index " << t[k] << " outside [0," << nv << ")";
        return bad(s.str());
      }
    }
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2])
      return bad("triangle " + std::to_string(f) + " repeats a vertex");
    for (int k = 0; k < 3; ++k) {
      const int a = t[k], b = t[(k + 1) % 3];
      const std::uint64_t dk = (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) | static_cast<std::uint32_t>(b);
      if (!directed.emplace(dk, f).second)
        return bad("edge " + std::to_string(a) + "-" + std::to_string(b) +
                   " is used twice in the same direction (non-manifold or flipped triangle " + std::to_string(f) + ")");
      const std::uint64_t key = edge_key(a, b);
      auto it = out.edge_index.find(key);
      if (it == out.edge_index.end()) {
        Edge e;
        e.v0 = std::min(a, b);
        e.v1 = std::max(a, b);
        e.f0 = f;
        out.edge_index.emplace(key, static_cast<int>(out.edges.size()));
        out.face_edges[f][k] = static_cast<int>(out.edges.size());
        out.edges.push_back(e);
      } else {
        Edge& e = out.edges[it->second];
        if (e.f1 >= 0)
          return bad("edge " + std::to_string(a) + "-" + std::to_string(b) + " is shared by more than two triangles");
        e.f1 = f;
        out.face_edges[f][k] = it->second;
      }
    }
  }

  // Ordered one-rings. For vertex v and face (v, a, b) in CCW order, the ring
  // steps from a to b; a boundary fan starts at the a that is no face's b.
  std::vector<std::vector<std::pair<int, int>>> fans(nv);  // (a, face) with b implied
  std::vector<std::vector<int>> nexts(nv);
  for (int f = 0; f < nf; ++f) {
    const Tri& t = mesh.triangles[f];
    for (int k = 0; k < 3; ++k) fans[t[k]].push_back({t[(k + 1) % 3], f});
  }
  out.rings.assign(nv, {});
  out.ring_faces.assign(nv, {});
  out.boundary_vertex.assign(nv, 0);
  for (const Edge& e : out.edges)
    if (e.boundary()) out.boundary_vertex[e.v0] = out.boundary_vertex[e.v1] = 1;

  for (int v = 0; v < nv; ++v) {
    auto& fan = fans[v];
    if (fan.empty()) continue;  // isolated vertex
    // next-of-a: b for face (v, a, b)
    std::unordered_map<int, std::pair<int, int>> step;  // a -> (b, face)
    std::unordered_map<int, int> is_b;
    for (auto& [a, f] : fan) {
      const Tri& t = mesh.triangles[f];
      int k = 0;
      while (t[k] != v) ++k;
      const int b = t[(k + 2) % 3];
      step[a] = {b, f};
      is_b[b] = 1;
    }
    int start = fan.front().first;
    if (out.boundary_vertex[v]) {
      int starts = 0;
      for (auto& [a, f] : fan)
        if (!is_b.count(a)) { start = a; ++starts; }
      if (starts != 1) return bad("vertex " + std::to_string(v) + " is non-manifold (its triangles form several fans)");
    }
    auto& ring = out.rings[v];
    auto& rf = out.ring_faces[v];
    int a = start;
    ring.push_back(a);
    for (size_t i = 0; i < fan.size(); ++i) {
      auto it = step.find(a);
      if (it == step.end()) break;
      rf.push_back(it->second.second);
      a = it->second.first;
      if (a == start) break;
      ring.push_back(a);
    }
    if (rf.size() != fan.size())
      return bad("vertex " + std::to_string(v) + " is non-manifold (its triangles form several fans)");
  }

  // Boundary loops: follow boundary half-edges a->b (the face's direction).
  std::unordered_map<int, int> bnext;
  for (const Edge& e : out.edges) {
    if (!e.boundary()) continue;
    const Tri& t = mesh.triangles[e.f0];
    for (int k = 0; k < 3; ++k) {
      const int a = t[k], b = t[(k + 1) % 3];
      if ((a == e.v0 && b == e.v1) || (a == e.v1 && b == e.v0)) bnext[b] = a;  // walk opposite to the face
    }
  }
  std::unordered_map<int, char> seen;
  for (const Edge& e : out.edges) {
    if (!e.boundary() || seen.count(e.v0)) continue;
    std::vector<int> loop;
    int v = e.v0;
    while (!seen.count(v)) {
      seen[v] = 1;
      loop.push_back(v);
      auto it = bnext.find(v);
      if (it == bnext.end()) break;
      v = it->second;
    }
    out.boundary_loops.push_back(std::move(loop));
  }
  return Status::success();
}

int euler_characteristic(const MeshTopology& topo, int num_triangles) {
  return topo.num_vertices - static_cast<int>(topo.edges.size()) + num_triangles;
}

std::vector<int> ring_distances(const MeshTopology& topo, const std::vector<int>& sources, int max_rings) {
  std::vector<int> ring(topo.num_vertices, -1);
  std::vector<int> frontier = sources;
  for (int v : sources) ring[v] = 0;
  for (int r = 1; r <= max_rings; ++r) {
    std::vector<int> next;
    for (int v : frontier)
      for (int u : topo.rings[v])
        if (ring[u] < 0) ring[u] = r, next.push_back(u);
    frontier = std::move(next);
  }
  return ring;
}

}  // namespace lk
