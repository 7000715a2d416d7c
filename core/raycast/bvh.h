// Bounding-volume hierarchy over a triangle mesh: first-hit and any-hit ray
// casts and closest-point-on-mesh queries.
//
// Not from the papers: a tool the stages share. The virtual range scanner
// (core/synth) casts camera and projector rays against the ground-truth head,
// fitting (jeong2002 Sec. 5, "closest point on the current surface") needs
// point-to-mesh projections, texturing (tarini2002 Sec. 3) needs occlusion.
//
// Layout: a binned-SAH build (Wald 2007, "On fast construction of SAH-based
// bounding volume hierarchies") into one flat array of nodes in depth-first
// order; the left child of an inner node is the next node, the right child is
// stored. Leaves reference a run of `triangle_order`. The BVH keeps its own
// copy of the triangle corners, so queries need no mesh; after the vertices
// move (same triangles), refit_bvh updates the boxes without rebuilding.
//
// Shapes: mesh positions #V by 3, triangles #F by 3. Barycentrics are the
// weights of the triangle's corners 0,1,2 (they sum to 1).
#pragma once
#include "common/status.h"
#include "mesh/tri_mesh.h"

#include <limits>

namespace lk {

struct BvhOptions {
  int max_leaf_triangles = 4;  // leaves hold at most this many triangles
  int sah_bins = 16;           // candidate split planes per axis and node
  // Natively, meshes of 20k+ triangles build their two top subtrees on two
  // threads; the tree is the same as a serial build's (false: serial).
  bool threads = true;
};

struct BvhNode {
  Vec3 box_min = Vec3::Zero(), box_max = Vec3::Zero();
  int first = 0;  // leaf: first index into triangle_order; inner: right child
  int count = 0;  // leaf: number of triangles (> 0); inner: 0
  bool leaf() const { return count > 0; }
};

struct MeshBvh {
  std::vector<BvhNode> nodes;       // nodes[0] is the root; empty for an empty mesh
  std::vector<int> triangle_order;  // #F: leaf runs index this, values are mesh triangle ids
  std::vector<Tri> triangles;       // #F, copy of the mesh's triangles
  std::vector<Vec3> positions;      // #V, copy of the mesh's positions

  bool empty() const { return nodes.empty(); }
  int num_triangles() const { return static_cast<int>(triangles.size()); }
};

// Builds the hierarchy. Fails with InvalidInput on out-of-range indices or
// non-finite positions; an empty mesh gives an empty BVH (queries miss).
Status build_bvh(const TriMesh& mesh, MeshBvh& out, const BvhOptions& options = {});

// Re-reads positions (same #V and triangles as at build time) and recomputes
// the node boxes bottom-up. Cheaper than a rebuild for small deformations,
// at the price of looser boxes as the shape drifts.
Status refit_bvh(const TriMesh& mesh, MeshBvh& bvh);

// What a refit after a few vertices moved needs: each node's parent, the
// leaf holding each triangle, and each vertex's triangles. Built once per
// BVH (same triangles; positions may change).
struct BvhRefitIndex {
  std::vector<int> parent;            // #nodes, -1 for the root
  std::vector<int> leaf_of_triangle;  // #F: node index of the leaf holding the triangle
  std::vector<int> vertex_offsets;    // #V + 1: vertex v's triangles are
  std::vector<int> vertex_triangles;  //   vertex_triangles[vertex_offsets[v] .. vertex_offsets[v+1])
};
void build_refit_index(const MeshBvh& bvh, BvhRefitIndex& out);

// Moves the listed vertices of the BVH to positions[v] (positions is #V
// long; only the listed entries are read) and recomputes exactly the boxes
// that contain them: the leaves of their triangles and those leaves'
// ancestors. The boxes come out bit-identical to refit_bvh with the same
// positions (each box is recomputed from scratch in the same order), at a
// cost proportional to the moved vertices, not to #F. Fails with
// InvalidInput on a size mismatch, an index out of range or a non-finite
// position (the BVH is then unchanged). Repeated indices are fine.
Status refit_bvh_vertices(MeshBvh& bvh, const BvhRefitIndex& index, const std::vector<Vec3>& positions,
                          const std::vector<int>& moved);

struct Ray {
  Vec3 origin = Vec3::Zero();
  Vec3 direction = Vec3::UnitZ();  // need not be unit; t is in units of |direction|
  double t_min = 0.0;
  double t_max = std::numeric_limits<double>::infinity();
};

struct RayHit {
  int triangle = -1;                 // mesh triangle id, -1 when the ray missed
  double t = 0.0;                    // hit point = origin + t * direction
  Vec3 barycentric = Vec3::Zero();   // weights of the triangle's corners 0,1,2
  bool hit() const { return triangle >= 0; }
};

// Nearest intersection with t in [t_min, t_max]. Both triangle sides count.
RayHit intersect_first(const MeshBvh& bvh, const Ray& ray);

// True if any triangle is hit with t in [t_min, t_max] (shadow rays: stops at
// the first hit found). skip_triangle (if >= 0) is ignored, so a ray leaving a
// surface point need not rely on t_min alone to avoid hitting its own triangle.
bool intersect_any(const MeshBvh& bvh, const Ray& ray, int skip_triangle = -1);

struct ClosestPoint {
  int triangle = -1;                  // -1 when nothing lies within max_distance
  Vec3 point = Vec3::Zero();          // closest point on the mesh
  Vec3 barycentric = Vec3::Zero();    // of point in `triangle`
  double distance = std::numeric_limits<double>::infinity();
  bool found() const { return triangle >= 0; }
};

// Closest point on the mesh surface to p, searched within max_distance.
ClosestPoint closest_point(const MeshBvh& bvh, const Vec3& p,
                           double max_distance = std::numeric_limits<double>::infinity());

// Closest point on the mesh to p, searched first within the distance to
// triangle `guess` (e.g. the triangle found for a neighbouring point or in a
// previous iteration; -1 or out of range: none), so most of the tree is
// pruned when the guess is near. The same answer as closest_point(bvh, p),
// bit for bit: the bound is widened by a relative 1e-9 so that the nearest
// triangle, and the first of exact ties, stays inside it.
ClosestPoint closest_point_near(const MeshBvh& bvh, const Vec3& p, int guess);

// Closest point on one triangle (a, b, c) to p; barycentric gets the weights.
// Exposed for tests and for callers that already know the triangle.
Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c,
                               Vec3& barycentric);

}  // namespace lk
