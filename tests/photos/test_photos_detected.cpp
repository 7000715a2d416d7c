// The real detector's points on synthetic renders with a known truth
// (tests/photos/data/detected, made by tests/browser/detect_synth_photos.mjs:
// MediaPipe in Chromium on `likeness synth-photos --seed N --cameras 8`
// renders). The truth is re-made here from the seed, so these tests also
// catch a change to the synthetic people or cameras that leaves the
// committed points stale (regenerate them with that script).
#include "head/generic_head.h"
#include "head/surface_quality.h"
#include "photos/added_folds.h"
#include "photos/ground_truth.h"
#include "photos/landmark_learning.h"
#include "photos/photos_job.h"
#include "photos/shape_fit.h"
#include "photos/synthetic_outlines.h"
#include "photos/synthetic_views.h"
#include "synth/synth_head.h"
#include "test_data.h"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>

namespace lk {
namespace {

struct DetectedSession {
  GenericHead person;
  SyntheticSession truth;
  std::vector<LandmarkPhoto> photos;
  std::vector<int> camera_of;  // #photos: the truth camera of each points file
};

void load_session(const GenericHead& generic, int seed, DetectedSession& s) {
  LandmarkMap ph_map;
  std::vector<SurfacePoint> ph_lms;
  REQUIRE(placeholder_landmark_map(generic, 468, ph_map));
  REQUIRE(attach_landmark_map(ph_map, generic.mesh, 1e-3, ph_lms));
  REQUIRE(synthesize_head(generic, std::uint32_t(seed), SynthHeadOptions{}, s.person));
  SyntheticViewsOptions vo;
  vo.num_cameras = 8;  // tests/photos/data/detected/session.json
  REQUIRE(make_synthetic_views(s.person, ph_lms, std::uint32_t(seed), vo, s.truth));
  for (int c = 0; c < vo.num_cameras; ++c) {
    char name[64];
    std::snprintf(name, sizeof name, "/tests/photos/data/detected/seed%d/view_%02d.json", seed, c);
    const std::string text = test::read_file_text(test::source_dir() + name);
    if (text.empty()) continue;  // no face found on that view
    LandmarkPhoto ph;
    REQUIRE(parse_landmarks_json(text, ph));
    s.photos.push_back(ph);
    s.camera_of.push_back(c);
  }
}

// The generic head and the shipped MediaPipe map (with its slide) attached to it.
void load_shipped_map(GenericHead& generic, LandmarkMap& map, std::vector<SurfacePoint>& lms) {
  REQUIRE(load_generic_head(generic));
  REQUIRE(parse_landmark_map_json(mediapipe_landmark_map_text(), map));
  REQUIRE(attach_landmark_map(map, generic.mesh, PhotosJobOptions{}.map_max_distance_m, lms));
}

// The generic head with the shipped map attached, in one object.
struct ShippedMap {
  GenericHead generic;
  LandmarkMap map;
  std::vector<SurfacePoint> lms;
  ShippedMap() { load_shipped_map(generic, map, lms); }
};

// A seed's committed detected session calibrated with options a and with
// b (the map's slide): both results, each focal's relative error, and the
// session (for its photos' count).
struct TwoCalibrations {
  DetectedSession session;
  SelfCalibResult a, b;
  double ea = 0, eb = 0;
};
void calibrate_twice(const GenericHead& generic, const LandmarkMap& map, const std::vector<SurfacePoint>& lms, int seed,
                     const SelfCalibOptions& oa, const SelfCalibOptions& ob, TwoCalibrations& out) {
  load_session(generic, seed, out.session);
  REQUIRE(self_calibrate(out.session.photos, generic.mesh, lms, oa, out.a, &map.slide));
  REQUIRE(self_calibrate(out.session.photos, generic.mesh, lms, ob, out.b, &map.slide));
  REQUIRE(out.b.num_used() == int(out.session.photos.size()));
  const double truth = SyntheticViewsOptions{}.focal_px;
  out.ea = (out.a.focal - truth) / truth;
  out.eb = (out.b.focal - truth) / truth;
}

TEST_CASE("the committed detector points match their synthetic truth (else regenerate them)", "[photos][detected]") {
  GenericHead generic;
  LandmarkMap map;
  std::vector<SurfacePoint> lms;
  load_shipped_map(generic, map, lms);
  DetectedSession s;
  load_session(generic, 2, s);
  REQUIRE(s.photos.size() == 5);  // the profiles have no face for MediaPipe
  // Nearly frontal views: each mapped landmark's true place (with the map's
  // slide at the true view), projected by the true camera, against the
  // detector's pixel. Measured 3.8 px mean with the map re-made from
  // seeds 11-20 (6.8 with the first map, made on the generic head's
  // renders); a different person or camera puts it at tens of pixels.
  double sum = 0;
  int n = 0;
  for (size_t i = 0; i < s.photos.size(); ++i) {
    const Camera& cam = s.truth.cameras[size_t(s.camera_of[i])];
    double yaw, pitch;
    view_angles(cam, yaw, pitch);
    if (std::abs(yaw) > 15) continue;
    for (size_t m = 0; m < lms.size(); ++m) {
      if (!lms[m].valid() || !s.photos[i].present[m]) continue;
      Vec2 uv;
      const Vec3 shift = landmark_shift(map.slide, int(m), slide_view(map.slide, cam.center()));
      REQUIRE(cam.project(surface_position(s.person.mesh, lms[m]) + shift, uv));
      sum += (uv - s.photos[i].points[m]).norm();
      ++n;
    }
  }
  REQUIRE(n > 400);
  std::printf("detector vs truth on the frontal views of seed 2: %.2f px mean over %d points\n", sum / n, n);
  CHECK(sum / n < 5.5);
}

TEST_CASE("the photos job on real-detector points keeps every view and the cameras' order", "[photos][detected]") {
  GenericHead generic;
  REQUIRE(load_generic_head(generic));
  LandmarkMap map;
  REQUIRE(parse_landmark_map_json(mediapipe_landmark_map_text(), map));
  DetectedSession s;
  load_session(generic, 2, s);
  PhotosJobResult r;
  REQUIRE(run_photos_job(generic, map, s.photos, {}, r));
  REQUIRE(r.calib.num_used() == int(s.photos.size()));
  // Each recovered yaw on the true side, in the true order and close to it:
  // with the map's slide (docs/design/photos.md, "The detector's slide")
  // measured within 4.5 deg (+58.6 -> +54.1 the worst) and the focal 7 %
  // short; with a map without the slide the turned views came out less
  // turned (+58 -> +48 deg) and the focal 20 % short (997 px). (With
  // --focal-jackknife, not the default: 1.5 % short, 1231 px.)
  double last = -1e9;
  for (size_t i = 0; i < s.photos.size(); ++i) {
    double ty, tp, y, p;
    view_angles(s.truth.cameras[size_t(s.camera_of[i])], ty, tp);
    view_angles(r.calib.photos[i].camera, y, p);
    std::printf("view %d: yaw %+.1f (truth %+.1f), pitch %+.1f (truth %+.1f)\n", s.camera_of[i], y, ty, p, tp);
    CHECK(y * ty > 0);
    CHECK(std::abs(y - ty) < 6);
    CHECK(y > last);
    last = y;
  }
  std::printf("focal %.0f px (truth 1250)\n", r.calib.focal);
  CHECK(r.calib.focal > 0.87 * 1250);
  CHECK(r.calib.focal < 1.1 * 1250);
  // The face against the person, each head brought onto the truth by its
  // best similarity: measured 1.19 mm for the fit, 1.18 for the generic
  // head; with the first map (no slide) the fit was 3.22 mm, with the
  // re-made map's points but the slide left out 1.79. Not yet closer than
  // the generic head (docs/design/photos.md, "The detector's slide").
  const std::vector<int>& face = generic.annotations.regions.at("face");
  auto aligned_face_mm = [&](const TriMesh& mesh) {
    TriMesh m = mesh;
    const Similarity sim = fit_similarity(mesh.positions, s.person.mesh.positions, face);
    for (Vec3& p : m.positions) p = sim.apply(p);
    return 1000 * surface_distances(s.person.mesh, face, m).mean;
  };
  const double fit_mm = aligned_face_mm(r.fit.mesh), generic_mm = aligned_face_mm(generic.mesh);
  std::printf("face, aligned: fit %.2f mm, generic head %.2f mm\n", fit_mm, generic_mm);
  CHECK(fit_mm < 1.1 * generic_mm);
  // Folds: the fit must not crease the smooth level 3 where the generic head
  // is smooth (photos/added_folds.h). Measured (2026-11-29): dihedral growth
  // p95 0.2-0.6 deg per region, cheeks max 2.3, eyes max 12.1 deg, no
  // edge grown by more than 15 deg.
  std::vector<AddedFolds> folds;
  REQUIRE(measure_added_folds(generic, r.fit.mesh.positions, 3, 15.0, folds));
  for (const AddedFolds& f : folds) {
    INFO(f.region << ": p95 " << f.p95_deg << " max " << f.max_deg << " deg, " << f.creased << " edges > 15 deg, "
                  << f.crossings << " level-3 crossing pairs (generic head " << f.generic_crossings << ")");
    // The lips do not cross (photos/lips.h): 398 pairs at level 3 with the
    // lips free (the generic head has 24, at the mouth corners); 0 with the
    // lip edges bound and the mouth bag kept inside.
    if (f.region == "lips") CHECK(f.crossings == 0);
    CHECK(f.edges > 0);
    CHECK(f.p95_deg < 1.5);
    // The face and lips regions hold the mouth bag: drawing its corners in
    // until no level 0..3 crosses (2026-12-01) grows 8 edges there by more
    // than 15 deg (0 when level 3 alone was checked and level 2 kept 4
    // pairs); the bag step moves bag vertices only. Measured with the creases
    // the head is exported with (head_creases: the canthi as corners and the
    // socket rings, 2026-12-02) the face also grows 3 edges at the outer eye
    // corners on seed 2 (11 in all; 8 with the rim curves alone).
    CHECK(f.creased <= (f.region == "face" ? 12 : f.region == "lips" ? 10 : 2));
    if (f.region != "face") CHECK(f.max_deg < 20);
  }
  // No crossing on any level 0..3 the head exports: 4 pairs over the mouth
  // bag below level 3 when the bag was kept inside by level 3 alone (before
  // 2026-12-01), 0 with every level checked.
  GenericHead fitted = generic;
  fitted.mesh.positions = r.fit.mesh.positions;
  fitted.mesh.normals.clear();
  HeadSurfaceQuality q;
  REQUIRE(measure_head_surface(fitted, 3, q));
  for (size_t l = 0; l < q.crossing_pairs.size(); ++l) {
    INFO("level " << l);
    CHECK(q.crossing_pairs[l] == 0);
  }
}

// A detector that sees every landmark 3 mm in front of the skin and 1 mm
// up: exact projections of those points on two synthetic people; the map
// re-made from them must find the shifted points, and a map attached with
// them must reproject the detector's pixels exactly (the offset is kept).
TEST_CASE("a landmark map re-made from a detector's points finds where it sees them, off the surface", "[photos][detected]") {
  GenericHead generic;
  REQUIRE(load_generic_head(generic));
  LandmarkMap start;
  std::vector<SurfacePoint> on_skin;
  REQUIRE(placeholder_landmark_map(generic, 200, start));
  REQUIRE(attach_landmark_map(start, generic.mesh, 1e-3, on_skin));
  const Vec3 shift(0, 0.001, 0.003);
  std::vector<GenericHead> people(2);
  std::vector<DetectedSessionView> sessions;
  for (int k = 0; k < 2; ++k) {
    REQUIRE(synthesize_head(generic, std::uint32_t(31 + k), SynthHeadOptions{}, people[size_t(k)]));
    std::vector<SurfacePoint> seen = on_skin;
    for (SurfacePoint& p : seen) p.offset += shift;
    SyntheticViewsOptions vo;
    vo.num_cameras = 8;
    vo.noise_px = 0;
    SyntheticSession ses;
    REQUIRE(make_synthetic_views(people[size_t(k)], seen, std::uint32_t(31 + k), vo, ses));
    sessions.push_back({&people[size_t(k)].mesh, ses.cameras, ses.photos});
  }
  LandmarkMap learned;
  LearnMapReport rep;
  REQUIRE(learn_landmark_map(generic.mesh, start, sessions, LearnMapOptions{}, learned, &rep));
  CHECK(rep.learned > 150);
  // The people differ from the generic head, so the carried point is exact
  // only up to how the surface bends under the offset: well under 1 mm.
  std::vector<double> err;
  for (size_t m = 0; m < start.points.size(); ++m)
    if (start.present[m] && learned.points[m] != start.points[m])
      err.push_back((learned.points[m] - (start.points[m] + shift)).norm());
  std::sort(err.begin(), err.end());
  REQUIRE(err.size() > 150);
  std::printf("re-made map: %d landmarks, error median %.3f mm, p95 %.3f mm (the shift is 3.2 mm)\n", rep.learned,
              1000 * err[err.size() / 2], 1000 * err[err.size() * 95 / 100]);
  CHECK(err[err.size() / 2] < 2e-4);
  CHECK(err[err.size() * 95 / 100] < 5e-4);
  // Attached, the re-made points stay where the map says (offset kept).
  std::vector<SurfacePoint> att;
  REQUIRE(attach_landmark_map(learned, generic.mesh, 0.01, att));
  for (size_t m = 0; m < att.size(); ++m)
    if (att[m].valid()) REQUIRE((surface_position(generic.mesh, att[m]) - learned.points[m]).norm() < 1e-9);
  // A session of another topology: refused.
  TriMesh small;
  small.positions = {Vec3::Zero(), Vec3::UnitX(), Vec3::UnitY()};
  small.triangles = {Tri{0, 1, 2}};
  std::vector<DetectedSessionView> bad = {{&small, {}, {}}};
  CHECK_FALSE(learn_landmark_map(generic.mesh, start, bad, LearnMapOptions{}, learned).ok());
}

// The shape fit's symmetry term (photos/shape_fit.h; weight 0.3 in the
// job). Detected seed 1 (MediaPipe's points on the synthetic renders, 8
// cameras), measured 2026-12-02: the face against the person after the best
// similarity 1.04 mm without the term, 0.75 with it; the fitted control
// mesh's asymmetry (mean |S d_a - d_b| over the mirror pairs) 3.22 -> 0.15
// mm.
TEST_CASE("on the detector's points the symmetric fit is closer to the person and mirror-symmetric", "[photos][detected][symmetry]") {
  const ShippedMap shipped;
  const GenericHead& generic = shipped.generic;
  const LandmarkMap& map = shipped.map;
  DetectedSession s;
  load_session(generic, 1, s);
  REQUIRE(s.photos.size() >= 4);
  const std::vector<LandmarkPhoto>& photos = s.photos;
  const GenericHead& person = s.person;
  const std::vector<std::array<int, 2>> pairs = mirror_vertex_pairs(generic.mesh);
  auto asymmetry_mm = [&](const std::vector<Vec3>& x) {
    double sum = 0;
    for (const auto& [a, b] : pairs) {
      const Vec3 da = x[size_t(a)] - generic.mesh.positions[size_t(a)], db = x[size_t(b)] - generic.mesh.positions[size_t(b)];
      sum += (Vec3(-da.x(), da.y(), da.z()) - db).norm();
    }
    return 1000 * sum / double(pairs.size());
  };
  auto aligned_mm = [&](const TriMesh& mesh, const std::vector<int>& region) {
    TriMesh m = mesh;
    const Similarity sim = fit_similarity(mesh.positions, person.mesh.positions, region);
    for (Vec3& p : m.positions) p = sim.apply(p);
    return 1000 * surface_distances(person.mesh, region, m).mean;
  };
  PhotosJobOptions on, off;
  REQUIRE(on.fit.symmetry_weight > 0);  // the job's default
  off.fit.symmetry_weight = 0;
  PhotosJobResult ron, roff;
  REQUIRE(run_photos_job(generic, map, photos, on, ron));
  REQUIRE(run_photos_job(generic, map, photos, off, roff));
  const std::vector<int>& face = generic.annotations.regions.at("face");
  const double face_on = aligned_mm(ron.fit.mesh, face), face_off = aligned_mm(roff.fit.mesh, face);
  const double asym_on = asymmetry_mm(ron.fit.mesh.positions), asym_off = asymmetry_mm(roff.fit.mesh.positions);
  std::printf("detected seed 1: face aligned %.2f mm without the symmetry term, %.2f with; asymmetry %.2f -> %.2f mm\n",
              face_off, face_on, asym_off, asym_on);
  CHECK(face_on < 0.85 * face_off);
  CHECK(asym_on < 0.2 * asym_off);
  // What one side's points alone ask for is left unexplained: the landmark
  // rms grows (measured 1.34 -> 1.70 px), well within the detector's error
  // (3-4 px against the truth on these renders).
  std::printf("landmark rms %.2f -> %.2f px\n", roff.fit.final_rms_px, ron.fit.final_rms_px);
  CHECK(ron.fit.final_rms_px > roff.fit.final_rms_px);
  CHECK(ron.fit.final_rms_px < roff.fit.final_rms_px + 1.0);
}

// The head's outline in each photo (what a plain background gives: the
// person's exact mask) through the cameras the detector's points give: the
// face's outline brings the face closer, and the scalp's, through those
// cameras (their focal short), would bend the back of the head; the job
// leaves the scalp and the ears out by default (SilhouetteOptions).
TEST_CASE("on the detector's points the face's outline brings the face closer and leaves the head's back alone",
          "[photos][detected][silhouettes]") {
  const ShippedMap shipped;
  const GenericHead& generic = shipped.generic;
  DetectedSession s;
  load_session(generic, 4, s);
  REQUIRE(s.photos.size() >= 4);
  std::vector<PhotoOutline> all, outlines;
  REQUIRE(synthetic_outlines(s.person.mesh, s.truth.cameras, {}, all));
  for (int c : s.camera_of) outlines.push_back(all[size_t(c)]);
  auto aligned_mm = [&](const TriMesh& mesh, const std::vector<const char*>& region_names) {
    const std::vector<int>& face = generic.annotations.regions.at("face");
    TriMesh m = mesh;
    const Similarity sim = fit_similarity(mesh.positions, s.person.mesh.positions, face);
    for (Vec3& p : m.positions) p = sim.apply(p);
    std::vector<int> region;
    for (const char* name : region_names)
      for (int v : generic.annotations.regions.at(name)) region.push_back(v);
    return 1000 * surface_distances(s.person.mesh, region, m).mean;
  };
  PhotosJobOptions face_only, whole;
  whole.silhouettes.excluded_regions = {"neck"};
  PhotosJobResult none, rf, rw;
  REQUIRE(run_photos_job(generic, shipped.map, s.photos, face_only, none));
  REQUIRE(run_photos_job(generic, shipped.map, s.photos, face_only, rf, &outlines));
  REQUIRE(run_photos_job(generic, shipped.map, s.photos, whole, rw, &outlines));
  double face[3], scalp[3], head[3];
  const PhotosJobResult* runs[3] = {&none, &rf, &rw};
  for (int k = 0; k < 3; ++k) {
    face[k] = aligned_mm(runs[k]->fit.mesh, {"face"});
    scalp[k] = aligned_mm(runs[k]->fit.mesh, {"scalp"});
    head[k] = aligned_mm(runs[k]->fit.mesh, {"face", "scalp", "ears"});
  }
  std::printf("detected seed 4, aligned mm, no outline / the face's outline (default) / the whole head's: face %.2f / "
              "%.2f / %.2f, scalp %.2f / %.2f / %.2f, head %.2f / %.2f / %.2f\n",
              face[0], face[1], face[2], scalp[0], scalp[1], scalp[2], head[0], head[1], head[2]);
  CHECK(face[1] < 0.8 * face[0]);
  CHECK(head[1] < head[0]);
  CHECK(scalp[1] < 0.5 * scalp[2]);
  CHECK(head[1] < 0.7 * head[2]);
}

}  // namespace
}  // namespace lk

namespace lk {
namespace {

// The same session with each detected point replaced by the map's point
// (with its slide at the true view) on the person, projected by the true
// camera, plus mix times the detector's residual there: the detector's
// photos, the same landmarks present, the same views, only the pixels
// exact (mix 0) or half-way (mix 0.5).
std::vector<LandmarkPhoto> mixed_points(const DetectedSession& s, const LandmarkMap& map,
                                        const std::vector<SurfacePoint>& lms, double mix) {
  std::vector<LandmarkPhoto> out = s.photos;
  for (size_t i = 0; i < out.size(); ++i) {
    const Camera& cam = s.truth.cameras[size_t(s.camera_of[i])];
    for (size_t m = 0; m < lms.size() && m < out[i].points.size(); ++m) {
      if (!lms[m].valid() || !out[i].present[m]) continue;
      const Vec3 X = surface_position(s.person.mesh, lms[m]) +
                     landmark_shift(map.slide, int(m), slide_view(map.slide, cam.center()));
      Vec2 uv;
      REQUIRE(cam.project(X, uv));
      out[i].points[m] = uv + mix * (out[i].points[m] - uv);
    }
  }
  return out;
}

}  // namespace

TEST_CASE("the self-calibration's short focal on detected points comes from the points, not the method",
          "[photos][detected]") {
  // docs/design/photos.md, "Why the focal comes out short": on the
  // detector's photos of seed 2 with exact pixels the focal and the views
  // are recovered (measured +0.1 %, rotations 0.07 deg; seeds 1-5 within
  // 0.5 %), so visibility, the slide in the bundle adjustment and the
  // landmarks' prior do not bias it; the error grows with the share of the
  // detector's residual kept (half: -4.6 %, all: -7.4 % on seed 2).
  GenericHead generic;
  LandmarkMap map;
  std::vector<SurfacePoint> lms;
  load_shipped_map(generic, map, lms);
  DetectedSession s;
  load_session(generic, 2, s);
  const double truth_focal = SyntheticViewsOptions{}.focal_px;
  // The bundle adjustment's own focal: no prior, no detector's ratio.
  SelfCalibOptions method;
  method.focal_from_jackknife = false;
  auto focal_error = [&](double mix, SelfCalibResult& r) {
    REQUIRE(self_calibrate(mixed_points(s, map, lms, mix), generic.mesh, lms, method, r, &map.slide));
    REQUIRE(r.num_used() == int(s.photos.size()));
    return (r.focal - truth_focal) / truth_focal;
  };
  SelfCalibResult exact, half, full;
  const double e0 = focal_error(0, exact), e_half = focal_error(0.5, half), e_full = focal_error(1, full);
  std::printf("seed 2 focal error: exact pixels %+.1f %%, half the detector's residual %+.1f %%, all of it %+.1f %%\n",
              100 * e0, 100 * e_half, 100 * e_full);
  CHECK(std::abs(e0) < 0.02);
  // The views, each brought into the truth's frame by the similarity of
  // the bundle-adjusted landmarks onto the person's.
  std::vector<Vec3> from, to;
  std::vector<int> idx;
  for (size_t m = 0; m < lms.size(); ++m)
    if (lms[m].valid() && exact.landmark_seen[m]) {
      idx.push_back(int(from.size()));
      from.push_back(exact.landmarks[m]);
      to.push_back(surface_position(s.person.mesh, lms[m]));
    }
  const Similarity sim = fit_similarity(from, to, idx);
  for (size_t i = 0; i < s.photos.size(); ++i)
    CHECK(rotation_angle_deg(transform_camera(exact.photos[i].camera, sim).R,
                             s.truth.cameras[size_t(s.camera_of[i])].R) < 1.0);
  CHECK(std::abs(e_half) < std::abs(e_full));
}

TEST_CASE("a per-photo depth scale learned on other seeds brings the detected sessions' focal closer", "[photos][detected]") {
  // docs/design/photos.md, "A per-photo depth scale": the detector's points
  // make each view look as if seen through another lens; the depth scale
  // learned on seeds 11-20 (the slide's training seeds, with the focal held
  // at the truth) takes that up. On the committed seeds 1-5 (not learned
  // on) the mean |focal error| was measured 15.9 % without, 7.6 % with it.
  GenericHead generic;
  LandmarkMap map;
  std::vector<SurfacePoint> lms;
  load_shipped_map(generic, map, lms);
  SelfCalibOptions plain, learned;  // the bundle adjustment's own focal (no prior, no detector's ratio)
  plain.focal_from_jackknife = learned.focal_from_jackknife = false;
  learned.depth_scale_sigma = 0.01;
  learned.depth_scale_0 = 1.160;
  learned.depth_scale_yaw2 = -0.212;
  double without = 0, with = 0;
  for (int seed = 1; seed <= 5; ++seed) {
    TwoCalibrations t;
    calibrate_twice(generic, map, lms, seed, plain, learned, t);
    const SelfCalibResult& b = t.b;
    const double ea = t.ea, eb = t.eb;
    std::printf("seed %d focal error: %+.1f %% -> %+.1f %% with the learned depth scale\n", seed, 100 * ea, 100 * eb);
    without += std::abs(ea) / 5;
    with += std::abs(eb) / 5;
    // Each photo's depth scale stays at its view's learned mean.
    for (const PhotoCalibration& pc : b.photos) CHECK((pc.depth_scale > 0.9 && pc.depth_scale < 1.2));
  }
  CHECK(without > 0.12);
  CHECK(with < 0.10);
}

TEST_CASE("the focal weighed by the photos' disagreement comes within 10 % on the detected sessions with no EXIF, and exact points override the prior",
          "[photos][detected]") {
  // docs/design/photos.md, "The focal from the landmarks, honestly
  // weighed": the bundle adjustment's focal over the detector's measured
  // ratio (0.853, learned on seeds 11-20), its spread over the photos left
  // out in turn (jackknife), combined with a phone's 26 mm prior. Seeds 1-5
  // (not learned on) were -18.9 .. -7.4 % and measured -4.8 .. -1.5 % so.
  const ShippedMap shipped;
  const GenericHead& generic = shipped.generic;
  const LandmarkMap& map = shipped.map;
  const std::vector<SurfacePoint>& lms = shipped.lms;
  const double truth_focal = SyntheticViewsOptions{}.focal_px;
  SelfCalibOptions plain, weighed;  // weighed: as `likeness photos --focal-jackknife` (not the default)
  weighed.focal_from_jackknife = true;
  weighed.slide_focal_ratio = PhotosJobOptions{}.mediapipe_focal_ratio;  // as the photos job sets it
  for (int seed = 1; seed <= 5; ++seed) {
    TwoCalibrations t;
    calibrate_twice(generic, map, lms, seed, plain, weighed, t);
    const SelfCalibResult &a = t.a, &b = t.b;
    const double ea = t.ea, eb = t.eb;
    std::printf("seed %d focal error: %+.1f %% -> %+.1f %% (landmarks over the ratio %+.1f %% +- %.1f %%)\n", seed,
                100 * ea, 100 * eb, 100 * (b.focal_landmarks - truth_focal) / truth_focal,
                100 * b.focal_landmarks_sigma / truth_focal);
    CHECK(std::abs(eb) < 0.10);
    CHECK(b.focal_landmarks_raw == Approx(a.focal).epsilon(1e-6));  // the same adjustment before the prior
    CHECK(b.focal_landmarks_sigma > 0);
    if (seed == 1) CHECK(ea < -0.15);  // the bias this replaces: seed 1 was -18.9 %
  }

  // Exact pixels (seed 2, no detector's ratio): a prior 50 % long (39 mm
  // instead of 26) is overridden; the photos agree, so the jackknife's
  // spread is small. Measured: see the printout.
  DetectedSession s;
  load_session(generic, 2, s);
  SelfCalibOptions far_prior;  // no detector's ratio: exact pixels are not MediaPipe's
  far_prior.focal_from_jackknife = true;
  far_prior.typical_focal_35mm = 39;
  SelfCalibResult r;
  REQUIRE(self_calibrate(mixed_points(s, map, lms, 0), generic.mesh, lms, far_prior, r, &map.slide));
  const double e = (r.focal - truth_focal) / truth_focal;
  std::printf("seed 2 exact pixels, prior at %.0f px: focal %+.2f %%, landmarks %+.2f %% +- %.2f %%\n", r.focal_prior,
              100 * e, 100 * (r.focal_landmarks - truth_focal) / truth_focal, 100 * r.focal_landmarks_sigma / truth_focal);
  CHECK(r.focal_prior > 1.4 * truth_focal);
  CHECK(std::abs(e) < 0.02);
  CHECK(r.focal_landmarks_sigma < 0.01 * truth_focal);
}

}  // namespace lk
