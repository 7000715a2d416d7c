#include "head/head_creases.h"

#include "mesh/topology.h"

#include <algorithm>

namespace lk {

namespace {

// The socket ring behind an eye rim: the vertices of the pocket side (the
// smaller of the two parts the rim cuts the mesh into) that share an edge
// with the rim, and as tagged edges the ring's edges facing the rim (a
// triangle with one rim corner and two ring corners). Without it Butterfly's
// extraordinary rule about the ring's valence-5 vertices reaches the next
// pocket ring and bulges the refined lid margin into the eye's opening
// (docs/design/muscles.md, "The lids closed at level 2").
void add_socket_ring(const TriMesh& mesh, const MeshTopology& topo, const std::vector<int>& rim, ButterflyCreases& creases) {
  const int nv = mesh.num_vertices();
  std::vector<char> on_rim(static_cast<std::size_t>(nv), 0);
  for (int v : rim)
    if (v < 0 || v >= nv) return;
    else on_rim[static_cast<std::size_t>(v)] = 1;
  // The two sides: flood from the rim's neighbours without crossing it.
  std::vector<int> side(static_cast<std::size_t>(nv), -1);
  std::vector<int> size;
  for (int r : rim)
    for (int n : topo.rings[static_cast<std::size_t>(r)]) {
      if (on_rim[static_cast<std::size_t>(n)] || side[static_cast<std::size_t>(n)] >= 0) continue;
      const int label = static_cast<int>(size.size());
      size.push_back(0);
      std::vector<int> stack{n};
      side[static_cast<std::size_t>(n)] = label;
      while (!stack.empty()) {
        const int v = stack.back();
        stack.pop_back();
        ++size.back();
        for (int w : topo.rings[static_cast<std::size_t>(v)])
          if (!on_rim[static_cast<std::size_t>(w)] && side[static_cast<std::size_t>(w)] < 0) {
            side[static_cast<std::size_t>(w)] = label;
            stack.push_back(w);
          }
      }
    }
  if (size.size() != 2) return;  // the rim does not cut the mesh in two: no pocket to find
  const int pocket = size[0] < size[1] ? 0 : 1;
  std::vector<char> ring(static_cast<std::size_t>(nv), 0);
  for (int r : rim)
    for (int n : topo.rings[static_cast<std::size_t>(r)])
      if (side[static_cast<std::size_t>(n)] == pocket) ring[static_cast<std::size_t>(n)] = 1;
  for (const Tri& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) {
      const int a = t[static_cast<std::size_t>(k)], b = t[static_cast<std::size_t>((k + 1) % 3)], c = t[static_cast<std::size_t>((k + 2) % 3)];
      if (ring[static_cast<std::size_t>(a)] && ring[static_cast<std::size_t>(b)] && on_rim[static_cast<std::size_t>(c)] && a < b)
        creases.edges.push_back({a, b});
      else if (ring[static_cast<std::size_t>(a)] && ring[static_cast<std::size_t>(b)] && on_rim[static_cast<std::size_t>(c)])
        creases.edges.push_back({b, a});
    }
}

}  // namespace

ButterflyCreases head_creases(const TriMesh& mesh, const HeadAnnotations& annotations) {
  MeshTopology topo;
  if (!build_topology(mesh, topo).ok()) topo = MeshTopology{};  // curves and corners only, as before
  return head_creases(mesh, topo, annotations);
}

ButterflyCreases head_creases(const TriMesh& mesh, const MeshTopology& topo, const HeadAnnotations& annotations) {
  ButterflyCreases creases;
  for (const CreaseCurve& c : annotations.creases) add_crease_polyline(c.vertices, c.closed, creases);
  const int nv = mesh.num_vertices();
  for (const EyeSocket* eye : {&annotations.eye_left, &annotations.eye_right}) {
    int lo = -1, hi = -1;
    for (int v : eye->rim) {
      if (v < 0 || v >= nv) continue;
      if (lo < 0 || mesh.positions[v].x() < mesh.positions[lo].x()) lo = v;
      if (hi < 0 || mesh.positions[v].x() > mesh.positions[hi].x()) hi = v;
    }
    if (lo < 0 || lo == hi) continue;
    creases.corners.push_back(lo);
    creases.corners.push_back(hi);
  }
  if (topo.rings.size() == static_cast<std::size_t>(nv)) {
    ButterflyCreases rings;
    for (const EyeSocket* eye : {&annotations.eye_left, &annotations.eye_right}) add_socket_ring(mesh, topo, eye->rim, rings);
    // An edge facing the rim twice is listed once; a ring vertex with other
    // than two ring edges ends its curve there (a corner).
    std::sort(rings.edges.begin(), rings.edges.end());
    rings.edges.erase(std::unique(rings.edges.begin(), rings.edges.end()), rings.edges.end());
    close_crease_ends(rings);
    creases.edges.insert(creases.edges.end(), rings.edges.begin(), rings.edges.end());
    creases.corners.insert(creases.corners.end(), rings.corners.begin(), rings.corners.end());
  }
  std::sort(creases.corners.begin(), creases.corners.end());
  creases.corners.erase(std::unique(creases.corners.begin(), creases.corners.end()), creases.corners.end());
  return creases;
}

}  // namespace lk
