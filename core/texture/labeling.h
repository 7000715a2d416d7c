// One photo per texture region (after Lempitsky & Ivanov 2007, "Seamless
// mosaicing of image-based texture maps"): every case-1 triangle (resample.h)
// gets one of its common photos as its label, minimising
//   E = sum_f D_f(l_f) + lambda * sum_{f~g, l_f != l_g} (seam_floor + d_fg)
// with D_f(i) = 1 - <N, V_i> (prefers frontal views; N the corners'
// normals, optionally mixed with the face-scale normal, face_weight) and
// d_fg the disagreement of photos l_f and l_g: the largest mean absolute
// difference (linear RGB, sampled along mesh edges) over the edges within
// seam_radius of the shared edge. So
// boundaries go where the photos agree over a band wider than the
// misregistration, not across a brow nor between the two copies of it that
// a mm-off surface shows (there the photos agree on the edge itself).
// Case-2/3 triangles keep kRegionFilled and add no seam term.
// Minimised by alpha-expansion (one min cut per photo and cycle, Boykov,
// Veksler & Zabih 2001; the cut by Boost.Graph's boykov_kolmogorov_max_flow)
// from the largest-<N,V> labels of classify_triangles; d is a metric, so
// every move is exact and the energy never rises.
//
// Shapes: mesh #V / #F, photos #P (same order as the binding), region #F.
#pragma once
#include "common/status.h"
#include "mesh/tri_mesh.h"
#include "texture/binding.h"
#include "texture/resample.h"

#include <vector>

namespace lk {

struct LabelingOptions {
  double smoothness = 1.0;   // lambda: weight of a boundary edge against the data term
  double seam_floor = 0.05;  // cost of a boundary edge where the photos agree exactly
  int max_passes = 5;        // expansion cycles over all photos (stops when no label changes)
  int edge_samples = 5;      // photo samples along a mesh edge (ends included)
  // Band around a boundary edge over which the photos must agree, mesh
  // units (metres for the heads here): above the expected parallax of a
  // feature between two photos (surface error x tan of their angle).
  double seam_radius = 0.004;
  // Weight of the face-scale view direction in the data term: D_f(i) =
  // 1 - ((1 - w) mean_k <N(v_k), V_i> + w <N_face(f), V_i>), N_face the
  // normals Gaussian-averaged with sigma face_radius (mesh units) around f,
  // so where the nose, eyes and brows turn small patches towards side
  // photos, the photo most frontal to the face as a whole still wins them
  // (one photo over the central face; 0 = the per-triangle term alone).
  double face_weight = 1.0;
  double face_radius = 0.05;
  // Minimise by iterated conditional modes instead of alpha-expansion (the
  // baseline the tests hold the expansion against).
  bool icm = false;
};

struct LabelingReport {
  double energy_before = 0, energy_after = 0;
  int boundary_edges_before = 0, boundary_edges_after = 0;  // case-1 edges between two labels
  int passes = 0;  // expansion cycles run
  int triangles_changed = 0;
};

// region: #F, in: classify_triangles' region, out: the labelling. cases from
// classify_triangles. Fails with InvalidInput on inconsistent sizes.
Status label_regions(const TriMesh& mesh, const VertexBinding& binding, const std::vector<TexturePhoto>& photos,
                     const std::vector<TriangleCase>& cases, const LabelingOptions& options,
                     std::vector<int>& region, LabelingReport& report);

}  // namespace lk
