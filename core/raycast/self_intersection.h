// Self-intersections of a triangle mesh: pairs of triangles that cross each
// other although the surface does not connect them there.
//
// Not from the papers: a quality check of jeong2002 Sec. 5's displaced
// levels, whose normal displacements can push one sheet of a thin feature
// (upper and lower lip, the rim of an ear) through the other.
//
// Test. Two non-coplanar triangles intersect exactly when an edge of one
// crosses the other (the ends of their common segment lie on edges), so each
// pair is decided by six segment-triangle tests built from signed volumes
// (orientation determinants), the predicate form of Moller 1997's test. A
// coplanar pair is decided in the 2-D projection on its plane (edge crossings
// or one triangle inside the other). Touching counts as crossing. The
// orientation signs are filtered (Shewchuk 1997's error bounds): a
// determinant too small for its sign to be sure counts as 0, i.e. as
// coplanar or touching, so nearly coplanar triangles (a flat sheet, a
// level of fine triangles) are decided in 2-D instead of by the sign of
// their rounding noise; triangles whose boxes are apart never cross. The
// answer for a pair is therefore the same whichever tree found it.
// Neighbours: triangles sharing an edge are skipped (they meet along it; a
// fold between them is a flipped triangle, another check); triangles sharing
// one vertex count only when the edge opposite the shared vertex in one of
// them crosses the other (their common segment then leaves the shared vertex).
// Candidate pairs come from a self-traversal of the mesh's SAH BVH.
//
// Shapes: positions #V by 3, triangles #F by 3; result #pairs, each (a, b)
// with a < b, sorted.
#pragma once
#include "common/status.h"
#include "mesh/tri_mesh.h"
#include "raycast/bvh.h"

#include <array>
#include <vector>

namespace lk {

struct SelfIntersectionOptions {
  // Stop after this many pairs (0: find all). A broken mesh can have
  // millions; callers that only count or show a few need not wait for them.
  int max_pairs = 0;
};

// Every intersecting pair of triangles (see above). Fails with InvalidInput
// on out-of-range indices or non-finite positions (as build_bvh).
Status find_self_intersections(const TriMesh& mesh, std::vector<std::array<int, 2>>& pairs,
                               const SelfIntersectionOptions& options = {});

// The same, on a BVH already built over the mesh.
void find_self_intersections(const MeshBvh& bvh, std::vector<std::array<int, 2>>& pairs,
                             const SelfIntersectionOptions& options = {});

// Only the pairs in which one triangle is in `triangles` (mesh triangle
// ids), each tested against every triangle of the BVH: the re-check after a
// local change. Same rules; pairs (a, b) with a < b, sorted, no duplicates.
void find_intersections_with(const MeshBvh& bvh, const std::vector<int>& triangles,
                             std::vector<std::array<int, 2>>& pairs);

// The crossings a deformation made: the intersecting pairs of the BVH's
// mesh (at the positions it was built or last refit with) that do NOT
// intersect at `reference` (#V by 3: the same triangles at other positions,
// e.g. the template the mesh was deformed from), each decided by
// mesh_triangles_cross. A pair that crosses at both is old: the same answer
// as searching the reference's mesh and dropping its pairs, without that
// search. `from_triangles` (null: the whole mesh) restricts the search to
// the pairs with a listed triangle, as find_intersections_with. Pairs (a, b)
// with a < b, sorted. Fails with InvalidInput when reference does not have
// the BVH's #V or holds a non-finite position (pairs then empty).
Status find_new_self_intersections(const MeshBvh& bvh, const std::vector<Vec3>& reference,
                                   std::vector<std::array<int, 2>>& pairs,
                                   const std::vector<int>* from_triangles = nullptr);

// The pairs after the triangles flagged in `changed` (#F) moved and were
// searched again: the pairs of `before` with no changed triangle, and
// `found` (the pairs with a changed triangle, e.g. from
// find_intersections_with). Sorted; the whole-mesh set when `before` was.
std::vector<std::array<int, 2>> pairs_after_change(const std::vector<std::array<int, 2>>& before,
                                                   const std::vector<char>& changed,
                                                   const std::vector<std::array<int, 2>>& found);

// The triangles with a corner whose position differs between `before` and
// `after` (#V each): flagged in `changed` (resized to #F) and listed in
// ascending order in `list`, as pairs_after_change and the searches
// `from_triangles` take them.
void moved_triangles(const std::vector<Tri>& triangles, const std::vector<Vec3>& before,
                     const std::vector<Vec3>& after, std::vector<char>& changed, std::vector<int>& list);

// One pair under the rules above (shared edge: no; one shared vertex: only
// if the common segment leaves it), corners read from positions.
bool mesh_triangles_cross(const std::vector<Vec3>& positions, const Tri& a, const Tri& b);

// Do triangles (a0, a1, a2) and (b0, b1, b2) share a point? (No adjacency
// logic: for two triangles given by their corners.)
bool triangles_intersect(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& b0, const Vec3& b1,
                         const Vec3& b2);

// The predicate of every test here: six times the signed volume of
// tetrahedron (a, b, c, d), > 0 when d lies on the side of plane abc that
// its normal (b - a) x (c - a) points to, 0 when floating point cannot tell
// the sign. Shewchuk 1997 ("Adaptive precision
// floating-point arithmetic and fast robust geometric predicates") bounds
// the rounding error of this determinant by (7 + 56 eps) eps times its
// permanent (the same products, all terms taken positive); a value within
// that bound (here 1e-15 times the permanent, a little wider, for fused
// multiply-adds) has no reliable sign and counts as 0: the point is on the
// plane. Without it four nearly coplanar points get the sign of their
// rounding noise, and two triangles side by side in a flat sheet were
// reported crossing (their boxes do not even overlap).
double orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

// Does the closed segment p-q meet the triangle (a, b, c)?
bool segment_intersects_triangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c);

}  // namespace lk
