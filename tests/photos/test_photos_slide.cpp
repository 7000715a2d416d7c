// The detector's view-dependent slide (photos/landmark_slide.h): the
// bundle adjustment's Jacobian with the slide against finite differences,
// the map's version 2 round trip, and a synthetic detector whose points
// turn with the view (as MediaPipe's do: turned views look less turned):
// the slide learned from sessions with their truth, then used on another
// person, brings the cameras' angles back.
#include "common/prng.h"
#include "head/generic_head.h"
#include "photos/landmark_learning.h"
#include "photos/photos_job.h"
#include "photos/self_calibration.h"
#include "photos/synthetic_views.h"
#include "synth/synth_head.h"
#include "observation_fd.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <cstdio>
#include <deque>

namespace lk {
namespace {

LandmarkSlide test_slide(int M, std::uint64_t seed) {
  LandmarkSlide s;
  s.yaw_range = 1.0;
  s.pitch_range = 0.25;
  s.terms = {{1, 0}, {0, 1}, {2, 0}, {1, 1}, {0, 2}, {3, 0}};
  SplitMix64 rng(seed);
  s.shifts.assign(size_t(M), {});
  for (int m = 0; m < M; ++m)
    for (size_t k = 0; k < s.terms.size(); ++k)
      s.shifts[size_t(m)].push_back(Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)) * 0.006);
  s.sigma_yaw = {-0.8, 0, 0.8};
  s.sigma.assign(size_t(M), {0.001, 0.002, 0.004});
  return s;
}

// A camera looking at the head's origin from a random yaw and pitch inside
// the test slide's range (not clamped), 0.5-0.7 m away.
Camera random_head_camera(SplitMix64& rng) {
  const double yaw = rng.uniform(-0.9, 0.9), pitch = rng.uniform(-0.2, 0.2), d = rng.uniform(0.5, 0.7);
  const Vec3 C(d * std::sin(yaw) * std::cos(pitch), d * std::sin(pitch), d * std::cos(yaw) * std::cos(pitch));
  const Vec3 f = -C.normalized(), r = Vec3::UnitY().cross(f).normalized(), u = f.cross(r);
  Camera c;
  c.fx = c.fy = rng.uniform(900, 1500);
  c.cx = 600;
  c.cy = 800;
  c.R.row(0) = r.transpose();
  c.R.row(1) = -u.transpose();
  c.R.row(2) = f.transpose();
  c.t = -c.R * C;
  return c;
}

TEST_CASE("the slid projection's Jacobian (the shift follows the camera) matches finite differences", "[photos][slide]") {
  const LandmarkSlide slide = test_slide(3, 11);
  SplitMix64 rng(5);
  int checked = 0;
  for (int trial = 0; trial < 30; ++trial) {
    // A camera looking at the head, rolled a little about its axis.
    Camera c = random_head_camera(rng);
    const Vec3 C = c.center();
    c.R = Eigen::AngleAxisd(rng.uniform(-0.1, 0.1), Vec3::UnitZ()).toRotationMatrix() * c.R;
    c.t = -c.R * C;
    const Vec3 X(rng.uniform(-0.05, 0.05), rng.uniform(-0.05, 0.05), rng.uniform(0.0, 0.1));
    const Vec2 obs(rng.uniform(400, 800), rng.uniform(600, 1000));
    const int m = trial % 3;
    ProjectionJacobian J, J0;
    REQUIRE(slid_projection_jacobian(c, X, slide, m, obs, J));
    REQUIRE(projection_jacobian(c, X, obs, J0));
    auto res = [&](const Camera& cc, const Vec3& XX) {
      ProjectionJacobian j;
      REQUIRE(slid_projection_jacobian(cc, XX, slide, m, obs, j));
      return j.residual;
    };
    const double h = 1e-6;
    double through = 0;  // how much the shift's dependence on the camera adds
    for (int k = 0; k < 3; ++k) {
      Vec3 e = Vec3::Zero();
      e[k] = h;
      Camera a = c, b = c;
      a.R = Eigen::AngleAxisd(h, Vec3::Unit(k)).toRotationMatrix() * c.R;
      b.R = Eigen::AngleAxisd(-h, Vec3::Unit(k)).toRotationMatrix() * c.R;
      const Vec2 fr = (res(a, X) - res(b, X)) / (2 * h);
      CHECK((fr - J.d_rotation.col(k)).norm() < 1e-4 * (1 + J.d_rotation.col(k).norm()));
      a = c;
      b = c;
      a.t += e;
      b.t -= e;
      const Vec2 ft = (res(a, X) - res(b, X)) / (2 * h);
      CHECK((ft - J.d_translation.col(k)).norm() < 1e-4 * (1 + J.d_translation.col(k).norm()));
      const Vec2 fx = (res(c, X + e) - res(c, X - e)) / (2 * h);
      CHECK((fx - J.d_point.col(k)).norm() < 1e-4 * (1 + J.d_point.col(k).norm()));
      through = std::max(through, (J.d_translation.col(k) - J0.d_translation.col(k)).norm());
    }
    Camera a = c, b = c;
    a.fx = a.fy = c.fx + 1e-3;
    b.fx = b.fy = c.fx - 1e-3;
    CHECK(((res(a, X) - res(b, X)) / 2e-3 - J.d_focal).norm() < 1e-6 * (1 + J.d_focal.norm()));
    // The term is not negligible: without it the translation column would be off.
    CHECK(through > 1);
    ++checked;
  }
  CHECK(checked == 30);
}

TEST_CASE("the per-photo depth scale's Jacobian (slid projection) matches finite differences", "[photos][slide]") {
  const LandmarkSlide slide = test_slide(3, 12);
  SplitMix64 rng(8);
  int checked = 0;
  double moved = 0;  // the largest pixel move per unit depth scale
  for (int trial = 0; trial < 30; ++trial) {
    Camera c = random_head_camera(rng);
    const Vec3 X(rng.uniform(-0.07, 0.07), rng.uniform(-0.07, 0.07), rng.uniform(-0.05, 0.1));
    const Vec2 obs(rng.uniform(400, 800), rng.uniform(600, 1000));
    const int m = trial % 3;
    const double k = rng.uniform(0.6, 1.8);
    ProjectionJacobian J, J1, Jd;
    REQUIRE(slid_projection_jacobian(c, X, slide, m, obs, J, k));
    // k = 1 is the plain projection.
    REQUIRE(slid_projection_jacobian(c, X, slide, m, obs, J1, 1.0));
    REQUIRE(slid_projection_jacobian(c, X, slide, m, obs, Jd));
    CHECK((J1.residual - Jd.residual).norm() < 1e-12);
    auto res = [&](const Camera& cc, const Vec3& XX, double kk) {
      ProjectionJacobian j;
      REQUIRE(slid_projection_jacobian(cc, XX, slide, m, obs, j, kk));
      return j.residual;
    };
    const double h = 1e-6;
    for (int a = 0; a < 3; ++a) {
      Vec3 e = Vec3::Zero();
      e[a] = h;
      Camera p = c, q = c;
      p.R = Eigen::AngleAxisd(h, Vec3::Unit(a)).toRotationMatrix() * c.R;
      q.R = Eigen::AngleAxisd(-h, Vec3::Unit(a)).toRotationMatrix() * c.R;
      const Vec2 fr = (res(p, X, k) - res(q, X, k)) / (2 * h);
      CHECK((fr - J.d_rotation.col(a)).norm() < 1e-4 * (1 + J.d_rotation.col(a).norm()));
      p = c;
      q = c;
      p.t += e;
      q.t -= e;
      const Vec2 ft = (res(p, X, k) - res(q, X, k)) / (2 * h);
      CHECK((ft - J.d_translation.col(a)).norm() < 1e-4 * (1 + J.d_translation.col(a).norm()));
      const Vec2 fx = (res(c, X + e, k) - res(c, X - e, k)) / (2 * h);
      CHECK((fx - J.d_point.col(a)).norm() < 1e-4 * (1 + J.d_point.col(a).norm()));
    }
    const Vec2 fk = (res(c, X, k + h) - res(c, X, k - h)) / (2 * h);
    CHECK((fk - J.d_depth_scale).norm() < 1e-4 * (1 + J.d_depth_scale.norm()));
    moved = std::max(moved, J.d_depth_scale.norm());
    Camera p = c, q = c;
    p.fx = p.fy = c.fx + 1e-3;
    q.fx = q.fy = c.fx - 1e-3;
    CHECK(((res(p, X, k) - res(q, X, k)) / 2e-3 - J.d_focal).norm() < 1e-6 * (1 + J.d_focal.norm()));
    ++checked;
  }
  CHECK(checked == 30);
  // The depth scale moves the pixels: a point off the head's origin is seen elsewhere.
  CHECK(moved > 5);
}

TEST_CASE("the feature observations with a slid offset keep their Jacobian", "[photos][slide]") {
  GenericHead generic;
  REQUIRE(load_generic_head(generic));
  LandmarkMap map;
  std::vector<SurfacePoint> lms;
  REQUIRE(placeholder_landmark_map(generic, 60, map));
  REQUIRE(attach_landmark_map(map, generic.mesh, 1e-3, lms));
  SyntheticViewsOptions vo;
  vo.num_cameras = 4;
  SyntheticSession ses;
  REQUIRE(make_synthetic_views(generic, lms, 3, vo, ses));
  const LandmarkSlide slide = test_slide(60, 3);
  std::vector<FeatureObservation> obs;
  for (size_t c = 0; c < ses.photos.size(); ++c)
    for (size_t m = 0; m < lms.size(); ++m)
      if (ses.photos[c].present[m]) {
        FeatureObservation o{int(c), lms[m], ses.photos[c].points[m], 1.0, 1.0};
        o.point.offset += landmark_shift(slide, int(m), slide_view(slide, ses.cameras[c].center()));
        obs.push_back(o);
      }
  REQUIRE(obs.size() > 50);
  FeatureSet set(generic.mesh, ses.cameras, obs, 4.0);
  std::vector<int> cols;
  for (const auto& o : obs)
    for (int v : generic.mesh.triangles[size_t(o.point.triangle)])
      for (int k = 0; k < 3; ++k) cols.push_back(3 * v + k);
  CHECK(test::check_fd_jacobian(set, generic.mesh.positions, cols).worst_relative < 1e-4);
}

TEST_CASE("a landmark map of version 2 keeps its slide, version 1 still reads, and a bad slide is refused", "[photos][slide]") {
  LandmarkMap map;
  map.detector = "d";
  map.points = {Vec3(0, 0, 0.1), Vec3(0.01, 0, 0.1), Vec3(0.02, 0, 0.1)};
  map.present = {1, 0, 1};
  map.slide = test_slide(3, 4);
  map.slide.shifts[1].clear();
  map.slide.sigma[1].clear();
  const std::string text = landmark_map_to_json(map);
  REQUIRE(text.find("\"version\":2") != std::string::npos);
  LandmarkMap back;
  REQUIRE(parse_landmark_map_json(text, back));
  REQUIRE(back.slide.has_slide());
  REQUIRE(back.slide.has_sigma());
  CHECK(back.slide.terms == map.slide.terms);
  CHECK(back.slide.shifts[1].empty());
  CHECK(back.slide.sigma[1].empty());
  CHECK(std::abs(back.slide.yaw_range - 1.0) < 1e-12);
  const SlideView v = slide_view(back.slide, Vec3(0.3, 0.05, 0.5));
  CHECK((landmark_shift(back.slide, 2, v) - landmark_shift(map.slide, 2, v)).norm() < 5e-5);  // written to 0.01 mm a term
  CHECK(std::abs(landmark_sigma(back.slide, 0, Vec3(0.3, 0, 0.5)) - landmark_sigma(map.slide, 0, Vec3(0.3, 0, 0.5))) < 1e-5);
  // Version 1 (no slide) as before.
  LandmarkMap v1 = map;
  v1.slide = {};
  const std::string t1 = landmark_map_to_json(v1);
  REQUIRE(t1.find("\"version\":1") != std::string::npos);
  REQUIRE(parse_landmark_map_json(t1, back));
  CHECK_FALSE(back.slide.has_slide());
  // Broken slides: named.
  auto refused = [&](const std::string& from, const std::string& to, const char* field) {
    std::string t = text;
    const size_t at = t.find(from);
    REQUIRE(at != std::string::npos);
    t.replace(at, from.size(), to);
    const Status s = parse_landmark_map_json(t, back);
    CHECK_FALSE(s.ok());
    CHECK(s.message.find(field) != std::string::npos);
  };
  refused("\"terms\":[[1,0]", "\"terms\":[[0,0]", "slide.terms");
  refused("\"yaw_range_deg\":", "\"yaw_range_deg\":-", "slide");
  refused("\"version\":2", "\"version\":3", "version");
  refused("\"shifts\":[[", "\"shifts\":[7,[", "slide.shifts");
}

// A synthetic detector whose points turn with the view: the landmarks
// seen from yaw theta are the true ones turned about the head's vertical
// axis by -0.2 theta (a view at +60 deg looks like +48 deg, as MediaPipe's
// +58 came out +45..+52 on the synthetic renders), 0.5 px noise.
void turning_detector(const GenericHead& person, const std::vector<SurfacePoint>& lms, std::uint32_t seed,
                      SyntheticSession& ses) {
  SyntheticViewsOptions vo;
  vo.num_cameras = 8;
  vo.azimuth_deg = 60;
  vo.noise_px = 0;
  REQUIRE(make_synthetic_views(person, lms, seed, vo, ses));
  SplitMix64 rng(seed * 7 + 1);
  for (size_t c = 0; c < ses.cameras.size(); ++c) {
    double yaw, pitch;
    view_angles(ses.cameras[c], yaw, pitch);
    const Mat3 turn = Eigen::AngleAxisd(-0.2 * yaw * 3.14159265358979 / 180, Vec3::UnitY()).toRotationMatrix();
    for (size_t m = 0; m < lms.size(); ++m) {
      if (!ses.photos[c].present[m]) continue;
      Vec2 uv;
      REQUIRE(ses.cameras[c].project(turn * surface_position(person.mesh, lms[m]), uv));
      ses.photos[c].points[m] = uv + 0.5 * Vec2(rng.uniform(-1.732, 1.732), rng.uniform(-1.732, 1.732));
    }
  }
}

TEST_CASE("a slide learned from a turning detector brings the cameras' angles back on another person", "[photos][slide]") {
  GenericHead generic;
  REQUIRE(load_generic_head(generic));
  LandmarkMap start;
  std::vector<SurfacePoint> lms;
  REQUIRE(placeholder_landmark_map(generic, 468, start));
  REQUIRE(attach_landmark_map(start, generic.mesh, 1e-3, lms));
  // Training: four people with their true cameras.
  std::deque<GenericHead> people;
  std::vector<DetectedSessionView> sessions;
  for (std::uint32_t seed = 41; seed < 45; ++seed) {
    people.emplace_back();
    REQUIRE(synthesize_head(generic, seed, SynthHeadOptions{}, people.back()));
    SyntheticSession ses;
    turning_detector(people.back(), lms, seed, ses);
    sessions.push_back({&people.back().mesh, ses.cameras, ses.photos});
  }
  LandmarkMap learned;
  LearnSlideReport rep;
  REQUIRE(learn_landmark_slide(generic.mesh, start, sessions, LearnSlideOptions{}, learned, &rep));
  std::printf("slide learned: %d landmarks, %d sliding, scatter %.2f mm fixed -> %.2f mm with the slide\n", rep.learned,
              rep.sliding, 1000 * rep.rms_fixed_m, 1000 * rep.rms_slide_m);
  CHECK(rep.sliding > 300);
  CHECK(rep.rms_slide_m < 0.4 * rep.rms_fixed_m);
  // Scored: another person, the same detector.
  GenericHead person;
  REQUIRE(synthesize_head(generic, 3, SynthHeadOptions{}, person));
  SyntheticSession ses;
  turning_detector(person, lms, 3, ses);
  auto worst_yaw = [&](const LandmarkMap& map, double& focal) {
    PhotosJobResult r;
    PhotosJobOptions o;
    REQUIRE(run_photos_job(generic, map, ses.photos, o, r));
    double worst = 0;
    for (size_t c = 0; c < ses.photos.size(); ++c) {
      if (!r.calib.photos[c].used) continue;
      double ty, tp, y, p;
      view_angles(ses.cameras[c], ty, tp);
      view_angles(r.calib.photos[c].camera, y, p);
      worst = std::max(worst, std::abs(y - ty));
    }
    focal = r.calib.focal;
    return worst;
  };
  double f_without = 0, f_with = 0;
  const double without = worst_yaw(start, f_without), with = worst_yaw(learned, f_with);
  std::printf("worst yaw error: %.1f deg without the slide (focal %.0f px), %.1f deg with it (focal %.0f px; truth %.0f)\n",
              without, f_without, with, f_with, ses.cameras[0].fx);
  CHECK(without > 6);
  CHECK(with < 2);
  CHECK(std::abs(f_with - ses.cameras[0].fx) < 0.05 * ses.cameras[0].fx);
}

}  // namespace
}  // namespace lk
