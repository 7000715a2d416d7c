// The generic head's pockets (head/head_model.h) as vertex flags: the eye
// sockets, which the eyeballs fill, the mouth bag behind the lips and the
// nostrils' pockets. The scanner never sees them (or little of a nostril):
// the fit does not displace them (fit_head.cpp), and the checks report their
// crossings apart (fit_quality.h).
#pragma once
#include "head/head_model.h"
#include "mesh/topology.h"

#include <vector>

namespace lk {

// The vertices a closed loop of the mesh cuts off from the rest of it: every
// connected piece of the mesh without the loop but the largest (the loop
// itself is not in it). #V flags (topo.num_vertices); none when the loop
// cuts nothing off.
std::vector<char> vertices_cut_off(const MeshTopology& topo, const std::vector<int>& loop);

// Each eye socket is the part of the mesh its rim loop (EyeSocket::rim)
// cuts off from the rest of the head; the rim itself is not in it. #V
// flags (topo.num_vertices); a rim that cuts nothing off gives no pocket.
std::vector<char> eye_socket_vertices(const MeshTopology& topo, const HeadAnnotations& ann);

// The eye sockets, the mouth bag (HeadAnnotations::constrained_vertices) and
// the nostrils' pockets where the head has them (regions nostril_left /
// nostril_right, GenericHeadBuildOptions::nostrils): a scan sees little of
// a nostril's inside, so like a socket it keeps its shape and follows its rim.
std::vector<char> pocket_vertices(const MeshTopology& topo, const HeadAnnotations& ann);

}  // namespace lk
