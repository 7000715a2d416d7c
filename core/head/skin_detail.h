// The generic head's skin detail (issues 35 and 37): the shape its smooth
// levels leave out.
//
// Every control vertex of the generic head lies on the shape it was cast
// from (head_shape.h), but the interpolating Butterfly levels between them
// sag and bulge where the grid bends round the eyes and the mouth: the
// furrows over the brows, across the cheeks and along the jaw that every
// head shows where no data covers it (docs/design/generic_head.md, "Fairing
// the skin"). Measured level by level (level l displaced before level l+1
// is refined, as multires.h evaluates), each skin vertex's signed distance
// along its level's normal to the shape is a displacement that puts the
// levels back on it. A head whose levels no scan measured (a photos head)
// carries these displacements, so it shows the shape and not the furrows.
#pragma once
#include "common/status.h"
#include "head/head_model.h"
#include "multires/multires.h"

#include <vector>

namespace lk {

struct SkinDetailOptions {
  // A vertex's distance to the shape along its normal is its detail in
  // full up to half of this, tapering linearly to 0 at it (m); a vertex
  // whose normal runs along the shape keeps 0. Cut off hard at 2 mm, the
  // outer eye corners (where the shape's lid fold is sharp) kept the
  // levels' pleats.
  double max_distance = 0.003;
  // The detail fades in over this many rings of each level from the
  // vertices that take none.
  int fade_rings = 2;
  // Passes of averaging each level's detail with its one-ring.
  int smooth_passes = 2;
};

// detail: levels + 1 arrays (#V_l of the generic head's levels, built with
// head_creases); detail[0] is all 0 (the control vertices lie on the shape).
// Skin: every control vertex but the ears, the nose's lower half (its tip
// and wings; the bridge above and the base on the upper lip are skin), the
// pockets (eye sockets, mouth bag, nostrils: head_pockets.h), the neck's
// open border, the creases' vertices (eye rims, the lip lines, socket
// rings) and each mouth corner with its one-ring (there the refined corners
// of photos heads crossed); a refined vertex is skin when both ends of its
// edge are. Other vertices take 0. Why not the nose tip: a fit moves it
// most, and the cast shape's tip laid on another nose raised a knob (seen
// on Kira's photos head); left out, the bridge, the nose's base and the
// lips kept the levels' furrows and the lower lip's ledge.
Status generic_skin_detail(const GenericHead& head, int levels, const SkinDetailOptions& options,
                           std::vector<std::vector<double>>& detail);

// Sets mesh's displacements to detail level by level (levels of mesh beyond
// detail, and mesh.displacements[0], are set to 0) and evaluates it. Fails
// with InvalidInput when a level's size differs (another head's topology).
Status apply_skin_detail(const std::vector<std::vector<double>>& detail, MultiresMesh& mesh);

}  // namespace lk
