// One-chart parameterization of a disk-topology head over [0,1]^2 that
// minimizes the view-weighted L2 texture stretch (tarini2002 Sec. 3.1, with
// the stretch norm of Sander et al. 2001, "Texture mapping progressive
// meshes", Sec. 3):
//   per triangle T with 3-D area A'(T), the Jacobian of the map texture->3-D
//   has singular values Gamma >= gamma; L2(T) = sqrt((Gamma^2 + gamma^2) / 2);
//   L2(M) = sqrt( sum L2(T)^2 w(T) A'(T) / sum w(T) A'(T) ),
//   w(T) = 1 / (<N(T), V> + k), k in [1.01, 2] (view-dependent weight).
// Sign of V: the paper wants face triangles LARGER in the texture ("triangles
// on the face become larger ... backfacing triangles become smaller"). With
// Sander's stretch (texture -> surface; high stretch = too little texture
// space) that needs a large weight on the face, i.e. <N,V> = -1 there: V is
// the direction a viewer looks at the face, V = -look. We therefore use
// w(T) = 1 / (k - <N(T), look>); UvOptions::view holds the look direction.
// Stretch is reported after scaling the chart so its area equals the 3-D
// area (Sander's normalization), so 1 is the optimum (developable surfaces).
//
// Method: boundary (the neck loop) on a circle with arc-length spacing,
// Tutte/mean-value interior (sparse Cholesky/LU), then a global
// stretch-reweighted solve (Sander's per-triangle weights used as Laplacian
// weights, iteratively reweighted, free boundary) with a flip-safe line
// search, then vertex-wise nonlinear relaxation as in Sander et al.
// No step is accepted that flips a triangle or collapses its area.
//
// Shapes: mesh positions #V by 3, triangles #F by 3 (one boundary loop);
// uv #V by 2 in [0,1]^2.
#pragma once
#include "common/progress.h"
#include "common/status.h"
#include "mesh/tri_mesh.h"

#include <vector>

namespace lk {

struct UvOptions {
  Vec3 view = Vec3::UnitZ();   // the direction the head looks (+z for the generic head); V = -view
  double k = 1.2;              // weight parameter; the paper uses [1.01, 2]; very large = unweighted
  bool view_weighted = true;   // false: plain L2 stretch (w = 1)
  int global_iterations = 30;  // stretch-reweighted global solves
  int local_sweeps = 200;      // vertex-wise relaxation sweeps after the global phase
  double margin = 0.01;        // empty border in [0,1]^2 on each side
  // Optional: vertices of the "face" region, used only for
  // UvStats::face_texture_share / face_area_share. Empty = not reported.
  std::vector<int> face_vertices;
};

struct UvStats {
  double l2_stretch = 0;           // weighted L2(M) as in the paper (weights per options)
  double l2_stretch_unweighted = 0;  // Sander's L2(M) with w = 1
  double linf_stretch = 0;         // max over triangles of Gamma
  double face_texture_share = 0;   // fraction of the chart's area on face triangles
  double face_area_share = 0;      // fraction of the 3-D area on face triangles
  int flipped = 0;                 // triangles with non-positive texture area (must be 0)
  int iterations = 0;              // global iterations + local sweeps done
  long evaluations = 0;            // per-triangle stretch evaluations
  double initial_l2_stretch = 0;   // weighted L2(M) of the Tutte initial map
};

// Computes the full parameterization. Fails with InvalidInput on a mesh that
// is not a disk (no boundary, several loops, non-manifold) or has NaN or
// degenerate triangles; Cancelled when progress returns false.
Status parameterize_stretch(const TriMesh& mesh, const UvOptions& options, std::vector<Vec2>& uv,
                            UvStats& stats, const ProgressFn& progress = {});

// The initial map only: boundary on a circle, mean-value interior (Floater),
// normalized into [0,1]^2. Same failure modes as parameterize_stretch.
Status parameterize_tutte(const TriMesh& mesh, const UvOptions& options, std::vector<Vec2>& uv);

// Stretch statistics of any map uv (#V) of mesh (e.g. from another
// parameterizer), with the weights of options. Leaves iterations/evaluations
// and initial_l2_stretch at 0. Works on any triangle mesh (the disk check
// of the solvers is not needed to measure).
Status measure_stretch(const TriMesh& mesh, const std::vector<Vec2>& uv, const UvOptions& options,
                       UvStats& stats);

// Per-triangle Sander stretch (Gamma, gamma) after the area normalization
// above; #F entries, (inf, inf) for a flipped/degenerate texture triangle.
std::vector<Vec2> triangle_stretch(const TriMesh& mesh, const std::vector<Vec2>& uv);

}  // namespace lk
