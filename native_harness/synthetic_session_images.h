// The photos of a synthetic session rendered as `likeness synth-photos`
// writes them (the person's skin and eyes, Lambert light from each camera's
// upper left, a plain background), for synth-photos and the benchmarks that
// need pixels (stereo).
#pragma once
#include "calib/camera.h"
#include "head/generic_head.h"
#include "image/image.h"
#include "synth/synthetic_eyes.h"
#include "synth/skin_field.h"
#include "texture/synthetic_photo.h"

#include <algorithm>
#include <cstdint>
#include <vector>

namespace lk::cli {

// One view: the skin on the head mesh, the eyeballs as spheres behind the lids.
inline Status render_session_image(const GenericHead& person, const SkinField& skin, const SyntheticEyes& eyes,
                                   const Camera& cam, Image& photo) {
  const Vec3 light = (cam.R.transpose() * Vec3(-0.4, -0.6, -1.0)).normalized();
  auto lit = [&](const Vec3& albedo, const Vec3& n) -> Vec3 { return albedo * (0.35 + 0.65 * std::max(0.0, n.dot(light))); };
  std::vector<SyntheticSphere> spheres;
  for (int e = 0; e < 2; ++e)
    spheres.push_back({eyes.placement.eye_center[e], eyes.placement.eye_radius[e],
                       [&, e](const Vec3& p, const Vec3& n) -> Vec3 { return lit(synthetic_eye_albedo(eyes, e, p), n); }});
  return render_synthetic_photo(
      person.mesh, cam, [&](const Vec3& p, const Vec3& n) -> Vec3 { return lit(skin_albedo(skin, p), n); },
      Vec3(0.55, 0.6, 0.65), photo, spheres);
}

inline bool render_session_images(const GenericHead& generic, const GenericHead& person, std::uint32_t seed,
                                  const std::vector<Camera>& cameras, std::vector<Image>& images) {
  SkinField skin;
  SyntheticEyes eyes;
  if (!make_skin_field(person, seed, {}, skin) || !make_synthetic_eyes(person, generic, seed, {}, eyes)) return false;
  images.clear();
  for (const Camera& cam : cameras) {
    Image photo;
    if (!render_session_image(person, skin, eyes, cam, photo)) return false;
    images.push_back(std::move(photo));
  }
  return true;
}

}  // namespace lk::cli
