// Posing the control mesh from channel values (face_controls.h), and the
// multiresolution head following it by the local update (jeong2002 Sec. 6).
#pragma once
#include "anim/face_rig.h"
#include "multires/multires.h"

namespace lk {

// The control mesh's positions (#V) at controls (clamped to their ranges):
// the muscle fields scaled by their activations, then the jaw's rigid
// motion blended by its weights, then the lids turned about the eyes'
// centres (a lid vertex keeps its distance to the centre: it slides over
// the eyeball), then the lips' contact. All channels zero: rig.rest exactly.
std::vector<Vec3> pose_face(const FaceRig& rig, const FaceControls& controls);

// Poses a multiresolution head whose level 0 is the rig's mesh: the
// vertices of rig.moved whose position changes go to pose_face's positions
// and levels up to max_level (-1: all) are recomputed inside their support
// only.
Status pose_multires(MultiresMesh& mesh, const FaceRig& rig, const FaceControls& controls, int max_level = -1,
                     UpdateFootprint* footprint = nullptr);

// The eye's turn (0 = left, 1 = right) for the gaze channels: yaw about +y
// (towards the head's left), pitch about the eye's x axis (up).
Mat3 eye_rotation(const FaceControls& controls, int eye);

// The jaw's rigid motion at controls (head frame): p -> R (p - hinge) + hinge + t.
void jaw_motion(const FaceRig& rig, const FaceControls& controls, Mat3& R, Vec3& t);

}  // namespace lk

namespace lk {

// Parts that ride on the face (head frame positions in, posed positions
// out): an eyeball turned about its centre by eye_rotation; the lower teeth
// by the jaw's motion; the tongue by the jaw's motion after tongue_out has
// pushed it forward (its tip, the front along +z, until it passes the
// lower lip's front by 12 mm, at least 2 cm; its root stays).
std::vector<Vec3> pose_eye(const FaceRig& rig, const std::vector<Vec3>& eye, const FaceControls& controls, int eye_index);
std::vector<Vec3> pose_lower_teeth(const FaceRig& rig, const std::vector<Vec3>& teeth, const FaceControls& controls);
std::vector<Vec3> pose_tongue(const FaceRig& rig, const std::vector<Vec3>& tongue, const FaceControls& controls);

}  // namespace lk
