// Coarse control triangulations for the photos shape fit (fua1998 Sec. 2.1,
// eq. 3, Fig. 1(b,c)): a triangulation of a few hundred nodes laid over the
// control mesh; every control-mesh vertex is attached to one coarse triangle
// by barycentric coordinates, so that a node's displacement moves a whole
// patch of the surface, P_i = P_i^0 + l1 d_j1 + l2 d_j2 + l3 d_j3 (eq. 3).
// The fit runs the coarse levels first, then finer ones, up to the control
// mesh itself ("a hierarchical fitting scheme", Sec. 2.1).
//
// How a level is made (the paper's were precomputed by hand): num_nodes
// control vertices picked by farthest-point sampling with the mesh's edge
// lengths as distances (Dijkstra); each control vertex belongs to its
// nearest node's cell; two nodes are neighbours (the level's own graph, the
// stiffness's) when their cells share a mesh edge; a coarse triangle is made
// by every mesh triangle whose three corners lie in three different cells
// (the dual of the cells). A vertex is attached to the coarse triangle round
// its own cell's node that holds it best: its position projected into the
// triangle's plane, barycentrics clamped to >= 0 and summed to 1; a node's
// own vertex gets weight 1 on it. Only the triangles round the vertex's own
// node are tried: a vertex is never attached to a far part of the head
// (a cell can still reach across the mouth slit through the mouth bag).
//
// Shapes: control #V; a level's nodes K; attachment #V by K (rows sum to 1);
// laplacian K by K.
#pragma once
#include "common/status.h"
#include "mesh/tri_mesh.h"
#include "photos/sparse_lm.h"

#include <vector>

namespace lk {

struct ControlLevel {
  std::vector<int> nodes;       // #K: the control vertex each node sits on
  std::vector<int> cell;        // #V: the node each control vertex belongs to
  std::vector<Tri> triangles;   // coarse triangles, node indices
  SparseMat attachment;         // #V by K, eq. 3's barycentric weights
  SparseMat laplacian;          // K by K uniform graph Laplacian of the level's graph
  bool identity = false;        // the control mesh itself (attachment = I)
  int num_nodes() const { return int(nodes.size()); }
};

// num_nodes in [4, #V]; #V or more gives the control mesh itself (identity
// attachment, its own Laplacian). Fails with InvalidInput on an empty mesh
// or a bad count.
Status build_control_level(const TriMesh& control, int num_nodes, ControlLevel& out);

// base + A delta (delta: 3 K, x y z of each node in turn). #V.
std::vector<Vec3> attached_positions(const ControlLevel& level, const std::vector<Vec3>& base,
                                     const Eigen::VectorXd& delta);

// Expands a Jacobian over vertex positions (rows by 3 #V) to one over the
// level's node displacements (rows by 3 K): J (A x I3), eq. 3's chain rule.
SparseMat attach_jacobian(const ControlLevel& level, const SparseMat& jacobian_over_vertices);

}  // namespace lk
