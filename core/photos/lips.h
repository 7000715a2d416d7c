// Lips that stay whole in a head made from photos (issue 37; issue 35's
// "the lips never tear or cross"). Not in fua1998. Two parts, each the
// photos counterpart of what the scan fit does (pipeline/fit_head.h):
//
// 1. Lip binding edges. The generic head's upper and lower lip lines are
//    0.3 mm apart; landmarks on each, with pixels of noise, moved them
//    independently and the smooth level 3 crossed (about 400 pairs). The
//    virtual lip edges of annotations.binding_edges (each upper line vertex
//    with the lower one under it, the scan fit's E_binding) are bound in the
//    shape fit (ShapeFitOptions::binding_edges): the two lips move together.
// 2. The mouth bag inside the mouth. At the mouth corners the bag's nearest
//    vertices sit 1.5 mm inside the corner, and the generic head's own
//    level 3 already crosses there (24 pairs); a fit that moves a corner
//    moves those crossings to other faces. So where the triangles of any
//    level 0..L over the bag (annotations.constrained_vertices, seen by no photo)
//    cross anything, the bag corners of the control faces under the pairs
//    and their bag neighbours are drawn towards the bag's centroid, step by
//    step (a share of each one's distance to it), until nothing crosses;
//    the step with the fewest such pairs is kept (ties: the smaller one).
//    (Carrying the whole bag with the lips first, as the scan fit does,
//    moved the bag more and measured worse: docs/design/photos.md.)
//
// Shapes: control #V (the generic head's triangles).
#pragma once
#include "common/status.h"
#include "head/head_model.h"

#include <array>
#include <vector>

namespace lk {

// The generic head's binding edges with both ends in its "lips" region.
std::vector<std::array<int, 2>> lip_binding_edges(const GenericHead& generic);

struct MouthBagOptions {
  int level = 3;              // the finest smooth level checked (1-4); 0: off
  double step_share = 0.005;  // each step draws the bag this share of the way to its centroid (half-steps:
                              // every level clear with the least draw, docs/design/photos.md)
  int max_steps = 20;         // at most 10 % of the way
  // Check every level 0..level, not the finest alone: the coarser levels
  // are exported too, and fits crossed there (over the bag below level 3;
  // the generic's own such pairs are on level 2 at the mouth corners)
  // where level 3 was clean (docs/design/photos.md, "No crossing at any
  // level").
  bool all_levels = true;
};

struct MouthBagResult {
  int pairs_before = 0;     // pairs with a triangle over the bag on the levels checked, as fitted
  int pairs_after = 0;
  double share = 0;         // the share of the way to the centroid kept (0: not drawn in)
};

// Draws the bag of `control` (fitted from generic.mesh) in as above. A head
// without a bag, or whose bag crosses nothing, is left as it is. Fails on a
// mesh of another size, bad options, or a mesh Butterfly cannot refine.
Status keep_mouth_bag_inside(const GenericHead& generic, const MouthBagOptions& options, TriMesh& control,
                             MouthBagResult& result);

}  // namespace lk
