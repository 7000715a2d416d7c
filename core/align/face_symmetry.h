// The yaw at which a scanned face looks most mirror-symmetric, seen from
// in front of an aligned generic face.
//
// Not from the papers. A bust whose head is turned on its shoulders (and a
// beard and a beret that carry face-like surface) can leave the face's
// closest-point match 20 deg short of the head's turn
// (docs/design/fit_real_scans.md, Gutenberg); a face is close to
// mirror-symmetric, so the turn that makes the scan's relief in front of
// the aligned face symmetric says how far the match is off. With
// FaceRefineOptions::symmetry_yaw_start (face_refine.h, off by default)
// the face's match tries that turn as a start and prefers pitch candidates
// whose face is symmetric; `likeness bench --only fit-real` prints it per
// scan. The scan is
// drawn as a height map along views
// turned about the face's vertical axis (orthographic, the first surface hit;
// a raw cloud's points splatted, the front-most kept) over the cells the
// face's samples cover, each map less its best quadric (the head's
// roundness) and clipped at clip_sigmas robust sigmas;
// its symmetry is the correlation of the map with its mirror image about a
// vertical midline, the best over midlines shifted across the face.
//
// Inputs are in the scan's frame: the aligned generic face's samples
// (e.g. upper_face_samples mapped by the alignment), the aligned face's
// viewing direction (toward the viewer) and up, the scan as a BVH (a mesh)
// or as points (surface empty).
#pragma once
#include "common/status.h"
#include "common/types.h"
#include "head/head_model.h"
#include "mesh/tri_mesh.h"
#include "raycast/bvh.h"

#include <vector>

namespace lk {

struct FaceSymmetryOptions {
  double yaw_range_deg = 45.0;    // views turned -range..range about the face's up
  double yaw_step_deg = 2.5;
  int cells_across = 40;          // height-map cells across the face's width
  double margin = 0.15;           // the map reaches this share of the face's size beyond it on each side
  double max_midline_shift = 0.15;  // midlines searched within this share of the width of the centre
  double clip_sigmas = 2.5;       // relief clipped at this many robust sigmas
  double min_paired = 0.3;        // a midline counts when this share of the cells pairs with its mirror
};

struct FaceSymmetry {
  double yaw_deg = 0;        // the most symmetric view's turn (about up, right-handed)
  double midline_shift = 0;  // its midline, across the face from the samples' centre (scan units)
  double score = -2;         // its correlation with the mirror image (-1..1; -2: no view paired enough cells)
  std::vector<double> yaws_deg, scores;  // every view tried and its best correlation
};

// Errors: InvalidInput (fewer than 10 samples, non-finite or parallel
// directions, bad options), Empty (no view drew enough of the scan to pair).
Status face_symmetry_yaw(const std::vector<Vec3>& face_samples, const Vec3& view, const Vec3& up,
                         const MeshBvh& surface, const std::vector<Vec3>& cloud, const FaceSymmetryOptions& options,
                         FaceSymmetry& out);

// The same, for a generic head aligned to a scan (world point = linear *
// generic point + translation): its upper face's samples (face_refine.h,
// upper_face_samples) seen along the aligned face; the scan as its
// triangles (faces over cloud) or, with faces empty, its points.
Status face_symmetry_of_alignment(const TriMesh& generic, const HeadAnnotations& ann, const std::vector<Vec3>& cloud,
                                  const std::vector<Tri>& faces, const Mat3& linear, const Vec3& translation,
                                  const FaceSymmetryOptions& options, FaceSymmetry& out);

}  // namespace lk
