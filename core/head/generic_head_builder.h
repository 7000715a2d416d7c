// Procedural construction of the generic head control mesh of jeong2002
// (Sec. 4, Fig. 4: "hand-designed generic control mesh" with feature boxes,
// landmarks, binding edges, constrained lip vertices and clipping planes).
// The committed asset core/head/data/generic_head.{obj,json} is the output of
// this builder (`likeness make-generic-head`); the app loads the asset, so
// changing the builder changes nothing until the asset is regenerated.
//
// How the mesh is made, so it can be improved:
//  1. The head's shape is a smooth signed distance function (SDF): cranium,
//     jaw, chin, cheekbones, brow ridge, nose, lips, lid spheres, neck.
//  2. A quad grid of rings (under the jaw .. crown) x 40 meridians (denser
//     over the face) is placed on it by casting one ray per vertex; a 10 x 10
//     quad patch closes the crown without a pole. Below the grid the neck is
//     7 rings of 24 meridians down to the boundary, joined to the grid by a
//     strip of triangles, so its triangles are nearly isotropic.
//  3. Blocks of the grid around the eyes and the mouth are warped into
//     concentric ellipses (edge loops for animation). The eye openings are
//     4 x 1 holes continued inwards as closed pockets around the eyeballs;
//     the mouth is a slit (upper and lower lip vertices separate) continued
//     as a closed mouth bag (with nostrils, each nostril is an oval on the
//     nose's underside continued as a shallow closed pocket). Ears are a 2 x 6 grid patch extruded into a flap
//     with a rim and a real concavity behind it (or, with ring_ear, rings
//     from that patch's border out to a helix rim and in to a concha).
//  4. Quads are split along their better diagonal, except behind the ears
//     and down the neck, where all lean the same way on each side (a
//     chevron: valence 6); the result is made exactly mirror-symmetric
//     (x -> -x) and annotated.
//  5. Optionally (fair_iterations) the face's skin vertices are faired on the
//     shape (Taubin passes, each projected back onto it; rims, lip lines,
//     ear roots, midline and nose kept), so the Butterfly levels furrow less.
//
// Output shapes: mesh.positions #V by 3 (metres; +z look, +y up, +x = the
// head's left), mesh.triangles #F by 3 (counter-clockwise seen from outside).
// The mesh is a topological disk whose one boundary loop is the neck's bottom.
#pragma once
#include "common/status.h"
#include "head/head_model.h"

namespace lk {

struct GenericHeadBuildOptions {
  double eyeball_radius = 0.012;   // radius of the separate eyeball models (m)
  double socket_clearance = 0.0007;  // gap between eyeball and socket pocket (m)
  double lip_gap = 0.0003;         // distance between upper and lower lip vertices in
                                   // the closed pose (m); > 0 keeps them distinct
  int relax_iterations = 8;        // smoothing passes evening out the surface grid (0: none)
  bool ring_ear = false;           // true: ears made of rings round the concha (helix rim,
                                   // antihelix, concha; 1422 vertices); false: the plate ear
                                   // of the committed asset (1366). docs/journal.md
                                   // "A ring ear" says why it is not the asset's yet.
  bool even_eye_corners = true;    // true: the eye rings' four corners halfway (in angle)
                                   // between their neighbours, not at 45 deg of the square:
                                   // no 4.3-4.9 mm edges among 13-27 mm ones at the brow.
                                   // The asset's since 3a8dc46; false: the 45-degree corners
                                   // of the asset before. docs/journal.md "Even corners
                                   // of the eye rings" says what it fixes.
  bool even_back_rows = true;      // true: behind the ears the rows are spread evenly along
                                   // their meridians, not at the face's elevations (5 mm rows
                                   // against 17 mm meridians at the nape rippled into a crease
                                   // across the back of every head). docs/journal.md
                                   // "Even rows at the back".
  bool regular_nape = true;        // true: behind the ears and down the neck each quad is split
                                   // along the same-leaning diagonal (a chevron, mirrored), so
                                   // every vertex there has six neighbours but a few at the ears
                                   // and where head and neck join, and that joining strip is
                                   // deeper at the back (no slivers). false: quads split by
                                   // shape, 4- to 8-valent vertices at random: wavy lines
                                   // across the nape and where the skull meets the neck.
                                   // docs/journal.md "A regular nape".
  bool wide_mouth_ring = false;    // true: the first ring round the mouth reaches 8 mm past the
                                   // lip line's corners (4.5 mm in the asset): its smooth levels
                                   // no longer cross themselves at the mouth corners (8 pairs at
                                   // level 2, 24 at level 3 -> 0). Not the asset's yet: six
                                   // tests fail with it, among them Demosthenes' ears on the
                                   // real scans (docs/design/generic_head_measured.md).
  int fair_iterations = 0;         // Taubin passes evening out the face's skin control vertices on
                                   // the shape (rims, lip lines, ear roots, midline, nose kept).
                                   // 3: fewer furrows on the smooth level 3 at brows, cheeks and
                                   // mouth and no crossings at any level; not the asset's: with it
                                   // Demosthenes' ears cross (4 pairs), Gutenberg turned 0.05 deg
                                   // is refused, Fran's face alignment varies by seed
                                   // (docs/design/generic_head.md "Fairing the skin"). 0: as cast.
  int fair_keep_rim_rings = 0;     // with fair_iterations: this many rings of vertices round the eye
                                   // rims and lip lines kept as cast too (session 50, measured:
                                   // docs/design/generic_head.md). 0: only the rims and lines.
  bool nostrils = false;            // true: each nostril an oval opening on the nose's underside
                                   // (8 rim vertices inset into the quad between the columella and
                                   // column 1, rows 11-12) continued as a shallow closed pocket
                                   // ~4 mm deep; its rim a crease, the pocket the region
                                   // nostril_left/right (issue 35). false: the asset's two dimples.
                                   // Every other vertex is the asset's; docs/design/generic_head.md
                                   // "Nostrils" says what it measured and why it is not the asset's.
  bool teeth_mouth_bag = false;     // true: the mouth bag holds the placed teeth (core/components):
                                   // a vestibule in front of them at their full height and a back
                                   // and sides beyond them, the same 36 vertices. Not the asset's
                                   // yet: the rig's shapes and the fits do not keep the teeth
                                   // inside it (docs/design/muscles.md, "The mouth bag round the
                                   // teeth"). false: the asset's bag, which the teeth pass through.
  bool mirror_diagonals = true;    // true: each quad on the -x side is split as its mirror image
                                   // on +x is, so triangles mirror as vertices do (issue 35);
                                   // false: each side by shape, as before: 6 quads of each eye
                                   // pocket split the same way on both sides.
};

// Builds the generic head and its annotations. Fails with Internal if one of
// the construction invariants (disk topology, mirror symmetry) does not hold.
Status build_generic_head(const GenericHeadBuildOptions& options, GenericHead& out);

}  // namespace lk
