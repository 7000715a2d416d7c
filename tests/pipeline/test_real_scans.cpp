// Every real scan in ../shared/data/head_scans fits without crossing
// itself, at the lips and the ears or anywhere else (issue 35), as given
// and turned by 0.05 degrees about the vertical (the fit is chaotic on
// busts: such a nudge changed Demosthenes' alignment and gave 100 pairs at
// the lips and ears before FitHeadOptions::guard_feature_crossings; it
// left 88 at his eye rims before guard_other_crossings). Skipped with a
// message when the folder is absent; the scans are never copied into the
// repo. Gutenberg (beret, beard, pedestal) as given is aligned again on his
// face (FitHeadOptions::refine_on_face) and held to the same 0 pairs; so is
// his copy turned by 0.05 deg, refused until the face's pitch was chosen by
// the share of his points near the head (FitHeadOptions::choose_face_pitch:
// its silhouettes leave 8 % of them near after the face's match,
// docs/design/align.md, "Choosing the pitch").
#include "align/face_symmetry.h"
#include "io/io.h"
#include "mesh/midpoint_split.h"
#include "pipeline/fit_head.h"
#include "pipeline/fit_quality.h"
#include "test_data.h"
#include "test_scan.h"

#include <catch2/catch.hpp>
#include <algorithm>
#include <filesystem>
#include <map>
#include <string>

using namespace lk;

namespace {

// Every OBJ/PLY/VTK/XYZ file one folder below head_scans/.
std::vector<std::string> real_scans() {
  namespace fs = std::filesystem;
  std::vector<std::string> out;
  std::error_code ec;
  for (const auto& folder : fs::directory_iterator(lk::test::shared_data_dir() + "/head_scans", ec))
    for (const auto& file : fs::directory_iterator(folder.path(), ec)) {
      const std::string ext = file.path().extension().string();
      if (ext == ".obj" || ext == ".ply" || ext == ".vtk" || ext == ".xyz") out.push_back(file.path().string());
    }
  std::sort(out.begin(), out.end());
  return out;
}

// The scan moved as the bench's sweep moves it (native_harness/
// bench_real.cpp, --fit-real-sweep): turned by `degrees` about `axis`
// through its centroid.
PointCloud turned_about(const PointCloud& scan, double degrees, const Vec3& axis, Mat3& rotation, Vec3& centroid) {
  centroid = Vec3::Zero();
  for (const Vec3& p : scan.positions) centroid += p;
  centroid /= std::max(1, scan.size());
  rotation = Mat3(Eigen::AngleAxisd(degrees * 3.14159265358979323846 / 180.0, axis));
  PointCloud out = scan;
  for (Vec3& p : out.positions) p = centroid + rotation * (p - centroid);
  for (Vec3& n : out.normals) n = rotation * n;
  return out;
}

// The aligned generic head's vertices in the unturned scan's frame.
std::vector<Vec3> aligned_in_scan(const FitHeadResult& r, const Mat3& rotation, const Vec3& centroid) {
  const Mat3 to_scan = r.scan_to_head.A.inverse();
  std::vector<Vec3> out;
  for (const Vec3& p : r.aligned.positions)
    out.push_back(centroid + rotation.transpose() * (to_scan * (p - r.scan_to_head.t) - centroid));
  return out;
}

// The rotation angle (deg) and scale of the least-squares linear map from
// a's vertices to b's (centred).
void pose_difference(const std::vector<Vec3>& a, const std::vector<Vec3>& b, double& degrees, double& scale) {
  Vec3 ca = Vec3::Zero(), cb = Vec3::Zero();
  for (size_t i = 0; i < a.size(); ++i) ca += a[i], cb += b[i];
  ca /= double(a.size());
  cb /= double(b.size());
  Mat3 A = Mat3::Zero(), B = Mat3::Zero();
  for (size_t i = 0; i < a.size(); ++i) {
    A += (b[i] - cb) * (a[i] - ca).transpose();
    B += (a[i] - ca) * (a[i] - ca).transpose();
  }
  const Mat3 M = A * B.inverse();
  Eigen::JacobiSVD<Mat3> svd(M, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Mat3 R = svd.matrixU() * svd.matrixV().transpose();
  degrees = std::acos(std::clamp(0.5 * (R.trace() - 1), -1.0, 1.0)) * 180 / 3.14159265358979323846;
  scale = std::cbrt(M.determinant());
}

// The scan turned by `degrees` about the vertical through its centroid (the
// bench's "turn 0.05 deg" copy, native_harness/bench_real.cpp).
PointCloud turned(const PointCloud& scan, double degrees) {
  Mat3 rotation;
  Vec3 centroid;
  return turned_about(scan, degrees, Vec3::UnitY(), rotation, centroid);
}

}  // namespace

TEST_CASE("fit_head: every real scan fits with no crossing pairs, at the lips and the ears or elsewhere",
          "[pipeline][real_scans][shared]") {
  LK_REQUIRE_SHARED("head_scans");
  const std::vector<std::string> scans = real_scans();
  REQUIRE(!scans.empty());
  for (const std::string& path : scans) {
    for (const double degrees : {0.0, 0.05}) {
      DYNAMIC_SECTION(path << ", turned " << degrees << " deg") {
        PointCloud scan;
        REQUIRE(load_point_cloud_file(path, scan).ok());
        if (degrees != 0) scan = turned(scan, degrees);
        FitHeadOptions options;
        options.measure_stages = false;  // the crossings are what is checked
        FitHeadResult r;
        const Status st = fit_head(scan, test::generic_head(), options, r);
        INFO(st.message);
        REQUIRE(st.ok());
        FitQuality q;
        REQUIRE(measure_fit_quality(r, test::generic_head().annotations, q).ok());
        INFO("level " << q.level << ": " << q.crossings.total << " pairs (lips " << q.crossings.lips << ", ears "
                      << q.crossings.ears << ", eye sockets " << q.crossings.eye_sockets << ", rest "
                      << q.crossings.rest << ")");
        CHECK(q.level == 3);
        CHECK(q.crossings.lips == 0);
        CHECK(q.crossings.ears == 0);
        // Nor anywhere else (FitHeadOptions::guard_other_crossings): the
        // eye rims, the scalp, the neck's seam.
        CHECK(q.crossings.eye_sockets == 0);
        CHECK(q.crossings.rest == 0);
        CHECK(q.crossings.total == 0);
      }
    }
  }
}

TEST_CASE("fit_head: Plato's ears, under carved hair, cross less when held in the generic shape",
          "[pipeline][real_scans][shared]") {
  // FitHeadOptions::hold_crossing_ears on the scan it was made for
  // (docs/design/fit_real_scans.md): it must lower the ear pairs and add none
  // elsewhere (0 is reached with the feature guard after it, tested above).
  LK_REQUIRE_SHARED("head_scans/threedscans_plato/plato.obj");
  PointCloud scan;
  REQUIRE(load_point_cloud_file(lk::test::shared_data_dir() + "/head_scans/threedscans_plato/plato.obj", scan).ok());
  FitHeadOptions on;
  on.measure_stages = false;
  on.guard_feature_crossings = false;  // the hold alone (the guard after it is tested above)
  FitHeadOptions off = on;
  off.hold_crossing_ears = false;
  FitHeadResult free_fit, held_fit;
  REQUIRE(fit_head(scan, test::generic_head(), off, free_fit).ok());
  REQUIRE(fit_head(scan, test::generic_head(), on, held_fit).ok());
  FitQuality free_q, held_q;
  REQUIRE(measure_fit_quality(free_fit, test::generic_head().annotations, free_q).ok());
  REQUIRE(measure_fit_quality(held_fit, test::generic_head().annotations, held_q).ok());
  INFO("ear pairs " << free_q.crossings.ears << " -> " << held_q.crossings.ears << ", all "
                    << free_q.crossings.total << " -> " << held_q.crossings.total);
  REQUIRE(free_q.crossings.ears > 0);  // else there is nothing to hold
  CHECK(held_fit.ears_held > 0);
  CHECK(held_q.crossings.ears < free_q.crossings.ears);
  CHECK(held_q.crossings.total - held_q.crossings.ears <= free_q.crossings.total - free_q.crossings.ears);
}

TEST_CASE("fit_head: with the wide mouth ring as the generic head, Demosthenes' ears hold by the fit itself and "
          "Plato is aligned",
          "[pipeline][real_scans][shared]") {
  // A generic head changed by a few millimetres at the mouth corners
  // (GenericHeadBuildOptions::wide_mouth_ring) sent the fit of the real
  // scans elsewhere: Demosthenes' global fit folded an ear (its control
  // mesh's smooth level 3: 20 ear pairs) that only the last guard could
  // relax, and Plato was refused (58.7 % of his points near after the
  // silhouettes, 15 % after the face's match). Now the ears are fitted
  // again with their edges bound where the free fit folds them
  // (FitHeadOptions::bind_ear_edges) and the silhouettes' alignment is kept
  // when its face lies on the scan (docs/design/fit_real_scans.md, "Ears
  // that hold"). Not checked here, because not met: Gutenberg with this
  // head keeps 3 ear pairs.
  LK_REQUIRE_SHARED("head_scans/demosthenes_photoscan/demosthenes-low-res.obj");
  LK_REQUIRE_SHARED("head_scans/threedscans_plato/plato.obj");
  GenericHeadBuildOptions wide_options;
  wide_options.wide_mouth_ring = true;
  wide_options.fair_iterations = 0;  // the wide ring as measured, on the skin as cast
  const GenericHead wide = test::built_generic_head(wide_options);
  for (const std::string& name : {std::string("demosthenes_photoscan/demosthenes-low-res.obj"),
                                  std::string("threedscans_plato/plato.obj")}) {
    DYNAMIC_SECTION(name) {
      const std::string path = lk::test::shared_data_dir() + "/head_scans/" + name;
      PointCloud scan;
      REQUIRE(load_point_cloud_file(path, scan).ok());
      FitHeadOptions options;
      options.measure_stages = false;
      FitHeadResult r;
      const Status st = fit_head(scan, wide, options, r);
      INFO(st.message);
      REQUIRE(st.ok());  // Plato: refused before
      FitQuality q;
      REQUIRE(measure_fit_quality(r, wide.annotations, q).ok());
      INFO("level " << q.level << ": lips " << q.crossings.lips << ", ears " << q.crossings.ears << ", rest "
                    << q.crossings.rest << "; ears bound " << r.ear_binding.bound << " (smooth pairs "
                    << r.ear_binding.free_pairs << " free, " << r.ear_binding.bound_pairs << " bound); the guard met "
                    << r.feature_guard.pairs_before << " pairs at the lips and ears, " << r.ears_held << " ears held");
      CHECK(q.crossings.lips == 0);
      CHECK(q.crossings.ears == 0);
      if (name.find("demosthenes") != std::string::npos) {
        // The ears hold by the fit, not by the last guard's relaxing.
        CHECK(r.ear_binding.bound);
        CHECK(r.feature_guard.pairs_before == 0);
        CHECK(r.ears_held == 0);
      }
    }
  }
}

// Issue 35: a fit must not change with a tiny turn of its input. On main
// the silhouettes' Powell stopped wherever a 0.05 deg turn of the scan led
// it: Demosthenes turned 0.05 deg about the vertical ended 13.2 deg from
// his pose as given (Table 1 0.0342 -> 0.0713 %), Plato 1.9-5 deg, Gutenberg
// 7 deg (docs/design/align.md, "Basins"). With AlignOptions' pitch starts
// 0, +-10 deg and the polish (not the default: Plato and Gutenberg fit
// worse) every start runs through the final resolution and is polished by
// point-to-plane ICP, and the polished clamped score chooses. With one
// start and no polish (main) it fails: Demosthenes turned 0.05 deg about
// the vertical ends 13.2 deg from his pose as given. Whole heads turned by 0.05 and 0.5
// deg about each axis: the alignment within 1.25 deg and 0.5 % of scale of
// the as-given one (measured in the bench's sweep: Demosthenes 0.09-0.21
// deg, Plato 0.43-1.04 deg, Gutenberg's copy 0.05 deg).
TEST_CASE("fit_head: the busts turned by 0.05 and 0.5 deg align to the pose they align to as given",
          "[pipeline][real_scans][shared]") {
  LK_REQUIRE_SHARED("head_scans");
  const std::vector<std::string> scans = real_scans();
  REQUIRE(!scans.empty());
  for (const std::string& path : scans) {
    PointCloud scan;
    REQUIRE(load_point_cloud_file(path, scan).ok());
    FitHeadOptions options;  // the options that hold (not the default: docs/design/align.md, "Basins")
    options.align.pitch_starts_deg = {0.0, 10.0, -10.0};
    options.align.polish = true;
    // Stopped once the alignment is final (the pose is what is compared).
    const ProgressFn stop = [](const char* stage, double f) {
      return !(std::string(stage) == "initial_alignment" && f >= 1.0);
    };
    auto align = [&](const PointCloud& cloud, FitHeadResult& r) {
      const Status st = fit_head(cloud, test::generic_head(), options, r, {}, stop);
      INFO(st.message);
      REQUIRE(st.code == ErrorCode::Cancelled);
    };
    // The as-given pose once per scan (Catch runs the body again for each
    // section); empty for face patches (align_face: tests/align).
    static std::map<std::string, std::vector<Vec3>> poses;
    if (!poses.count(path)) {
      FitHeadResult given;
      align(scan, given);
      poses[path] = given.face_only ? std::vector<Vec3>{} : aligned_in_scan(given, Mat3::Identity(), Vec3::Zero());
    }
    const std::vector<Vec3>& given_pose = poses[path];
    if (given_pose.empty()) continue;
    // Gutenberg (beret, beard, pedestal: the polish pulls his head into
    // them) holds only for the bench's copy, 0.05 deg about the vertical;
    // his other copies part by 1.2-18 deg (docs/design/align.md, "Basins").
    const bool gutenberg = path.find("gutenberg") != std::string::npos;
    for (const double degrees : {0.05, 0.5})
      for (int axis = 0; axis < 3; ++axis) {
        if (gutenberg && (degrees != 0.05 || axis != 1)) continue;
        DYNAMIC_SECTION(path << " turned " << degrees << " deg about axis " << axis) {
          Mat3 R;
          Vec3 c;
          FitHeadResult r;
          align(turned_about(scan, degrees, Vec3::Unit(axis), R, c), r);
          double angle = 0, scale = 1;
          pose_difference(given_pose, aligned_in_scan(r, R, c), angle, scale);
          INFO("the alignment " << angle << " deg and scale " << scale << " from the as-given one");
          CHECK(angle < 1.25);
          CHECK(std::fabs(scale - 1) < 0.005);
        }
      }
  }
}

// The orientation search's closest-point score puts a wrong turn of
// Demosthenes' bust first when every start runs through (1.27x smaller
// than as given; the default screening happens to cut that start), while
// Fran's face patch does need its turn: fit_head aligns a proposed turn and
// the scan as given and keeps the one with more of the scan's points near
// the head (check_turn in fit_head.cpp; docs/design/align.md, "A turn
// checked against the scan as given").
// The fit's notes, one per line, and how far (deg) its facing in the
// scan's frame lies from `facing`.
static std::string notes_of(const FitHeadResult& r) {
  std::string notes;
  for (const std::string& n : r.notes) notes += n + "\n";
  return notes;
}
// How far the axes the orientation check chose (scan_to_head less the
// turn to the aligned face's frame, FitHeadOptions::face_frame) face from
// `facing`, in the scan's frame.
static double facing_off_deg(const FitHeadResult& r, const Vec3& facing) {
  const Mat3 oriented = r.face_frame_turn.transpose() * r.scan_to_head.A;
  const Vec3 f = (oriented.transpose() * Vec3::UnitZ()).normalized();
  return std::acos(std::clamp(f.dot(facing.normalized()), -1.0, 1.0)) * 180 / 3.14159265358979323846;
}

TEST_CASE("fit_head: a proposed turn is kept only where more of the scan lies near the aligned head (Demosthenes "
          "as given, Fran turned)",
          "[pipeline][real_scans][shared]") {
  LK_REQUIRE_SHARED("head_scans/demosthenes_photoscan/demosthenes-low-res.obj");
  LK_REQUIRE_SHARED("head_scans/fran_cyberware/fran_cut.vtk");
  struct Case {
    const char* path;
    bool full_search;  // every start runs through (OrientationOptions::screen_iterations 0)
    bool turned;
    Vec3 facing;        // in the scan's frame
    const char* note;
  };
  for (const Case& c : {Case{"/head_scans/demosthenes_photoscan/demosthenes-low-res.obj", true, false, Vec3::UnitZ(),
                             "the orientation search proposed a turn, but the scan as given lies closer"},
                        Case{"/head_scans/fran_cyberware/fran_cut.vtk", false, true, Vec3(0.794, 0, -0.608),
                             "the turn was checked against the scan as given"}}) {
    INFO(c.path);
    PointCloud scan;
    REQUIRE(load_point_cloud_file(test::shared_data_dir() + c.path, scan).ok());
    FitHeadOptions options;
    if (c.full_search) options.orientation.screen_iterations = 0;
    FitHeadResult r;
    const Status st = fit_head(scan, test::generic_head(), options, r);
    INFO(st.message);
    REQUIRE(st.ok());
    const std::string notes = notes_of(r);
    INFO(notes);
    CHECK(r.orientation.differs);  // the search proposed a turn: what this test is about
    CHECK(notes.find(c.note) != std::string::npos);
    CHECK(r.turned == c.turned);
    CHECK(facing_off_deg(r, c.facing) < 10);
    // Today's 0.034 and 0.039 %; Demosthenes turned gives 0.19 %.
    REQUIRE(!r.stages.empty());
    CHECK(r.stages.back().distance.mean_pct < 0.05);
  }
}

TEST_CASE("fit_head: when the screened orientation search leaves the scan refused, the unscreened search finds "
          "the turn (Fran, one start kept by the screening)",
          "[pipeline][real_scans][shared]") {
  LK_REQUIRE_SHARED("head_scans/fran_cyberware/fran_cut.vtk");
  PointCloud scan;
  REQUIRE(load_point_cloud_file(test::shared_data_dir() + "/head_scans/fran_cyberware/fran_cut.vtk", scan).ok());
  // The screening keeps one start: Fran's right turn is not it (a stand-in
  // for a scan whose right start ranks just below the kept ones).
  FitHeadOptions options;
  options.orientation.screen_keep = 1;
  options.orientation_retry_unscreened = false;
  options.orientation_surface_retry_cell = 0;  // (the search on her surface turns her too)
  options.suggest_z_up = false;  // the refusal as the search left it, named again by the retry's note
  FitHeadResult without;
  const Status refused = fit_head(scan, test::generic_head(), options, without);
  INFO(refused.message);
  CHECK(refused.code == ErrorCode::NotAHead);  // what the retry is for

  options.orientation_retry_unscreened = true;
  FitHeadResult r;
  const Status st = fit_head(scan, test::generic_head(), options, r);
  INFO(st.message);
  REQUIRE(st.ok());
  const std::string notes = notes_of(r);
  INFO(notes);
  CHECK(notes.find("searched again with every start run through") != std::string::npos);
  CHECK(notes.find(refused.message) != std::string::npos);  // the first refusal is named
  CHECK(r.turned);
  CHECK(facing_off_deg(r, Vec3(0.794, 0, -0.608)) < 10);
  REQUIRE(!r.stages.empty());
  CHECK(r.stages.back().distance.mean_pct < 0.05);  // 0.039 % as with the defaults
}

TEST_CASE("fit_head: a face scan split 1:4 at its midpoints, the same surface, is turned and fitted as the original "
          "(Fran)",
          "[pipeline][real_scans][shared]") {
  LK_REQUIRE_SHARED("head_scans/fran_cyberware/fran_cut.vtk");
  PointCloud scan;
  REQUIRE(load_point_cloud_file(test::shared_data_dir() + "/head_scans/fran_cyberware/fran_cut.vtk", scan).ok());
  const PointCloud denser = split_at_midpoints(scan);
  REQUIRE(denser.size() > 3 * scan.size());
  // The orientation search on her vertices refuses the denser copy as "not
  // a head" (kept as given, where the original is turned): the density, not
  // the surface, decides. The second search on the surface's cell averages
  // after that refusal (FitHeadOptions::orientation_surface_retry_cell, on
  // by default) turns her as the original; so does the first search on the
  // surface (orientation_surface_cell, off by default: on turned busts it
  // makes wrong heads of refusals).
  struct Variant {
    const char* what;
    double first_cell, retry_cell;
  };
  for (const Variant& v : {Variant{"defaults", 0.0, FitHeadOptions{}.orientation_surface_retry_cell},
                           Variant{"no second search", 0.0, 0.0}, Variant{"first search on the surface", 0.005, 0.0}}) {
    FitHeadOptions options;
    options.orientation_surface_cell = v.first_cell;
    options.orientation_surface_retry_cell = v.retry_cell;
    options.levels = 1;
    FitHeadResult r;
    const Status st = fit_head(denser, test::generic_head(), options, r);
    INFO(v.what << ": " << st.message);
    if (v.first_cell == 0 && v.retry_cell == 0) {
      CHECK(st.code == ErrorCode::NotAHead);  // what the surface's averages mend
      continue;
    }
    REQUIRE(st.ok());
    CHECK(r.turned);
    CHECK(r.face_only);
    CHECK(facing_off_deg(r, Vec3(0.794, 0, -0.608)) < 10);
    CHECK(r.near_fraction > 0.7);  // 77 % as the original's
    // The second search says what it did, and names the first refusal.
    CHECK((notes_of(r).find("searched again on the scan's surface") != std::string::npos) == (v.retry_cell > 0));
  }
}

TEST_CASE("fit_head: a bust written as Blender writes it (+z up, face along -y) is refused naming those axes, and "
          "fitted with them as the upright bust (Gutenberg)",
          "[pipeline][real_scans][shared]") {
  LK_REQUIRE_SHARED("head_scans/threedscans_gutenberg/gutenberg.obj");
  PointCloud scan;
  REQUIRE(load_point_cloud_file(test::shared_data_dir() + "/head_scans/threedscans_gutenberg/gutenberg.obj", scan).ok());
  // Blender's import of a +y-up file: y -> z, z -> -y.
  Mat3 to_blender;
  to_blender << 1, 0, 0, 0, 0, -1, 0, 1, 0;
  for (Vec3& p : scan.positions) p = to_blender * p;
  for (Vec3& n : scan.normals) n = to_blender * n;
  FitHeadOptions options;
  options.levels = 1;
  options.suggest_z_up = false;
  FitHeadResult r;
  Status st = fit_head(scan, test::generic_head(), options, r);
  INFO(st.message);
  REQUIRE(st.code == ErrorCode::NotAHead);  // the search does not see a bust's up (docs/design/align.md)
  CHECK(st.message.find("--up 0 0 1") == std::string::npos);

  options.suggest_z_up = true;
  st = fit_head(scan, test::generic_head(), options, r);
  INFO(st.message);
  REQUIRE(st.code == ErrorCode::NotAHead);  // named, not fitted
  CHECK(st.message.find("the alignment passes; try --facing 0 -1 0 --up 0 0 1)") != std::string::npos);
  CHECK(st.message.find("pass --up and --facing, e.g.") == std::string::npos);  // the named axes stand for the guess

  // The axes it names fit him as the upright bust is fitted: his face along -y.
  options.up = Vec3::UnitZ();
  options.facing = -Vec3::UnitY();
  st = fit_head(scan, test::generic_head(), options, r);
  INFO(st.message);
  REQUIRE(st.ok());
  CHECK(facing_off_deg(r, -Vec3::UnitY()) < 10);
  const Vec3 up = (r.scan_to_head.A.transpose() * Vec3::UnitY()).normalized();
  CHECK(std::acos(std::clamp(up.z(), -1.0, 1.0)) * 180 / 3.14159265358979323846 < 15);
  // Table 1 as the upright bust's, fitted with the same options.
  PointCloud upright;
  REQUIRE(load_point_cloud_file(test::shared_data_dir() + "/head_scans/threedscans_gutenberg/gutenberg.obj", upright).ok());
  FitHeadOptions plain;
  plain.levels = 1;
  FitHeadResult u;
  REQUIRE(fit_head(upright, test::generic_head(), plain, u).ok());
  REQUIRE(!r.stages.empty());
  REQUIRE(!u.stages.empty());
  CHECK(r.stages.back().distance.mean_pct < 1.1 * u.stages.back().distance.mean_pct);
}

TEST_CASE("fit_head: a bust split 1:64 at its midpoints, the same surface, is aligned again on its surface's "
          "averages and lands near the original's pose (Gutenberg)",
          "[pipeline][real_scans][shared]") {
  LK_REQUIRE_SHARED("head_scans/threedscans_gutenberg/gutenberg.obj");
  PointCloud scan;
  REQUIRE(load_point_cloud_file(test::shared_data_dir() + "/head_scans/threedscans_gutenberg/gutenberg.obj", scan).ok());
  const PointCloud dense = split_at_midpoints(split_at_midpoints(split_at_midpoints(scan)));
  REQUIRE(dense.size() > 40 * scan.size());
  FitHeadOptions options;
  options.levels = 1;
  FitHeadResult original;
  REQUIRE(fit_head(scan, test::generic_head(), options, original).ok());
  REQUIRE(!original.face_only);
  const std::vector<Vec3> original_pose = aligned_in_scan(original, Mat3::Identity(), Vec3::Zero());
  // Without the retry the dense copy's silhouettes pitch him about 20 deg
  // off and too few of his points lie near the head: refused, though the
  // original's pose leaves 34 % of either copy's points near it.
  FitHeadOptions no_retry = options;
  no_retry.dense_mesh_retry_cell = 0;
  FitHeadResult r;
  Status st = fit_head(dense, test::generic_head(), no_retry, r);
  INFO(st.message);
  CHECK(st.code == ErrorCode::NotAHead);
  // With it (the default) he is fitted, near the original's pose, and the
  // note says how.
  st = fit_head(dense, test::generic_head(), options, r);
  INFO(st.message);
  REQUIRE(st.ok());
  CHECK(r.near_fraction > 0.3);  // 33 %; the original's 34 %
  double degrees = 0, scale = 0;
  pose_difference(original_pose, aligned_in_scan(r, Mat3::Identity(), Vec3::Zero()), degrees, scale);
  INFO("pose " << degrees << " deg, scale " << scale);
  CHECK(degrees < 15);  // 8.8 deg measured
  CHECK(std::abs(scale - 1) < 0.1);
  CHECK(notes_of(r).find("aligned again with its silhouettes taken from") != std::string::npos);
}

TEST_CASE("fit_head: Gutenberg's face, his head turned on the bust, is matched along its own axis (the scan's face "
          "symmetric in front of it)",
          "[pipeline][real_scans][shared]") {
  LK_REQUIRE_SHARED("head_scans/threedscans_gutenberg/gutenberg.obj");
  PointCloud scan;
  REQUIRE(load_point_cloud_file(test::shared_data_dir() + "/head_scans/threedscans_gutenberg/gutenberg.obj", scan).ok());
  const GenericHead& g = test::generic_head();
  const ProgressFn stop = [](const char* stage, double f) {
    return !(std::string(stage) == "initial_alignment" && f >= 1.0);
  };
  // The turn at which his scan's relief in front of the aligned face is
  // most mirror-symmetric, and its correlation.
  auto align = [&](bool symmetry, FaceSymmetry& s) {
    FitHeadOptions options;
    options.face_refine.symmetry_yaw_start = symmetry;
    FitHeadResult r;
    const Status st = fit_head(scan, g, options, r, {}, stop);
    INFO(st.message);
    REQUIRE(st.code == ErrorCode::Cancelled);
    REQUIRE(r.refined_on_face);
    std::vector<Vec3> in_head;
    for (const Vec3& p : scan.positions) in_head.push_back(r.scan_to_head.apply(p));
    REQUIRE(face_symmetry_of_alignment(g.mesh, g.annotations, in_head, scan.faces, r.generic_to_head.A,
                                       r.generic_to_head.t, FaceSymmetryOptions{}, s)
                .ok());
    return r.near_fraction;
  };
  FaceSymmetry with, without;
  const double near_with = align(true, with), near_without = align(false, without);
  INFO("with the symmetric turns: " << with.yaw_deg << " deg (" << with.score << "), " << near_with
                                    << " near; without: " << without.yaw_deg << " deg (" << without.score << "), "
                                    << near_without << " near");
  // Without them his face stops about 20 deg short of his head's turn
  // (docs/design/fit_real_scans.md: -17.5 deg, 0.90).
  CHECK(std::fabs(without.yaw_deg) >= 10);
  CHECK(std::fabs(with.yaw_deg) <= 5);
  CHECK(with.score > 0.8);
  CHECK(near_with > 0.3);  // the share near the head that still passes the face's rule
}
