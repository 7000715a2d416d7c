// The named shapes of the muscle layer: ten expressions, Apple ARKit's 52
// blendshapes (exact names; "Left" is the face's own left, +x) and the 15
// visemes avatar and lip-sync tools use (../shared/FACE_NAMES.md). Each is a
// set of channel values (face_controls.h): data, not geometry.
#pragma once
#include "anim/face_controls.h"
#include "common/status.h"

#include <map>
#include <string>
#include <vector>

namespace lk {

const std::vector<std::string>& expression_names();  // neutral, smile, openMouth, ..., wink (10)
const std::vector<std::string>& arkit_names();       // eyeBlinkLeft ... tongueOut (52, ARKit's order)
const std::vector<std::string>& viseme_names();      // viseme_sil ... viseme_U (15, OVRLipSync's order)
// The three lists in that order (77 names).
const std::vector<std::string>& face_shape_names();

// The shape's channel values at full weight. InvalidInput naming the
// unknown shape otherwise.
Status face_shape(const std::string& name, FaceControls& out);

// Weights per shape name (each clamped to [0, 1]) summed into channel
// values (clamped to their ranges): what set_expression poses. InvalidInput
// on an unknown name.
Status face_controls_from_weights(const std::map<std::string, double>& weights, FaceControls& out);

}  // namespace lk
