// Connectivity of a triangle mesh: edges, edge lookup, ordered one-rings,
// valence, boundary loops. Built once from the triangles; positions are not
// used, so the same topology serves every deformation of the mesh.
#pragma once
#include "common/status.h"
#include "mesh/tri_mesh.h"

#include <unordered_map>

namespace lk {

struct Edge {
  int v0 = -1, v1 = -1;  // v0 < v1
  int f0 = -1, f1 = -1;  // adjacent faces; f1 == -1 on the boundary
  bool boundary() const { return f1 < 0; }
};

struct MeshTopology {
  int num_vertices = 0;
  std::vector<Edge> edges;                     // #E
  std::vector<std::array<int, 3>> face_edges;  // #F: edge k joins corners k and (k+1)%3
  // Per vertex, neighbours in counter-clockwise order (seen from outside).
  // For a boundary vertex the ring starts and ends at its two boundary
  // neighbours, and ring_faces has one entry fewer than the ring.
  std::vector<std::vector<int>> rings;       // #V
  std::vector<std::vector<int>> ring_faces;  // #V: face between ring[i] and ring[i+1]
  std::vector<char> boundary_vertex;         // #V, 1 on the boundary
  std::vector<std::vector<int>> boundary_loops;  // vertex loops, in boundary order
  std::unordered_map<std::uint64_t, int> edge_index;

  int valence(int v) const { return static_cast<int>(rings[v].size()); }
  bool is_boundary(int v) const { return boundary_vertex[v] != 0; }
  // Index of the edge joining a and b, or -1.
  int find_edge(int a, int b) const;
  // The vertex of face f opposite to edge e (whose face it must be).
  int opposite_vertex(const TriMesh& mesh, int f, int e) const;
};

// Builds the topology. Fails (InvalidInput) on out-of-range indices,
// degenerate triangles (repeated vertex), edges shared by more than two
// triangles, inconsistently oriented neighbours, or vertices whose triangles
// form more than one fan (non-manifold vertices).
Status build_topology(const TriMesh& mesh, MeshTopology& out);

// Euler characteristic V - E + F (2 for a sphere, 1 for a disk).
int euler_characteristic(const MeshTopology& topo, int num_triangles);

// Per vertex, the fewest edges from any of `sources` (0 there), or -1 when
// more than max_rings away.
std::vector<int> ring_distances(const MeshTopology& topo, const std::vector<int>& sources, int max_rings);

}  // namespace lk
