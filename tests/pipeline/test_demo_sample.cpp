// The built-in demo sample (scripts/demo: `likeness synth-scan --seed 1` then
// `likeness fit --scan scan.ply`), fitted as the demo fits it: 300k points
// written to PLY (float32) and read back. Its level 3 must not cross itself
// (jeong2002 Sec. 5 hierarchy after the fold limiter, multires/fold_limit.h).
//
// Why the PLY round trip: the same scan fitted in double precision (the fit
// benchmark, seed 1) had no crossing pair, while the float32 copy left 10 in
// the right ear's fold at 22e0d1f: the fold limiter gave a pair up when its
// corners were held on the smooth surface, although a later restart had
// moved their base (a corner 1.3 mm off the smooth surface). The rounding
// (~1e-8 m) only decides which of the two happens; this test keeps the exact
// input on which it did.
#include "io/io.h"
#include "pipeline/fit_head.h"
#include "pipeline/fit_quality.h"
#include "raycast/self_intersection.h"
#include "test_scan.h"

#include <catch2/catch.hpp>

#include <algorithm>

using namespace lk;

namespace {

// The demo sample made from `generic` as `likeness synth-scan --seed 1`
// makes it (native_harness/cmd_synth.cpp), written to PLY and read back as
// `likeness fit --scan scan.ply` reads it; another seed gives that seed's
// person and scan the same way.
PointCloud demo_scan(const GenericHead& generic, std::uint32_t seed = 1) {
  const GenericHead person = test::make_test_head(seed, {}, generic);
  const TruthSurface truth = test::make_test_truth(person, seed);
  ScannerOptions so;
  so.look = person.annotations.look;
  so.up = person.annotations.up;
  const PointCloud exact = test::scan_test_truth(truth, seed, 300000, so);
  REQUIRE(exact.size() > 250000);
  const Bytes ply = write_ply(exact);
  TriMesh mesh;
  PointCloud scan;
  GeometryKind kind;
  const Status st = read_geometry("scan.ply", ply.data(), ply.size(), mesh, scan, kind);
  INFO(st.message);
  REQUIRE(st.ok());
  REQUIRE(scan.size() == exact.size());
  return scan;
}

}  // namespace

TEST_CASE("fit_head: the demo sample (seed 1, 300k points through float32 PLY) has no crossing pair at level 3") {
  const GenericHead& generic = test::generic_head();
  const PointCloud scan = demo_scan(generic);

  FitHeadResult r;
  Status st = fit_head(scan, generic, FitHeadOptions{}, r);
  INFO(st.message);
  REQUIRE(st.ok());
  FitQuality q;
  REQUIRE(measure_fit_quality(r, generic.annotations, q).ok());
  INFO("level 3 pairs: lips " << q.crossings.lips << ", ears " << q.crossings.ears << ", rest " << q.crossings.rest
                              << "; smooth level 3: " << q.smooth_crossings.total);
  CHECK(q.flipped == 0);
  CHECK(q.degenerate == 0);
  // Pairs that cross on the smooth surface too are not the displacements'
  // doing (FoldLimitOptions::max_intersection_rounds); the sample has none.
  REQUIRE(q.smooth_crossings.total == 0);
  CHECK(q.crossings.total == 0);

  // The other direction on these points (what likeness fit and the page
  // print for a point cloud): the face's 27k scanned vertices lie 0.077 mm
  // from the points' patches on average (the truth says 0.092 mm), the
  // farthest 2.9 mm (at a mouth corner; truth 2.9 mm).
  CoveredDistances to_scan;
  REQUIRE(measure_fit_to_scan(r, scan, generic, to_scan).ok());
  INFO("face to scan points: " << to_scan.vertices << " vertices, mean " << to_scan.mean << " m, p99 " << to_scan.p99
                               << ", max " << to_scan.max);
  CHECK(to_scan.to_points);
  CHECK(to_scan.vertices > 25000);
  CHECK(to_scan.mean < 0.0001);
  CHECK(to_scan.p99 < 0.001);
  CHECK(to_scan.max < 0.004);

  // The fold limiter's second pass fires on this sample (a given-up ear
  // pair crossed again): its full searches ran on the first run's tree,
  // refitted, and the quality report took their pairs. They must be what a
  // search on a fresh tree finds. (Since the displacements fade across the
  // data's edge, DisplacementOptions::edge_fade_control_edges, the default
  // fit leaves the second pass nothing to do here: the check runs on the
  // fit without the fade, where it fires. Since the asset's eye-ring
  // corners are even (22 Nov) it does not fire there either: the check
  // then runs on the demo sample as it was, made from and fitted with the
  // generic head with its corners at 45 deg, and since the local fit's
  // boxes have more starts (23 Nov), with one start per box as then.)
  if (r.fold_limit.second_pass_before == 0) {
    FitHeadOptions no_fade;
    no_fade.displacement.edge_fade_control_edges = 0;
    r = FitHeadResult{};
    REQUIRE(fit_head(scan, generic, no_fade, r).ok());
  }
  if (r.fold_limit.second_pass_before == 0) {
    FitHeadOptions no_fade;
    no_fade.displacement.edge_fade_control_edges = 0;
    no_fade.local.start_shifts.clear();  // the local fit as it was then (one start per box)
    r = FitHeadResult{};
    const GenericHead& corner45 = test::corner45_generic_head();
    REQUIRE(fit_head(demo_scan(corner45), corner45, no_fade, r).ok());
  }
  INFO("second pass: " << r.fold_limit.second_pass_before << " -> " << r.fold_limit.second_pass_after);
  CHECK(r.fold_limit.second_pass_before > 0);
  REQUIRE(r.fold_limit.finest_pairs_known);
  const TriMesh finest = level_mesh(r.multires, r.multires.num_levels());
  std::vector<std::array<int, 2>> fresh;
  REQUIRE(find_self_intersections(finest, fresh).ok());
  CHECK(r.fold_limit.finest_pairs == fresh);
  REQUIRE(finest_pairs_of(r.fold_limit, finest.positions) != nullptr);
  // After an edit the level moved: the report searches again.
  std::vector<Vec3> moved = finest.positions;
  moved[0].x() += 1e-3;
  CHECK(finest_pairs_of(r.fold_limit, moved) == nullptr);
}

TEST_CASE("fit_head: synthetic seed 6's mouth is fitted in the right basin: no lip crossing") {
  // Made from the generic head of 23 Nov (even back rows), seed 6's
  // slightly open mouth sent the mouth box from the alignment 9 mm up
  // towards the nose (a local minimum, E_local 1.1e-6); the global fit
  // crumpled the lips it was handed: 125 level-3 pairs, 122 at the lips,
  // face to scan max 6 mm. The box's extra starts (LocalFitOptions::
  // start_shifts) find the basin 5 mm down (7.1e-7), where the previous
  // head's fit lands too (docs/journal.md "The mouth box's starts"). That head
  // (test::back_rows_generic_head) keeps the case; the asset's seed 6
  // (the regular nape) lands in the right basin from either start, and is
  // checked the same way.
  auto mouth = [](const FitHeadResult& fit) {
    const auto it = std::find_if(fit.local_fit.boxes.begin(), fit.local_fit.boxes.end(),
                                 [](const BoxFit& b) { return b.name == "mouth"; });
    REQUIRE(it != fit.local_fit.boxes.end());
    REQUIRE(!it->energies.empty());
    return *it;
  };
  for (const GenericHead* generic : {&test::back_rows_generic_head(), &test::generic_head()}) {
    const bool subject = generic == &test::back_rows_generic_head();
    INFO((subject ? "the head of 23 Nov (even back rows)" : "the asset"));
    const PointCloud scan = demo_scan(*generic, 6);
    FitHeadResult r;
    // Measured in the scan's frame: the same fit turned by its aligned
    // face's whole rotation (1.0 deg; FitHeadOptions::face_frame's first
    // form) had one vertex of 27,882 flip to another closest triangle, the
    // maximum reading 4.9 mm instead of 3.2.
    FitHeadOptions in_scan_frame;
    in_scan_frame.face_frame = false;
    Status st = fit_head(scan, *generic, in_scan_frame, r);
    INFO(st.message);
    REQUIRE(st.ok());
    FitQuality q;
    REQUIRE(measure_fit_quality(r, generic->annotations, q).ok());
    CoveredDistances to_scan;
    REQUIRE(measure_fit_to_scan(r, scan, *generic, to_scan).ok());
    INFO("mouth box: E_local " << mouth(r).energies.back());
    INFO("level 3 pairs: lips " << q.crossings.lips << ", rest " << q.crossings.rest << "; smooth level 3: "
                                << q.smooth_crossings.total << "; face to scan max " << 1000 * to_scan.max << " mm");
    CHECK(q.crossings.total == 0);
    CHECK(q.smooth_crossings.total == 0);
    CHECK(to_scan.max < 0.004);
    if (!subject) continue;
    // From the alignment's map alone the same box ends in the higher
    // basin: the case still has the subject this test is about.
    FitHeadOptions one_start;
    one_start.local.start_shifts.clear();
    FitHeadResult r1;
    REQUIRE(fit_head(scan, *generic, one_start, r1).ok());
    INFO("one start: mouth box E_local " << mouth(r1).energies.back());
    CHECK(mouth(r1).energies.back() > 1.3 * mouth(r).energies.back());
  }
}
