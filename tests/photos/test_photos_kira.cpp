// The photos job on real photos: the page's detector's landmarks on nine
// photos of one real person (Kira, tests/photos/data/kira; the photos
// themselves stay in ../shared/data and are not needed here) with the
// MediaPipe map that ships with the head. All are the same person, so
// every photo must be used except 0004, whose landmarks are the detector's
// misreading of a full profile (an upside-down face).
#include "head/generic_head.h"
#include "photos/photos_job.h"
#include "test_data.h"
#include "test_kira.h"

#include <algorithm>
#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <map>

namespace lk {
namespace {

TEST_CASE("the photos job uses every Kira photo the detector read, with cameras where the photos were taken", "[photos][kira]") {
  const std::vector<std::string> names = {"0001", "0002", "0003", "0004", "0006", "0007", "0008", "0009", "0010"};
  const std::vector<LandmarkPhoto> photos = test::kira_landmark_photos();  // in the order of names
  GenericHead generic;
  REQUIRE(load_generic_head(generic));
  LandmarkMap map;
  REQUIRE(parse_landmark_map_json(mediapipe_landmark_map_text(), map));
  PhotosJobResult r;
  REQUIRE(run_photos_job(generic, map, photos, {}, r));

  std::map<std::string, std::array<double, 2>> view;  // yaw, pitch in degrees
  std::vector<double> medians;
  for (size_t i = 0; i < names.size(); ++i) {
    const PhotoCalibration& pc = r.calib.photos[i];
    if (!pc.used) {
      std::printf("%s: refused: %s\n", names[i].c_str(), pc.refusal.c_str());
      continue;
    }
    double yaw, pitch;
    view_angles(pc.camera, yaw, pitch);
    view[names[i]] = {yaw, pitch};
    medians.push_back(pc.median_px);
    std::printf("%s: yaw %+.1f pitch %+.1f, median error %.2f px, %d landmarks turned away\n", names[i].c_str(), yaw,
                pitch, pc.median_px, pc.num_hidden);
  }
  std::printf("focal %.1f px (the tutorial's lens: 3813.6 px), rms %.2f -> %.2f px, shape fit %.2f -> %.2f px\n",
              r.calib.focal, r.calib.initial_rms_px, r.calib.final_rms_px, r.fit.initial_rms_px, r.fit.final_rms_px);

  // 0004: refused, and for the true reason.
  CHECK_FALSE(r.calib.photos[3].used);
  CHECK(r.calib.photos[3].refusal.find("upside-down") != std::string::npos);
  REQUIRE(r.calib.num_used() == 8);

  // Where the cameras are, by eye on the photos (yaw + = from the head's
  // left, pitch + = from above): 0001 frontal; 0002, 0008, 0010 from her
  // left; 0003, 0006, 0009 from her right; 0006-0008 from below, 0009-0010
  // from above.
  CHECK(std::abs(view["0001"][0]) < 10);
  CHECK(std::abs(view["0001"][1]) < 10);
  for (const char* n : {"0002", "0008", "0010"}) CHECK(view[n][0] > 15);
  for (const char* n : {"0003", "0006", "0009"}) CHECK(view[n][0] < -8);
  CHECK(std::abs(view["0007"][0]) < 10);
  for (const char* n : {"0006", "0007", "0008"}) CHECK(view[n][1] < -10);
  for (const char* n : {"0009", "0010"}) CHECK(view[n][1] > 8);
  // The order by yaw: 0006 (most from her right), 0003, 0009, then 0001 and
  // 0007 (frontal), then 0008, 0010, 0002 within a few degrees of each other.
  CHECK(view["0006"][0] < view["0003"][0]);
  CHECK(view["0003"][0] < view["0009"][0]);
  CHECK(view["0009"][0] < view["0001"][0] - 5);
  for (const char* n : {"0002", "0008", "0010"}) CHECK(view[n][0] > view["0001"][0] + 15);

  // Reprojection: with the map's slide (core/head/data/README.md) measured
  // 2.6-4.9 px per photo (median 3.8), the three from below 3.8-4.9; with
  // the first map (no slide) 2.2-3.6 px at or above eye level but 4.4-7.1 px
  // from below (the detector's bias changes with the view).
  std::sort(medians.begin(), medians.end());
  CHECK(medians[medians.size() / 2] < 4.0);
  CHECK(medians.back() < 6.0);
  CHECK(r.calib.final_rms_px < 6.0);
  CHECK(r.fit.final_rms_px < r.fit.initial_rms_px);

  // The focal: the self-calibration does NOT recover the lens (3813.6 px,
  // SOURCES.md); it settles at about 2100 px with the map's slide (1800 px
  // without it; docs/design/photos.md, "On real photos: Kira"). Held here to
  // its measured neighbourhood so a change shows.
  CHECK(r.calib.focal > 1900);
  CHECK(r.calib.focal < 2400);

  // With the focal weighed by the photos' disagreement (--focal-jackknife,
  // not the default) and her lens's focal as the prior (`--focal-px
  // 3813.6`, 5 % sigma; her JPEGs give our EXIF reader none): the
  // landmarks' spread no longer outweighs it; measured 3506 px (without
  // the weighing: 2221 px; docs/design/photos.md, "The focal from the
  // landmarks, honestly weighed").
  PhotosJobOptions exif;
  exif.calib.focal_prior_px = 3813.6;
  exif.calib.focal_from_jackknife = true;
  PhotosJobResult e;
  REQUIRE(run_photos_job(generic, map, photos, exif, e));
  std::printf("focal with the EXIF prior, weighed: %.1f px\n", e.calib.focal);
  CHECK(e.calib.focal_landmarks_raw > 1900);
  CHECK(e.calib.focal_landmarks_raw < 2400);
  CHECK(e.calib.focal > 3300);
  CHECK(e.calib.focal < 3813.6);
}

}  // namespace
}  // namespace lk
