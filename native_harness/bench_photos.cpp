// likeness bench --only photos: photos to head (issue 37, fua1998) on
// synthetic sessions with known cameras: camera errors, truth->fit and
// fit->truth distances over the face, per-stage CPU times. The paper reports
// no camera figures (its cameras were calibrated) and its distances are to
// stereo points on real faces (Fig. 7: medians 2.33 / 6.38 / 0.55, units
// not stated); they are printed for reference, not as a like-for-like goal.
#include "command.h"
#include "photos_fit_options.h"
#include "photos_pulls_report.h"
#include "synthetic_session_images.h"
#include "timing.h"

#include "io/io.h"

#include "head/generic_head.h"
#include "head/head_creases.h"
#include "head/skin_detail.h"
#include "head/surface_quality.h"
#include "components/components.h"
#include "photos/added_folds.h"
#include "photos/eye_lids.h"
#include "photos/ground_truth.h"
#include "photos/photos_job.h"
#include "photos/synthetic_outlines.h"
#include "photos/synthetic_views.h"
#include "raycast/bvh.h"
#include "synth/skin_field.h"
#include "synth/synth_head.h"
#include "texture/synthetic_photo.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <map>

namespace lk::cli {
namespace {

// --photos-detected DIR: the real detector's points (MediaPipe in Chromium,
// tests/browser/detect_synth_photos.mjs) on synth-photos renders, with the
// MediaPipe map; the truth (person, cameras) re-made from each seed. Prints
// the head against the truth with and without the best similarity (the
// gauge of a photo head is free up to scale; unaligned = in the generic
// head's frame, where the fit's prior keeps it), and the detector's error
// against the truth's projections per landmark group and view.

// --photos-coarse N:S[,N:S...], --photos-schedule S[,S...]|none and --photos-follow K[:W] (photos_fit_options.h).
// --photos-symmetry W: the shape fit's mirror-symmetry weight (shape_fit.h).
bool parse_fit_levels(const Args& args, ShapeFitOptions& fit) {
  std::string why;
  if (!args.get_double("photos-symmetry", fit.symmetry_weight, fit.symmetry_weight, 0, 1e6)) return false;
  if (lk::cli::parse_fit_levels(args.get("photos-coarse"), args.get("photos-schedule"), args.get("photos-follow"), fit, why))
    return true;
  std::printf("  --photos-coarse / --photos-schedule / --photos-follow: %s\n", why.c_str());
  return false;
}

// Folds (issue 37): per region, how much the fit grew the dihedral angles
// of the smooth level 3 over the generic head's (photos/added_folds.h: p95,
// max, and edges grown by more than 15 deg), and the self-crossing pairs of
// levels 0..3 (head/surface_quality.h).
constexpr double kCreaseDeg = 15;
const char* const kFoldRegions[] = {"face", "cheeks", "eyes", "nose", "brow", "lips", "eye pockets"};

struct FoldFigures {
  std::map<std::string, AddedFolds> regions;
  int crossings = 0;
  // The levels as the photos project makes them, with the generic head's
  // skin detail (head/skin_detail.h): their crossing pairs (levels 0..3)
  // and the smooth level 3's roughness p95 (deg) per region without and
  // with it (head/surface_quality.h).
  bool detailed = false;
  int detail_crossings = 0;
  std::map<std::string, double> plain_p95, detail_p95;
};

// The skin detail the photos project puts on a head's levels, once per
// bench, with its CPU time.
const std::vector<std::vector<double>>* bench_skin_detail(const GenericHead& generic) {
  static std::vector<std::vector<double>> detail;
  static bool done = false, ok = false;
  if (!done) {
    done = true;
    const double t0 = cpu_clock_ms();
    ok = generic_skin_detail(generic, 3, SkinDetailOptions{}, detail).ok();
    std::printf("  the generic head's skin detail (levels 1..3): %s, %.0f ms CPU\n", ok ? "made" : "failed",
                cpu_clock_ms() - t0);
  }
  return ok ? &detail : nullptr;
}

bool measure_folds(const GenericHead& generic, const TriMesh& mesh, FoldFigures& out) {
  out = {};
  std::vector<AddedFolds> added;
  if (!measure_added_folds(generic, mesh.positions, 3, kCreaseDeg, added)) return false;
  for (const AddedFolds& r : added) out.regions[r.region] = r;
  GenericHead h = generic;
  h.mesh.positions = mesh.positions;
  h.mesh.normals.clear();
  HeadSurfaceQuality q;
  const ButterflyCreases creases = head_creases(generic.mesh, generic.annotations);
  if (!measure_head_surface(h, creases, 3, q)) return false;
  for (int c : q.crossing_pairs) out.crossings += c;
  HeadSurfaceQuality qd;
  if (const auto* detail = bench_skin_detail(generic); detail && measure_head_surface(h, creases, 3, qd, detail)) {
    out.detailed = true;
    for (int c : qd.crossing_pairs) out.detail_crossings += c;
    for (const RegionRoughness& r : q.regions) out.plain_p95[r.region] = r.p95_deg;
    for (const RegionRoughness& r : qd.regions) out.detail_p95[r.region] = r.p95_deg;
  }
  return true;
}

const char* const kDetailRegions[] = {"cheeks", "brow", "nose", "eyes", "mouth"};

struct FoldSums {
  std::map<std::string, double> p95, max, creased, crossings_in;
  double crossings = 0;
  int n = 0;
  std::map<std::string, double> plain_p95, detail_p95;
  double detail_crossings = 0;
  int detailed = 0;
};

void add_folds(const FoldFigures& f, FoldSums& sums) {
  for (const auto& [name, r] : f.regions) {
    sums.p95[name] += r.p95_deg;
    sums.max[name] += r.max_deg;
    sums.creased[name] += r.creased;
    sums.crossings_in[name] += r.crossings;
  }
  sums.crossings += f.crossings;
  ++sums.n;
  if (f.detailed) {
    for (const auto& [name, v] : f.plain_p95) sums.plain_p95[name] += v;
    for (const auto& [name, v] : f.detail_p95) sums.detail_p95[name] += v;
    sums.detail_crossings += f.detail_crossings;
    ++sums.detailed;
  }
}

void print_fold_means(const FoldSums& sums, const char* label) {
  if (!sums.n) return;
  std::printf("  folds added, mean over %d fits (%s), p95 / max deg / edges > %.0f deg:", sums.n, label, kCreaseDeg);
  for (const char* r : kFoldRegions) {
    auto it = sums.p95.find(r);
    if (it != sums.p95.end())
      std::printf(" %s %.2f / %.1f / %.1f", r, it->second / sums.n, sums.max.at(r) / sums.n, sums.creased.at(r) / sums.n);
  }
  std::printf("; crossing pairs %.1f (levels 0..3); level-3 crossings by region:", sums.crossings / sums.n);
  for (const char* r : kFoldRegions) {
    auto it = sums.crossings_in.find(r);
    if (it != sums.crossings_in.end()) std::printf(" %s %.1f", r, it->second / sums.n);
  }
  std::printf("\n");
  if (!sums.detailed) return;
  std::printf("  skin detail, mean over %d fits (%s): smooth level 3 roughness p95 deg without -> with:", sums.detailed,
              label);
  for (const char* r : kDetailRegions)
    if (sums.plain_p95.count(r) && sums.detail_p95.count(r))
      std::printf(" %s %.2f -> %.2f", r, sums.plain_p95.at(r) / sums.detailed, sums.detail_p95.at(r) / sums.detailed);
  std::printf("; crossing pairs with it %.1f (levels 0..3)\n", sums.detail_crossings / sums.detailed);
}

void print_folds(const char* label, const FoldFigures& f) {
  std::printf("       folds added (%s), p95 / max deg / edges > %.0f deg:", label, kCreaseDeg);
  for (const char* r : kFoldRegions) {
    auto it = f.regions.find(r);
    if (it != f.regions.end()) std::printf(" %s %.1f / %.1f / %d", r, it->second.p95_deg, it->second.max_deg, it->second.creased);
  }
  std::printf("; level-3 crossings by region, generic -> fit:");
  for (const char* r : kFoldRegions) {
    auto it = f.regions.find(r);
    if (it != f.regions.end()) std::printf(" %s %d -> %d", r, it->second.generic_crossings, it->second.crossings);
  }
  std::printf("; crossing pairs %d", f.crossings);
  if (f.detailed) {
    std::printf("; with the skin detail %d, roughness p95", f.detail_crossings);
    for (const char* r : kDetailRegions)
      if (f.plain_p95.count(r) && f.detail_p95.count(r))
        std::printf(" %s %.1f -> %.1f", r, f.plain_p95.at(r), f.detail_p95.at(r));
  }
  std::printf("\n");
}

// RMS distance of the bundle-adjusted landmarks (seen in >= 2 photos) from
// their generic-head places: how far the data pulls the shape.
double landmark_pull_mm(const SelfCalibResult& c, const TriMesh& generic, const std::vector<SurfacePoint>& lms) {
  double sum = 0;
  int n = 0;
  for (size_t m = 0; m < lms.size() && m < c.landmarks.size(); ++m)
    if (lms[m].valid() && c.landmark_seen[m]) {
      sum += (c.landmarks[m] - surface_position(generic, lms[m])).squaredNorm();
      ++n;
    }
  return n ? 1000 * std::sqrt(sum / n) : 0.0;
}

struct DetectedScores {
  DistanceStats face, head;
};

DetectedScores score_head(const TriMesh& mesh, const TriMesh& truth, const std::vector<int>& face,
                          const std::vector<int>& head, bool aligned, Similarity* used = nullptr) {
  TriMesh m = mesh;
  if (aligned) {
    const Similarity s = fit_similarity(mesh.positions, truth.positions, face);
    for (Vec3& p : m.positions) p = s.apply(p);
    if (used) *used = s;
  }
  return {surface_distances(truth, face, m), surface_distances(truth, head, m)};
}

int run_bench_detected(const Args& args, const std::string& dir, const GenericHead& generic,
                       const std::vector<int>& face, const std::vector<int>& head) {
  using Json = nlohmann::json;
  Bytes bytes;
  Json session, groups_json;
  try {
    if (!read_file(dir + "/session.json", bytes, 1 << 20)) throw std::runtime_error("no session.json");
    session = Json::parse(std::string(bytes.begin(), bytes.end()));
    if (read_file(dir + "/groups.json", bytes, 1 << 20)) groups_json = Json::parse(std::string(bytes.begin(), bytes.end()));
  } catch (const std::exception& e) {
    std::printf("  --photos-detected %s: %s (make it with tests/browser/detect_synth_photos.mjs)\n", dir.c_str(), e.what());
    return 1;
  }
  const int cameras = session.value("cameras", 0);
  // Landmark groups: the detector's own (face oval = "contour"), the rest "other" (nose, cheeks, forehead).
  std::vector<std::string> group_of(468, "other");
  if (groups_json.is_object())
    for (auto it = groups_json.begin(); it != groups_json.end(); ++it) {
      std::string g = it.key();
      if (g == "FACE_OVAL") g = "contour";
      else if (g.find("EYEBROW") != std::string::npos) g = "brows";
      else if (g.find("EYE") != std::string::npos) g = "eyes";
      else if (g == "LIPS") g = "lips";
      for (int k : it.value()) if (k >= 0 && k < 468) group_of[size_t(k)] = g;
    }
  LandmarkMap mp_map, ph_map;
  std::vector<SurfacePoint> mp_lms, ph_lms;
  // --photos-detected-map FILE: another map for the detected points (default: the one that ships).
  std::string map_text = mediapipe_landmark_map_text();
  if (args.has("photos-detected-map")) {
    if (!read_file(args.get("photos-detected-map"), bytes, kMaxLandmarkFileBytes)) return 1;
    map_text.assign(bytes.begin(), bytes.end());
  }
  Status map_status = parse_landmark_map_json(map_text, mp_map);
  if (map_status) map_status = attach_landmark_map(mp_map, generic.mesh, PhotosJobOptions{}.map_max_distance_m, mp_lms);
  if (map_status) map_status = placeholder_landmark_map(generic, 468, ph_map);
  if (map_status) map_status = attach_landmark_map(ph_map, generic.mesh, 1e-3, ph_lms);
  if (!map_status) {
    std::printf("  the map: %s\n", map_status.message.c_str());
    return 1;
  }
  // --photos-drop GROUP[,GROUP]: those landmark groups left out of the map (what they cost or bring).
  for (const std::string& g : split_list(args.get("photos-drop")))
    for (size_t m = 0; m < mp_map.points.size() && m < group_of.size(); ++m)
      if (group_of[m] == g) {
        mp_map.present[m] = 0;
        mp_lms[m] = SurfacePoint{};
      }
  std::printf("photos on the real detector's points (%s, %d cameras per seed, MediaPipe map%s; mm, CPU ms)\n", dir.c_str(),
              cameras, !mp_map.slide.has_slide() ? "" : args.has("photos-no-slide") ? ", its slide left out" : " with its slide");
  std::printf("  %-4s %5s %7s %6s | %-27s | %-27s | %-27s | %-27s | %5s\n", "seed", "used", "focal", "rot",
              "face unaligned gen -> fit", "face aligned gen -> fit", "head unaligned gen -> fit",
              "head aligned gen -> fit", "ms");
  // Detector error by group and yaw bucket (points facing the camera; those turned away apart).
  const std::vector<std::string> gnames = {"contour", "brows", "eyes", "lips", "other"};
  constexpr int kBuckets = 4;  // |yaw| < 15, < 35, < 60, >= 60
  std::map<std::string, std::array<double, kBuckets>> det_sum, det_n;
  std::array<double, kBuckets> hidden_sum{}, hidden_n{};
  // The detector's residual at the truth read as a lens: per view, the
  // relative focal change that best explains it with the view's pose free
  // (the mapped points facing the camera); negative = the points look
  // like a shorter lens (docs/design/photos.md, "Why the focal comes out short").
  std::array<double, kBuckets> lens_sum{}, lens_n{}, lens_min, lens_max;
  lens_min.fill(1e9);
  lens_max.fill(-1e9);
  double sums[9] = {0};
  int done = 0;
  FoldFigures generic_folds;
  if (measure_folds(generic, generic.mesh, generic_folds))
    std::printf("  the generic head: crossing pairs %d (levels 0..3)\n", generic_folds.crossings);
  FoldSums fold_sums;
  double outline_acc[3][2][3][3] = {};  // |yaw| bucket, near / far side, temple / cheek / jaw: sum px, sum |px|, count
  // Lid openings (gap / width, photos/eye_lids.h) in the views within 35 deg of
  // the front, both eyes: the detector's and the fitted head's against the
  // person's own rim (true cameras; the fitted head by its recovered camera).
  double lid_acc[4] = {0, 0, 0, 0};  // sum truth, sum detected, sum fitted, count
  double lid_abs[2] = {0, 0};        // sum |detected - truth|, sum |fitted - truth|
  int lid_fitted_n = 0;
  // --photos-pulls: per group the fitted displacement's outward share on
  // the cheeks and the jaw (photos/fit_pulls.h), summed over seeds; and
  // against the truth: the fit's and the generic's outward offset from the
  // person (each brought onto it by its best similarity over the face), mm.
  std::map<std::string, std::array<double, 6>> pull_sums;  // group: start, end per region (cheeks, jaw, ears)
  std::array<double, 9> width_sums{};                       // per region: fit - truth, generic - truth, fit itself
  int pull_runs = 0;
  for (int seed : session.value("seeds", std::vector<int>{})) {
    GenericHead person;
    SyntheticViewsOptions vo;
    vo.num_cameras = cameras;
    SyntheticSession truth;
    if (!synthesize_head(generic, std::uint32_t(seed), SynthHeadOptions{}, person) ||
        !make_synthetic_views(person, ph_lms, std::uint32_t(seed), vo, truth))
      return 1;
    std::vector<LandmarkPhoto> photos;
    std::vector<int> cam_of;
    for (int c = 0; c < cameras; ++c) {
      char name[32];
      std::snprintf(name, sizeof name, "view_%02d", c);
      const std::string path = dir + "/seed" + std::to_string(seed) + "/" + name + ".json";
      LandmarkPhoto ph;
      if (!read_file(path, bytes, kMaxLandmarkFileBytes)) continue;  // no face found on that view
      if (!parse_landmarks_json(std::string(bytes.begin(), bytes.end()), ph)) {
        std::printf("  %s: unreadable\n", path.c_str());
        return 1;
      }
      photos.push_back(ph);
      cam_of.push_back(c);
    }
    // The detector's face outline against the person's rim, true cameras
    // (photos/contour_obs.h): mean signed px (+ = outside the rim) and
    // mean |px| per |yaw| bucket, the near and far side apart.
    {
      SelfCalibResult tc;
      tc.photos.resize(photos.size());
      for (size_t i = 0; i < photos.size(); ++i) {
        tc.photos[i].used = true;
        tc.photos[i].camera = truth.cameras[size_t(cam_of[i])];
      }
      TriMesh at = generic.mesh;
      at.positions = person.mesh.positions;
      std::string line;
      for (const ContourDistance& d : contour_distances(at, mp_lms, photos, tc, person.mesh.positions, PhotosJobOptions{}.contours)) {
        double yaw, pitch;
        view_angles(tc.photos[size_t(d.photo)].camera, yaw, pitch);
        const size_t b = std::abs(yaw) < 15 ? 0 : std::abs(yaw) < 35 ? 1 : 2;
        // Loop positions 1..17 are the person's left (+x): the near side when yaw > 0.
        const bool near = std::abs(yaw) < 15 || ((d.loop_index < 18) == (yaw > 0));
        if (!std::isfinite(d.px) || d.loop_index == 0 || d.loop_index == 18) continue;
        const int j = d.loop_index <= 18 ? d.loop_index : 36 - d.loop_index;  // 1..17 from the top
        auto& acc = outline_acc[b][near ? 0 : 1][j <= 6 ? 0 : j <= 12 ? 1 : 2];
        acc[0] += d.px;
        acc[1] += std::abs(d.px);
        acc[2] += 1;
      }
    }
    // The detector against the truth: each mapped landmark's true place projected by the true camera.
    for (size_t i = 0; i < photos.size(); ++i) {
      const Camera& cam = truth.cameras[size_t(cam_of[i])];
      double yaw, pitch;
      view_angles(cam, yaw, pitch);
      const size_t b = std::abs(yaw) < 15 ? 0 : std::abs(yaw) < 35 ? 1 : std::abs(yaw) < 60 ? 2 : 3;
      const Vec3 C = -cam.R.transpose() * cam.t;
      Eigen::Matrix<double, 7, 7> lens_N = Eigen::Matrix<double, 7, 7>::Zero();
      Eigen::Matrix<double, 7, 1> lens_g = Eigen::Matrix<double, 7, 1>::Zero();
      for (size_t m = 0; m < mp_lms.size() && m < photos[i].points.size(); ++m) {
        if (!mp_lms[m].valid() || !photos[i].present[m]) continue;
        // Where the map (with its slide, if any, at the true view) puts the landmark on the person.
        const Vec3 X = surface_position(person.mesh, mp_lms[m]) +
                       (args.has("photos-no-slide") ? Vec3::Zero()
                                                    : landmark_shift(mp_map.slide, int(m), slide_view(mp_map.slide, C)));
        const Tri& t = person.mesh.triangles[size_t(mp_lms[m].triangle)];
        const std::vector<Vec3>& P = person.mesh.positions;
        const Vec3 n = (P[size_t(t[1])] - P[size_t(t[0])]).cross(P[size_t(t[2])] - P[size_t(t[0])]).normalized();
        Vec2 uv;
        if (!cam.project(X, uv)) continue;
        const double e = (uv - photos[i].points[m]).norm();
        if (n.dot((C - X).normalized()) < 0.3) {
          hidden_sum[b] += e;
          hidden_n[b] += 1;
          continue;
        }
        det_sum[group_of[m]][b] += e;
        det_n[group_of[m]][b] += 1;
        ProjectionJacobian pj;
        if (!projection_jacobian(cam, X, photos[i].points[m], pj)) continue;
        Eigen::Matrix<double, 2, 7> a;
        a << cam.fx * pj.d_focal, pj.d_rotation, pj.d_translation;
        lens_N += a.transpose() * a;
        lens_g -= a.transpose() * pj.residual;
      }
      // The focal change (relative) this view's residual alone asks for, its pose free.
      const double lens = lens_N.ldlt().solve(lens_g)[0];
      if (std::isfinite(lens)) {
        lens_sum[b] += lens;
        lens_n[b] += 1;
        lens_min[b] = std::min(lens_min[b], lens);
        lens_max[b] = std::max(lens_max[b], lens);
      }
    }
    PhotosJobOptions opt;
    // Sensitivity: the bench's --photos-stiffness-scale, and the calibration's focal prior.
    double stiffness_scale = 1;
    if (!args.get_double("photos-stiffness-scale", 1.0, stiffness_scale, 1e-6, 1e6) ||
        !args.get_double("photos-focal-px", 0, opt.calib.focal_prior_px, 0, 1e6) ||
        !args.get_double("photos-focal-sigma", opt.calib.focal_prior_sigma, opt.calib.focal_prior_sigma, 1e-6, 10) ||
        !args.get_double("photos-shape-sigma", opt.calib.shape_sigma_m, opt.calib.shape_sigma_m, 1e-6, 1) ||
        !args.get_double("photos-view-cos", opt.calib.min_view_cos, opt.calib.min_view_cos, -1, 0.99) ||
        !args.get_double("photos-depth-scale", 0, opt.calib.depth_scale_sigma, 0, 10) ||
        !args.get_double("photos-depth-yaw2", 0, opt.calib.depth_scale_yaw2, -10, 10) ||
        !args.get_double("photos-depth-0", 1, opt.calib.depth_scale_0, 0.1, 10) ||
        !args.get_double("photos-contour-lambda", opt.contour_lambda_scale, opt.contour_lambda_scale, 0, 100))
      return 1;
    for (double& k : opt.fit.stiffness_schedule) k *= stiffness_scale;
    // --photos-contours: the face outline's jaw landmarks as contour observations (photos/contour_obs.h).
    opt.contour_landmarks = args.has("photos-contours");
    // --photos-lids: the lid contour observed on the eye rims, the lids turned to it (photos/eye_lids.h).
    opt.lids_on_rim = args.has("photos-lids");
    // --photos-no-slide: the map's slide model left out; --photos-no-slide-sigma: its scatter as weights left out.
    opt.use_slide = !args.has("photos-no-slide");
    opt.calib.focal_from_jackknife = args.has("photos-focal-jackknife");
    if (args.has("photos-sil-exclude")) opt.silhouettes.excluded_regions = split_list(args.get("photos-sil-exclude"));
    opt.calib.use_slide_sigma = !args.has("photos-no-slide-sigma");
    if (!parse_fit_levels(args, opt.fit)) return 1;
    // --photos-detected-silhouettes: each view rendered as synth-photos
    // writes it, its outline found on its plain background as the page and
    // `likeness photos --photos` find it.
    std::vector<PhotoOutline> outlines;
    const bool with_outlines = args.has("photos-detected-silhouettes");
    if (with_outlines) {
      std::vector<Image> images;
      if (!render_session_images(generic, person, std::uint32_t(seed), truth.cameras, images)) return 1;
      const double o0 = cpu_clock_ms();
      for (size_t i = 0; i < photos.size(); ++i) {
        PhotoOutline o;
        const Status os = outline_from_plain_photo(images[size_t(cam_of[i])], photos[i].width, photos[i].height,
                                                   kPlainOutlineMaxSide,
                                                   PlainBackgroundOptions{}, OutlineOptions{}, o);
        if (!os) std::printf("       view %d: %s\n", cam_of[i], os.message.c_str());
        outlines.push_back(o);
      }
      if (!photos.empty())
        std::printf("       outlines: %zu photos of %dx%d, %.0f ms CPU each (shrunk to %d px, found, put back)\n",
                    photos.size(), photos[0].width, photos[0].height, (cpu_clock_ms() - o0) / photos.size(),
                    kPlainOutlineMaxSide);
    }
    PhotosJobResult r;
    const double t0 = cpu_clock_ms();
    const Status st = run_photos_job(generic, mp_map, photos, opt, r, with_outlines ? &outlines : nullptr);
    const double ms = cpu_clock_ms() - t0;
    if (!st) {
      std::printf("  %-4d failed: %s\n", seed, st.message.c_str());
      continue;
    }
    // --photos-true-cameras: the shape fit again with the true cameras
    // (the calibration's weights kept): what the cameras' errors cost.
    if (args.has("photos-true-cameras")) {
      SelfCalibResult calib = r.calib;
      for (size_t i = 0; i < photos.size(); ++i)
        if (calib.photos[i].used) calib.photos[i].camera = truth.cameras[size_t(cam_of[i])];
      calib.focal = vo.focal_px;
      if (!fit_photos_shape(generic, mp_lms, photos, calib, opt, r.fit, nullptr, nullptr, nullptr,
                            opt.use_slide ? &mp_map.slide : nullptr))
        return 1;
    }
    Similarity sf;
    const DetectedScores gu = score_head(generic.mesh, person.mesh, face, head, false),
                         ga = score_head(generic.mesh, person.mesh, face, head, true),
                         fu = score_head(r.fit.mesh, person.mesh, face, head, false),
                         fa = score_head(r.fit.mesh, person.mesh, face, head, true, &sf);
    double rot = 0;
    int n = 0;
    std::string views;  // per used photo: true yaw -> recovered yaw (the fit's frame brought onto the truth)
    for (size_t i = 0; i < photos.size(); ++i)
      if (r.calib.photos[i].used) {
        const Camera c = transform_camera(r.calib.photos[i].camera, sf);
        rot += rotation_angle_deg(c.R, truth.cameras[size_t(cam_of[i])].R);
        ++n;
        double ty, tp, y, p;
        view_angles(truth.cameras[size_t(cam_of[i])], ty, tp);
        view_angles(c, y, p);
        char buf[80];
        std::snprintf(buf, sizeof buf, " %+.0f/%+.0f->%+.0f/%+.0f", ty, tp, y, p);
        views += buf;
      }
    {
      GenericHead fitted = generic;
      fitted.mesh.positions = r.fit.mesh.positions;
      ComponentPlacement tp, fp;
      if (!place_components(person, generic, tp) || !place_components(fitted, generic, fp)) return 1;
      for (size_t i = 0; i < photos.size(); ++i) {
        const Camera& cam = truth.cameras[size_t(cam_of[i])];
        double yaw, pitch;
        view_angles(cam, yaw, pitch);
        if (std::abs(yaw) >= 35) continue;
        for (int e = 0; e < 2; ++e) {
          Vec2 c = Vec2::Zero(), fc = Vec2::Zero();
          LidOpening t, d, f;
          if (!cam.project(tp.eye_center[e], c) || !head_lid_opening(person.mesh, generic, e, 3, cam, c, t) ||
              !landmark_lid_opening(photos[i], e, c, d))
            continue;
          lid_acc[0] += t.ratio();
          lid_acc[1] += d.ratio();
          lid_abs[0] += std::abs(d.ratio() - t.ratio());
          lid_acc[3] += 1;
          const Camera& rc = r.calib.photos[i].camera;
          if (r.calib.photos[i].used && rc.project(fp.eye_center[e], fc) &&
              head_lid_opening(r.fit.mesh, generic, e, 3, rc, fc, f)) {
            lid_acc[2] += f.ratio();
            lid_abs[1] += std::abs(f.ratio() - t.ratio());
            ++lid_fitted_n;
          }
        }
      }
    }
    if (args.has("photos-pulls") || args.has("photos-pulls-by-photo")) {
      SelfCalibResult calib = r.calib;
      if (args.has("photos-true-cameras"))
        for (size_t i = 0; i < photos.size(); ++i)
          if (calib.photos[i].used) calib.photos[i].camera = truth.cameras[size_t(cam_of[i])];
      PhotosFitPulls pulls;
      const Status ps = measure_photos_fit_pulls(generic, mp_lms, photos, calib, opt, r.fit.mesh.positions, pulls,
                                                 nullptr, nullptr, opt.use_slide ? &mp_map.slide : nullptr,
                                                 args.has("photos-pulls-by-photo") ? PullGrouping::Photos
                                                                                   : PullGrouping::Landmarks);
      if (!ps) {
        std::printf("       pulls: %s\n", ps.message.c_str());
      } else {
        std::printf("%s", fit_pulls_table(pulls, "       ").c_str());
        const Similarity sg = fit_similarity(generic.mesh.positions, person.mesh.positions, face);
        const Vec3 lateral = generic.annotations.up.cross(generic.annotations.look).normalized();
        std::string line = "       outward offset from the person (aligned), mm:";
        for (size_t k = 0; k < pulls.regions.size() && k < 3; ++k) {
          double fit_off = 0, gen_off = 0;
          int cnt = 0;
          for (int v : pulls.regions[k].vertices) {
            const double side = generic.mesh.positions[size_t(v)].dot(lateral) > 0 ? 1.0 : -1.0;
            const Vec3& t = person.mesh.positions[size_t(v)];
            fit_off += side * (sf.apply(r.fit.mesh.positions[size_t(v)]) - t).dot(lateral);
            gen_off += side * (sg.apply(generic.mesh.positions[size_t(v)]) - t).dot(lateral);
            ++cnt;
          }
          fit_off /= std::max(1, cnt);
          gen_off /= std::max(1, cnt);
          char buf[120];
          std::snprintf(buf, sizeof buf, " %s generic %+.2f, fit %+.2f;", pulls.regions[k].name.c_str(), 1000 * gen_off,
                        1000 * fit_off);
          line += buf;
          width_sums[3 * k] += fit_off;
          width_sums[3 * k + 1] += gen_off;
          width_sums[3 * k + 2] += pulls.end.displacement_m[k];
        }
        std::printf("%s\n", line.c_str());
        for (const FitPullGroup& g : pulls.end.groups) {
          auto& acc = pull_sums[g.name];
          for (size_t k = 0; k < 3 && k < g.share_m.size(); ++k)
            acc[3 + k] += std::isfinite(g.share_m[k]) ? g.share_m[k] : 0.0;
        }
        for (const FitPullGroup& g : pulls.start.groups) {
          auto& acc = pull_sums[g.name];
          for (size_t k = 0; k < 3 && k < g.share_m.size(); ++k)
            acc[k] += std::isfinite(g.share_m[k]) ? g.share_m[k] : 0.0;
        }
        ++pull_runs;
      }
    }
    const double focal_err = 100 * (r.calib.focal - vo.focal_px) / vo.focal_px;
    std::printf("  %-4d %2d/%-2zu %+6.1f%% %6.2f | %5.2f -> %5.2f (p95 %5.2f) | %5.2f -> %5.2f (p95 %5.2f) | "
                "%5.2f -> %5.2f (p95 %5.2f) | %5.2f -> %5.2f (p95 %5.2f) | %5.0f\n",
                seed, r.calib.num_used(), photos.size(), focal_err, rot / std::max(1, n), 1000 * gu.face.mean,
                1000 * fu.face.mean, 1000 * fu.face.p95, 1000 * ga.face.mean, 1000 * fa.face.mean, 1000 * fa.face.p95,
                1000 * gu.head.mean, 1000 * fu.head.mean, 1000 * fu.head.p95, 1000 * ga.head.mean, 1000 * fa.head.mean,
                1000 * fa.head.p95, ms);
    std::printf("       yaw/pitch deg, truth -> recovered:%s\n", views.c_str());
    {
      // The head's error by region (aligned on the face), generic -> fit: where the outline helps or hurts.
      const Similarity sg = fit_similarity(generic.mesh.positions, person.mesh.positions, face);
      TriMesh fm = r.fit.mesh, gm = generic.mesh;
      for (Vec3& p : fm.positions) p = sf.apply(p);
      for (Vec3& p : gm.positions) p = sg.apply(p);
      std::string line;
      for (const char* region : {"scalp", "ears"}) {
        const std::vector<int>& rv = generic.annotations.regions.at(region);
        const DistanceStats a = surface_distances(person.mesh, rv, gm), b = surface_distances(person.mesh, rv, fm);
        char buf[120];
        std::snprintf(buf, sizeof buf, " %s %.2f -> %.2f (p95 %.2f -> %.2f);", region, 1000 * a.mean, 1000 * b.mean,
                      1000 * a.p95, 1000 * b.p95);
        line += buf;
      }
      std::printf("       by region, aligned, mm:%s\n", line.c_str());
    }
    if (r.calib.focal_landmarks > 0)
      std::printf("       focal from the landmarks %+.1f%%, over the detector's ratio %+.1f%% +- %.1f%% (jackknife over the photos), prior %+.1f%% +- %.1f%%\n",
                  100 * (r.calib.focal_landmarks_raw - vo.focal_px) / vo.focal_px,
                  100 * (r.calib.focal_landmarks - vo.focal_px) / vo.focal_px,
                  100 * r.calib.focal_landmarks_sigma / vo.focal_px, 100 * (r.calib.focal_prior - vo.focal_px) / vo.focal_px,
                  100 * r.calib.focal_prior_sigma / vo.focal_px);
    if (opt.calib.depth_scale_sigma > 0) {
      std::printf("       per-photo depth scale:");
      for (size_t i = 0; i < photos.size(); ++i)
        if (r.calib.photos[i].used) std::printf(" %.3f", r.calib.photos[i].depth_scale);
      std::printf("\n");
    }
    std::printf("       scale %.3f; focal before the bundle adjustment %+.1f%%; BA landmarks from the generic's %.2f mm rms; landmark error %.2f -> %.2f px (calibration), %.2f -> %.2f px (shape fit)\n", sf.scale,
                100 * (r.calib.focal_before_ba - vo.focal_px) / vo.focal_px, landmark_pull_mm(r.calib, generic.mesh, mp_lms),
                r.calib.initial_rms_px, r.calib.final_rms_px, r.fit.initial_rms_px, r.fit.final_rms_px);
    FoldFigures folds;
    if (measure_folds(generic, r.fit.mesh, folds)) {
      print_folds("fit", folds);
      add_folds(folds, fold_sums);
    }
    const double v[9] = {std::abs(focal_err), gu.face.mean, fu.face.mean, ga.face.mean, fa.face.mean,
                         gu.head.mean,        fu.head.mean, ga.head.mean, fa.head.mean};
    for (int k = 0; k < 9; ++k) sums[k] += v[k];
    ++done;
  }
  if (!done) return 1;
  const double d = done;
  std::printf("  mean over %d seeds: |focal err| %.1f %%; face unaligned %.2f -> %.2f, aligned %.2f -> %.2f; "
              "head unaligned %.2f -> %.2f, aligned %.2f -> %.2f mm (generic -> fit)\n",
              done, sums[0] / d, 1000 * sums[1] / d, 1000 * sums[2] / d, 1000 * sums[3] / d, 1000 * sums[4] / d,
              1000 * sums[5] / d, 1000 * sums[6] / d, 1000 * sums[7] / d, 1000 * sums[8] / d);
  print_fold_means(fold_sums, "fit");
  if (pull_runs > 0) {
    const double pr = pull_runs;
    std::printf("  pulls, mean over %d seeds, outward mm (first step / fitted share) on the cheeks, the jaw, the ears:\n",
                pull_runs);
    for (const auto& [name, a] : pull_sums)
      if (name != "stiffness")
        std::printf("    %-16s cheeks %+6.2f / %+6.2f   jaw %+6.2f / %+6.2f   ears %+6.2f / %+6.2f\n", name.c_str(),
                    1000 * a[0] / pr, 1000 * a[3] / pr, 1000 * a[1] / pr, 1000 * a[4] / pr, 1000 * a[2] / pr,
                    1000 * a[5] / pr);
    std::printf("    the fit moved the cheeks %+.2f, the jaw %+.2f, the ears %+.2f mm outward; against the person (aligned): "
                "cheeks generic %+.2f -> fit %+.2f, jaw generic %+.2f -> fit %+.2f, ears generic %+.2f -> fit %+.2f mm "
                "(+ = wider than the person)\n",
                1000 * width_sums[2] / pr, 1000 * width_sums[5] / pr, 1000 * width_sums[8] / pr, 1000 * width_sums[1] / pr,
                1000 * width_sums[0] / pr, 1000 * width_sums[4] / pr, 1000 * width_sums[3] / pr, 1000 * width_sums[7] / pr,
                1000 * width_sums[6] / pr);
  }
  if (lid_acc[3] > 0)
    std::printf("  lid opening gap/width, views within 35 deg of the front, both eyes (%.0f): truth %.3f, detected %.3f "
                "(mean |error| %.3f), fitted %.3f (mean |error| %.3f)\n",
                lid_acc[3], lid_acc[0] / lid_acc[3], lid_acc[1] / lid_acc[3], lid_abs[0] / lid_acc[3],
                lid_fitted_n ? lid_acc[2] / lid_fitted_n : 0.0, lid_fitted_n ? lid_abs[1] / lid_fitted_n : 0.0);
  std::printf("  detector vs truth, mean px (count) by |yaw| <15 / <35 / <60 / >=60 deg, points facing the camera:\n");
  for (const std::string& g : gnames) {
    std::printf("    %-8s", g.c_str());
    for (size_t b = 0; b < kBuckets; ++b)
      std::printf(" %6.2f (%4.0f)", det_n[g][b] ? det_sum[g][b] / det_n[g][b] : 0.0, det_n[g][b]);
    std::printf("\n");
  }
  std::printf("  the detector's face outline to the person's rim (true cameras), mean signed / mean |px| (count), + = outside, by |yaw| <15 / <35 / >=35 deg:\n");
  static const char* band_names[3] = {"temple", "cheek", "jaw"};
  for (int side = 0; side < 2; ++side)
    for (int band = 0; band < 3; ++band) {
      std::printf("    %-4s %-7s", side ? "far" : "near", band_names[band]);
      for (int b = 0; b < 3; ++b) {
        const double* a = outline_acc[b][side][band];
        if (a[2] > 0) std::printf(" %+6.2f / %5.2f (%4.0f)", a[0] / a[2], a[1] / a[2], a[2]);
        else std::printf("   -                  ");
      }
      std::printf("\n");
    }
  std::printf("    %-8s", "hidden");
  for (size_t b = 0; b < kBuckets; ++b)
    std::printf(" %6.2f (%4.0f)", hidden_n[b] ? hidden_sum[b] / hidden_n[b] : 0.0, hidden_n[b]);
  std::printf("  (mapped points turned away from the camera, cos < 0.3)\n");
  std::printf("  the detector's residual at the truth as a focal change, one view alone with its pose free, mean (min .. max) %% by |yaw| bucket:\n   ");
  for (size_t b = 0; b < kBuckets; ++b)
    if (lens_n[b]) std::printf(" %+.0f (%+.0f .. %+.0f)", 100 * lens_sum[b] / lens_n[b], 100 * lens_min[b], 100 * lens_max[b]);
    else std::printf(" -");
  std::printf("\n");
  return 0;
}

int run_bench_photos(const Args& args) {
  int seeds = 5, cameras = 10;
  double noise = 2.0;
  if (!args.get_int("photos-seeds", 5, seeds, 1, 50) || !args.get_int("photos-cameras", 10, cameras, 2, 64) ||
      !args.get_double("photos-noise-px", 2.0, noise, 0, 50))
    return 1;
  // --photos-stiffness-scale: multiplies the stiffness schedule (sensitivity).
  int first_seed = 1;
  if (!args.get_int("photos-first-seed", 1, first_seed, 0, 1000000)) return 1;
  double lambda_sil = 0.3;  // --photos-lambda-sil: fua1998 Sec. 4's 0.3 (its Fig. 6 varies it over 0..0.5)
  if (!args.get_double("photos-lambda-sil", 0.3, lambda_sil, 0, 10)) return 1;
  int grow_px = 0;  // --photos-mask-grow: the truth's masks grown (shrunk) by that many pixels, a biased segmentation
  if (!args.get_int("photos-mask-grow", 0, grow_px, -20, 20)) return 1;
  double stiffness_scale = 1;
  if (!args.get_double("photos-stiffness-scale", 1.0, stiffness_scale, 1e-6, 1e6)) return 1;
  // --photos-silhouettes both|on|off: each seed fitted without and with the
  // truth's exact outlines (fua1998 Sec. 3.2), or only one of the two.
  const std::string sil_mode = args.get("photos-silhouettes", "both");
  if (sil_mode != "both" && sil_mode != "on" && sil_mode != "off") {
    std::printf("  --photos-silhouettes takes both, on or off, got '%s'\n", sil_mode.c_str());
    return 1;
  }
  // --photos-stereo: render each view (as synth-photos does) and add the
  // stereo attractors (fua1998 Sec. 3.1) to the landmarks.
  const bool stereo = args.has("photos-stereo");
  // --photos-lambda-features: fua1998 Fig. 6 varies it in [0, 0.5] with lambda_stereo = 1.
  double lambda_features = 0.3;
  if (!args.get_double("photos-lambda-features", 0.3, lambda_features, 0, 10)) return 1;
  GenericHead generic;
  if (!load_generic_head(generic)) return 1;
  LandmarkMap map;
  std::vector<SurfacePoint> landmarks;
  if (!placeholder_landmark_map(generic, 468, map) || !attach_landmark_map(map, generic.mesh, 1e-3, landmarks))
    return 1;
  // --photos-map interior: the same landmarks moved off the vertices, into
  // one of their triangles (as the real MediaPipe map's points will be).
  const std::string map_kind = args.get("photos-map", "vertices");
  if (map_kind == "interior") {
    for (size_t m = 0; m < landmarks.size(); ++m)
      if (landmarks[m].valid()) {
        int k = 0;
        landmarks[m].barycentric.maxCoeff(&k);
        Vec3 b = Vec3::Constant(0.25);
        b[k] = 0.5;
        landmarks[m].barycentric = b;
        map.points[m] = surface_position(generic.mesh, landmarks[m]);
      }
  } else if (map_kind != "vertices") {
    std::printf("  --photos-map takes vertices or interior, got '%s'\n", map_kind.c_str());
    return 1;
  }
  const std::vector<int>& face = generic.annotations.regions.at("face");
  // The head as photos see it: face, scalp and ears (not the neck, pockets included with the face).
  std::vector<int> head;
  for (const char* region : {"face", "scalp", "ears"})
    for (int v : generic.annotations.regions.at(region)) head.push_back(v);
  const std::string detected_dir = args.get("photos-detected");
  if (!detected_dir.empty()) return run_bench_detected(args, detected_dir, generic, face, head);
  std::printf("photos (fua1998 + self-calibration): %d cameras, %.1f px landmark noise, placeholder map of %d "
              "generic-head face points (%s), stiffness x%g, lambda_sil %g, masks grown %d px, lambda_feat %g%s (CPU ms)\n",
              cameras, noise, int(landmarks.size()), map_kind.c_str(), stiffness_scale, lambda_sil, grow_px,
              lambda_features, stereo ? ", with stereo from rendered views" : ", no stereo");
  std::printf("  %-4s %6s %7s %7s | %-13s %-13s | %-13s %-13s | %6s %6s\n", "seed", "focal", "rot", "rot",
              "generic face", "", "fit face", "", "calib", "fit");
  std::printf("  %-4s %6s %7s %7s | %-13s %-13s | %-13s %-13s | %6s %6s\n", "", "err %", "mean", "max",
              "t->g mean/p95", "g->t mean/p95", "t->f mean/p95", "f->t mean/p95", "ms", "ms");
  double sum_gen = 0, sum_head_gen = 0, sum_focal = 0, sum_rot = 0;
  double sum_fit_m[2] = {0, 0}, sum_head_fit_m[2] = {0, 0}, sum_head_p95_m[2] = {0, 0}, sum_out[2] = {0, 0};
  double sum_stereo_ms = 0, sum_patch_fit[2] = {0, 0};
  FoldFigures generic_folds;
  if (measure_folds(generic, generic.mesh, generic_folds))
    std::printf("  the generic head: crossing pairs %d (levels 0..3)\n", generic_folds.crossings);
  FoldSums fold_sums[2];
  for (int seed = first_seed; seed < first_seed + seeds; ++seed) {
    GenericHead person;
    SyntheticViewsOptions vo;
    vo.num_cameras = cameras;
    vo.noise_px = noise;
    SyntheticSession session;
    if (!synthesize_head(generic, std::uint32_t(seed), SynthHeadOptions{}, person) ||
        !make_synthetic_views(person, landmarks, std::uint32_t(seed), vo, session))
      return 1;
    PhotosJobOptions opt;
    for (double& k : opt.fit.stiffness_schedule) k *= stiffness_scale;
    opt.lambda_silhouettes = lambda_sil;
    opt.silhouettes.facet_equations = args.has("photos-sil-facets");
    if (args.has("photos-sil-exclude")) opt.silhouettes.excluded_regions = split_list(args.get("photos-sil-exclude"));
    opt.fit.lambda_features = lambda_features;
    opt.stereo = stereo;
    if (!parse_fit_levels(args, opt.fit)) return 1;
    // The views rendered as synth-photos writes them (Lambert, light from each camera's upper left).
    std::vector<Image> images;
    double render_ms = 0;
    if (stereo) {
      const double r0 = cpu_clock_ms();
      if (!render_session_images(generic, person, std::uint32_t(seed), session.cameras, images)) return 1;
      render_ms = cpu_clock_ms() - r0;
    }
    PhotosJobResult r;
    const double t0 = cpu_clock_ms();
    Status st = self_calibrate(session.photos, generic.mesh, landmarks, opt.calib, r.calib);
    const double calib_ms = cpu_clock_ms() - t0;
    const double s0 = cpu_clock_ms();
    if (st && stereo) st = run_photos_stereo(generic, session.photos, r.calib, images, opt.stereo_options, r.stereo);
    const double stereo_ms = cpu_clock_ms() - s0;
    // The truth's exact masks (plain background, neck included).
    std::vector<PhotoOutline> outlines;
    if (st && sil_mode != "off") st = synthetic_outlines(person.mesh, session.cameras, OutlineOptions{}, outlines, grow_px);
    if (!st) {
      std::printf("  %-4d failed: %s\n", seed, st.message.c_str());
      continue;
    }
    for (int with_sil = 0; with_sil < 2; ++with_sil) {
      if ((with_sil && sil_mode == "off") || (!with_sil && sil_mode == "on")) continue;
      const double t1 = cpu_clock_ms();
      st = fit_photos_shape(generic, landmarks, session.photos, r.calib, opt, r.fit, with_sil ? &outlines : nullptr,
                            &r.stereo, &r.stereo_fit);
      const double fit_ms = cpu_clock_ms() - t1;
      if (!st) {
        std::printf("  %-4d failed: %s\n", seed, st.message.c_str());
        continue;
      }
      // Fit and generic each brought onto the truth by their best similarity.
      const Similarity sf = fit_similarity(r.fit.mesh.positions, person.mesh.positions, face);
      const Similarity sg = fit_similarity(generic.mesh.positions, person.mesh.positions, face);
      TriMesh fit = r.fit.mesh, gen = generic.mesh;
      for (Vec3& p : fit.positions) p = sf.apply(p);
      for (Vec3& p : gen.positions) p = sg.apply(p);
      const DistanceStats tf = surface_distances(person.mesh, face, fit), ft = surface_distances(fit, face, person.mesh);
      const DistanceStats tg = surface_distances(person.mesh, face, gen), gt = surface_distances(gen, face, person.mesh);
      double rot_sum = 0, rot_max = 0;
      int n = 0;
      for (size_t i = 0; i < session.cameras.size(); ++i) {
        if (!r.calib.photos[i].used) continue;
        const double a = rotation_angle_deg(transform_camera(r.calib.photos[i].camera, sf).R, session.cameras[i].R);
        rot_sum += a;
        rot_max = std::max(rot_max, a);
        ++n;
      }
      const double focal_err = 100 * (r.calib.focal - vo.focal_px) / vo.focal_px;
      std::printf("  %-2d%-2s %+6.2f %7.2f %7.2f | %5.2f / %5.2f %5.2f / %5.2f | %5.2f / %5.2f %5.2f / %5.2f | %6.0f %6.0f\n",
                  seed, with_sil ? "+s" : "", focal_err, rot_sum / std::max(1, n), rot_max, 1000 * tg.mean,
                  1000 * tg.p95, 1000 * gt.mean, 1000 * gt.p95, 1000 * tf.mean, 1000 * tf.p95, 1000 * ft.mean,
                  1000 * ft.p95, calib_ms, fit_ms);
      const DistanceStats hf = surface_distances(person.mesh, head, fit), hg = surface_distances(person.mesh, head, gen);
      std::printf("       head (face+scalp+ears) truth->generic %.2f / %.2f mm, truth->fit %.2f / %.2f mm (mean / p95)\n",
                  1000 * hg.mean, 1000 * hg.p95, 1000 * hf.mean, 1000 * hf.p95);
      if (!outlines.empty()) {
        // Rim to outline in the photos, at the generic head and at the fit (the photos' own cameras).
        const auto sil = make_silhouette_set(generic, generic.mesh, r.calib, outlines, opt.silhouettes);
        const SilhouetteStats a = sil->stats(generic.mesh.positions), b = sil->stats(r.fit.mesh.positions);
        std::printf("       outline: rim to outline %.2f / %.2f px (%d of %d points matched) -> %.2f / %.2f px (%d) "
                    "(mean / p95)\n",
                    a.mean_px, a.p95_px, a.matched, a.points, b.mean_px, b.p95_px, b.matched);
        sum_out[with_sil] += b.mean_px;
      }
      std::printf("       BA landmarks from the generic's %.2f mm rms\n", landmark_pull_mm(r.calib, generic.mesh, landmarks));
      std::printf("       scale of the fit vs truth %.3f; landmark error %.2f -> %.2f px (calibration), %.2f -> %.2f px "
                  "(shape fit); %d photos used\n",
                  sf.scale, r.calib.initial_rms_px, r.calib.final_rms_px, r.fit.initial_rms_px, r.fit.final_rms_px,
                  r.calib.num_used());
      FoldFigures folds;
      if (measure_folds(generic, r.fit.mesh, folds)) {
        print_folds(with_sil ? "fit+sil" : "fit", folds);
        add_folds(folds, fold_sums[with_sil]);
      }
      if (stereo) {
        // The patches against the truth (brought by the fit's similarity): the stereo's own accuracy.
        MeshBvh truth_bvh;
        std::vector<double> pd;
        if (build_bvh(person.mesh, truth_bvh))
          for (const StereoPatch& p : r.stereo.patches) pd.push_back(closest_point(truth_bvh, sf.apply(p.centre)).distance);
        std::sort(pd.begin(), pd.end());
        int pairs_used = 0;
        for (const StereoPairReport& p : r.stereo.pairs) pairs_used += p.patches > 0;
        std::printf("       stereo: %d of %zu pairs, %zu patches, to truth median %.2f p95 %.2f mm; to the fit median "
                    "%.2f (start %.2f) p95 %.2f mm, %d inliers; render %.0f ms, stereo %.0f ms\n",
                    pairs_used, r.stereo.pairs.size(), r.stereo.patches.size(),
                    pd.empty() ? 0.0 : 1000 * sf.scale * pd[pd.size() / 2], pd.empty() ? 0.0 : 1000 * pd[pd.size() * 95 / 100],
                    1000 * r.stereo_fit.median_fit_m, 1000 * r.stereo_fit.median_start_m, 1000 * r.stereo_fit.p95_fit_m,
                    r.stereo_fit.inliers, render_ms, stereo_ms);
        sum_patch_fit[with_sil] += r.stereo_fit.median_fit_m;
      }
      sum_fit_m[with_sil] += tf.mean;
      sum_head_fit_m[with_sil] += hf.mean;
      sum_head_p95_m[with_sil] += hf.p95;
      if (with_sil && sil_mode != "on") continue;  // the generic and camera sums once per seed
      sum_head_gen += hg.mean;
      sum_gen += tg.mean;
      sum_stereo_ms += stereo_ms;
      sum_focal += std::abs(focal_err);
      sum_rot += rot_sum / std::max(1, n);
    }
  }
  std::printf("  mean over seeds: |focal err| %.2f %%, rotation %.2f deg, truth->face mm: generic %.2f; "
              "truth->head mm: generic %.2f\n",
              sum_focal / seeds, sum_rot / seeds, 1000 * sum_gen / seeds, 1000 * sum_head_gen / seeds);
  for (int k = 0; k < 2; ++k) {
    if ((k && sil_mode == "off") || (!k && sil_mode == "on")) continue;
    std::printf("  %s%s: truth->face mean %.2f mm, truth->head mean %.2f mm (p95 %.2f mm)%s%s\n",
                k ? "landmarks + silhouettes" : "landmarks only", stereo ? " + stereo" : "", 1000 * sum_fit_m[k] / seeds,
                1000 * sum_head_fit_m[k] / seeds, 1000 * sum_head_p95_m[k] / seeds,
                sil_mode == "off" ? "" : (", rim to outline " + std::to_string(sum_out[k] / seeds).substr(0, 5) + " px").c_str(),
                stereo ? (", stereo patches to the fit median " + std::to_string(1000 * sum_patch_fit[k] / seeds).substr(0, 5) +
                          " mm").c_str() : "");
  }
  for (int k = 0; k < 2; ++k) print_fold_means(fold_sums[k], k ? "fit+sil" : "fit");
  if (stereo) std::printf("  stereo: %.0f ms CPU per session (render not counted)\n", sum_stereo_ms / seeds);
  std::printf("  issue 37 goal: face mean <= 1.0 mm, visible head mean <= 2.5 mm\n");
  std::printf("  paper Fig. 7 (stereo points to the fitted face, median; real faces, LM): 2.33 6.38 0.55\n");
  return 0;
}

BenchRegistrar reg({"photos", "photos to head on synthetic sessions: camera errors, face distances, stage times "
                              "(--photos-seeds N --photos-cameras C --photos-noise-px S --photos-map vertices|interior --photos-stiffness-scale K --photos-first-seed S --photos-silhouettes both|on|off --photos-lambda-sil L --photos-mask-grow PX --photos-sil-facets --photos-sil-exclude REGION,... --photos-stereo --photos-lambda-features L --photos-coarse N:S,... --photos-schedule S,...|none --photos-follow K[:W] --photos-symmetry W; --photos-detected DIR: real-detector points on synth-photos renders, made by tests/browser/detect_synth_photos.mjs, with --photos-detected-map FILE --photos-detected-silhouettes --photos-depth-scale SIGMA --photos-depth-0 K0 --photos-depth-yaw2 C --photos-no-slide --photos-no-slide-sigma --photos-true-cameras --photos-drop GROUP --photos-contours --photos-contour-lambda K --photos-lids --photos-pulls --photos-pulls-by-photo)",
                    run_bench_photos});

}  // namespace
}  // namespace lk::cli
