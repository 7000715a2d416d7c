// How clean the generic head's smooth surface is (issue 35): the smooth
// Modified Butterfly levels of a control mesh, refined with the creases its
// levels are refined with (head/head_creases.h), measured for what a person
// would notice.
//  - Roughness per region: the angle between the normals of adjacent
//    level-L triangles whose control ancestors both lie in the region. A
//    smooth head with ~2 mm triangles turns by a few degrees per edge; folds,
//    creases and ledges are the tail (p99, max).
//  - Crossings: self-intersecting triangle pairs (raycast/self_intersection.h)
//    of every level 0..L.
// Regions (control faces, all three corners in): cheeks, brow, nose ("cheeks",
// "brow", "nose" of the annotations; the nose without the nostril pockets,
// "nostril_left" / "nostril_right", where there are any), eyes (skin within 22 mm of an eyeball
// centre, the socket pocket left out), mouth ("lips" without the mouth bag),
// ears ("ears").
#pragma once
#include "common/status.h"
#include "head/head_model.h"
#include "subdiv/butterfly.h"

#include <string>
#include <vector>

namespace lk {

struct RegionRoughness {
  std::string region;
  int edges = 0;           // level-L edges measured (both faces in the region)
  double mean_deg = 0, p95_deg = 0, p99_deg = 0, max_deg = 0;
};

struct HeadSurfaceQuality {
  int level = 3;
  std::vector<RegionRoughness> regions;  // cheeks, brow, nose, eyes, mouth, ears
  std::vector<int> crossing_pairs;       // level 0..L
};

// Refines head.mesh smoothly to `level` (1..4) with `creases` and measures
// it; with `detail`, its levels displaced by it (head/skin_detail.h,
// apply_skin_detail). Fails with InvalidInput on a mesh Butterfly cannot
// refine, annotations that name no such region or a detail of another
// topology.
Status measure_head_surface(const GenericHead& head, const ButterflyCreases& creases, int level,
                            HeadSurfaceQuality& out, const std::vector<std::vector<double>>* detail = nullptr);

// The same with the head's own creases (head/head_creases.h: its rims,
// canthi and socket rings, as its levels are refined). A fitted head is
// measured with its generic head's creases, the overload above.
Status measure_head_surface(const GenericHead& head, int level, HeadSurfaceQuality& out);

// The dihedral angles (deg, sorted) between adjacent triangles of `mesh`
// whose faces are both flagged in `face_in` (#F); the measure above, on one
// mesh. Edges with one face, or non-manifold ones, are skipped.
std::vector<double> dihedral_angles(const TriMesh& mesh, const std::vector<char>& face_in);

}  // namespace lk
