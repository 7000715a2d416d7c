// The generic head's crease curves (head/head_model.h: the eye rims and the
// lip lines) as Butterfly creases (subdiv/butterfly.h), the one place the
// fit, the checks' helpers and the benchmarks take them from.
#pragma once
#include "head/head_model.h"
#include "mesh/topology.h"
#include "subdiv/butterfly.h"

namespace lk {

// Every HeadAnnotations::creases curve as tagged edges (open ends are
// corners), and each eye rim's two corners of the eye opening (the canthi:
// the rim vertices furthest along -x and +x in `mesh`, the head the
// annotations belong to, facing +z) as crease corners: the 4-point rule
// would otherwise carry the rim round the sharp corner in a smooth loop,
// which pleated the lids at James's outer eye corners (docs/journal.md,
// "The eye corners as crease corners"); and behind each rim its socket
// ring (the pocket's vertices next to the rim) as a crease too, so the
// refined lid margin, the strip between the two, depends on those rings
// alone and does not bulge into the eye's opening (docs/design/muscles.md,
// "The lids closed at level 2").
//
// The canthi are read off `mesh`'s positions, so a fitted head takes its
// generic head's creases (pass the generic head, as the scan fit does): on
// a fitted or turned head another rim vertex can lie furthest along x, and
// the head would then be refined with other corners than the ones its
// checks and its other levels used.
ButterflyCreases head_creases(const TriMesh& mesh, const HeadAnnotations& annotations);

// The same, with `mesh`'s topology already built.
ButterflyCreases head_creases(const TriMesh& mesh, const MeshTopology& topology, const HeadAnnotations& annotations);

}  // namespace lk
