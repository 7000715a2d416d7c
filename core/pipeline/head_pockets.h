// The generic head's pockets (head/head_model.h) as vertex flags: the eye
// sockets, which the eyeballs fill, and the mouth bag behind the lips. The
// scanner never sees them: the fit does not displace them (fit_head.cpp),
// and the checks report their crossings apart (fit_quality.h).
#pragma once
#include "head/head_model.h"
#include "mesh/topology.h"

#include <vector>

namespace lk {

// Each eye socket is the part of the mesh its rim loop (EyeSocket::rim)
// cuts off from the rest of the head; the rim itself is not in it. #V
// flags (topo.num_vertices); a rim that cuts nothing off gives no pocket.
std::vector<char> eye_socket_vertices(const MeshTopology& topo, const HeadAnnotations& ann);

// The eye sockets and the mouth bag (HeadAnnotations::constrained_vertices).
std::vector<char> pocket_vertices(const MeshTopology& topo, const HeadAnnotations& ann);

}  // namespace lk
