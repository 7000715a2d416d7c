// Untangling the fitted control mesh's smooth Butterfly surface before the
// displacements are measured (not in the papers; fit_head's step between
// global fitting and subdivision).
//
// The global fit's crossing guard sees only the control triangles; their
// Modified Butterfly surface can still cross itself where the fit bends the
// control mesh more sharply than the generic head. Crossing pairs count
// only when new: pairs of the smooth level K that the reference's (the
// aligned generic head's) level K does not have. Two steps, each kept only
// while it leaves fewer new pairs and turns (against the reference) and
// crosses no more control triangles than the mesh had:
//
// 1. Erosion. Two sheets pulled onto the same points (an ear's back and the
//    scalp behind it) face each other: the corners of the control faces
//    under the new pairs move erode_pct of the diagonal against their
//    vertex normals, up to `iterations` times (two steps in a row without
//    fewer pairs end it). With hinges_last, a first pass leaves out the
//    hinges, corners that are corners of the pair's other face or next to
//    one (the root of an ear lying on the scalp, where the sheets meet in a
//    wedge), and a second pass from its best moves all corners. A fold
//    within one sheet does not open this way.
// 2. Restore. A fold within one sheet (a face capture's outer eye corners:
//    the rim crease bent into the socket's first ring) is taken part of the
//    way back to the reference's
//    shape: the unpinned corners of the control faces under the pairs that
//    are left, grown by r rings, are solved for the reference's uniform
//    umbrella vectors with everything outside held (L(v) = L0(v) for v in
//    the region, Gauss-Seidel), and moved restore_share of the way there.
//    r starts at 0 and grows (up to restore_rings) whenever a step is not
//    kept. A full step is no good: the reference's umbrella vectors at a
//    corner that bends into a pocket push the skin through the pocket's
//    ring (far more pairs than a quarter of the way leaves). Each trial updates level K inside the moved vertices' support
//    (update_control_vertices) and searches only the level's triangles that
//    moved (on the first search's tree, refit).
//
// The displacements measured afterwards put the detail back.
#pragma once
#include "common/status.h"
#include "mesh/topology.h"
#include "mesh/tri_mesh.h"
#include "subdiv/butterfly.h"

#include <vector>

namespace lk {

struct UntangleOptions {
  int level = 2;               // K; 0: off
  int iterations = 6;          // erosion steps (0: no erosion)
  double erode_pct = 0.03;     // per step, percent of the diagonal
  bool hinges_last = true;     // a first erosion pass without the hinges
  int restore_rings = 4;       // restore's largest ring count (-1: no restore)
  double restore_share = 0.25; // of the way to the solved shape, in (0, 1]
};

struct UntangleResult {
  int pairs_before = 0;        // new pairs of the smooth level K at the start
  int pairs_eroded = 0;        // ... after the erosion
  int pairs_after = 0;         // ... at the end
  int restore_steps = 0;       // restore steps kept
  int restored_vertices = 0;   // control vertices a kept restore step moved
  std::vector<int> crossing_faces;  // control faces under the new pairs left at the end (sorted, unique)
};

// reference: the aligned generic head's positions (#V, same triangles as
// control); creases: the Butterfly creases of the fit; diagonal: the scan's
// bounding-box diagonal in the control mesh's units; topology: control's;
// pinned: #V flags of vertices never moved (may be empty). control is
// changed in place. Fails on size mismatches, bad options, or a mesh
// Butterfly cannot refine.
Status untangle_smooth_surface(const std::vector<Vec3>& reference, const ButterflyCreases& creases, double diagonal,
                               const MeshTopology& topology, const std::vector<char>& pinned,
                               const UntangleOptions& options, TriMesh& control, UntangleResult& result);

}  // namespace lk
