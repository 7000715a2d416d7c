// Self-calibration and shape fit on synthetic sessions with known cameras.
#include "photos/ground_truth.h"
#include "photos/photos_job.h"
#include "photos/self_calibration.h"
#include "photos/shape_fit.h"
#include "photos_scenario.h"

#include <cstdio>

namespace lk {
namespace {

std::vector<int> face_vertices(const GenericHead& h) { return h.annotations.regions.at("face"); }

TEST_CASE("self-calibration recovers the shared focal and the rotations", "[photos]") {
  for (std::uint32_t seed : {1u, 2u}) {
    test::PhotoScenario s = test::make_photo_scenario(seed);
    SelfCalibResult calib;
    REQUIRE(self_calibrate(s.session.photos, s.generic.mesh, s.landmarks, {}, calib));
    REQUIRE(calib.num_used() == int(s.session.photos.size()));
    const double truth_focal = s.session.cameras[0].fx;
    const double focal_err = std::abs(calib.focal - truth_focal) / truth_focal;
    // The BA's landmarks against the person's: the similarity between the frames.
    std::vector<Vec3> fitted, truth;
    std::vector<int> idx;
    for (size_t m = 0; m < s.landmarks.size(); ++m)
      if (s.landmarks[m].valid() && calib.landmark_seen[m]) {
        idx.push_back(int(fitted.size()));
        fitted.push_back(calib.landmarks[m]);
        truth.push_back(surface_position(s.person.mesh, s.landmarks[m]));
      }
    const Similarity sim = fit_similarity(fitted, truth, idx);
    double worst = 0;
    for (size_t i = 0; i < s.session.cameras.size(); ++i) {
      const Camera c = transform_camera(calib.photos[i].camera, sim);
      worst = std::max(worst, rotation_angle_deg(c.R, s.session.cameras[i].R));
    }
    std::printf("seed %u: focal %.1f (truth %.1f, %.2f %%), worst rotation %.2f deg, rms %.2f -> %.2f px, "
                "scale %.3f\n", seed, calib.focal, truth_focal, 100 * focal_err, worst, calib.initial_rms_px,
                calib.final_rms_px, sim.scale);
    CHECK(focal_err < 0.04);
    CHECK(worst < 2.0);
    CHECK(calib.final_rms_px < calib.initial_rms_px);
  }
}

TEST_CASE("the fitted head is closer to the person than the generic head", "[photos]") {
  test::PhotoScenario s = test::make_photo_scenario(1);
  PhotosJobResult r;
  REQUIRE(run_photos_job(s.generic, s.map, s.session.photos, {}, r));
  const std::vector<int> face = face_vertices(s.generic);
  // Both brought onto the truth by their best similarity (scale is not observable).
  TriMesh fit = r.fit.mesh, gen = s.generic.mesh;
  const Similarity sf = fit_similarity(fit.positions, s.person.mesh.positions, face);
  const Similarity sg = fit_similarity(gen.positions, s.person.mesh.positions, face);
  for (Vec3& p : fit.positions) p = sf.apply(p);
  for (Vec3& p : gen.positions) p = sg.apply(p);
  const DistanceStats tf = surface_distances(s.person.mesh, face, fit);
  const DistanceStats tg = surface_distances(s.person.mesh, face, gen);
  std::printf("truth->face mean: generic %.2f mm, fit %.2f mm (p95 %.2f / %.2f)\n", 1000 * tg.mean, 1000 * tf.mean,
              1000 * tg.p95, 1000 * tf.p95);
  CHECK(tf.mean < 0.5 * tg.mean);  // measured: 0.22 against 0.85 mm
  CHECK(tf.p95 < tg.p95);
  CHECK(r.fit.final_rms_px < r.fit.initial_rms_px);
}

// Landmarks of another person seen by the same camera replace one photo's.
// The refusal margin (3x the photos' median of median errors) is set above
// what the real detector reaches on real photos of one person (Kira: 2.0x),
// so only a clearly different face is caught: this stranger is drawn with
// three times the usual variation (median error ~9.5 px against ~2.5 px);
// one of usual (1x, 2x) variation is not caught, see docs/design/photos.md:
// landmarks alone are a weak identity check.
TEST_CASE("a photo of somebody else is refused, named, and the rest kept", "[photos]") {
  test::PhotoScenario s = test::make_photo_scenario(5);
  GenericHead other;
  SynthHeadOptions stranger;
  stranger.variation = 3;
  REQUIRE(synthesize_head(s.generic, 77, stranger, other));
  SyntheticSession os;
  REQUIRE(make_synthetic_views(other, s.landmarks, 5, {}, os));
  const size_t victim = 4;
  s.session.photos[victim] = os.photos[victim];
  s.session.photos[victim].name = "stranger.jpg";
  PhotosJobResult r;
  REQUIRE(run_photos_job(s.generic, s.map, s.session.photos, {}, r));
  CHECK_FALSE(r.calib.photos[victim].used);
  CHECK(r.calib.num_used() == int(s.session.photos.size()) - 1);
  bool named = false;
  for (const std::string& n : r.notes) named = named || n.find("stranger.jpg dropped") != std::string::npos;
  CHECK(named);
  CHECK(std::abs(r.calib.focal - s.session.cameras[0].fx) / s.session.cameras[0].fx < 0.05);
}

// A detector that misreads a photo can return an upside-down face (seen on a
// real full profile); its points rotated by 180 degrees in the image fit a
// camera rolled upside down, which is refused with that reason.
TEST_CASE("a photo whose landmarks make an upside-down face is refused with that reason", "[photos]") {
  test::PhotoScenario s = test::make_photo_scenario(3);
  LandmarkPhoto& ph = s.session.photos[2];
  for (Vec2& p : ph.points) p = Vec2(ph.width, ph.height) - p;
  ph.name = "flipped.jpg";
  PhotosJobResult r;
  REQUIRE(run_photos_job(s.generic, s.map, s.session.photos, {}, r));
  CHECK_FALSE(r.calib.photos[2].used);
  CHECK(r.calib.photos[2].refusal.find("upside-down") != std::string::npos);
  CHECK(r.calib.num_used() == int(s.session.photos.size()) - 1);
  // Without the check the flipped photo's camera is simply rolled: used.
  PhotosJobOptions keep;
  keep.calib.refuse_upside_down = false;
  REQUIRE(run_photos_job(s.generic, s.map, s.session.photos, keep, r));
  CHECK(r.calib.photos[2].used);
}

TEST_CASE("wrong landmarks lose their pull", "[photos]") {
  test::PhotoScenario s = test::make_photo_scenario(6);
  LandmarkPhoto& ph = s.session.photos[5];
  std::vector<int> moved;
  for (size_t m = 0; m < ph.points.size() && moved.size() < 12; m += 29)
    if (ph.present[m]) {
      ph.points[m] += Vec2(60, -45);
      moved.push_back(int(m));
    }
  REQUIRE(moved.size() >= 8);
  SelfCalibResult calib;
  REQUIRE(self_calibrate(s.session.photos, s.generic.mesh, s.landmarks, {}, calib));
  CHECK(calib.photos[5].used);
  // A landmark seen in only one other photo can partly absorb its shift
  // (the 3-D point moves along the other photo's ray): most, not all, drop.
  int dropped = 0;
  for (int m : moved) dropped += calib.photos[5].weights[size_t(m)] < 0.2;
  CHECK(dropped >= int(moved.size()) - 2);
  CHECK(calib.photos[5].num_outliers >= int(moved.size()) - 2);
  CHECK(std::abs(calib.focal - s.session.cameras[0].fx) / s.session.cameras[0].fx < 0.04);
}

TEST_CASE("too few usable photos are refused with the reasons, one photo alone gives a head and a note", "[photos]") {
  test::PhotoScenario s = test::make_photo_scenario(2);
  std::vector<LandmarkPhoto> three(s.session.photos.begin(), s.session.photos.begin() + 3);
  for (int i : {0, 2}) std::fill(three[size_t(i)].present.begin(), three[size_t(i)].present.end(), 0);
  PhotosJobResult r;
  const Status st = run_photos_job(s.generic, s.map, three, {}, r);
  CHECK(st.code == ErrorCode::NotConverged);
  CHECK(st.message.find("1 usable photo") != std::string::npos);
  REQUIRE(r.notes.size() == 2);
  CHECK(r.notes[0].find("no face found") != std::string::npos);

  std::vector<LandmarkPhoto> one = {s.session.photos[s.session.photos.size() / 2]};
  PhotosJobResult r1;
  REQUIRE(run_photos_job(s.generic, s.map, one, {}, r1));
  REQUIRE(!r1.notes.empty());
  CHECK(r1.notes[0].find("only photo") != std::string::npos);
  CHECK(r1.fit.final_rms_px < r1.fit.initial_rms_px);

  std::vector<LandmarkPhoto> other_detector = s.session.photos;
  other_detector[1].detector = "dlib-68";
  CHECK(run_photos_job(s.generic, s.map, other_detector, {}, r).code == ErrorCode::InvalidInput);
}

}  // namespace
}  // namespace lk
