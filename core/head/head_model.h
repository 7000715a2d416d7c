// The generic head of jeong2002 (Sec. 4, Fig. 4): a hand-designed triangle
// control mesh plus its annotations. Data only; see generic_head.h for loading.
//
// Conventions: the head looks along +z, up is +y, +x is the head's LEFT side
// (the viewer's right in a frontal view). Units: metres, the generic head is
// about 0.24 m tall from chin to crown. The mesh is a topological disk: its
// only boundary loop runs around the neck. The eye openings and the mouth slit
// continue inwards as closed pockets (eye sockets where separate eyeball
// models sit; a mouth bag behind lips whose upper and lower vertices are
// distinct), so they add no boundary and one texture chart covers the head.
#pragma once
#include "mesh/tri_mesh.h"

#include <map>
#include <string>

namespace lk {

// Axis-aligned box around a feature (ear, nose, mouth) with its landmark
// vertices (3 per ear, 4 for nose and mouth) used for blending (Sec. 4.2).
struct FeatureBox {
  std::string name;  // "ear_left", "ear_right", "nose", "mouth"
  Vec3 min = Vec3::Zero(), max = Vec3::Zero();
  std::vector<int> landmarks;  // vertex indices into the generic mesh
  bool contains(const Vec3& p) const {
    return (p.array() >= min.array()).all() && (p.array() <= max.array()).all();
  }
};

// A clipping plane: points with dot(normal, p - point) < 0 are cut away.
struct ClipPlane {
  Vec3 point = Vec3::Zero();
  Vec3 normal = Vec3::UnitY();
  bool keeps(const Vec3& p) const { return normal.dot(p - point) >= 0; }
};

struct EyeSocket {
  Vec3 center = Vec3::Zero();   // eyeball centre
  double radius = 0.012;        // eyeball radius
  std::vector<int> rim;         // vertex loop of the eyelid opening (ordered)
};

// A crease curve of the control mesh (subdiv/butterfly.h, ButterflyCreases):
// a polyline of vertices joined by mesh edges along which the surface turns
// sharply (the eye rims and the lip lines, where the skin folds back into
// the pockets). Refined as a curve, with the two sides kept apart.
struct CreaseCurve {
  std::string name;           // "eye_rim_left", "eye_rim_right", "upper_lip_line", "lower_lip_line"
  std::vector<int> vertices;  // consecutive vertices share a mesh edge
  bool closed = false;        // closed: the last joins the first; open: the ends are corners
};

struct HeadAnnotations {
  std::vector<FeatureBox> boxes;                // ear_left, ear_right, nose, mouth
  std::vector<std::array<int, 2>> binding_edges;  // E_binding: mesh edges + virtual lip edges
  std::vector<int> constrained_vertices;        // E_constraint: inner lip / mouth bag vertices
  ClipPlane neck_clip;                          // removes the neck below it
  ClipPlane back_clip;                          // removes the back of the head (hair)
  Vec3 look = Vec3::UnitZ();
  Vec3 up = Vec3::UnitY();
  // Named vertex sets: "face", "scalp", "ears", "ear_left", "ear_right",
  // "ear_rim_left", "ear_rim_right" (the helix rims, within the ears; only
  // from the builder's ring ear),
  // "neck", "lips", "upper_lip", "lower_lip", "eye_rim_left", "eye_rim_right",
  // "nose", "brow", "jaw", "chin", "cheeks". Sets may overlap. "lips" holds
  // both lips, the mouth corners and the mouth bag; "upper_lip"/"lower_lip"
  // leave out the two corner vertices, which both lips share. "face"
  // includes the eye socket pockets and the mouth bag; "ears" does not touch
  // "face".
  std::map<std::string, std::vector<int>> regions;
  EyeSocket eye_left, eye_right;                // +x is left
  Vec3 mouth_center = Vec3::Zero();             // between the lips, for teeth/tongue
  double mouth_width = 0.05;
  std::vector<CreaseCurve> creases;             // rims refined as creases (may be empty)
};

struct GenericHead {
  TriMesh mesh;
  HeadAnnotations annotations;
  // The skin as cast, before its control vertices were faired on the shape
  // (the same shape, other samples; empty when the head was not faired):
  // what the initial alignment matches, so that the alignment's choices do
  // not hang on how the face's grid samples the shape.
  std::vector<Vec3> alignment_positions;
};

}  // namespace lk
