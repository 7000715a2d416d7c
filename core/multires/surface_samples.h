// Points on a scan's own triangles, for scans that come as meshes.
//
// jeong2002 measures displacements on dense point clouds. A scan that comes
// as a mesh (an OBJ from a face capture, a Cyberware VTK) is often far
// sparser than the level-3 mesh (James: 6.4k vertices 3-5 mm apart against
// level-3 edges of ~1.3 mm), so each level-3 vertex's height is a quadric
// fitted to a handful of samples several edges away, and neighbouring
// vertices disagree: the level-3 surface ripples where the scan is smooth.
// Its triangles say where the surface lies between the samples, so they are
// sampled as densely as the finest level needs and the samples join the
// points the displacements are measured on (the scan's own points stay the
// ones Table 1 is measured on).
//
// Sampling: each kept triangle (all three corners kept, no edge longer than
// max_edge_ratio x the median edge of the kept triangles: a triangle that
// bridges a hole or joins two sheets is not surface; and one edge at least
// longer than the spacing, else its corners are dense enough) is cut into n x n
// similar sub-triangles, n = ceil(longest edge / spacing), and each
// sub-triangle's centroid is a sample. No sample lies on an edge, so two
// triangles sharing one never duplicate a sample; the density is uniform.
// The samples lie on the triangle's Phong tessellation (Boubekeur & Alexa
// 2008, alpha 1/2, exact to second order on quadrics: the flat point blended with its projections on the
// corners' tangent planes, vertex normals from the kept triangles' areas),
// not on the flat triangle: a coarse scan's (Fran: 3.4 mm) flat facets
// would otherwise come out as facets on level 3.
// Normals (when the scan has them): the corners' normals interpolated.
//
// Shapes: positions #P by 3, normals #P by 3 or empty, faces #F by 3
// (indices into positions), keep #P flags.
#pragma once
#include "common/status.h"
#include "mesh/tri_mesh.h"

#include <vector>

namespace lk {

struct SurfaceSampleStats {
  int triangles_sampled = 0;
  int triangles_skipped_long = 0;  // an edge above the cap
  int triangles_dense = 0;         // no edge longer than the spacing: the corners suffice
  int samples = 0;
};

// Appends the samples to out.positions (and to out.normals when normals is
// #P and out.normals has one per position). Fails on indices out of range
// or non-positive spacing (InvalidInput), or with TooLarge when there would
// be more than max_samples samples; nothing is appended then.
Status sample_scan_surface(const std::vector<Vec3>& positions, const std::vector<Vec3>& normals,
                           const std::vector<Tri>& faces, const std::vector<char>& keep, double spacing,
                           double max_edge_ratio, int max_samples, PointCloud& out, SurfaceSampleStats& stats);

}  // namespace lk
