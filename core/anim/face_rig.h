// The face's muscle layer on a head with the generic head's topology (issue
// 38; jeong2002's animation by muscles on the control mesh, after Kähler et
// al. 2001 and Waters 1987): linear muscles and sphincters as displacement
// fields, the jaw turning about its hinge, the eyelids turning about the
// eyeballs' centres. Everything is derived from the generic head's
// annotations (regions, eye rims, lip lines) and the head's own positions,
// so a fitted control mesh inherits it. Head frame: +x the head's left, +y
// up, +z the face's front, metres. Design: docs/design/muscles.md.
#pragma once
#include "anim/face_controls.h"
#include "common/status.h"
#include "head/head_model.h"

#include <array>
#include <vector>

namespace lk {

// A per-vertex displacement at unit activation, on a few vertices.
struct SparseField {
  std::vector<int> index;
  std::vector<Vec3> delta;
};

// Control vertices the semantic checks and the contact rules read. Index 0
// of a pair is the head's left (+x), 1 its right.
struct FaceLandmarks {
  std::array<int, 2> mouth_corner{};
  std::vector<int> upper_lip_line, lower_lip_line;  // paired columns between the corners, by x
  int upper_lip_mid = 0, lower_lip_mid = 0;          // the lip-line pair nearest the midline
  int upper_lip_top = 0, lower_lip_bottom = 0;       // the lips' outer edges at the midline
  std::array<int, 2> upper_lip_side{}, lower_lip_side{};  // lip-line vertices halfway to each corner
  int chin = 0;                                      // the chin's lowest front vertex
  std::array<int, 2> brow_inner{}, brow_outer{}, nose_wing{}, cheek{};
  std::array<std::vector<int>, 2> upper_lid, lower_lid;  // eye rim halves, paired columns, corners first and last
};

// One eye's lids: every vertex that turns about the eye's centre, with its
// share (weight) and its column's gap (the angle between the upper and the
// lower rim there, radians).
struct EyeLids {
  Vec3 center = Vec3::Zero();
  double radius = 0.012;
  std::vector<int> index;
  std::vector<double> weight;  // 1 on the rim and the socket's first ring, falling to 0 outwards
  std::vector<double> gap;     // the column's rest gap angle (0 at the corners)
  std::vector<double> radial;  // the column's mean rim radius minus this lid's rim radius (metres)
  std::vector<double> shift;   // the column's mean rim x minus this lid's rim x (metres)
  std::vector<char> upper;     // 1: upper lid, 0: lower lid
  // Where the vertex sits in its column's opening at rest, as a share of the
  // angle from the lower rim (0) to the upper rim (1), clamped: 1 on and
  // above the upper rim, 0 on and below the lower rim. Closing maps the
  // opening onto the closed one, so no two vertices pass each other.
  std::vector<double> opening;
  // How much further than the others this vertex turns once the lids have
  // closed, as a factor on its closing turn: 1 but on the rims with a
  // LidSeal beyond today's (the rims then meet closer while the socket
  // rings behind keep the others' 4 % gap).
  std::vector<double> seal;
};

// How far the closed lids' rims close (docs/design/muscles.md, "The closed
// eye's light line"; an option, off by default): each rim column by `rim`
// of its rest gap, the corner columns (the canthi) by corner x rim; every
// other lid vertex keeps 0.96 (the 4 % light line). {0.96, 0.6} is the
// default rig. {0.995, 0.6} hides most of the line on the generic head and
// synthetic people with no new pair, but adds lid pairs and turned
// triangles on real scans' fits.
// The share of its rest gap a closed lid pair closes (the 4 % light line),
// and the share of a column's gap the corner columns (the canthi) close by.
constexpr double kLidClosedShare = 0.96;
constexpr double kCanthusGapShare = 0.6;

struct LidSeal {
  double rim = kLidClosedShare;
  double corner = kCanthusGapShare;
};

// The jaw: vertices with their share of its rigid motion.
struct JawRig {
  Vec3 hinge = Vec3::Zero();
  std::vector<int> index;
  std::vector<double> weight;
};

// The lips' contact: when a column's lower lip rises above its upper lip,
// the two sides part again by these weights (upper lip up, lower lip down).
struct LipContact {
  std::vector<double> column_x;  // the lip-line columns' x
  std::array<SparseField, 2> side;  // 0: upper lip (delta = unit weight in +y), 1: lower (-y)
};

struct FaceRig {
  std::vector<Vec3> rest;                 // the control mesh's rest positions
  std::vector<SparseField> field;         // kChannelCount; empty for the kinematic channels
  JawRig jaw;
  std::array<EyeLids, 2> lids;
  LipContact lips;
  FaceLandmarks landmarks;
  double eye_distance = 0.064;            // between the eyeballs' centres
  double scale = 1.0;                     // eye_distance / 64 mm: the rig's distances are the generic head's times this
  double mouth_width = 0.045;             // corner to corner
  Vec3 mouth_center = Vec3::Zero();
  std::vector<int> moved;                 // every vertex some channel moves, ascending
};

// The rig of a head with the generic head's topology (control.positions in
// the head frame; the eyeballs where components/components.h places them).
// InvalidInput when the mesh does not have the generic head's vertex count
// or a region, rim or lip line the rig needs is missing or malformed.
Status make_face_rig(const TriMesh& control, const GenericHead& generic, FaceRig& out, const LidSeal& seal = {});

// The jaw's hinge: at the head's middle in x, at the top and back of the
// lower lip, chin and jaw regions (the temporomandibular joint's place).
// Shared with the project's brow/jaw rig (project/pose.h).
Vec3 jaw_hinge(const std::vector<Vec3>& positions, const HeadAnnotations& annotations);

}  // namespace lk
