// Folds a shape fit adds to the head (issue 37): the smooth level L of the
// fitted control mesh against the generic head's own level L, edge by edge.
// The generic head has furrows of its own (brow, nose, lids); what a fit
// must not do is crease the surface where the generic is smooth, so the
// figure is how much each level-L edge's dihedral angle grew, over regions
// chosen on the generic head (the same edges for every fit).
//
// Regions (control faces with all three corners in): face, cheeks, brow,
// nose (annotations), eyes (skin 1.2-22 mm outside an eyeball's socket
// sphere, as head/surface_quality.h; chosen at the generic's positions),
// lips (annotation), eye pockets (within 1.2 mm of the socket sphere:
// hidden behind the eyeballs). Crossings: level-L self-intersecting pairs
// (raycast/self_intersection.h) with a face in the region, the fit's and
// the generic's.
#pragma once
#include "common/status.h"
#include "head/head_model.h"

#include <string>
#include <vector>

namespace lk {

struct AddedFolds {
  std::string region;
  int edges = 0;
  double p95_deg = 0, max_deg = 0;  // growth of the dihedral angle over the generic's (deg; < 0 = smoother)
  int creased = 0;                  // edges whose angle grew by more than crease_deg
  int crossings = 0, generic_crossings = 0;  // level-L crossing pairs touching the region
};

// fitted: #V positions of the generic head's control mesh. level 1..4.
// Fails with InvalidInput on a size mismatch or a mesh Butterfly cannot refine.
Status measure_added_folds(const GenericHead& generic, const std::vector<Vec3>& fitted, int level,
                           double crease_deg, std::vector<AddedFolds>& out);

}  // namespace lk
