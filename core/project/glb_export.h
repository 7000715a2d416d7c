// A head project as one GLB (glTF 2.0 binary) for avatar tools and
// viewers (issue 38's export): the head at a chosen level with its uvs and
// skin, the eyeballs, upper and lower teeth and tongue as their own meshes
// with their textures, and a small skeleton (Neck > Head > LeftEye,
// RightEye, UpperTeeth, Jaw > LowerTeeth, Tongue) whose eye and jaw joints
// sit at the eyes' centres and the jaw's hinge. The head mesh (node
// HeadMesh, at the root) is skinned to Neck, Head and Jaw, so a tool that
// turns bones turns the head, bends the neck and opens the mouth; the eyes,
// teeth and tongue ride their nodes. Head frame, metres, +y up, the face
// towards +z (glTF's front). At rest, with every expression, ARKit
// blendshape and viseme of the muscle layer (anim/face_shapes.h) as a morph
// target of the head, baked on its level (sparse where that is smaller);
// the eyes carry the gaze shapes, the lower teeth and tongue the shapes that
// move the jaw or the tongue, under the same names. With the talking demo,
// a blink and a gaze as glTF animations: weights channels (CUBICSPLINE:
// exactly the page's curves) on every mesh that has targets the clip
// drives, except the eyeballs, which Gaze turns by their joints' rotations.
#pragma once
#include "anim/speech.h"
#include "head/head_model.h"
#include "image/image.h"
#include "io/io.h"
#include "project/project.h"

#include <string>
#include <vector>

namespace lk {

struct GlbExportOptions {
  int level = 2;          // the head's level (0 = the control mesh); clamped to the levels there are
  Image eye_texture;      // the eyeballs' texture (parts.h: generic_eyeball_texture); empty: white
  Image teeth_texture;    // RGBA, voids transparent (generic_teeth_texture); empty: ivory
  // glTF animations (anim/clips.h: Talk, Blink, Gaze), for
  // viewers that only play clips (model-viewer cannot set single weights).
  bool animations = true;
  // Words the head says, as one more animation named "Say" (anim/clips.h
  // speech_clip), with or without the others; no visemes: none.
  Speech say;
};

// The generic eyeball (256 px) and teeth (512 x 256) textures the page
// shows, into options; a texture that cannot be made is left empty (plain).
void use_generic_part_textures(GlbExportOptions& options);

struct GlbExportReport {
  int level = 0;
  int head_vertices = 0, head_triangles = 0;
  std::vector<std::string> nodes;  // in file order
  int head_targets = 0;            // morph targets on the head
  std::vector<std::string> animations;  // the clips written, in file order
};

// The GLB bytes. Puts the project at rest first. InvalidInput without a
// fit; the parts left out (with a reason in report) when they cannot be placed.
Status export_glb(HeadProject& project, const GenericHead& generic, const GlbExportOptions& options, Bytes& out,
                  GlbExportReport* report = nullptr);

}  // namespace lk
