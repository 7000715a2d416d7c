#include "synth/synthetic_eyes.h"

#include "common/prng.h"
#include "iris/iris.h"
#include "texture/color.h"

#include <algorithm>
#include <cmath>

namespace lk {

namespace {

// Iris base colours people have (linear RGB): dark brown, brown, hazel,
// green, blue, grey.
const Vec3 kIrisColors[] = {Vec3(0.045, 0.022, 0.010), Vec3(0.13, 0.060, 0.022), Vec3(0.16, 0.11, 0.040),
                            Vec3(0.075, 0.12, 0.060), Vec3(0.060, 0.11, 0.22), Vec3(0.13, 0.15, 0.17)};

// The iris as a polar image (iris/iris.h): the seed's colour with radial
// fibres and a lighter ring round the pupil. eyeball_texture reads it as
// display values, so the colour is encoded.
PolarIris seeded_polar_iris(const Vec3& color, std::uint64_t seed) {
  PolarIris iris;
  iris.angles = 128;
  iris.radii = 24;
  iris.rgb.resize(static_cast<size_t>(iris.angles) * iris.radii * 3);
  iris.valid.assign(static_cast<size_t>(iris.angles) * iris.radii, 1);
  for (int a = 0; a < iris.angles; ++a) {
    const double fibre = 0.8 + 0.4 * (hash_mix(seed, static_cast<std::uint64_t>(a)) >> 11) * (1.0 / 9007199254740992.0);
    for (int r = 0; r < iris.radii; ++r) {
      const double t = (r + 0.5) / iris.radii;  // 0 at the pupil, 1 at the limbus
      const double collarette = t < 0.3 ? 1.35 : 1.0;
      const Vec3 c = (color * (fibre * collarette)).cwiseMin(1.0);
      float* px = iris.at(a, r);
      for (int k = 0; k < 3; ++k) px[k] = linear_to_srgb8(static_cast<float>(c[k])) / 255.0f;
    }
  }
  return iris;
}

}  // namespace

Status make_synthetic_eyes(const GenericHead& person, const GenericHead& generic, std::uint32_t seed,
                           const SyntheticEyesOptions& options, SyntheticEyes& out) {
  if (Status s = place_components(person, generic, out.placement); !s) return s;
  SplitMix64 rng(hash_mix(seed, 0xE7E5));
  const int n = static_cast<int>(sizeof(kIrisColors) / sizeof(kIrisColors[0]));
  const Vec3 base = kIrisColors[rng.below(n)];
  out.iris_color = base * rng.uniform(0.85, 1.15);
  EyeballTextureOptions to;
  to.size = options.texture_size;
  to.iris_angle_deg = options.iris_angle_deg;
  to.seed = static_cast<std::uint32_t>(hash_mix(seed, 0xE7E6));
  return eyeball_texture(seeded_polar_iris(out.iris_color, hash_mix(seed, 0xE7E7)), options.pupil_ratio, to,
                         out.texture);
}

Vec3 synthetic_eye_albedo(const SyntheticEyes& eyes, int e, const Vec3& point) {
  const Vec3 d = (point - eyes.placement.eye_center[e]).normalized();
  const Image& t = eyes.texture;
  if (eyeball_rho(d) >= 1 || t.width <= 0) {
    const std::uint8_t* p = t.width > 0 ? t.at(t.width - 1, t.height / 2) : nullptr;  // sclera
    return p ? Vec3(srgb8_to_linear(p[0]), srgb8_to_linear(p[1]), srgb8_to_linear(p[2])) : Vec3(0.8, 0.78, 0.75);
  }
  const Vec2 uv = eyeball_uv(d);
  const int x = std::clamp(static_cast<int>(uv.x() * t.width), 0, t.width - 1);
  const int y = std::clamp(static_cast<int>(uv.y() * t.height), 0, t.height - 1);
  const std::uint8_t* p = t.at(x, y);
  return Vec3(srgb8_to_linear(p[0]), srgb8_to_linear(p[1]), srgb8_to_linear(p[2]));
}

}  // namespace lk
