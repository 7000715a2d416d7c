// The scanned surface near a point, from an unstructured point cloud alone.
//
// Two places ask "where is the scan's surface under this vertex, and was it
// scanned there?" without any triangles: the global fit's scan-to-mesh term
// (global_fit.h, E_back) and the other direction of Table 1 on a scan that
// came as points (closest_point.h, surface_to_cloud). Both take the k scan
// points nearest the vertex, their principal plane, and a quadric height
// field over that plane evaluated at the vertex's foot. The centroid's
// plane alone lies inside a curved patch by half its sag (r^2 / 4R at the
// centre of a patch of radius r on a sphere of radius R), which would read
// as the vertex being outside a convex surface everywhere.
//
// Shapes: points #P by 3 (the tree's); k >= 6 (the quadric's 6 unknowns).
#pragma once
#include "common/cloud_tree.h"
#include "common/types.h"

#include <vector>

namespace lk {

struct PointPatch {
  std::vector<size_t> index;   // the points, nearest first
  int count = 0;               // how many (k, fewer after trimming)
  double radius = 0;           // distance from the vertex to the farthest of them
  Vec3 centroid = Vec3::Zero();
  Mat3 axes = Mat3::Identity();      // principal axes (columns), by ascending eigenvalue
  Vec3 plane_normal = Vec3::Zero();  // axes.col(0) (sign arbitrary)
  Vec3 eigenvalues = Vec3::Zero();   // of the scatter matrix, ascending
  double height = 0;           // the vertex's signed offset from the plane along plane_normal
  double tangential = 0;       // the vertex's foot's distance from the centroid, in the plane
  double spread = 0;           // the patch's standard deviation along its second axis
  double extent = 0;           // the farthest point's distance from the centroid, in the plane
  double foot_gap = 0;         // the nearest point's distance from the vertex's foot, in the plane
  // The quadric surface under the vertex (valid when quadric_ok): the point
  // at the vertex's tangential position and the surface's unit normal
  // there (on plane_normal's side).
  bool quadric_ok = false;
  Vec3 foot = Vec3::Zero();
  Vec3 normal = Vec3::Zero();

  // One sheet: the smallest spread is at most `flatness` times the middle
  // one (a fold, a lip gap or two sides of an ear are not).
  bool flat(double flatness) const { return eigenvalues[0] <= flatness * eigenvalues[1]; }
  // Spread in two directions, not a line of points (one stripe of a
  // structured-light scan along the columella): across a line the quadric
  // is free, and a vertex beside the line read 5 mm off.
  bool two_dimensional(double ratio) const { return eigenvalues[1] >= ratio * eigenvalues[2]; }
  // The vertex lies over the patch, not beyond its rim (a hole's edge, the
  // scan's border): its foot is within one spread of the centroid.
  bool over_patch() const { return tangential <= spread; }
  // And scanned under it: a point lies within half the patch's extent of
  // the foot. The k points nearest a vertex over the middle of a hole (or
  // beyond a round border) form a ring around its foot, centred and flat,
  // with nothing under the vertex.
  bool covers_foot() const { return over_patch() && foot_gap <= 0.5 * extent; }
};

// The plane of the k points nearest q. With trim > 0 the points farther
// from that plane than trim times 1.4826 x their median distance
// (outliers) are dropped and the plane fitted again to the rest. False
// when the tree holds fewer than k points. `out` may be reused between
// calls (its index keeps its capacity).
bool fit_patch_plane(const CloudTree& tree, const std::vector<Vec3>& points, const Vec3& q, int k, PointPatch& out,
                     double trim = 0);

// Adds the quadric height field over out's plane (after fit_patch_plane
// with the same q) and its value at q's foot. With trim > 0 the points
// farther from the first fit than trim times 1.4826 x their median
// residual (outliers) are dropped and the quadric fitted again. False (and
// quadric_ok false) when it is not finite.
bool fit_patch_quadric(const std::vector<Vec3>& points, const Vec3& q, PointPatch& out, double trim = 0);

}  // namespace lk
