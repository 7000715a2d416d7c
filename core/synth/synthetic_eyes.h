// Eyes for the synthetic people's photos (issue 37): the detector marks a
// lid on a render only where it sees an eye, so `likeness synth-photos`
// draws each eyeball in its socket. The spheres are placed as the pipeline
// places a fitted head's eyes (components/components.h, place_components,
// from the rims), their colour is the eyeball texture of iris/iris.h
// (eyeball_texture: sclera, iris, limbus, pupil) with an iris whose hue is
// drawn per seed. The lids in front of them are the head mesh itself.
#pragma once
#include "common/status.h"
#include "components/components.h"
#include "head/head_model.h"
#include "image/image.h"

#include <cstdint>

namespace lk {

struct SyntheticEyesOptions {
  double iris_angle_deg = 30;  // limbus seen from the eyeball's centre (EyeballTextureOptions's default)
  double pupil_ratio = 0.35;   // pupil / iris radius (generic_eyeball_texture's)
  int texture_size = 512;
};

struct SyntheticEyes {
  ComponentPlacement placement;  // eye_center, eye_radius: 0 = left (+x), 1 = right
  Vec3 iris_color = Vec3::Zero();  // the iris's base colour (linear RGB), drawn per seed
  Image texture;                 // the eyeball texture (iris/iris.h layout, sRGB), one for both eyes
};

// Places the eyes in `person` (the generic head's topology, head frame: the
// eyes look along +z) and draws the iris. Fails as place_components does.
Status make_synthetic_eyes(const GenericHead& person, const GenericHead& generic, std::uint32_t seed,
                           const SyntheticEyesOptions& options, SyntheticEyes& out);

// Albedo (linear RGB) of eye `e` at a point on (or near) its sphere.
Vec3 synthetic_eye_albedo(const SyntheticEyes& eyes, int e, const Vec3& point);

}  // namespace lk
