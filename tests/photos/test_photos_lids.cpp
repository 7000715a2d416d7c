// The lid opening of a head from photos against the detector's lid points
// (photos/eye_lids.h; docs/design/photos.md, "Lids that follow the photos").
#include "anim/face_pose.h"
#include "anim/face_shapes.h"
#include "components/components.h"
#include "head/generic_head.h"
#include "photos/eye_lids.h"
#include "photos/photos_job.h"
#include "photos/synthetic_views.h"
#include "synth/synth_head.h"
#include "test_data.h"
#include "test_kira.h"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <random>

namespace lk {
namespace {

// Each eye's opening in the most frontal used photo: the detector's, the
// fitted head's and the generic head's (same camera, across the fitted
// eyeball's projected centre).
struct EyeReport {
  LidOpening detected, fitted, generic, truth;
};

int most_frontal(const SelfCalibResult& calib) {
  int best = -1;
  double best_yaw = 1e9;
  for (size_t i = 0; i < calib.photos.size(); ++i) {
    if (!calib.photos[i].used) continue;
    double yaw, pitch;
    view_angles(calib.photos[i].camera, yaw, pitch);
    if (std::abs(yaw) + std::abs(pitch) < best_yaw) best_yaw = std::abs(yaw) + std::abs(pitch), best = int(i);
  }
  return best;
}

void report_eyes(const GenericHead& generic, const TriMesh& fitted, const LandmarkPhoto& photo, const Camera& cam,
                 EyeReport out[2], const GenericHead* truth = nullptr, const Camera* truth_cam = nullptr) {
  GenericHead f = generic;
  f.mesh.positions = fitted.positions;
  ComponentPlacement place;
  REQUIRE(place_components(f, generic, place));
  for (int e = 0; e < 2; ++e) {
    Vec2 c;
    REQUIRE(cam.project(place.eye_center[e], c));
    REQUIRE(landmark_lid_opening(photo, e, c, out[e].detected));
    REQUIRE(head_lid_opening(fitted, generic, e, 3, cam, c, out[e].fitted));
    REQUIRE(head_lid_opening(generic.mesh, generic, e, 3, cam, c, out[e].generic));
    {
      const LidContour& lc = mediapipe_lid_contour(e);
      const Vec2 mid = 0.5 * (photo.points[size_t(lc.upper[3])] + photo.points[size_t(lc.lower[3])]);
      std::printf("  eye %d: eyeball centre at (%.1f, %.1f) px, the detected lids' middle at (%.1f, %.1f), radius %.1f px\n",
                  e, c.x(), c.y(), mid.x(), mid.y(), place.eye_radius[e] * cam.fx / cam.to_camera(place.eye_center[e]).z());
    }
    if (truth) {
      ComponentPlacement tp;
      REQUIRE(place_components(*truth, generic, tp));
      Vec2 tc;
      REQUIRE(truth_cam->project(tp.eye_center[e], tc));
      REQUIRE(head_lid_opening(truth->mesh, generic, e, 3, *truth_cam, tc, out[e].truth));
    }
    std::printf("  eye %d: detected %.1f/%.1f = %.3f, fitted %.1f/%.1f = %.3f, generic %.3f, truth %.3f\n", e,
                out[e].detected.gap_px, out[e].detected.width_px, out[e].detected.ratio(), out[e].fitted.gap_px,
                out[e].fitted.width_px, out[e].fitted.ratio(), out[e].generic.ratio(), out[e].truth.ratio());
  }
}

// The generic head, the shipped MediaPipe map, and Kira's nine points files
// (tests/photos/data/kira).
void load_generic_and_map(GenericHead& generic, LandmarkMap& map) {
  REQUIRE(load_generic_head(generic));
  REQUIRE(parse_landmark_map_json(mediapipe_landmark_map_text(), map));
}

// ... with the map attached to the generic head and its lid contour on the rims.
void load_lid_points(GenericHead& generic, LandmarkMap& map, std::vector<SurfacePoint>& lms,
                     std::vector<SurfacePoint>& rim) {
  load_generic_and_map(generic, map);
  REQUIRE(attach_landmark_map(map, generic.mesh, PhotosJobOptions{}.map_max_distance_m, lms));
  REQUIRE(lid_margin_points(generic, lms, rim));
}

std::vector<LandmarkPhoto> kira_photos() { return test::kira_landmark_photos(); }

PhotosJobOptions lids_on() {
  PhotosJobOptions o;
  o.lids_on_rim = true;  // off by default
  return o;
}

// The figures of docs/design/photos.md ("Lids that follow the photos"): run
// by name, not by ctest (hidden).
TEST_CASE("lid openings of the photos head on Kira and the detected seeds (report)", "[.][photos][lids][report]") {
  GenericHead generic;
  LandmarkMap map;
  load_generic_and_map(generic, map);
  for (bool lids : {false, true}) {
    const std::vector<LandmarkPhoto> photos = kira_photos();
    PhotosJobOptions o;
    o.lids_on_rim = lids;
    PhotosJobResult r;
    REQUIRE(run_photos_job(generic, map, photos, o, r));
    const int p = most_frontal(r.calib);
    std::printf("Kira, photo %s, lids on the rim %s\n", photos[size_t(p)].name.c_str(), lids ? "on" : "off");
    EyeReport rep[2];
    report_eyes(generic, r.fit.mesh, photos[size_t(p)], r.calib.photos[size_t(p)].camera, rep);
  }
  for (int seed = 1; seed <= 5; ++seed) {
    LandmarkMap ph_map;
    std::vector<SurfacePoint> ph_lms;
    REQUIRE(placeholder_landmark_map(generic, 468, ph_map));
    REQUIRE(attach_landmark_map(ph_map, generic.mesh, 1e-3, ph_lms));
    GenericHead person;
    REQUIRE(synthesize_head(generic, std::uint32_t(seed), SynthHeadOptions{}, person));
    SyntheticViewsOptions vo;
    vo.num_cameras = 8;
    SyntheticSession truth;
    REQUIRE(make_synthetic_views(person, ph_lms, std::uint32_t(seed), vo, truth));
    std::vector<LandmarkPhoto> photos;
    std::vector<int> cam_of;
    for (int c = 0; c < 8; ++c) {
      char name[64];
      std::snprintf(name, sizeof name, "/tests/photos/data/detected/seed%d/view_%02d.json", seed, c);
      const std::string text = test::read_file_text(test::source_dir() + name);
      if (text.empty()) continue;
      LandmarkPhoto ph;
      REQUIRE(parse_landmarks_json(text, ph));
      photos.push_back(ph);
      cam_of.push_back(c);
    }
    PhotosJobResult r;
    REQUIRE(run_photos_job(generic, map, photos, lids_on(), r));
    const int p = most_frontal(r.calib);
    std::printf("seed %d, photo %s\n", seed, photos[size_t(p)].name.c_str());
    EyeReport rep[2];
    report_eyes(generic, r.fit.mesh, photos[size_t(p)], r.calib.photos[size_t(p)].camera, rep, &person,
                &truth.cameras[size_t(cam_of[size_t(p)])]);
  }
}

// A synthetic person (seed 2) whose lids the face rig has turned (upper
// lid `upper`, lower lid `lower`: + closes), seen by 8 known cameras: the
// shipped map's landmarks projected (no slide), and MediaPipe's lid contour
// where a detector marks it on real eyes, on the person's eye rim (the lid
// margin), with 1 px of noise. Returns each eye's fitted opening ratio minus
// the truth's, in the most frontal photo.
void lid_session(double upper, double lower, bool lids_on_rim, double error[2], double truth_ratio[2]) {
  GenericHead generic;
  LandmarkMap map;
  std::vector<SurfacePoint> lms, rim;
  load_lid_points(generic, map, lms, rim);
  GenericHead person;
  REQUIRE(synthesize_head(generic, 2u, SynthHeadOptions{}, person));
  FaceRig rig;
  REQUIRE(make_face_rig(person.mesh, generic, rig));
  FaceControls controls;
  controls[kLidL] = controls[kLidR] = upper;
  controls[kLowerLidL] = controls[kLowerLidR] = lower;
  person.mesh.positions = pose_face(rig, controls);
  SyntheticViewsOptions vo;
  vo.num_cameras = 8;
  vo.noise_px = 1.0;
  SyntheticSession truth;
  REQUIRE(make_synthetic_views(person, lms, 2u, vo, truth));
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, vo.noise_px);
  for (size_t c = 0; c < truth.photos.size(); ++c) {
    LandmarkPhoto& ph = truth.photos[c];
    ph.detector = kMediaPipeDetector;
    for (size_t m = 0; m < rim.size() && m < ph.points.size(); ++m) {
      if (!rim[m].valid()) continue;
      Vec2 uv;
      const bool seen = camera_sees_lids(generic, lid_contour_eye(int(m)), truth.cameras[c]) &&
                        truth.cameras[c].project(surface_position(person.mesh, rim[m]), uv);
      ph.present[m] = seen;
      ph.points[m] = seen ? Vec2(uv + Vec2(noise(rng), noise(rng))) : Vec2(Vec2::Zero());
    }
  }
  PhotosJobOptions options;
  options.use_slide = false;
  options.lids_on_rim = lids_on_rim;
  PhotosJobResult r;
  REQUIRE(run_photos_job(generic, map, truth.photos, options, r));
  const int p = most_frontal(r.calib);
  REQUIRE(p >= 0);
  EyeReport rep[2];
  report_eyes(generic, r.fit.mesh, truth.photos[size_t(p)], r.calib.photos[size_t(p)].camera, rep, &person,
              &truth.cameras[size_t(p)]);
  for (int e = 0; e < 2; ++e) {
    error[e] = rep[e].fitted.ratio() - rep[e].truth.ratio();
    truth_ratio[e] = rep[e].truth.ratio();
  }
}

TEST_CASE("the fitted lid opening follows a synthetic person's narrower and wider lids", "[photos][lids]") {
  // Measured (gap / width, fitted minus truth): lids closed by 0.3 (truth
  // 0.28): -0.023 / +0.010 with the lids on the rim and turned, +0.057 /
  // +0.106 without; upper lids opened by 0.5 (truth 0.50): -0.033 / -0.006
  // against -0.080 / -0.034. The generic head's is 0.46.
  for (const auto& [upper, lower] : {std::pair<double, double>{0.3, 0.3}, std::pair<double, double>{-0.5, 0.0}}) {
    double fixed[2], truth[2], without[2];
    std::printf("lids %+.2f %+.2f\n", upper, lower);
    lid_session(upper, lower, true, fixed, truth);
    lid_session(upper, lower, false, without, truth);
    std::printf("  truth %.3f %.3f, error %+.3f %+.3f (without: %+.3f %+.3f)\n", truth[0], truth[1], fixed[0], fixed[1],
                without[0], without[1]);
    CHECK(std::abs(truth[0] - 0.46) > 0.04);  // the person's lids are not the generic head's
    for (int e = 0; e < 2; ++e) CHECK(std::abs(fixed[e]) < 0.04);
    CHECK(std::max(std::abs(without[0]), std::abs(without[1])) > 0.06);
  }
}

// The rig's blink on a head whose lids were turned to the photos: the
// middle rim column closes to under 10 % of its rest opening (as
// tests/anim checks on the generic head).
void check_blink(const GenericHead& generic, const TriMesh& head) {
  FaceRig rig;
  REQUIRE(make_face_rig(head, generic, rig));
  FaceControls c;
  REQUIRE(face_shape("blink", c));
  const std::vector<Vec3> P = pose_face(rig, c);
  for (int e = 0; e < 2; ++e) {
    const auto& up = rig.landmarks.upper_lid[size_t(e)];
    const auto& lo = rig.landmarks.lower_lid[size_t(e)];
    const size_t k = up.size() / 2;
    const double ratio = (P[size_t(up[k])] - P[size_t(lo[k])]).norm() / (rig.rest[size_t(up[k])] - rig.rest[size_t(lo[k])]).norm();
    std::printf("  blink: eye %d closes to %.3f of its opening\n", e, ratio);
    CHECK(ratio < 0.10);
  }
}

TEST_CASE("Kira's fitted lid opening is the detector's, and her head still blinks", "[photos][lids][kira]") {
  GenericHead generic;
  LandmarkMap map;
  load_generic_and_map(generic, map);
  const std::vector<LandmarkPhoto> photos = kira_photos();
  // Measured in 0001 (frontal), gap / width: detected 0.421 and 0.414;
  // fitted 0.423 and 0.401 (0.531 and 0.536 before: white above the iris).
  for (bool fix : {true, false}) {
    PhotosJobOptions options;
    options.lids_on_rim = fix;
    PhotosJobResult r;
    REQUIRE(run_photos_job(generic, map, photos, options, r));
    const int p = most_frontal(r.calib);
    REQUIRE(photos[size_t(p)].name == "0001.jpg");
    EyeReport rep[2];
    report_eyes(generic, r.fit.mesh, photos[size_t(p)], r.calib.photos[size_t(p)].camera, rep);
    for (int e = 0; e < 2; ++e) {
      const double rel = rep[e].fitted.ratio() / rep[e].detected.ratio() - 1;
      if (fix) {
        CHECK(std::abs(rel) < 0.08);
      } else {
        CHECK(rel > 0.15);  // the map's lid points, learned without eyeballs, open them too wide
      }
    }
    if (fix) {
      CHECK(r.lids.observations > 0);
      CHECK(r.lids.rms_after_px < r.lids.rms_before_px);
      check_blink(generic, r.fit.mesh);
    }
  }
}

TEST_CASE("the gap across an outline and MediaPipe's lid contour on the eye rims", "[photos][lids]") {
  // An ellipse of semi-axes 30 and 10 px: across its centre 20, across
  // x = 15 2 * 10 * sqrt(1 - 1/4); fewer than two crossings: 0.
  std::vector<Vec2> ellipse;
  for (int i = 0; i < 720; ++i) {
    const double a = 2 * 3.14159265358979323846 * i / 720;
    ellipse.emplace_back(30 * std::cos(a), 10 * std::sin(a));
  }
  CHECK(opening_gap(ellipse, Vec2(-30, 0), Vec2(30, 0), Vec2(0, 0)) == Approx(20).margin(0.01));
  CHECK(opening_gap(ellipse, Vec2(-30, 0), Vec2(30, 0), Vec2(15, 0)) == Approx(20 * std::sqrt(0.75)).margin(0.02));
  CHECK(opening_gap(ellipse, Vec2(-30, 0), Vec2(30, 0), Vec2(50, 0)) == 0);

  GenericHead generic;
  LandmarkMap map;
  std::vector<SurfacePoint> lms, rim;
  load_lid_points(generic, map, lms, rim);
  REQUIRE(rim.size() == lms.size());
  int valid = 0;
  for (size_t m = 0; m < rim.size(); ++m) {
    if (!rim[m].valid()) {
      CHECK(lid_contour_eye(int(m)) < 0);
      continue;
    }
    ++valid;
    const int eye = lid_contour_eye(int(m));
    REQUIRE(eye >= 0);
    // On the level-3 rim curve.
    std::vector<Vec3> curve;
    REQUIRE(refined_eye_rim(generic.mesh, generic, eye, 3, curve));
    const Vec3 q = surface_position(generic.mesh, rim[m]);
    double nearest = 1e9;
    for (size_t i = 0; i < curve.size(); ++i) {
      const Vec3 a = curve[i], b = curve[(i + 1) % curve.size()];
      const double t = std::clamp((q - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
      nearest = std::min(nearest, (a + t * (b - a) - q).norm());
    }
    CHECK(nearest < 1e-7);
  }
  CHECK(valid == 32);
  for (int e = 0; e < 2; ++e) {
    const LidContour& c = mediapipe_lid_contour(e);
    const Vec3 outer = surface_position(generic.mesh, rim[size_t(c.outer)]);
    const Vec3 inner = surface_position(generic.mesh, rim[size_t(c.inner)]);
    CHECK((e == 0 ? outer.x() > inner.x() : outer.x() < inner.x()));
    // Each upper lid point above the lower one at about the same place.
    for (size_t k = 0; k < 7; ++k) {
      const Vec3 u = surface_position(generic.mesh, rim[size_t(c.upper[k])]);
      const Vec3 l = surface_position(generic.mesh, rim[size_t(c.lower[k])]);
      CHECK(u.y() > l.y());
    }
  }
  // A head of another topology is refused.
  TriMesh small;
  small.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  small.triangles = {Tri{0, 1, 2}};
  std::vector<Vec3> curve;
  CHECK_FALSE(refined_eye_rim(small, generic, 0, 3, curve));
}

}  // namespace
}  // namespace lk
