// Closest points on a triangle mesh, and scan-to-surface distance statistics.
//
// jeong2002 Sec. 4.2/4.3: E_dist needs Pi(G, p), the projection of a scan
// point p onto the nearest surface point of the mesh G; Sec. 7 (Table 1)
// reports the mean and maximum of |Pi(G, p) - p| over the scan in percent of
// the point cloud's bounding-box diagonal. Both come from this exact query
// (not an approximation through mesh vertices), answered by the SAH
// bounding-volume hierarchy of core/raycast; this header only adapts it to
// the fitting stages' squared-distance form.
//
// Shapes: positions #V by 3, triangles #F by 3, query points #P by 3.
#pragma once
#include "mesh/tri_mesh.h"
#include "raycast/bvh.h"

#include <functional>
#include <vector>

namespace lk {

// The nearest surface point of one query. (Not "SurfacePoint": that is
// photos/landmarks.h's, and one program links both modules.)
struct SurfaceHit {
  int face = -1;                     // triangle index, -1 when the mesh is empty
  Vec3 barycentric = Vec3::Zero();   // weights of the triangle's corners 0,1,2
  Vec3 point = Vec3::Zero();         // the closest point itself
  double squared_distance = 1e300;
};

// A BVH over a mesh's triangles for closest-point queries. It stores a copy
// of the positions it was built from; rebuild it after the mesh moves.
class ClosestPointTree {
 public:
  ClosestPointTree() = default;
  explicit ClosestPointTree(const TriMesh& mesh) { build(mesh); }
  void build(const TriMesh& mesh);
  // Takes over `tree` (moved out) when it is a tree over exactly `mesh`
  // (the same triangles, its boxes fitted to the same positions, e.g. one
  // refitted there), else builds one. Closest distances do not depend on
  // the tree.
  void build(const TriMesh& mesh, MeshBvh& tree);

  bool empty() const { return bvh_.empty(); }
  // Exact closest point on the mesh. When a finite upper bound on the squared
  // distance is known (e.g. from the previous iteration's triangle) passing
  // it prunes the search; if nothing is nearer than the bound the result's
  // face is -1.
  SurfaceHit closest(const Vec3& p, double max_squared_distance = 1e300) const;
  // Exact closest point, searched first within the distance to triangle
  // `guess` (e.g. the triangle found for a neighbouring point; -1: none).
  // Same answer as closest(p), bit for bit (the bound is widened a little
  // so that the nearest triangle, and the first of exact ties, is always
  // inside it), only faster when the guess is near.
  SurfaceHit closest_near(const Vec3& p, int guess) const;

 private:
  MeshBvh bvh_;
};

// Closest point on triangle (a, b, c) to p, with barycentric weights.
SurfaceHit closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

// Distances from scan points to a surface, the measure of jeong2002 Table 1.
struct DistanceStats {
  int count = 0;           // points measured
  double mean = 0;         // mean distance, scan units
  double max = 0;          // maximum distance
  double rms = 0;
  double p95 = 0;          // 95th percentile
  double mean_pct = 0;     // mean in percent of the reference diagonal
  double max_pct = 0;
};

// Distances from every point (or every stride-th point when stride > 1) to
// the mesh, normalized by reference_diagonal (the cloud's bbox diagonal).
// Runs of consecutive points are measured on parallel_for's threads, each
// point searched near its predecessor's triangle (scans list neighbours
// together); the figures do not depend on either.
DistanceStats point_to_surface_stats(const std::vector<Vec3>& points, const TriMesh& mesh,
                                     double reference_diagonal, int stride = 1);
// The same on a tree already built over the mesh.
DistanceStats point_to_surface_stats(const std::vector<Vec3>& points, const ClosestPointTree& tree,
                                     double reference_diagonal, int stride = 1);

// Summary of a list of distances (consumed: it is partially sorted).
DistanceStats summarize_distances(std::vector<double>& distances, double reference_diagonal);


// The other direction of jeong2002's Table 1: from a fitted surface to the
// scanned surface, counted only where that surface was scanned. Table 1
// measures scan points to the fit; a fit that bulges away from the scan (a
// spike over the nose tip) is invisible to it, because no scan point lies
// near the bulge. Shapes: surface #V by 3, skip #V flags (or empty),
// reference #R by 3.
struct CoveredDistances {
  int vertices = 0;                // vertices counted
  double mean = 0, p99 = 0, max = 0;  // metres
  int over_1mm = 0;                // vertices farther than 1 mm
  bool to_points = false;          // measured to a point cloud's local patches, not to triangles
};

// Each vertex of `surface` not flagged in `skip` is projected onto
// `reference`; its distance counts when covered(closest point) says the
// reference was scanned there and the reference's triangle faces the
// vertex's way (within 60 degrees; the reference's orientation is taken
// from the vertices within 2 mm). Both meshes in metres (the head frame).
// per_vertex (optional): #V distances, -1 where a vertex is not counted.
CoveredDistances surface_to_reference(const TriMesh& surface, const std::vector<char>& skip, const TriMesh& reference,
                                      const std::function<bool(const SurfaceHit&)>& covered,
                                      std::vector<double>* per_vertex = nullptr);

// A covered() for a scan's own triangles: the closest point is not on the
// mesh's boundary (an edge with one triangle, or a vertex on one), so a
// vertex beyond the scan's rim or over one of its holes does not count.
// Edges are counted directly, not by build_topology: scans need not be
// manifold.
std::function<bool(const SurfaceHit&)> inside_scan_mesh(const TriMesh& scan);

// The same on a scan that came as points (no triangles to project onto):
// each vertex's distance to the scanned surface under it, the quadric
// height field of its k nearest points (fit/point_patch.h) evaluated at
// the vertex's foot, measured along that surface's normal. A vertex counts
// where the patch is one sheet (flatness 0.2, as the global fit's E_back)
// spread in two directions (not one line of points), the vertex lies over
// it with points under its foot (not beyond the scan's border, nor over a
// hole's edge or middle) and it faces the vertex's way within 60 degrees
// (sign-free: points carry no orientation, and a face's two sides are
// never one vertex's nearest). Points farther from the patch's plane, then
// from its quadric, than 4 robust spreads (outliers) are dropped before
// each is fitted again. The patches' own noise is in the figure (about
// 0.03 mm on a dense scan with 0.2 mm noise), and on a sparse cloud (James's
// 6,400 vertices) their quadric is too coarse for a nose: use the
// triangles there. Points and surface in metres (the head frame).
// per_vertex as surface_to_reference's.
CoveredDistances surface_to_cloud(const TriMesh& surface, const std::vector<char>& skip,
                                  const std::vector<Vec3>& points, int k = 16,
                                  std::vector<double>* per_vertex = nullptr);

}  // namespace lk
