// Waters' (1987) geometric muscle models as displacement fields at unit
// contraction: a vertex's displacement is linear in the contraction, so a
// field computed once per head is scaled per pose (face_pose.h).
#pragma once
#include "anim/face_rig.h"

#include <functional>

namespace lk {

// A linear muscle: fixed to the bone at `attachment`, to the skin at
// `insertion`. Contracting pulls the skin in its cone (half-angle `cone`,
// radians, about the attachment -> insertion axis) towards the attachment:
// by `pull` x its length at the insertion, falling to 0 at the attachment
// (cos ramp) and `reach` beyond the insertion (cos ramp), and by the
// angle's cosine to the cone's edge.
struct LinearMuscle {
  Vec3 attachment = Vec3::Zero(), insertion = Vec3::UnitZ();
  double cone = 0.6;
  double reach = 0.02;
  double pull = 0.2;
};

// A sphincter about `center`: an ellipse of semi-axes (a, b) in the x-y
// plane; a vertex at elliptic radius rho < 1 moves by the falloff
// cos(pi/2 rho) times `squeeze` x its x-offset towards the centre, plus
// `protrude` metres along +z.
struct Sphincter {
  Vec3 center = Vec3::Zero();
  double a = 0.03, b = 0.02;
  double squeeze = 0.35;
  double protrude = 0.006;
  double depth = 0.02;  // vertices further than this behind the centre are left out
};

// The fields over positions; mask(v) in [0, 1] scales each vertex (a side of
// the lips, a region); vertices with a zero displacement are left out.
SparseField linear_muscle_field(const LinearMuscle& muscle, const std::vector<Vec3>& positions,
                                const std::function<double(int)>& mask);
SparseField sphincter_field(const Sphincter& sphincter, const std::vector<Vec3>& positions,
                            const std::function<double(int)>& mask);

// 3t^2 - 2t^3 on t clamped to [0, 1].
double smoothstep01(double t);

}  // namespace lk
