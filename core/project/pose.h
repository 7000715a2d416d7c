// Animation of a head project (jeong2002 Sec. 6): brows up and jaw open by
// an amount in [0, 1], applied to the rest pose through the multires local
// update (only the moved vertices' support is recomputed).
#pragma once
#include "project/project.h"

namespace lk {

// The rig from the control mesh's regions (generic head annotations):
//  - brows: the "brow" region is lifted fully and the skin around it
//    follows with a smooth falloff (to zero at 3 % of the head's size), so
//    the forehead stretches instead of tearing at the region's edge;
//  - jaw: "lower_lip", "chin" and "jaw" rotate down rigidly about a hinge
//    at the jaw region's top back (the temporomandibular joint's place).
AnimationRig make_animation_rig(const TriMesh& control, const HeadAnnotations& annotations);

// amount in [0, 1] (NaN: 0), as every function here takes it.
double clamp_pose_amount(double amount);

// The jaw's opening angle (radians) and the brow lift (metres) at amount.
double jaw_angle(double amount);
double brow_lift(const AnimationRig& rig, double amount);

// The rig's moved control vertices (rig.moved) posed with the jaw open by
// jaw_amount and the brows up by brow_amount (each clamped to [0, 1]).
std::vector<Vec3> rig_targets(const AnimationRig& rig, double jaw_amount, double brow_amount);

// Poses the project: amount is clamped to [0, 1] (NaN: 0), levels up to
// max_level are updated (-1: all; the others are brought up to date by
// ensure_current before they are read). InvalidInput when the project has
// no fit or max_level is not a level.
Status pose_project(HeadProject& project, double amount, int max_level = -1,
                    UpdateFootprint* footprint = nullptr);

// Back at rest, every level current: the pose the checks, the texture and
// the distance map are of.
Status rest_pose(HeadProject& project);

// The jaw's rigid motion at amount, in the scan frame, as a 4x4 matrix:
// p' = A^-1 (c + R (A p + t - c) - t) with the scan -> head map (A, t), the
// rotation R about the pivot c. The parts riding on the jaw (lower teeth,
// tongue) follow it.
Mat4 jaw_motion(const HeadProject& project, double amount);

}  // namespace lk
