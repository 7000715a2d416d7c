// The iris found in a head's own photos (project/eye_from_views.h): photos
// painted with a known light-blue iris where a known camera sees the
// generic head's eyeballs, through a head frame that is not the identity.
#include "project/eye_from_views.h"
#include "project/parts.h"
#include "test_scan.h"

#include <catch2/catch.hpp>

#include <cmath>

using namespace lk;

namespace {

constexpr double kPi = 3.14159265358979323846;

// A camera at `eye` looking at `target` (+y up in the scan frame), image w x h.
Camera look_at(const Vec3& eye, const Vec3& target, double focal, int w, int h) {
  const Vec3 f = (target - eye).normalized();
  const Vec3 right = f.cross(Vec3(0, 1, 0)).normalized();
  const Vec3 down = f.cross(right);
  Camera c;
  c.fx = c.fy = focal;
  c.cx = w / 2.0;
  c.cy = h / 2.0;
  c.width = w;
  c.height = h;
  c.R.row(0) = right.transpose();
  c.R.row(1) = down.transpose();
  c.R.row(2) = f.transpose();
  c.t = -c.R * eye;
  return c;
}

struct Scene {
  HeadFrame frame;
  HeadParts parts;
  Vec3 front = Vec3::Zero();  // the head's forward direction, scan frame
  Vec3 centre = Vec3::Zero(); // between the eyes, scan frame
};

Scene make_scene() {
  const GenericHead& g = test::generic_head();
  Scene s;
  const double a = 10 * kPi / 180;
  Mat3 ry;
  ry << std::cos(a), 0, std::sin(a), 0, 1, 0, -std::sin(a), 0, std::cos(a);
  s.frame.head_to_scan = 0.9 * ry;
  s.frame.head_offset = Vec3(0.01, -0.02, 0.03);
  REQUIRE(place_head_parts(g.mesh, g, s.parts).ok());
  s.front = (s.frame.to_scan(Vec3(0, 0, 1)) - s.frame.to_scan(Vec3::Zero())).normalized();
  s.centre = s.frame.to_scan(0.5 * (s.parts.placement.eye_center[0] + s.parts.placement.eye_center[1]));
  return s;
}

// Skin, with each eye seen by cam painted: a white sclera ellipse, a
// light-blue iris of radius iris_fraction x the eyeball's radius in
// pixels, a dark pupil. Gives back each eye's projected centre and iris radius.
Image paint(const Scene& s, const Camera& cam, double iris_fraction, Vec2 centre_px[2], double iris_px[2]) {
  Image im = Image::make(cam.width, cam.height, 3);
  for (size_t i = 0; i < im.pixels.size(); i += 3) {
    im.pixels[i] = 205;
    im.pixels[i + 1] = 160;
    im.pixels[i + 2] = 135;
  }
  for (int e = 0; e < 2; ++e) {
    const Vec3 c = s.frame.to_scan(s.parts.placement.eye_center[e]);
    const Vec3 side = s.frame.to_scan(s.parts.placement.eye_center[e] + Vec3(s.parts.placement.eye_radius[e], 0, 0));
    Vec2 p, q;
    REQUIRE(cam.project(c, p));
    REQUIRE(cam.project(side, q));
    const double ball = (q - p).norm();
    centre_px[e] = p;
    iris_px[e] = iris_fraction * ball;
    const double r = iris_px[e];
    for (int y = std::max(0, int(p.y() - 2 * ball)); y < std::min(cam.height, int(p.y() + 2 * ball)); ++y)
      for (int x = std::max(0, int(p.x() - 2 * ball)); x < std::min(cam.width, int(p.x() + 2 * ball)); ++x) {
        const double dx = x - p.x(), dy = y - p.y(), d = std::hypot(dx, dy);
        std::uint8_t* px = im.at(x, y);
        if (std::hypot(dx / 2.2, dy / 1.1) < r) { px[0] = 235; px[1] = 232; px[2] = 228; }
        if (d < r) {
          const double v = 0.85 + 0.15 * std::sin(9 * std::atan2(dy, dx));
          px[0] = std::uint8_t(90 * v); px[1] = std::uint8_t(140 * v); px[2] = std::uint8_t(200 * v);
        }
        if (d < 0.35 * r) { px[0] = px[1] = px[2] = 12; }
      }
  }
  return im;
}

}  // namespace

TEST_CASE("eye from views: the iris is found where the frontal camera sees the eyeball, its colour kept") {
  const GenericHead& g = test::generic_head();
  const Scene s = make_scene();
  const int w = 1200, h = 1600;
  // A frontal camera 0.5 m away and one 70 degrees round to the side.
  const Camera front = look_at(s.centre + 0.5 * s.front, s.centre, 3000, w, h);
  const Vec3 side_dir = (s.front * std::cos(70 * kPi / 180) + s.front.cross(Vec3(0, 1, 0)).normalized() * std::sin(70 * kPi / 180));
  const Camera side = look_at(s.centre + 0.5 * side_dir, s.centre, 3000, w, h);
  Vec2 centre_px[2], side_centre[2];
  double iris_px[2], side_iris[2];
  const double fraction = 0.52;
  const Image front_image = paint(s, front, fraction, centre_px, iris_px);
  const Image side_image = paint(s, side, fraction, side_centre, side_iris);

  EyeFromViewsResult out;
  const Status st = eye_texture_from_views(g.mesh, g, s.frame, {&side_image, &front_image}, {side, front},
                                           {"side.jpg", "front.jpg"}, EyeFromViewsOptions{}, out);
  INFO(st.message);
  REQUIRE(st.ok());
  CHECK(out.photo == 1);  // the side camera is 70 deg round: never tried
  REQUIRE((out.eye == 0 || out.eye == 1));
  INFO("found " << out.circle.center.transpose() << " r " << out.circle.radius << ", painted "
                << centre_px[out.eye].transpose() << " r " << iris_px[out.eye]);
  // (The lateral arcs place the centre less sharply up and down.)
  CHECK((out.circle.center - centre_px[out.eye]).norm() < 2.0);
  CHECK(std::abs(out.circle.radius - iris_px[out.eye]) < 1.5);
  CHECK(out.view_angle_deg < 10);
  // The iris's size on the eyeball: asin(0.52) = 31.3 deg.
  CHECK(std::abs(out.iris_angle_deg - std::asin(fraction) * 180 / kPi) < 2.5);
  // The texture's iris is the painted light blue (blue well over red), not
  // the generic brown: sampled on a ring at 0.7 of the iris's angular radius.
  REQUIRE(out.texture.width > 0);
  const double rho = 0.7 * out.iris_angle_deg / 90;
  double rgb[3] = {0, 0, 0};
  for (int i = 0; i < 64; ++i) {
    const double phi = 2 * kPi * i / 64;
    const int x = int((0.5 + 0.5 * rho * std::cos(phi)) * out.texture.width);
    const int y = int((0.5 - 0.5 * rho * std::sin(phi)) * out.texture.height);
    for (int k = 0; k < 3; ++k) rgb[k] += out.texture.at(x, y)[k] / 64.0;
  }
  INFO("iris ring colour " << rgb[0] << " " << rgb[1] << " " << rgb[2]);
  CHECK(rgb[2] > rgb[0] + 50);
  CHECK(rgb[1] > rgb[0] + 20);

  // The generic iris on the same ring is brown, red well over blue (the
  // browser flow real-photos tells the two apart by this).
  Image generic_eye;
  EyeballTextureOptions eo;
  eo.size = 256;
  REQUIRE(generic_eyeball_texture(eo, generic_eye).ok());
  double g_rgb[3] = {0, 0, 0};
  const double g_rho = 0.7 * 30 / 90;
  for (int i = 0; i < 64; ++i) {
    const double phi = 2 * kPi * i / 64;
    const int x = int((0.5 + 0.5 * g_rho * std::cos(phi)) * generic_eye.width);
    const int y = int((0.5 - 0.5 * g_rho * std::sin(phi)) * generic_eye.height);
    for (int k = 0; k < 3; ++k) g_rgb[k] += generic_eye.at(x, y)[k] / 64.0;
  }
  INFO("generic iris ring colour " << g_rgb[0] << " " << g_rgb[1] << " " << g_rgb[2]);
  CHECK(g_rgb[0] > g_rgb[2] + 30);
}

TEST_CASE("eye from views: no frontal photo, or eyes too small, keep the generic iris with the reason") {
  const GenericHead& g = test::generic_head();
  const Scene s = make_scene();
  const Vec3 side_dir = s.front.cross(Vec3(0, 1, 0)).normalized();
  const Camera side = look_at(s.centre + 0.5 * side_dir, s.centre, 3000, 800, 800);
  const Image skin = Image::make(800, 800, 3, 170);
  EyeFromViewsResult out;
  Status st = eye_texture_from_views(g.mesh, g, s.frame, {&skin}, {side}, {"profile.jpg"}, EyeFromViewsOptions{}, out);
  CHECK(st.code == ErrorCode::NotAHead);
  CHECK(st.message.find("within 25 deg") != std::string::npos);
  // Frontal but far: the eyeball a few pixels across.
  const Camera far = look_at(s.centre + 5.0 * s.front, s.centre, 1000, 800, 800);
  st = eye_texture_from_views(g.mesh, g, s.frame, {&skin}, {far}, {"far.jpg"}, EyeFromViewsOptions{}, out);
  CHECK(st.code == ErrorCode::NotAHead);
  CHECK(st.message.find("too small") != std::string::npos);
  CHECK(st.message.find("far.jpg") != std::string::npos);
  // Frontal and near enough, but no eye painted: no iris edge.
  const Camera front = look_at(s.centre + 0.5 * s.front, s.centre, 3000, 1200, 1600);
  const Image plain = Image::make(1200, 1600, 3, 170);
  st = eye_texture_from_views(g.mesh, g, s.frame, {&plain}, {front}, {"front.jpg"}, EyeFromViewsOptions{}, out);
  CHECK(st.code == ErrorCode::NotAHead);
  CHECK(st.message.find("no iris edge") != std::string::npos);
  // Counts that differ are refused.
  CHECK(eye_texture_from_views(g.mesh, g, s.frame, {&plain}, {}, {}, EyeFromViewsOptions{}, out).code ==
        ErrorCode::InvalidInput);
}
