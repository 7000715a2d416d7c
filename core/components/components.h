// Generic eyes, teeth arch and tongue (Tarini et al. 2002, Sec. 4 and
// Fig. 7/8), placed and scaled into a (fitted) head from its annotations.
//
// Model frames: +z forward (out of the face), +y up, +x the head's left.
// make_eyeball: unit sphere, per-vertex uvs in the eyeball texture layout of
//   iris/iris.h (eyeball_uv: azimuthal equidistant, frontal hemisphere; the
//   back hemisphere maps onto the rim, i.e. sclera).
// make_teeth_arch: upper and lower arches around a parabola, width 1 (x in
//   [-0.5, 0.5]), each a closed band; its uvs put the upper front teeth in the
//   texture's upper half and the lower ones in the lower half. A plain band:
//   superseded by make_teeth_model, kept for comparison.
// make_teeth_model: the paper's teeth model (Sec. 4.2, Fig. 7), see below.
// make_tongue: a flattened half-ellipsoid of length 1 along -z.
#pragma once
#include "common/status.h"
#include "head/head_model.h"
#include "mesh/tri_mesh.h"

#include <cstdint>
#include <vector>

namespace lk {

TriMesh make_eyeball(int rings = 16, int segments = 24);
TriMesh make_teeth_arch(int segments = 24);
TriMesh make_tongue(int rings = 8, int segments = 16);

// The paper's teeth model (Sec. 4.2): "the six middle teeth ... using a
// billboard", bent along the arch; "only the upper part of the lower teeth
// and the lower part of the upper ones is actually modeled as a billboard.
// The remaining parts ... smoothly gain some width as they go up and down";
// the side teeth are 3-D (a closed crown band of side_thickness); "the
// transition between the billboard (in the middle) and the 3D structure
// (left and right) is smooth".
//
// Frame as make_teeth_arch: arch width 1 (x in [-0.5, 0.5]), +y up, the bite
// plane at y = 0, the arch a parabola z = -depth * (2x)^2 (front at z = 0).
// Texture layout = teeth_composite_generic's (teeth/teeth.h): u is the
// normalized arc length along the arch (the six front teeth get the middle
// middle_width of it, the photo's region), v = 0.5 at the bite, 1 at the
// upper arch's gum end, 0 at the lower's (OBJ convention: v = 0 at the
// image's bottom row). The back sheet and caps reuse the front's (u, v).
struct TeethModelOptions {
  int segments = 48;               // rings along each arch (plus the two at the front/side boundaries)
  int rows = 8;                    // rings from the bite to the gum end
  double middle_width = 0.5;       // arc-length share of the six front teeth = TeethCompositeOptions::middle_width
  double depth = 0.6;              // arch depth, in arch widths
  double upper_height = 0.27;      // bite to the upper gum end (crowns ~75 % of it, gums beyond)
  double lower_height = 0.25;
  double side_thickness = 0.08;    // bucco-lingual thickness of the 3-D side teeth
  double billboard_fraction = 0.5; // front teeth: zero thickness from the bite to this share of the height
  double root_thickness = 0.05;    // front teeth: thickness they gain up to the gum end
  double transition = 0.08;        // arc-length share over which billboard and side teeth blend (at the canines)
  double lower_scale = 0.94;       // the lower arch is narrower ...
  double lower_inset = 0.03;       // ... and sits behind the upper one (overjet), arch widths
};

enum class TeethPart : std::uint8_t {
  Billboard = 0,    // zero-thickness front sheet of the six middle teeth
  FrontVolume = 1,  // the middle teeth where they gain width (front, back and caps)
  Side = 2,         // the 3-D side teeth
};

struct TeethModel {
  TriMesh mesh;                 // positions, uvs (per vertex)
  std::vector<TeethPart> part;  // #F
};

TeethModel make_teeth_model(const TeethModelOptions& options = {});

struct ComponentPlacement {
  Vec3 eye_center[2] = {Vec3::Zero(), Vec3::Zero()};  // 0 = left (+x), 1 = right
  double eye_radius[2] = {0, 0};
  Vec3 mouth_center = Vec3::Zero();  // the bite plane's middle, behind the lips
  double mouth_width = 0;
  double teeth_height[2] = {1, 1};   // upper, lower arch: height over the generic relation (<= 1)
};

// Placement from the fitted head's annotated vertices, so it follows the
// fitted geometry. Eyes: each keeps its offset from the centroid of its rim
// in the generic head, scaled by the ratio of the rim's size (mean distance
// to its centroid) fitted/generic. Mouth (teeth, tongue): from the fitted
// lip lines and mouth bag, each measure keeping the generic head's relation
// to its own feature: across from the slit between the lips, depth behind
// the lip lines' rearmost vertex, size from the corners' distance, and each
// arch cut short where the fitted lip and chin skin in front of it comes
// nearer than half the generic head's least clearance.
// Both heads must share the generic head's topology and be in the head frame.
Status place_components(const GenericHead& fitted, const GenericHead& generic, ComponentPlacement& out);

// The three meshes moved into the head: eyes (2), teeth (make_teeth_model), tongue.
struct PlacedComponents {
  TriMesh eye[2], teeth, tongue;
};
PlacedComponents build_placed_components(const ComponentPlacement& placement);

}  // namespace lk
