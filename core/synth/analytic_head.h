// An analytic stand-in for the generic head (jeong2002 Sec. 4): a lumpy
// ellipsoid with a nose, two ears and a neck opening, with annotations made
// from its parametrisation. Tests and the synthetic-data tools use it when
// the real generic head is not wanted; its features are simple enough that
// expectations (where shadows fall, which vertices are scalp) are known.
//
// Conventions as head_model.h: looks along +z, up +y, +x is the head's left,
// metres. About 0.16 m wide, 0.23 m tall, 0.2 m deep; a topological disk whose
// only boundary is the neck opening. Shapes: mesh #V by 3, #F by 3.
#pragma once
#include "head/head_model.h"

namespace lk {

struct AnalyticHeadOptions {
  int segments_around = 96;  // vertices per latitude ring (>= 8)
  int segments_down = 64;    // latitude rings from crown to neck opening (>= 8)
};

// Regions provided: face, scalp, ears, ear_left, ear_right, neck, lips,
// upper_lip, lower_lip, nose, brow, jaw, chin, cheeks; boxes ear_left,
// ear_right, nose, mouth; eye sockets (no rims), clip planes, mouth centre.
GenericHead analytic_head(const AnalyticHeadOptions& options = {});

}  // namespace lk
