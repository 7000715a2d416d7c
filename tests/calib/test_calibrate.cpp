// Calibration recovers known synthetic cameras (tarini2002 Sec. 3): exact
// points, distortion, 1 px noise, a gross outlier, known-focal mode, and the
// broken inputs that must give clear errors.
#include "calib/calibrate.h"
#include "synthetic_cameras.h"

#include <catch2/catch.hpp>
#include <cmath>

using namespace lk;
using namespace lk::calib_test;

TEST_CASE("calibration recovers known cameras from exact points") {
  for (int distortion = 0; distortion < 2; ++distortion) {
    SplitMix64 rng(11 + distortion);
    for (int trial = 0; trial < 20; ++trial) {
      INFO("distortion " << distortion << " trial " << trial);
      const Camera truth = random_camera(rng, distortion);
      const auto cs = observe(truth, head_points(rng, 14));
      CalibOptions opt;  // exact data: every intrinsic can be recovered
      opt.fix_principal_point = false;
      opt.estimate_k1 = true;
      opt.estimate_k2 = distortion;
      CalibResult res;
      const Status s = calibrate_camera(cs, 1800, 1200, opt, res);
      REQUIRE(s.ok());
      CHECK(res.num_inliers == 14);
      for (double e : res.errors) CHECK(e < 0.5);
      CHECK(res.rms < 0.5);
      CHECK(std::abs(res.camera.fx / truth.fx - 1) < 0.005);
      CHECK(std::abs(res.camera.fy / truth.fy - 1) < 0.005);
      CHECK(std::abs(res.camera.cx - truth.cx) < 1.0);
      CHECK(std::abs(res.camera.cy - truth.cy) < 1.0);
      CHECK(rotation_error_deg(res.camera.R, truth.R) < 0.1);
      CHECK((res.camera.center() - truth.center()).norm() < 0.005 * truth.center().norm());
    }
  }
}

TEST_CASE("calibration is stable under 1 px Gaussian noise") {
  SplitMix64 rng(21), noise(22);
  double worst_rms = 0, worst_focal = 0, worst_rot = 0;
  for (int trial = 0; trial < 20; ++trial) {
    INFO("trial " << trial);
    const Camera truth = random_camera(rng, false);
    const auto cs = observe(truth, head_points(rng, 15), &noise, 1.0);
    CalibResult res;
    // Defaults: principal point at the centre, no distortion. With 15 points
    // on a head filling a third of the frame, freeing them fits the noise
    // (measured: k1 up to 0.7, focal 27 % off, rotation 18 deg off).
    CalibOptions opt;
    REQUIRE(calibrate_camera(cs, 1800, 1200, opt, res).ok());
    // About 1 px per coordinate: the RMS residual of a point is ~sqrt(2) px,
    // reduced by the degrees of freedom the fit absorbs.
    CHECK(res.rms > 0.4);
    CHECK(res.rms < 2.0);
    CHECK(res.num_inliers >= 14);
    worst_rms = std::max(worst_rms, res.rms);
    worst_focal = std::max(worst_focal, std::abs(res.camera.fx / truth.fx - 1));
    worst_rot = std::max(worst_rot, rotation_error_deg(res.camera.R, truth.R));
  }
  WARN("1 px noise, 15 points: worst RMS " << worst_rms << " px, worst focal error "
       << 100 * worst_focal << " %, worst rotation error " << worst_rot << " deg");
  CHECK(worst_focal < 0.2);
  CHECK(worst_rot < 2.0);
}

TEST_CASE("a point off by 50 px is flagged and does not spoil the camera") {
  SplitMix64 rng(31), noise(32);
  for (int trial = 0; trial < 10; ++trial) {
    INFO("trial " << trial);
    const Camera truth = random_camera(rng, false);
    auto cs = observe(truth, head_points(rng, 13), &noise, 0.3);
    const int bad = trial % 13;
    const double ang = rng.uniform(0, 2 * kPi);
    cs[bad].pixel += 50 * Vec2(std::cos(ang), std::sin(ang));
    CalibResult res;
    CalibOptions opt;
    opt.fix_principal_point = false;
    REQUIRE(calibrate_camera(cs, 1800, 1200, opt, res).ok());
    CHECK(res.outlier[bad] == 1);
    CHECK(res.errors[bad] > 25);
    CHECK(res.num_inliers == 12);
    CHECK(res.rms < 1.0);
    CHECK(std::abs(res.camera.fx / truth.fx - 1) < 0.05);  // 13 points, 0.3 px noise, free centre
    CHECK(rotation_error_deg(res.camera.R, truth.R) < 1.0);
  }
}

TEST_CASE("known focal length: pose from 6 points, also coplanar ones") {
  SplitMix64 rng(41);
  const Camera truth = look_at_head(25, 10, 2, 0.8, 3813.6, 900, 600);
  CalibOptions opt;
  opt.known_focal = 3813.6;
  CalibResult res;
  REQUIRE(calibrate_camera(observe(truth, head_points(rng, 6)), 1800, 1200, opt, res).ok());
  CHECK(res.rms < 0.5);
  CHECK(res.camera.fx == 3813.6);
  CHECK(rotation_error_deg(res.camera.R, truth.R) < 0.1);

  std::vector<Vec3> plane;
  for (int i = 0; i < 10; ++i) plane.push_back(Vec3(rng.uniform(-0.08, 0.08), rng.uniform(-0.1, 0.1), 0.05));
  REQUIRE(calibrate_camera(observe(truth, plane), 1800, 1200, opt, res).ok());
  CHECK(res.rms < 0.5);
  CHECK(rotation_error_deg(res.camera.R, truth.R) < 0.1);
}

TEST_CASE("bad calibration input gives clear errors") {
  SplitMix64 rng(51);
  const Camera truth = look_at_head(0, 0, 0, 0.8, 3000, 900, 600);
  const auto pts = head_points(rng, 12);
  auto cs = observe(truth, pts);
  CalibResult res;

  std::vector<Correspondence> five(cs.begin(), cs.begin() + 5);
  Status s = calibrate_camera(five, 1800, 1200, CalibOptions{}, res);
  CHECK(s.code == ErrorCode::InvalidInput);
  CHECK(s.message.find("at least 6") != std::string::npos);

  std::vector<Vec3> plane;
  for (int i = 0; i < 10; ++i) plane.push_back(Vec3(rng.uniform(-0.08, 0.08), rng.uniform(-0.1, 0.1), 0.05));
  s = calibrate_camera(observe(truth, plane), 1800, 1200, CalibOptions{}, res);
  CHECK(s.code == ErrorCode::InvalidInput);
  CHECK(s.message.find("coplanar") != std::string::npos);

  std::vector<Vec3> line;
  for (int i = 0; i < 8; ++i) line.push_back(Vec3(0.01 * i, 0.02 * i, 0.005 * i));
  s = calibrate_camera(observe(truth, line), 1800, 1200, CalibOptions{}, res);
  CHECK(s.code == ErrorCode::InvalidInput);
  CHECK(s.message.find("collinear") != std::string::npos);

  auto nan = cs;
  nan[3].pixel.x() = std::nan("");
  s = calibrate_camera(nan, 1800, 1200, CalibOptions{}, res);
  CHECK(s.code == ErrorCode::InvalidInput);
  CHECK(s.message.find("NaN") != std::string::npos);

  // Points reflected through the camera centre project to the same pixels
  // but lie behind the camera: no valid camera exists.
  auto behind = cs;
  for (auto& c : behind) c.point = 2 * truth.center() - c.point;
  s = calibrate_camera(behind, 1800, 1200, CalibOptions{}, res);
  CHECK(s.code == ErrorCode::InvalidInput);
  CHECK(s.message.find("behind") != std::string::npos);

  s = calibrate_camera(cs, 0, 1200, CalibOptions{}, res);
  CHECK(s.code == ErrorCode::InvalidInput);
}

TEST_CASE("a free focal length never comes out absurd: noisy, nearly flat points fail clearly instead") {
  // Six points on a shallow patch (2 mm deep over 15 cm) seen from 3 m with
  // 6 px click noise: focal length and distance can trade off freely, and
  // LM can drift towards an affine camera. Every result is either a focal
  // within [0.2, 50] image diagonals or NotConverged naming the focal.
  SplitMix64 rng(77);
  const double diagonal = std::hypot(1800.0, 1200.0);
  int refused = 0, accepted = 0, implausible = 0;
  for (int trial = 0; trial < 60; ++trial) {
    std::vector<Vec3> pts;
    for (int i = 0; i < 6; ++i)
      pts.push_back(Vec3(rng.uniform(-0.075, 0.075), rng.uniform(-0.075, 0.075), rng.uniform(0, 0.002)));
    const Camera truth = look_at_head(rng.uniform(-10, 10), rng.uniform(-10, 10), 0, 3.0, 12000, 900, 600);
    const std::vector<Correspondence> cs = observe(truth, pts, &rng, 6.0);
    CalibOptions options;
    options.robust = false;
    CalibResult r;
    const Status s = calibrate_camera(cs, 1800, 1200, options, r);
    if (s.ok()) {
      ++accepted;
      CHECK(r.camera.fx >= 0.2 * diagonal);
      CHECK(r.camera.fx <= 50 * diagonal);
    } else {
      ++refused;
      CHECK(!s.message.empty());
      implausible += s.message.find("no camera has") != std::string::npos;
    }
  }
  INFO("accepted " << accepted << ", refused " << refused << " (" << implausible << " for an absurd focal)");
  CHECK(accepted + refused == 60);
  CHECK(implausible > 0);  // the case happens here: without the check these would be returned
}
