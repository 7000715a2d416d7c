// What a user should know about a fitted head before animating it: triangles
// a displacement turned over, degenerate triangles, and self-intersecting
// triangle pairs by head region.
//
// Not from the papers. jeong2002 Sec. 5's normal displacements can push one
// sheet of a thin feature (upper and lower lip, an ear's rim) through
// another; Sec. 6 animates the result, and a crossing shows as a dark seam
// or a lip that pokes through. `likeness fit` prints these figures and
// writes them to report.json; the fit benchmark prints them per seed.
//
// Shapes: pairs #pairs by 2 (triangle ids of the level, a < b).
#pragma once
#include "common/status.h"
#include "fit/closest_point.h"
#include "head/head_model.h"
#include "mesh/tri_mesh.h"
#include "multires/multires.h"

#include <array>
#include <map>
#include <string>
#include <vector>

namespace lk {

struct FitHeadResult;
struct GenericHead;

// Crossing pairs split by head region (annotations carried down the
// levels): a pair touching a lip vertex counts as lips, else one touching an
// ear vertex as ears, else one touching an eye socket's pocket
// (head/head_pockets.h: behind the lids, where the eyeball sits) as
// eye_sockets, else rest.
struct CrossingCounts {
  int total = 0, lips = 0, ears = 0, eye_sockets = 0, rest = 0;
  std::map<std::string, int> rest_by_region;  // "rest" pairs touching each named region (regions overlap)
};

struct FitQuality {
  int level = 0;                 // the finest level checked (L)
  int triangles = 0;             // of level L
  int flipped = 0;               // level-L triangles turned against the smooth (undisplaced) level L
  int degenerate = 0;            // level-L triangles of (near) zero area
  CrossingCounts crossings;      // level L, displaced
  CrossingCounts smooth_crossings;  // level L of the fitted control mesh without displacements
  int control_crossings = 0;     // pairs of the control mesh itself
};

// Pairs of mesh's level `level` (1..L; 0 is the control mesh) by region.
CrossingCounts count_crossings_by_region(const MultiresMesh& mesh, int level,
                                         const std::vector<std::array<int, 2>>& pairs,
                                         const HeadAnnotations& annotations);

// How many pairs have a triangle touching a level-`level` vertex of the
// region given by its control vertices (carried down the levels).
int count_pairs_touching(const MultiresMesh& mesh, int level, const std::vector<std::array<int, 2>>& pairs,
                         const std::vector<int>& control_vertices);

// Triangles of m whose normal points against the same triangle's of
// reference (same connectivity), and triangles of m whose area is below
// 1e-6 of m's mean triangle area.
void count_turned_and_degenerate(const TriMesh& m, const TriMesh& reference, int& flipped, int& degenerate);

// The flags measure_fit_to_scan (below) skips on the finest level: every vertex
// outside the named region (a new vertex when both its parents are; an
// empty name: none) and the pockets. InvalidInput as there.
Status finest_region_skip(const FitHeadResult& fit, const GenericHead& generic, const std::string& region,
                          std::vector<char>& skip);

// The other direction of Table 1: the finest level's vertices of a head
// region (given by name; pockets left out: no scanner sees them) to the
// scan, moved to the head frame, where scanned, in metres. A scan that
// came as a mesh is measured to its own triangles (fit/closest_point.h,
// surface_to_reference with inside_scan_mesh), a point cloud to the
// quadric patches of its points (surface_to_cloud; out.to_points) less the
// isolated ones the fit leaves out too (multires/displacement.h). "face"
// by default: the scans' hair, collars and shoulders are surfaces the head
// does not model. InvalidInput when the fit has no levels, the region is
// unknown or the scan holds non-finite positions.
// per_vertex (optional): the finest level's #V distances, -1 where a
// vertex is not counted (outside the region, a pocket, not scanned).
Status measure_fit_to_scan(const FitHeadResult& fit, const PointCloud& scan, const GenericHead& generic,
                           CoveredDistances& out, const std::string& region = "face",
                           std::vector<double>* per_vertex = nullptr);

// A distance map's colours (linear RGB, TriMesh::colors), one per entry of
// measure_fit_to_scan's per_vertex: near white up to 0.25 mm, yellow at
// 1 mm, red from 3 mm on, grey where nothing was measured.
std::vector<Vec3> distance_colors(const std::vector<double>& metres);

// All of FitQuality for a fit's finest level. InvalidInput when the result
// holds no levels or non-finite positions.
Status measure_fit_quality(const FitHeadResult& fit, const HeadAnnotations& annotations, FitQuality& out);

}  // namespace lk
