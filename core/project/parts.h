// The parts of tarini2002 Sec. 4 for a head project: generic eyeballs,
// teeth and tongue placed from the fitted control mesh (core/components),
// the lower teeth split off to ride on the jaw, and the textures they wear:
// an iris from an eye photo or a generic one, teeth from a smile photo or
// from the synthetic smile.
#pragma once
#include "components/components.h"
#include "iris/iris.h"
#include "project/project.h"
#include "teeth/teeth.h"

namespace lk {

struct HeadParts {
  ComponentPlacement placement;
  PlacedComponents placed;      // head frame
  TriMesh upper_teeth, lower_teeth;  // placed.teeth split at the bite plane (the mouth centre's height)
};

// The parts of a head with the generic head's connectivity (a fitted
// control mesh, or any mesh of it), with the generic head's annotations.
Status place_head_parts(const TriMesh& head, const GenericHead& generic, HeadParts& out);

// Splits a mesh by its triangles' centroids: below height y or not; each
// part keeps only its own vertices (and their uvs).
void split_below(const TriMesh& mesh, double y, TriMesh& above, TriMesh& below);

// A generic iris while no eye photo is given (Sec. 4.1 synthesizes one from
// a photo; this stands in for it): brown, radial streaks, darker towards
// the limbus, as a polar image.
PolarIris generic_polar_iris();

// The eyeball texture of the generic iris (pupil 0.35 of the iris).
Status generic_eyeball_texture(const EyeballTextureOptions& options, Image& texture);

// A smile photo -> (refused unless check_smile_closeup finds an open mouth
// in close-up) the teeth found (Sec. 4.2: classification, voids
// transparent, equalization, hidden parts) and, when composite is given,
// the composite texture in make_teeth_model's uv layout with the generic
// side teeth around them.
Status teeth_photo_texture(const Image& photo, const TeethOptions& options, TeethResult& teeth,
                           const TeethCompositeOptions* composite_options = nullptr, Image* composite = nullptr);

// The composite from the synthetic smile (lips hiding parts of two teeth,
// as `likeness teeth --synthetic-smile`): the teeth texture while no smile
// photo is given.
Status generic_teeth_texture(const TeethCompositeOptions& composite_options, Image& texture);

}  // namespace lk
