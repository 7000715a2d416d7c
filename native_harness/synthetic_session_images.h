// The photos of a synthetic session rendered as `likeness synth-photos`
// writes them (the person's skin, Lambert light from each camera's upper
// left, a plain background), for the benchmarks that need pixels (stereo).
#pragma once
#include "calib/camera.h"
#include "head/generic_head.h"
#include "image/image.h"
#include "synth/skin_field.h"
#include "texture/synthetic_photo.h"

#include <algorithm>
#include <cstdint>
#include <vector>

namespace lk::cli {

inline bool render_session_images(const GenericHead& person, std::uint32_t seed, const std::vector<Camera>& cameras,
                                  std::vector<Image>& images) {
  SkinField skin;
  if (!make_skin_field(person, seed, {}, skin)) return false;
  images.clear();
  for (const Camera& cam : cameras) {
    const Vec3 light = (cam.R.transpose() * Vec3(-0.4, -0.6, -1.0)).normalized();
    Image photo;
    if (!render_synthetic_photo(
            person.mesh, cam,
            [&](const Vec3& p, const Vec3& nn) -> Vec3 {
              return skin_albedo(skin, p) * (0.35 + 0.65 * std::max(0.0, nn.dot(light)));
            },
            Vec3(0.55, 0.6, 0.65), photo))
      return false;
    images.push_back(std::move(photo));
  }
  return true;
}

}  // namespace lk::cli
