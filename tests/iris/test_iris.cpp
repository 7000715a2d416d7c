// Iris finding and synthesis (Tarini et al. 2002, Sec. 4.1) on synthetic eyes
// with known centre and radius, and on the real eye photo when present.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>

#include "io/io.h"
#include "iris/iris.h"
#include "test_data.h"

namespace {

constexpr double kPi = 3.14159265358979323846;

struct SyntheticEye {
  double cx = 121.3, cy = 98.7, radius = 40, pupil = 14;
  bool eyelid = true, highlight = true;
  bool light = false;      // a light grey-blue iris, brighter than the skin (find_iris's dark disk fails there)
  bool lower_lid = false;  // the lower lid over the iris's bottom too
};

// Radial fibres: per-angle noise made of sines with random phases, a colour
// gradient across the radius, a dark limbus ring; the eye sits in white
// sclera inside skin; an upper eyelid band and a highlight occlude parts.
lk::Image make_eye(const SyntheticEye& e, int w = 240, int h = 200) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> U(0, 2 * kPi);
  double ph[6];
  for (double& p : ph) p = U(rng);
  const int freq[6] = {37, 53, 71, 89, 23, 61};
  lk::Image im = lk::Image::make(w, h, 3);
  const int ss = 3;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      double acc[3] = {0, 0, 0};
      for (int sy = 0; sy < ss; ++sy)
        for (int sx = 0; sx < ss; ++sx) {
          const double px = x + (sx + 0.5) / ss - 0.5, py = y + (sy + 0.5) / ss - 0.5;
          const double dx = px - e.cx, dy = py - e.cy, r = std::hypot(dx, dy), t = std::atan2(dy, dx);
          double c[3];
          const double skin[3] = {0.80, 0.60, 0.50};
          if (std::hypot(dx / 2.2, dy / 1.3) < e.radius) { c[0] = 0.92; c[1] = 0.90; c[2] = 0.88; }
          else { c[0] = skin[0]; c[1] = skin[1]; c[2] = skin[2]; }
          if (r < e.radius) {
            const double f = (r - e.pupil) / (e.radius - e.pupil);
            double fib = 0;
            for (int k = 0; k < 6; ++k) fib += std::sin(freq[k] * t + ph[k] + 3 * f) / 6;
            const double v = 0.75 + 0.35 * fib;
            c[0] = (0.25 + 0.15 * f) * v; c[1] = (0.35 - 0.1 * f) * v; c[2] = (0.45 - 0.2 * f) * v;
            if (e.light) { c[0] = (0.50 + 0.1 * f) * v; c[1] = (0.60 + 0.05 * f) * v; c[2] = 0.68 * v; }
            if (f > 0.85) for (double& q : c) q *= 0.7;
            if (r < e.pupil) c[0] = c[1] = c[2] = 0.03;
          }
          if (e.eyelid && py < e.cy - 0.6 * e.radius) { c[0] = skin[0]; c[1] = skin[1]; c[2] = skin[2]; }
          if (e.lower_lid && py > e.cy + 0.75 * e.radius) { c[0] = skin[0]; c[1] = skin[1]; c[2] = skin[2]; }
          if (e.highlight && std::hypot(px - (e.cx + 12), py - (e.cy - 15)) < 5) c[0] = c[1] = c[2] = 1.0;
          for (int k = 0; k < 3; ++k) acc[k] += c[k];
        }
      for (int k = 0; k < 3; ++k)
        im.at(x, y)[k] = static_cast<std::uint8_t>(std::lround(std::clamp(acc[k] / (ss * ss), 0.0, 1.0) * 255));
    }
  return im;
}

}  // namespace

TEST_CASE("find_iris recovers a synthetic iris's centre within 1 px and radius within 2 px") {
  SyntheticEye e;
  const lk::Image im = make_eye(e);
  for (const lk::Vec2& guess : {lk::Vec2(e.cx + 3, e.cy - 2), lk::Vec2(e.cx - 8, e.cy + 6)}) {
    lk::IrisCircle c;
    const lk::Status s = lk::find_iris(im, guess, {}, c);
    REQUIRE(s.ok());
    INFO("centre " << c.center.transpose() << " radius " << c.radius << " pupil " << c.pupil_radius);
    CHECK((c.center - lk::Vec2(e.cx, e.cy)).norm() < 1.0);
    CHECK(std::abs(c.radius - e.radius) < 2.0);
    CHECK(std::abs(c.pupil_radius - e.pupil) < 2.0);
  }
  // Without a guess: the darkest blob near the centre.
  lk::Vec2 g;
  REQUIRE(lk::iris_default_guess(im, g).ok());
  CHECK((g - lk::Vec2(e.cx, e.cy)).norm() < e.pupil);
}

TEST_CASE("find_iris_near finds a light iris under both lids with a catchlight in the pupil") {
  SyntheticEye e;
  e.light = true;
  e.lower_lid = true;
  e.radius = 26;
  e.pupil = 9;
  e.cx = 104.6;
  e.cy = 101.2;
  lk::Image im = make_eye(e, 211, 211);
  // A window's reflection across the pupil and the iris (as in a real photo).
  for (int y = 90; y < 100; ++y)
    for (int x = 98; x < 114; ++x)
      for (int k = 0; k < 3; ++k) im.at(x, y)[k] = 245;
  // The guess as a fitted head's eyeball would give it: some pixels off.
  for (const lk::Vec2& guess : {lk::Vec2(e.cx + 6, e.cy + 7), lk::Vec2(e.cx - 9, e.cy - 3)}) {
    lk::IrisCircle c;
    const lk::Status s = lk::find_iris_near(im, guess, 17, 14, 38, c);
    REQUIRE(s.ok());
    INFO("centre " << c.center.transpose() << " radius " << c.radius << " pupil " << c.pupil_radius);
    CHECK((c.center - lk::Vec2(e.cx, e.cy)).norm() < 1.0);
    CHECK(std::abs(c.radius - e.radius) < 1.5);
    CHECK(std::abs(c.pupil_radius - e.pupil) < 2.0);
  }
  // Skin only: no iris edge, said so.
  const lk::Image skin = lk::Image::make(211, 211, 3, 180);
  lk::IrisCircle c;
  const lk::Status s = lk::find_iris_near(skin, lk::Vec2(105, 105), 17, 14, 38, c);
  CHECK(s.code == lk::ErrorCode::NotAHead);
  CHECK(s.message.find("no iris edge") != std::string::npos);
  CHECK(lk::find_iris_near(skin, lk::Vec2(105, 105), 17, 38, 14, c).code == lk::ErrorCode::InvalidInput);
}

TEST_CASE("pixel removal drops the eyelid and the highlight, keeps the clean iris") {
  SyntheticEye e;
  const lk::Image im = make_eye(e);
  lk::IrisCircle c{lk::Vec2(e.cx, e.cy), e.radius, e.pupil};
  lk::PolarIris p;
  REQUIRE(lk::iris_to_polar(im, c, {}, p).ok());
  // Rows at the top (angle 90 deg, under the eyelid) are mostly invalid;
  // rows at the bottom (270 deg) are mostly valid.
  auto valid_share = [&](double deg) {
    const int a = static_cast<int>(deg / 360 * p.angles);
    int n = 0;
    // The outer half of the band: the eyelid covers radii beyond 24 px.
    for (int r = p.radii / 2; r < p.radii; ++r) n += p.valid[static_cast<size_t>(a) * p.radii + r];
    return static_cast<double>(n) / (p.radii - p.radii / 2);
  };
  CHECK(valid_share(90) < 0.2);
  CHECK(valid_share(270) > 0.8);
  // The highlight centre (dx=12, dy=-15 -> r ~ 19.2, angle ~ 51 deg) is removed.
  const double hr = std::hypot(12.0, 15.0), ha = std::atan2(15.0, 12.0) * 180 / kPi;
  const int a = static_cast<int>(ha / 360 * p.angles);
  const int r = static_cast<int>((hr - e.pupil) / (e.radius - e.pupil) * p.radii);
  CHECK(p.valid[static_cast<size_t>(a) * p.radii + r] == 0);
}

namespace {

// Per-ring mean colour and std over valid samples.
void ring_stats(const lk::PolarIris& p, int r, Eigen::Vector3d& mean, double& sd) {
  mean.setZero();
  int n = 0;
  for (int a = 0; a < p.angles; ++a)
    if (p.valid[static_cast<size_t>(a) * p.radii + r]) {
      const float* q = p.at(a, r);
      mean += Eigen::Vector3d(q[0], q[1], q[2]);
      ++n;
    }
  mean /= std::max(n, 1);
  double v = 0;
  for (int a = 0; a < p.angles; ++a)
    if (p.valid[static_cast<size_t>(a) * p.radii + r]) {
      const float* q = p.at(a, r);
      v += (Eigen::Vector3d(q[0], q[1], q[2]) - mean).squaredNorm();
    }
  sd = std::sqrt(v / std::max(n, 1));
}

void check_ring_statistics(const lk::PolarIris& in, const lk::PolarIris& out) {
  REQUIRE(out.angles == in.angles);
  REQUIRE(out.radii == in.radii);
  double worst_mean = 0, worst_sd = 0;
  // Rings at the pupil edge and the limbus mix iris with pupil/sclera under a
  // sub-pixel circle error: compare the inner 80% of the band.
  for (int r = in.radii / 10; r < in.radii - in.radii / 10; ++r) {
    Eigen::Vector3d mi, mo;
    double si, so;
    ring_stats(in, r, mi, si);
    ring_stats(out, r, mo, so);
    worst_mean = std::max(worst_mean, (mi - mo).norm());
    worst_sd = std::max(worst_sd, std::abs(si - so) / std::max(si, 1e-3));
  }
  INFO("worst ring mean difference " << worst_mean << ", worst relative std difference " << worst_sd);
  CHECK(worst_mean < 0.05);
  CHECK(worst_sd < 0.35);
}

}  // namespace

TEST_CASE("synthesized iris rings match the input's valid pixels (1-D chain and 2-D fallback)") {
  SyntheticEye e;
  const lk::Image im = make_eye(e);
  lk::IrisCircle c;
  REQUIRE(lk::find_iris(im, lk::Vec2(e.cx, e.cy), {}, c).ok());
  lk::PolarIris in;
  REQUIRE(lk::iris_to_polar(im, c, {}, in).ok());

  lk::PolarIris out;
  lk::IrisSynthesisReport rep;
  REQUIRE(lk::iris_synthesize(in, {}, out, &rep).ok());
  CHECK_FALSE(rep.used_2d);
  CHECK(rep.sector_deg <= 60.5);
  CHECK(rep.sector_deg >= 20);
  check_ring_statistics(in, out);

  lk::IrisSynthesisOptions o2;
  o2.force_2d = true;
  lk::PolarIris out2;
  REQUIRE(lk::iris_synthesize(in, o2, out2, &rep).ok());
  CHECK(rep.used_2d);
  check_ring_statistics(in, out2);

  // A scrambled iris would fail the check: rings shifted by a third of the band.
  lk::PolarIris shifted = out;
  const int shift = in.radii / 3;
  for (int a = 0; a < in.angles; ++a)
    for (int r = 0; r < in.radii; ++r)
      std::copy(out.at(a, (r + shift) % in.radii), out.at(a, (r + shift) % in.radii) + 3, shifted.at(a, r));
  double worst = 0;
  for (int r = 0; r < in.radii; ++r) {
    Eigen::Vector3d mi, mo;
    double si, so;
    ring_stats(in, r, mi, si);
    ring_stats(shifted, r, mo, so);
    worst = std::max(worst, (mi - mo).norm());
  }
  CHECK(worst > 0.05);
}

TEST_CASE("eyeball texture: black pupil, iris colour at the iris, white-ish sclera outside") {
  SyntheticEye e;
  lk::IrisResult res;
  const lk::Image im = make_eye(e);
  REQUIRE(lk::iris_texture_from_photo(im, nullptr, res).ok());
  const lk::Image& t = res.texture;
  REQUIRE(t.width == 512);
  const std::uint8_t* centre = t.at(256, 256);
  CHECK(centre[0] < 20);
  const std::uint8_t* corner = t.at(5, 256);  // rho ~ 1: sclera
  CHECK(corner[0] > 180);
  CHECK(corner[1] > 170);
  // Mid-iris (rho = 0.5 * (pupil + iris)): bluish like the synthetic iris (b > r).
  const double rho_i = 30.0 / 90, rho_p = rho_i * res.circle.pupil_radius / res.circle.radius;
  const int x = 256 + static_cast<int>(0.5 * (rho_i + rho_p) * 256);
  CHECK(t.at(x, 256)[2] > t.at(x, 256)[0]);
}

TEST_CASE("eyeball_uv follows the texture layout: pupil on the axis, the iris ring at its angle, no seam") {
  const double deg = kPi / 180;
  auto dir = [&](double theta_deg, double phi_deg) {
    const double t = theta_deg * deg, p = phi_deg * deg;
    return lk::Vec3(std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t));
  };
  // The layout as iris.h writes it, from the angles.
  for (double theta : {0.0, 10.0, 30.0, 60.0, 89.0, 90.0})
    for (double phi = -180; phi < 180; phi += 15) {
      const double rho = theta / 90;
      const lk::Vec2 want(0.5 + 0.5 * rho * std::cos(phi * deg), 0.5 - 0.5 * rho * std::sin(phi * deg));
      INFO("theta " << theta << " phi " << phi);
      CHECK((lk::eyeball_uv(dir(theta, phi)) - want).norm() < 1e-12);
      CHECK(std::abs(lk::eyeball_rho(dir(theta, phi)) - rho) < 1e-12);
    }
  CHECK(lk::eyeball_uv(lk::Vec3(0, 0, 1)) == lk::Vec2(0.5, 0.5));
  // +x right, +y up (v down) on the equator; behind it the rim, the back pole at (1, 0.5).
  CHECK((lk::eyeball_uv(lk::Vec3(1, 0, 0)) - lk::Vec2(1, 0.5)).norm() < 1e-15);
  CHECK((lk::eyeball_uv(lk::Vec3(0, 1, 0)) - lk::Vec2(0.5, 0)).norm() < 1e-15);
  CHECK(lk::eyeball_uv(lk::Vec3(0, 0, -1)) == lk::Vec2(1, 0.5));
  CHECK(lk::eyeball_rho(dir(120, 40)) > 1);
  CHECK(std::abs((lk::eyeball_uv(dir(120, 40)) - lk::Vec2(0.5, 0.5)).norm() - 0.5) < 1e-12);
  // No seam: across atan2's cut (phi = +-180) and across the equator.
  CHECK((lk::eyeball_uv(dir(45, 180 - 1e-7)) - lk::eyeball_uv(dir(45, -180 + 1e-7))).norm() < 1e-8);
  CHECK((lk::eyeball_uv(dir(90 - 1e-7, 70)) - lk::eyeball_uv(dir(90 + 1e-7, 70))).norm() < 1e-8);

  // eyeball_texture draws its iris where eyeball_uv puts the documented
  // angles: a uniform green iris of 30 deg, the pupil 0.35 of it (10.5 deg).
  lk::PolarIris iris;
  iris.angles = 16;
  iris.radii = 4;
  iris.valid.assign(16 * 4, 1);
  for (int i = 0; i < 16 * 4; ++i) iris.rgb.insert(iris.rgb.end(), {0.1f, 0.6f, 0.2f});
  lk::EyeballTextureOptions o;
  o.veins = 0;
  lk::Image t;
  REQUIRE(lk::eyeball_texture(iris, 0.35, o, t).ok());
  auto texel = [&](const lk::Vec3& d) {
    const lk::Vec2 uv = lk::eyeball_uv(d);
    return t.at(std::min(t.width - 1, int(uv.x() * t.width)), std::min(t.height - 1, int(uv.y() * t.height)));
  };
  for (double phi = -180; phi < 180; phi += 30) {
    INFO("phi " << phi);
    CHECK(texel(dir(5, phi))[1] < 20);  // pupil
    const std::uint8_t* in = texel(dir(20, phi));
    CHECK((in[1] > 140 && in[0] < 40));  // iris
    // The iris ends at 30 deg: the first sclera texel (all channels bright)
    // outward from 20 deg lies within the limbus's blend (0.08 of the iris).
    double edge = 0;
    for (double theta = 20; theta < 45 && edge == 0; theta += 0.1)
      if (texel(dir(theta, phi))[0] > 180) edge = theta;
    CHECK(edge > 30 - 2.5);
    CHECK(edge < 30 + 2.5);
  }
}

TEST_CASE("iris: bad input gives clear errors") {
  lk::IrisCircle c;
  lk::Vec2 g;
  CHECK(lk::find_iris(lk::Image{}, lk::Vec2(1, 1), {}, c).code == lk::ErrorCode::InvalidInput);
  const lk::Image uniform = lk::Image::make(200, 150, 3, 128);
  const lk::Status s = lk::iris_default_guess(uniform, g);
  CHECK(s.code == lk::ErrorCode::NotAHead);
  CHECK(s.message.find("no eye") != std::string::npos);
  CHECK_FALSE(lk::find_iris(uniform, lk::Vec2(100, 75), {}, c).ok());
  SyntheticEye e;
  CHECK(lk::find_iris(make_eye(e), lk::Vec2(-5, 10), {}, c).code == lk::ErrorCode::InvalidInput);
  // A dark image with one bright stripe: no round dark iris, the circle hits
  // the stripe on one side only and walks off.
  lk::Image dark = lk::Image::make(200, 150, 3, 20);
  for (int y = 0; y < 150; ++y)
    for (int x = 0; x < 10; ++x) for (int k = 0; k < 3; ++k) dark.at(x, y)[k] = 250;
  lk::IrisResult res;
  CHECK_FALSE(lk::iris_texture_from_photo(dark, nullptr, res).ok());
}

TEST_CASE("real eye photo: iris found and texture synthesized") {
  LK_REQUIRE_SHARED("eye_photos/Iris_-_left_eye_of_a_girl.jpg");
  lk::Image im;
  REQUIRE(lk::load_image_file(lk::test::shared_data_dir() + "/eye_photos/Iris_-_left_eye_of_a_girl.jpg", im, 3).ok());
  lk::IrisResult res;
  const lk::Status s = lk::iris_texture_from_photo(im, nullptr, res);
  INFO(s.message);
  REQUIRE(s.ok());
  INFO("centre " << res.circle.center.transpose() << " radius " << res.circle.radius);
  // The iris is about 140 px across (SOURCES.md).
  CHECK(res.circle.radius > 55);
  CHECK(res.circle.radius < 85);
}

TEST_CASE("iris: the polar iris is capped, so a huge circle cannot make the synthesis slow") {
  // A whole-face photo once gave a 524 px "iris": 3300 x 350 polar samples
  // and minutes of synthesis in the page (issue 36, class 9).
  const lk::Image im = lk::Image::make(1200, 1200, 3, 90);
  lk::IrisCircle c;
  c.center = lk::Vec2(600, 600);
  c.radius = 524;
  c.pupil_radius = 170;
  lk::PolarIris polar;
  REQUIRE(lk::iris_to_polar(im, c, {}, polar).ok());
  CHECK(polar.angles == 720);
  CHECK(polar.radii == 128);
  // A close-up's iris keeps about one sample per pixel.
  c.radius = 70;
  c.pupil_radius = 24;
  REQUIRE(lk::iris_to_polar(im, c, {}, polar).ok());
  CHECK(polar.angles == 440);
  CHECK(polar.radii == 46);
}

TEST_CASE("iris: portraits are refused as eye photos, and a crop of one eye is taken", "[shared]") {
  // Issue 36, class 9: a whole-face photo gave a "texture" of its hair or
  // chin (and minutes of work in the page). Each is refused, with a reason.
  const std::string dir = lk::test::shared_data_dir() + "/multiview_faces/keentools_kira/";
  LK_REQUIRE_SHARED("multiview_faces/keentools_kira/0001.jpg");
  for (const char* name : {"0001.jpg", "0002.jpg", "0003.jpg", "0004.jpg", "0005.jpg", "0006.jpg", "0007.jpg",
                           "0008.jpg", "0009.jpg", "0010.jpg"}) {
    lk::Image im;
    REQUIRE(lk::load_image_file(dir + name, im, 3).ok());
    lk::IrisResult res;
    const lk::Status s = lk::iris_texture_from_photo(im, nullptr, res);
    INFO(name << ": " << s.message);
    CHECK(s.code == lk::ErrorCode::NotAHead);
    CHECK(s.message.find("no eye close-up") != std::string::npos);
  }
  // A guess at the right eye of 0001 once grew into the face's outline
  // (radius 557 px, round and darker at its centre): refused by its size.
  {
    lk::Image im;
    REQUIRE(lk::load_image_file(dir + "0001.jpg", im, 3).ok());
    const lk::Vec2 guess(780, 548);
    lk::IrisResult res;
    const lk::Status s = lk::iris_texture_from_photo(im, &guess, res);
    INFO(s.message);
    CHECK(s.code == lk::ErrorCode::NotAHead);
  }
  // The right eye of 0001 cut out (160 x 100 px, the iris about 56 px
  // across): a small but real close-up, accepted.
  lk::Image face;
  REQUIRE(lk::load_image_file(dir + "0001.jpg", face, 3).ok());
  lk::Image eye = lk::Image::make(160, 100, 3);
  for (int y = 0; y < 100; ++y)
    for (int x = 0; x < 160; ++x)
      for (int k = 0; k < 3; ++k) eye.at(x, y)[k] = face.at(700 + x, 500 + y)[k];
  lk::IrisResult res;
  const lk::Status s = lk::iris_texture_from_photo(eye, nullptr, res);
  INFO(s.message);
  REQUIRE(s.ok());
  CHECK(res.circle.radius > 22);
  CHECK(res.circle.radius < 34);
}
