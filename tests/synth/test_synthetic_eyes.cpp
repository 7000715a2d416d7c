// The synthetic people's eyes (synth/synthetic_eyes.h) in their renders:
// eyeballs placed as the pipeline places them show through the lid opening,
// white round an iris of the seed's colour, and nowhere else.
#include "head/generic_head.h"
#include "synth/synthetic_eyes.h"
#include "synth/skin_field.h"
#include "synth/synth_head.h"
#include "texture/color.h"
#include "texture/synthetic_photo.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <set>

namespace lk {
namespace {

constexpr double kDeg = 3.14159265358979323846 / 180;

bool inside(const std::vector<Vec2>& poly, const Vec2& p) {
  bool in = false;
  for (size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++)
    if ((poly[i].y() > p.y()) != (poly[j].y() > p.y()) &&
        p.x() < poly[j].x() + (p.y() - poly[j].y()) * (poly[i].x() - poly[j].x()) / (poly[i].y() - poly[j].y()))
      in = !in;
  return in;
}

double distance_to(const std::vector<Vec2>& poly, const Vec2& p) {
  double best = 1e300;
  for (size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
    const Vec2 ab = poly[i] - poly[j];
    const double t = std::clamp((p - poly[j]).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
    best = std::min(best, (poly[j] + t * ab - p).norm());
  }
  return best;
}

Vec3 linear(const std::uint8_t* p) { return Vec3(srgb8_to_linear(p[0]), srgb8_to_linear(p[1]), srgb8_to_linear(p[2])); }

}  // namespace

TEST_CASE("synthetic eyes show in the lid opening of a frontal render, white round the iris, and nowhere else",
          "[photos][synth][eye]") {
  GenericHead generic, person;
  REQUIRE(load_generic_head(generic));
  for (std::uint32_t seed : {2u, 4u}) {
    REQUIRE(synthesize_head(generic, seed, SynthHeadOptions{}, person));
    SkinField skin;
    REQUIRE(make_skin_field(person, seed, {}, skin));
    SyntheticEyes eyes;
    REQUIRE(make_synthetic_eyes(person, generic, seed, {}, eyes));
    const ComponentPlacement& pl = eyes.placement;
    const Vec3 mid = 0.5 * (pl.eye_center[0] + pl.eye_center[1]);
    const Camera cam = look_at_camera(mid + Vec3(0, 0, 0.6), mid, Vec3::UnitY(), 1250, 1200, 1600);
    const auto skin_fn = [&](const Vec3& p, const Vec3&) { return skin_albedo(skin, p); };
    std::vector<SyntheticSphere> spheres;
    for (int e = 0; e < 2; ++e)
      spheres.push_back({pl.eye_center[e], pl.eye_radius[e],
                         [&, e](const Vec3& p, const Vec3&) { return synthetic_eye_albedo(eyes, e, p); }});
    Image with, without;
    REQUIRE(render_synthetic_photo(person.mesh, cam, skin_fn, Vec3(0.5, 0.5, 0.5), with, spheres));
    REQUIRE(render_synthetic_photo(person.mesh, cam, skin_fn, Vec3(0.5, 0.5, 0.5), without));
    const double iris_rad = SyntheticEyesOptions{}.iris_angle_deg * kDeg;
    const double pupil_rad = std::asin(SyntheticEyesOptions{}.pupil_ratio * std::sin(iris_rad));
    for (int e = 0; e < 2; ++e) {
      const EyeSocket& socket = e == 0 ? generic.annotations.eye_left : generic.annotations.eye_right;
      std::vector<Vec2> rim;
      for (int v : socket.rim) {
        Vec2 p = Vec2::Zero();
        REQUIRE(cam.project(person.mesh.positions[size_t(v)], p));
        rim.push_back(p);
      }
      Vec2 c = Vec2::Zero();
      REQUIRE(cam.project(pl.eye_center[e], c));
      const double r_px = pl.eye_radius[e] * cam.fx / cam.to_camera(pl.eye_center[e]).z();
      int inside_px = 0, eye_px = 0, outside_eye = 0, white = 0, iris = 0, iris_seen = 0, dark_pupil = 0;
      for (int y = int(c.y() - r_px - 2); y <= int(c.y() + r_px + 2); ++y)
        for (int x = int(c.x() - r_px - 2); x <= int(c.x() + r_px + 2); ++x) {
          const Vec2 p(x + 0.5, y + 0.5);
          const bool shows = linear(with.at(x, y)) != linear(without.at(x, y));
          const bool in = inside(rim, p);
          // Pixels on the rim's outline may go either way.
          if (distance_to(rim, p) < 1.5) continue;
          inside_px += in;
          eye_px += in && shows;
          outside_eye += !in && shows;
          if (!in || !shows) continue;
          // The sphere point this pixel sees, and its angle from the look (+z).
          const Vec3 o = cam.center();
          const Vec3 d = (cam.R.transpose() * Vec3((p.x() - cam.cx) / cam.fx, (p.y() - cam.cy) / cam.fy, 1)).normalized();
          const Vec3 oc = o - pl.eye_center[e];
          const double b = oc.dot(d), disc = b * b - (oc.squaredNorm() - pl.eye_radius[e] * pl.eye_radius[e]);
          REQUIRE(disc >= 0);
          const Vec3 q = o + (-b - std::sqrt(disc)) * d;
          const double angle = std::acos(std::clamp((q - pl.eye_center[e]).normalized().z(), -1.0, 1.0));
          const Vec3 rgb = linear(with.at(x, y));
          if (angle > iris_rad * 1.15) {
            // Sclera: bright and nearly grey (skin is saturated and below 0.7).
            white += rgb.minCoeff() > 0.45 && rgb.maxCoeff() < 1.3 * rgb.minCoeff();
          } else if (angle > pupil_rad * 1.3 && angle < iris_rad * 0.85) {
            ++iris_seen;
            // Iris: the seed's hue (within the texture's fibre and collarette
            // variation), darker than sclera.
            const Vec3 ic = eyes.iris_color;
            const double k = rgb.dot(ic) / ic.squaredNorm();
            iris += k > 0.5 && k < 2.0 && (rgb - k * ic).norm() < 0.25 * k * ic.norm() + 0.01;
          } else if (angle < pupil_rad * 0.7) {
            dark_pupil += rgb.maxCoeff() < 0.02;
          }
        }
      INFO("seed " << seed << " eye " << e << ": opening " << inside_px << " px, eye seen in " << eye_px
                   << ", outside " << outside_eye << ", white " << white << ", iris " << iris << " of "
                   << iris_seen << ", pupil " << dark_pupil);
      CHECK(inside_px > 200);
      CHECK(outside_eye == 0);
      // The eyeball fills the opening (no skin pocket shows).
      CHECK(eye_px > 0.95 * inside_px);
      CHECK(white > 0.15 * inside_px);
      CHECK(iris_seen > 0.15 * inside_px);
      CHECK(iris > 0.9 * iris_seen);
      CHECK(dark_pupil > 10);
    }
  }
}

TEST_CASE("synthetic eyes: the albedo is the eyeball texture's texel at the layout's angles, sclera behind",
          "[photos][synth][eye]") {
  GenericHead generic, person;
  REQUIRE(load_generic_head(generic));
  REQUIRE(synthesize_head(generic, 2, SynthHeadOptions{}, person));
  SyntheticEyes eyes;
  REQUIRE(make_synthetic_eyes(person, generic, 2, {}, eyes));
  const Image& t = eyes.texture;
  REQUIRE(t.width > 0);
  int compared = 0;
  for (int e = 0; e < 2; ++e)
    for (double theta = 0.5; theta < 180; theta += 3)
      for (double phi = -179; phi < 180; phi += 7) {
        const Vec3 d(std::sin(theta * kDeg) * std::cos(phi * kDeg), std::sin(theta * kDeg) * std::sin(phi * kDeg),
                     std::cos(theta * kDeg));
        // The layout (iris/iris.h) from the angles; behind the equator the
        // sclera texel at the disk's right edge.
        const double rho = theta / 90, u = 0.5 + 0.5 * rho * std::cos(phi * kDeg),
                     v = 0.5 - 0.5 * rho * std::sin(phi * kDeg);
        const double fx = u * t.width, fy = v * t.height;
        // A texel border within rounding of the direction: either side is right.
        if (rho < 1 && (std::abs(fx - std::round(fx)) < 1e-6 || std::abs(fy - std::round(fy)) < 1e-6)) continue;
        const std::uint8_t* want = rho >= 1 ? t.at(t.width - 1, t.height / 2) : t.at(int(fx), int(fy));
        INFO("eye " << e << " theta " << theta << " phi " << phi);
        CHECK(synthetic_eye_albedo(eyes, e, eyes.placement.eye_center[e] + eyes.placement.eye_radius[e] * d) ==
              linear(want));
        ++compared;
      }
  CHECK(compared > 3000);
}

TEST_CASE("synthetic eyes: the iris colour varies with the seed", "[photos][synth][eye]") {
  GenericHead generic, person;
  REQUIRE(load_generic_head(generic));
  std::set<std::tuple<int, int, int>> hues;
  for (std::uint32_t seed = 1; seed <= 8; ++seed) {
    REQUIRE(synthesize_head(generic, seed, SynthHeadOptions{}, person));
    SyntheticEyes eyes;
    REQUIRE(make_synthetic_eyes(person, generic, seed, {}, eyes));
    const Vec3 c = eyes.iris_color / eyes.iris_color.sum();
    hues.insert({int(std::lround(c.x() * 10)), int(std::lround(c.y() * 10)), int(std::lround(c.z() * 10))});
    // The eyes sit where place_components puts a fitted head's eyes.
    ComponentPlacement pl;
    REQUIRE(place_components(person, generic, pl));
    CHECK((pl.eye_center[0] - eyes.placement.eye_center[0]).norm() == 0.0);
    CHECK(pl.eye_radius[1] == eyes.placement.eye_radius[1]);
  }
  CHECK(hues.size() >= 3);
}

}  // namespace lk
