// End-to-end fit (jeong2002 Sec. 4-5) on small synthetic scans with known
// truth, conventions (units, orientation) and the rejection of non-heads.
#include "fit/closest_point.h"
#include "head/generic_head.h"
#include "mesh/geometry.h"
#include "mesh/topology.h"
#include "pipeline/fit_head.h"
#include "pipeline/fit_quality.h"
#include "raycast/self_intersection.h"
#include "test_scan.h"

#include <catch2/catch.hpp>
#include <algorithm>
#include <random>

using namespace lk;

namespace {

// The generic head and a 40k-point scan of a person made from it (seed 1),
// shared by the tests below.
struct Scene {
  const GenericHead& generic = test::generic_head();
  test::TestScan person = test::make_test_scan(1, 40000);
  const TruthSurface& truth = person.truth;
  const PointCloud& scan = person.scan;
};

const Scene& scene() {
  static const Scene s;
  return s;
}

// The result in the scene's frame, where the truth is (FitHeadOptions::
// face_frame turns it to the aligned face's; the fit is the same: tested
// below, "the result in the aligned face's frame").
FitHeadOptions quick_options() {
  FitHeadOptions o;
  o.levels = 2;
  o.face_frame = false;
  return o;
}

// The scan's points between the aligned neck cut and the aligned generic
// neck's lower end (5 mm off each: off the cut and the neck's end), in the
// frame of `fit`.
std::vector<Vec3> points_along_neck(const PointCloud& scan, const FitHeadResult& fit, const ClipPlane& generic_cut) {
  const AffineMap& m = fit.generic_to_head;
  const Vec3 p0 = m.apply(generic_cut.point);
  const Vec3 n = (m.A.inverse().transpose() * generic_cut.normal).normalized();
  double lowest = 0;
  for (const Vec3& v : fit.aligned.positions) lowest = std::min(lowest, n.dot(v - p0));
  std::vector<Vec3> neck;
  for (const Vec3& p : scan.positions) {
    const double h = n.dot(p - p0);
    if (h < -0.005 && h > lowest + 0.005) neck.push_back(p);
  }
  return neck;
}

// The median distance of `points` to `mesh`.
double median_distance_to(const TriMesh& mesh, const std::vector<Vec3>& points) {
  const ClosestPointTree tree(mesh);
  std::vector<double> d;
  for (const Vec3& p : points) d.push_back(std::sqrt(tree.closest(p).squared_distance));
  std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
  return d[d.size() / 2];
}

}  // namespace

TEST_CASE("fit_head: a synthetic scan is fitted, each stage closer than the last") {
  const Scene& s = scene();
  std::vector<std::string> events;
  FitStageObserver obs;
  obs.started = [&](const std::string& n) { events.push_back("start " + n); };
  obs.finished = [&](const std::string& n, const TriMesh& m) {
    events.push_back("finish " + n);
    CHECK(m.num_triangles() > 0);
  };
  obs.measured = [&](const FitStageReport& r) { events.push_back("measure " + r.name); };
  FitHeadResult r;
  const Status st = fit_head(s.scan, s.generic, quick_options(), r, obs);
  INFO(st.message);
  REQUIRE(st.ok());
  const std::vector<std::string> names = {"initial_alignment", "local_fitting", "global_fitting", "subdivision"};
  REQUIRE(r.stages.size() == 4);
  REQUIRE(events.size() == 12);
  for (size_t i = 0; i < 4; ++i) {
    CHECK(r.stages[i].name == names[i]);
    CHECK(events[3 * i] == "start " + names[i]);
    CHECK(events[3 * i + 1] == "finish " + names[i]);
    CHECK(events[3 * i + 2] == "measure " + names[i]);
  }
  for (const auto& st2 : r.stages) INFO(st2.name << " mean % " << st2.distance.mean_pct);
  CHECK(r.stages[1].distance.mean_pct <= r.stages[0].distance.mean_pct * 1.02);
  CHECK(r.stages[2].distance.mean_pct < 0.5 * r.stages[1].distance.mean_pct);
  CHECK(r.stages[3].distance.mean_pct <= r.stages[2].distance.mean_pct);
  // Loose accuracy bound on a small scan (the bench measures the real target).
  CHECK(r.stages[2].distance.mean_pct < 0.15);
  CHECK(r.stages[3].distance.mean_pct < 0.12);
  CHECK(r.unit_to_metres == 1.0);
  // The truth's surface lies on the fitted control mesh within a few mm.
  const DistanceStats back = point_to_surface_stats(s.truth.mesh.positions, r.control, 1.0);
  INFO("truth to control mesh: mean " << back.mean << " m, p95 " << back.p95 << " m");
  CHECK(back.mean < 0.003);
  // Connectivity is the generic head's; no control triangle turned over.
  REQUIRE(r.control.triangles == s.generic.mesh.triangles);
  const auto n0 = face_normals(r.aligned);
  int flipped = 0;
  for (int f = 0; f < r.control.num_triangles(); ++f) flipped += face_normal_area(r.control, f).dot(n0[f]) < 0;
  CHECK(flipped <= 2);
  REQUIRE(r.level_meshes.size() == 2);
  CHECK(r.level_meshes[1].num_triangles() == 16 * r.control.num_triangles());
  // The displaced levels turn no triangle over and collapse none, against
  // the smooth Butterfly levels of the same control mesh.
  std::vector<std::vector<Vec3>> smooth;
  REQUIRE(smooth_positions(r.multires, smooth).ok());
  for (int l = 0; l <= 2; ++l) {
    int flipped_l = 0, collapsed_l = 0;
    count_bad_triangles(r.multires, l, smooth[l], FoldLimitOptions{}, flipped_l, collapsed_l);
    INFO("level " << l);
    CHECK(flipped_l == 0);
    CHECK(collapsed_l == 0);
  }
  CHECK(r.fold_limit.remaining_bad == 0);
  CHECK(r.fold_limit.bad_found[2] > 0);  // there was something to limit
  // Crossing sheets: the separation pass removes most of those the
  // displacements made; the rest cross on the smooth surface too (the
  // Butterfly surface of the control mesh) or come from coarser levels
  // (measured here: 384 left of 628, 94 of them not on the smooth surface).
  std::vector<std::array<int, 2>> pairs;
  REQUIRE(find_self_intersections(r.level_meshes[1], pairs).ok());
  int made_by_displacement = 0;
  for (const auto& p : pairs)
    made_by_displacement += !mesh_triangles_cross(smooth[2], r.level_meshes[1].triangles[p[0]], r.level_meshes[1].triangles[p[1]]);
  INFO(pairs.size() << " crossing pairs at level 2, found before separating " << r.fold_limit.intersections_found);
  CHECK(static_cast<int>(pairs.size()) < r.fold_limit.intersections_found);
  // Under half: since the eye sockets follow their rims in global fitting
  // (fit_head.cpp), lids displaced inwards cross the nearer socket more
  // often (about a third of the pairs found; under a quarter with the
  // sockets held in place, when this bound was a quarter).
  CHECK(2 * made_by_displacement < r.fold_limit.intersections_found);
  // Global fit energies decrease monotonically.
  for (const auto& it : r.global_fit.iterations) CHECK(it.energy_after <= it.energy_before);
}

TEST_CASE("fit_head: any unit and orientation give the same head") {
  const Scene& s = scene();
  // Millimetres, lying on its back (+z up, facing -y), somewhere else.
  PointCloud mm = s.scan;
  const Mat3 R = Eigen::AngleAxisd(M_PI / 2, Vec3::UnitX()).toRotationMatrix();  // y -> z, z -> -y
  for (Vec3& p : mm.positions) p = 1000.0 * (R * p) + Vec3(500, -200, 80);
  FitHeadOptions o = quick_options();
  o.up = R * Vec3::UnitY();
  o.facing = R * Vec3::UnitZ();
  FitHeadResult r;
  const Status st = fit_head(mm, s.generic, o, r);
  INFO(st.message);
  REQUIRE(st.ok());
  CHECK(r.unit_to_metres == 0.001);
  CHECK(r.stages.back().distance.mean_pct < 0.12);
  // Mapped back to the scan frame, the control mesh lies on the mm scan.
  TriMesh back = r.control;
  const Mat3 inv = r.scan_to_head.A.inverse();
  for (Vec3& p : back.positions) p = inv * (p - r.scan_to_head.t);
  const DistanceStats d = point_to_surface_stats(mm.positions, back, r.bbox_diagonal, 7);
  CHECK(d.mean_pct < 0.5);
  CHECK(d.mean > 0.0);
}

// The control mesh's eye line (left rim's centroid minus the right's).
Vec3 eye_line(const TriMesh& control, const HeadAnnotations& a) {
  return test::vertices_centroid(control, a.eye_left.rim) - test::vertices_centroid(control, a.eye_right.rim);
}

// The eye line's turn about +y off +x, degrees.
double eye_line_yaw_deg(const Vec3& line) { return std::atan2(-line.z(), line.x()) * 180 / M_PI; }

TEST_CASE("fit_head: the result in the aligned face's frame, a head turned 20 deg on its shoulders facing +z") {
  // The scan turned 20 deg about its up (the face towards +x), the axes
  // given as +y up, +z facing: with face_frame the result turns back by
  // the aligned face's yaw, and is otherwise the same fit, turned.
  const Scene& s = scene();
  const double yaw = 20 * M_PI / 180;
  const Mat3 R = Eigen::AngleAxisd(yaw, Vec3::UnitY()).toRotationMatrix();
  PointCloud turned = s.scan;
  for (Vec3& p : turned.positions) p = R * p;
  for (Vec3& n : turned.normals) n = R * n;
  FitHeadOptions on = quick_options(), off = quick_options();
  on.face_frame = true;
  FitHeadResult r_on, r_off;
  REQUIRE(fit_head(turned, s.generic, on, r_on).ok());
  REQUIRE(fit_head(turned, s.generic, off, r_off).ok());
  INFO("face's yaw undone " << r_on.face_frame_deg << " deg; eye line yaw " << eye_line_yaw_deg(eye_line(r_off.control, s.generic.annotations))
                            << " deg unturned, " << eye_line_yaw_deg(eye_line(r_on.control, s.generic.annotations)) << " turned");
  CHECK(std::abs(r_on.face_frame_deg - 20) < 3);
  CHECK(r_off.face_frame_deg == 0);
  CHECK(r_off.face_frame_turn == Mat3::Identity());
  // The face looks along +z: its eye line along +x (within the fit's own
  // error, about 1 deg here), where unturned it is 20 deg off.
  CHECK(std::abs(eye_line_yaw_deg(eye_line(r_on.control, s.generic.annotations))) < 3);
  CHECK(std::abs(eye_line_yaw_deg(eye_line(r_off.control, s.generic.annotations)) - 20) < 3);
  // The same fit, turned: every mesh, the levels, the maps; figures equal.
  const Mat3& Q = r_on.face_frame_turn;
  CHECK((Q * Vec3::UnitY()).isApprox(Vec3::UnitY(), 1e-12));
  CHECK((r_on.scan_to_head.A - Q * r_off.scan_to_head.A).norm() < 1e-12);
  auto same_turned = [&](const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
    REQUIRE(a.size() == b.size());
    double worst = 0;
    for (size_t i = 0; i < a.size(); ++i) worst = std::max(worst, (a[i] - Q * b[i]).norm());
    return worst;
  };
  CHECK(same_turned(r_on.control.positions, r_off.control.positions) < 1e-12);
  CHECK(same_turned(r_on.aligned.positions, r_off.aligned.positions) < 1e-12);
  REQUIRE(r_on.level_meshes.size() == r_off.level_meshes.size());
  CHECK(same_turned(r_on.level_meshes.back().positions, r_off.level_meshes.back().positions) < 1e-12);
  CHECK(same_turned(r_on.multires.state.displaced.back(), r_off.multires.state.displaced.back()) < 1e-12);
  for (const Vec3& g : s.generic.mesh.positions)
    CHECK((r_on.generic_to_head.apply(g) - Q * r_off.generic_to_head.apply(g)).norm() < 1e-12);
  REQUIRE(r_on.stages.size() == r_off.stages.size());
  for (size_t k = 0; k < r_on.stages.size(); ++k) CHECK(r_on.stages[k].distance.mean == r_off.stages[k].distance.mean);
  // The quality report takes the limiter's pairs on the turned level too.
  CHECK(finest_pairs_of(r_on.fold_limit, r_on.multires.state.displaced.back()) != nullptr);
  FitQuality q_on, q_off;
  REQUIRE(measure_fit_quality(r_on, s.generic.annotations, q_on).ok());
  REQUIRE(measure_fit_quality(r_off, s.generic.annotations, q_off).ok());
  CHECK(q_on.crossings.total == q_off.crossings.total);
  // Mapped back through scan_to_head, the turned control mesh lies where the unturned one does.
  const Mat3 back_on = r_on.scan_to_head.A.inverse(), back_off = r_off.scan_to_head.A.inverse();
  for (size_t i = 0; i < r_on.control.positions.size(); ++i)
    CHECK((back_on * r_on.control.positions[i] - back_off * r_off.control.positions[i]).norm() < 1e-12);
}

TEST_CASE("fit_head rejects what is not a head with a clear error") {
  const Scene& s = scene();
  FitHeadResult r;
  PointCloud none;
  CHECK(fit_head(none, s.generic, quick_options(), r).code == ErrorCode::Empty);
  PointCloud few;
  few.positions.assign(s.scan.positions.begin(), s.scan.positions.begin() + 300);
  Status st = fit_head(few, s.generic, quick_options(), r);
  CHECK(st.code == ErrorCode::NotAHead);
  CHECK(st.message.find("300 points") != std::string::npos);
  PointCloud bad = s.scan;
  bad.positions[5].x() = std::nan("");
  CHECK(fit_head(bad, s.generic, quick_options(), r).code == ErrorCode::InvalidInput);

  std::mt19937 rng(3);
  std::uniform_real_distribution<double> U(-0.12, 0.12);
  PointCloud plane, noise;
  for (int i = 0; i < 20000; ++i) {
    plane.positions.emplace_back(U(rng), U(rng), 0.0001 * U(rng));
    noise.positions.emplace_back(U(rng), 1.2 * U(rng), U(rng));
  }
  st = fit_head(plane, s.generic, quick_options(), r);
  INFO(st.message);
  CHECK(st.code == ErrorCode::NotAHead);
  st = fit_head(noise, s.generic, quick_options(), r);
  INFO(st.message);
  CHECK(st.code == ErrorCode::NotAHead);
  // A box-shaped "chair": six noisy faces of a 0.4 x 0.45 x 0.4 m box.
  PointCloud chair;
  std::uniform_real_distribution<double> V(0, 1);
  for (int i = 0; i < 30000; ++i) {
    Vec3 p(V(rng) * 0.4, V(rng) * 0.45, V(rng) * 0.4);
    const int face = i % 6;
    p[face / 2] = (face % 2) ? (face / 2 == 1 ? 0.45 : 0.4) : 0.0;
    chair.positions.push_back(p);
  }
  st = fit_head(chair, s.generic, quick_options(), r);
  INFO(st.message);
  CHECK(st.code == ErrorCode::NotAHead);
  // Parallel conventions are refused.
  FitHeadOptions o = quick_options();
  o.facing = o.up;
  CHECK(fit_head(s.scan, s.generic, o, r).code == ErrorCode::InvalidInput);
}

TEST_CASE("unit guess picks m, cm or mm from a head-sized diagonal") {
  CHECK(guess_unit_to_metres(0.4) == 1.0);
  CHECK(guess_unit_to_metres(38.0) == 0.01);
  CHECK(guess_unit_to_metres(420.0) == 0.001);
  Mat3 R;
  REQUIRE(orientation_from_conventions(Vec3::UnitZ(), -Vec3::UnitY(), R).ok());
  CHECK((R * Vec3::UnitZ()).isApprox(Vec3::UnitY()));
  CHECK((R * -Vec3::UnitY()).isApprox(Vec3::UnitZ()));
  CHECK(R.determinant() == Approx(1.0));
}

TEST_CASE("fit_head: the levels near the neck cut follow the scan just below it, not the smooth surface") {
  // Measured from the points above the cut only, the displacements dropped
  // to the control mesh's smooth surface (about 1 mm inside the truth) at
  // the cut, in streaks along the neck's long triangles.
  const Scene& s = scene();
  // On the control mesh's flat triangles (the paper's global fit), whose
  // smooth surface lies inside the scan: what the band is for. With the
  // refined surface fitted (whole_head_data_level, the default on whole
  // heads) the smooth neck here is already on the scan and the band's
  // gain is gone in this small scene (0.160 vs 0.150 mm); on seeds 1-5 it
  // is still 0.519 vs 0.524 mm where scanned (docs/journal.md).
  FitHeadOptions on = quick_options(), off = quick_options();
  on.whole_head_data_level = off.whole_head_data_level = -1;
  // The band, not the whole scanned neck (fit_scanned_neck, off by
  // default; tested below).
  on.fit_scanned_neck = off.fit_scanned_neck = false;
  off.displacement_below_neck_cut = 0;
  FitHeadResult r_on, r_off;
  REQUIRE(fit_head(s.scan, s.generic, on, r_on).ok());
  REQUIRE(fit_head(s.scan, s.generic, off, r_off).ok());
  // Truth vertices up to 8 mm above the aligned neck cut.
  const ClipPlane& cut = s.generic.annotations.neck_clip;
  const AffineMap& m = r_on.generic_to_head;
  const Vec3 p0 = m.apply(cut.point), n = (m.A.inverse().transpose() * cut.normal).normalized();
  std::vector<Vec3> band;
  for (const Vec3& p : s.truth.mesh.positions) {
    const double h = n.dot(p - p0);
    if (h >= 0 && h < 0.008) band.push_back(p);
  }
  REQUIRE(band.size() > 100);
  const double d_on = point_to_surface_stats(band, r_on.level_meshes.back(), 1.0).mean;
  const double d_off = point_to_surface_stats(band, r_off.level_meshes.back(), 1.0).mean;
  INFO(band.size() << " truth vertices above the cut: mean distance " << 1e3 * d_on << " mm with the scan below it, "
                   << 1e3 * d_off << " mm without");
  // Measured: 0.350 vs 0.450 mm with the old neck of 5:1 slivers; 0.247 vs
  // 0.287 mm since the generic neck is meshed in round triangles (both
  // closer, the band's share of the gain smaller); 0.247 vs 0.271 mm since
  // the displacements fade across the data's edge (the fit without the
  // band gained, DisplacementOptions::edge_fade_control_edges); 0.252 vs
  // 0.270 mm since the smooth-surface guard runs on whole heads too (it
  // moves this small scene's control mesh a little: both fits change);
  // 0.189 vs 0.196 mm since the regular nape (generic_head_builder.h: the
  // neck's quads split alike and the strip to the neck deeper at the back,
  // so the smooth neck the fit without the band falls back on is closer).
  // Without the band the two would be equal.
  CHECK(d_on < 0.98 * d_off);
  // Table 1's distances stay over the points above the cut.
  CHECK(r_on.fitted_points == r_off.fitted_points);
}

TEST_CASE("fit_head: a scanned neck thicker than the generic one is fitted where it is scanned") {
  // The scan's points below the generic neck plane pushed 6 mm out along
  // their normals: a neck the generic one does not have. Fitted from the
  // points above the cut and a 10 mm band (fit_scanned_neck off), the
  // neck stays near the generic one, millimetres inside those points;
  // with it on, the neck down to the generic neck's end lies on them.
  const Scene& s = scene();
  const ClipPlane& generic_cut = s.generic.annotations.neck_clip;
  PointCloud scan = s.scan;
  REQUIRE(scan.normals.size() == scan.positions.size());
  int pushed = 0;
  for (size_t i = 0; i < scan.positions.size(); ++i)
    if (!generic_cut.keeps(scan.positions[i])) scan.positions[i] += 0.006 * scan.normals[i].normalized(), ++pushed;
  REQUIRE(pushed > 1000);
  FitHeadOptions on = quick_options(), off = quick_options();
  on.fit_scanned_neck = true;
  off.fit_scanned_neck = false;
  FitHeadResult r_on, r_off;
  REQUIRE(fit_head(scan, s.generic, on, r_on).ok());
  REQUIRE(fit_head(scan, s.generic, off, r_off).ok());
  CHECK(r_on.neck_points > 1000);
  CHECK(r_off.neck_points == 0);
  // Table 1's points are those above the cut either way.
  CHECK(r_on.fitted_points == r_off.fitted_points);
  // The scan's points between the aligned cut and the aligned neck's lower
  // end, to each fit's finest level.
  const std::vector<Vec3> neck = points_along_neck(scan, r_on, generic_cut);
  REQUIRE(neck.size() > 500);
  auto median_distance = [&](const TriMesh& mesh) { return median_distance_to(mesh, neck); };
  const double d_on = median_distance(r_on.level_meshes.back());
  const double d_off = median_distance(r_off.level_meshes.back());
  INFO(neck.size() << " neck points: median distance " << 1e3 * d_on << " mm with the scanned neck fitted, "
                   << 1e3 * d_off << " mm without");
  CHECK(d_on < 0.001);
  CHECK(d_off > 0.003);
  // The neck's fit with the smooth-surface guard (main's before session 51)
  // lies on the same points: the guard's work is at the held head.
  REQUIRE(!on.scanned_neck_smooth_guard);
  FitHeadOptions guarded = on;
  guarded.scanned_neck_smooth_guard = true;
  FitHeadResult r_guarded;
  REQUIRE(fit_head(scan, s.generic, guarded, r_guarded).ok());
  const double d_guarded = median_distance(r_guarded.level_meshes.back());
  INFO("with the neck's fit guarded: " << 1e3 * d_guarded << " mm");
  CHECK(d_guarded < 0.001);
  CHECK(std::abs(d_on - d_guarded) < 0.0002);
  FitHeadResult bad;
  on.scanned_neck_max_angle_deg = -1;
  const Status st = fit_head(scan, s.generic, on, bad);
  CHECK(st.code == ErrorCode::InvalidInput);
  CHECK(st.message.find("scanned_neck_max_angle_deg") != std::string::npos);
}

TEST_CASE("fit_head: a scanned neck centimetres off the generic one is reached with scanned_neck_reach") {
  // The scan's points below the generic neck plane pushed 25 mm out along
  // their normals (Gutenberg's neck lay 45 mm off the head's fit, median).
  // The held round trims residuals beyond the head fit's trimming distance
  // (a few millimetres), so without the reach it pulls almost none of them.
  const Scene& s = scene();
  const ClipPlane& generic_cut = s.generic.annotations.neck_clip;
  PointCloud scan = s.scan;
  REQUIRE(scan.normals.size() == scan.positions.size());
  for (size_t i = 0; i < scan.positions.size(); ++i)
    if (!generic_cut.keeps(scan.positions[i])) scan.positions[i] += 0.025 * scan.normals[i].normalized();
  FitHeadOptions on = quick_options(), off = quick_options();
  on.fit_scanned_neck = off.fit_scanned_neck = true;
  on.scanned_neck_reach = true;
  off.scanned_neck_reach = false;
  // The control mesh each global fit hands on (the neck's fit included).
  TriMesh global_on, global_off;
  FitStageObserver obs_on, obs_off;
  obs_on.finished = [&](const std::string& name, const TriMesh& m) {
    if (name == "global_fitting") global_on = m;
  };
  obs_off.finished = [&](const std::string& name, const TriMesh& m) {
    if (name == "global_fitting") global_off = m;
  };
  FitHeadResult r_on, r_off;
  REQUIRE(fit_head(scan, s.generic, on, r_on, obs_on).ok());
  REQUIRE(fit_head(scan, s.generic, off, r_off, obs_off).ok());
  REQUIRE(r_on.neck_points > 1000);
  CHECK(r_on.neck_points == r_off.neck_points);
  CHECK(r_on.neck_reach.reached);
  CHECK(r_on.neck_reach.median_before > r_on.neck_reach.trim_distance);
  CHECK(!r_off.neck_reach.reached);
  CHECK(r_on.fitted_points == r_off.fitted_points);
  // The pushed points between the aligned cut and the aligned neck's lower
  // end, to each fit's finest level.
  const std::vector<Vec3> neck = points_along_neck(scan, r_on, generic_cut);
  REQUIRE(neck.size() > 500);
  auto median_distance = [&](const TriMesh& mesh) { return median_distance_to(mesh, neck); };
  const double d_on = median_distance(r_on.level_meshes.back());
  const double d_off = median_distance(r_off.level_meshes.back());
  INFO(neck.size() << " neck points: median distance " << 1e3 * d_on << " mm with the reach, " << 1e3 * d_off
                   << " mm without; the neck's median " << 1e3 * r_on.neck_reach.median_before
                   << " mm off the head's fit, trimmed beyond " << 1e3 * r_on.neck_reach.trim_distance << " mm");
  CHECK(d_on < 0.001);
  CHECK(d_off > 0.005);
  // Only the neck's control vertices moved: the head's are where the
  // head's fit left them, to the bit, with the reach as without it.
  REQUIRE(global_on.num_vertices() == global_off.num_vertices());
  std::vector<char> neck_vertex(global_on.num_vertices(), 0);
  for (int v : s.generic.annotations.regions.at("neck")) neck_vertex[v] = 1;
  int head_moved = 0, neck_moved = 0;
  for (int v = 0; v < global_on.num_vertices(); ++v) {
    const bool moved = global_on.positions[v] != global_off.positions[v];
    (neck_vertex[v] ? neck_moved : head_moved) += moved ? 1 : 0;
  }
  CHECK(head_moved == 0);
  CHECK(neck_moved > 0);
}

// The scan with a sheet over the left ear: every point within 0.6 ear
// sizes of the ear's centre pushed out to the ear's outer side (it crosses
// the ear at level 3). ears: the "ears" region of head.
static PointCloud sheet_over_left_ear(const PointCloud& scan_in, const TriMesh& head, const std::vector<int>& ears) {
  PointCloud scan = scan_in;
  scan.normals.clear();
  std::vector<Vec3> ear;
  for (int v : ears)
    if (head.positions[v].x() > 0) ear.push_back(head.positions[v]);  // +x is left
  REQUIRE(!ear.empty());
  const BBox box = bounding_box(ear);
  const Vec3 centre = 0.5 * (box.min + box.max);
  for (Vec3& p : scan.positions)
    if ((p - centre).norm() < 0.6 * box.diagonal() && p.x() - centre.x() > -0.01) p.x() = box.max.x();
  return scan;
}

// The scene's scan with the sheet over the generic head's left ear.
static PointCloud scene_sheet_over_left_ear() {
  const Scene& s = scene();
  const auto region = s.generic.annotations.regions.find("ears");
  REQUIRE(region != s.generic.annotations.regions.end());
  return sheet_over_left_ear(s.scan, s.generic.mesh, region->second);
}

TEST_CASE("fit_head: holding a crossing ear that does not help leaves the fit as it was") {
  // A sheet over the left ear (every scan point within 0.6 ear sizes of its
  // centre pushed out to the ear's outer side) crosses the ear at level 3.
  // Holding it in the generic shape (FitHeadOptions::hold_crossing_ears)
  // crosses more there (the head around it is pulled onto the sheet too):
  // the fit must come back exactly as without the hold, with a note saying
  // so. (Plato's ears, where holding helps, are checked in
  // test_real_scans.cpp.)
  const Scene& s = scene();
  const PointCloud scan = scene_sheet_over_left_ear();
  FitHeadOptions on;
  on.measure_stages = false;
  on.guard_feature_crossings = false;  // the hold alone (the guard is tested below)
  // The ears free, as they were before bind_ear_edges' WhereTheyCross
  // (which takes this sheet's pairs away before the hold: tested below).
  on.bind_ear_edges = FitHeadOptions::EarBinding::FaceOnlyScans;
  FitHeadOptions off = on;
  off.hold_crossing_ears = false;
  FitHeadResult free_fit, held_fit;
  REQUIRE(fit_head(scan, s.generic, off, free_fit).ok());
  REQUIRE(fit_head(scan, s.generic, on, held_fit).ok());
  std::vector<std::array<int, 2>> pairs;
  REQUIRE(find_self_intersections(free_fit.level_meshes.back(), pairs).ok());
  const int ears_free = count_pairs_touching(free_fit.multires, free_fit.multires.num_levels(), pairs, s.generic.annotations.regions.at("ears"));
  INFO(pairs.size() << " pairs at level 3 without the hold, " << ears_free << " at the ears");
  REQUIRE(ears_free > 0);  // else the hold is not tried and this tests nothing
  bool noted = false;
  for (const std::string& n : held_fit.notes) noted = noted || n.find("did not help") != std::string::npos;
  CHECK(noted);
  CHECK(held_fit.ears_held == 0);
  CHECK(held_fit.control.positions == free_fit.control.positions);
  REQUIRE(held_fit.level_meshes.size() == free_fit.level_meshes.size());
  CHECK(held_fit.level_meshes.back().positions == free_fit.level_meshes.back().positions);
}

TEST_CASE("fit_head: the feature guard leaves no crossing pair at the ears and lips, and nothing else changes") {
  // The sheet over the left ear of the test above: the hold cannot help, the
  // guard (FitHeadOptions::guard_feature_crossings) must take the ear's
  // pairs to 0 without adding pairs elsewhere, and leave the control mesh
  // as fitted away from the crossing (the rest of the head follows the
  // scan as before).
  const Scene& s = scene();
  const PointCloud scan = scene_sheet_over_left_ear();
  FitHeadOptions guarded;
  guarded.measure_stages = false;
  guarded.bind_ear_edges = FitHeadOptions::EarBinding::FaceOnlyScans;  // free ears, as above
  FitHeadOptions unguarded = guarded;
  unguarded.guard_feature_crossings = false;
  FitHeadResult before, after;
  REQUIRE(fit_head(scan, s.generic, unguarded, before).ok());
  REQUIRE(fit_head(scan, s.generic, guarded, after).ok());
  FitQuality qb, qa;
  REQUIRE(measure_fit_quality(before, s.generic.annotations, qb).ok());
  REQUIRE(measure_fit_quality(after, s.generic.annotations, qa).ok());
  // The quality report's pairs (handed over by the guard) are a whole search's.
  std::vector<std::array<int, 2>> pairs;
  REQUIRE(find_self_intersections(after.level_meshes.back(), pairs).ok());
  CHECK(static_cast<int>(pairs.size()) == qa.crossings.total);
  INFO("ears " << qb.crossings.ears << " -> " << qa.crossings.ears << ", lips " << qb.crossings.lips << " -> "
               << qa.crossings.lips << ", all " << qb.crossings.total << " -> " << qa.crossings.total);
  REQUIRE(qb.crossings.ears + qb.crossings.lips > 0);  // else the guard has nothing to do
  CHECK(after.feature_guard.pairs_before == qb.crossings.ears + qb.crossings.lips);
  CHECK(after.feature_guard.steps > 0);
  CHECK(qa.crossings.ears == 0);
  CHECK(qa.crossings.lips == 0);
  CHECK(qa.crossings.total - qa.crossings.ears - qa.crossings.lips <=
        qb.crossings.total - qb.crossings.ears - qb.crossings.lips);
  // Only the relaxed control vertices moved: at most the count reported.
  int moved = 0;
  for (size_t v = 0; v < after.control.positions.size(); ++v)
    moved += after.control.positions[v] != before.control.positions[v];
  CHECK(moved <= after.feature_guard.moved_vertices);
  CHECK(after.feature_guard.relaxed_vertices < after.control.num_vertices() / 10);
}

TEST_CASE("fit_head: an ear the free fit folds is fitted again bound, and holds without the later steps") {
  // The sheet over the left ear of the tests above: fitted free, the ear
  // crosses itself at the smooth level 3 and at level 3. With the ears
  // bound where they cross (FitHeadOptions::bind_ear_edges, the default)
  // the global fit runs again with the ear edges as binding edges: no ear
  // pair at level 3 and neither the hold nor the guard has to act.
  const Scene& s = scene();
  const PointCloud scan = scene_sheet_over_left_ear();
  FitHeadOptions bound;
  bound.measure_stages = false;
  // The displacements without the scanned neck's points (the 10 mm band),
  // as when this was measured: with them (the default) the bound fit's
  // smooth ears still do not cross but level 3 has 6 ear pairs, left to
  // the hold and the guard (docs/design/fit_real_scans.md, 2026-11-30).
  bound.fit_scanned_neck = false;
  FitHeadOptions free_ears = bound;
  free_ears.bind_ear_edges = FitHeadOptions::EarBinding::FaceOnlyScans;
  free_ears.hold_crossing_ears = bound.hold_crossing_ears = false;
  free_ears.guard_feature_crossings = bound.guard_feature_crossings = false;
  FitHeadResult free_fit, bound_fit;
  REQUIRE(fit_head(scan, s.generic, free_ears, free_fit).ok());
  REQUIRE(fit_head(scan, s.generic, bound, bound_fit).ok());
  FitQuality qf, qb;
  REQUIRE(measure_fit_quality(free_fit, s.generic.annotations, qf).ok());
  REQUIRE(measure_fit_quality(bound_fit, s.generic.annotations, qb).ok());
  INFO("ear pairs at level 3: free " << qf.crossings.ears << " (smooth " << qf.smooth_crossings.ears << "), bound "
                                     << qb.crossings.ears << " (smooth " << qb.smooth_crossings.ears
                                     << "); smooth ear pairs the fit saw: " << bound_fit.ear_binding.free_pairs
                                     << " free, " << bound_fit.ear_binding.bound_pairs << " bound");
  REQUIRE(qf.crossings.ears > 0);  // the free fit folds the ear
  CHECK(free_fit.ear_binding.free_pairs == 0);  // not searched with the ears free
  CHECK(bound_fit.ear_binding.free_pairs > 0);
  CHECK(bound_fit.ear_binding.bound);
  CHECK(bound_fit.ear_binding.bound_pairs == 0);
  CHECK(qb.crossings.ears == 0);
  CHECK(qb.crossings.lips == 0);
  CHECK(qb.crossings.total <= qf.crossings.total);
  bool noted = false;
  for (const std::string& n : bound_fit.notes) noted = noted || n.find("fitted again with their edges bound") != std::string::npos;
  CHECK(noted);
}

TEST_CASE("fit_head: the ear refit decided after the rounds gives the head decided after the guards") {
  // FitHeadOptions::ear_refit_after_rounds: the free fit's ears are judged
  // before its smooth-surface guard and the free fit's guard is skipped
  // when the bound fit is kept. On the sheet over the left ear (the free fit
  // folds it, the bound fit is kept) and on the plain synthetic scan (no ear
  // folds, no refit) the heads must be the late decision's to the bit.
  const Scene& s = scene();
  const PointCloud sheet = scene_sheet_over_left_ear();
  FitHeadOptions early;
  early.measure_stages = false;
  REQUIRE(early.ear_refit_after_rounds);
  FitHeadOptions late = early;
  late.ear_refit_after_rounds = false;
  for (const PointCloud* scan : {&sheet, &s.scan}) {
    const bool folded = scan == &sheet;
    FitHeadResult e, l;
    REQUIRE(fit_head(*scan, s.generic, early, e).ok());
    REQUIRE(fit_head(*scan, s.generic, late, l).ok());
    INFO((folded ? "the sheet" : "the plain scan") << ": smooth ear pairs early " << e.ear_binding.free_pairs
                                                   << " free, " << e.ear_binding.bound_pairs << " bound; late "
                                                   << l.ear_binding.free_pairs << " free, "
                                                   << l.ear_binding.bound_pairs << " bound");
    CHECK((e.ear_binding.free_pairs > 0) == folded);  // the refit runs on the sheet only
    CHECK((l.ear_binding.free_pairs > 0) == folded);
    CHECK(e.ear_binding.bound == folded);
    CHECK(l.ear_binding.bound == folded);
    CHECK(e.control.positions == l.control.positions);
    REQUIRE(e.level_meshes.size() == l.level_meshes.size());
    CHECK(e.level_meshes.back().positions == l.level_meshes.back().positions);
    CHECK(e.global_fit.iterations.size() == l.global_fit.iterations.size());
    CHECK(e.global_fit.fold_crease_edges == l.global_fit.fold_crease_edges);
  }
}

TEST_CASE("fit_head: a bound ear refit given up after its rounds leaves the free fit's head to the bit") {
  // FitHeadOptions::ear_refit_give_up_pairs: the bound fit ends after its
  // rounds when its ears cross there in more pairs than the option allows.
  // On the sheet over the left ear (free fit folds, bound fit kept with
  // its ears crossing after its rounds) a bound of 1 gives it up: the head
  // must be the free fit's (ears never bound) to the bit, the bound count
  // the one after its rounds. A bound above that count changes nothing:
  // the head is the one judged at the end (0, the default), to the bit.
  const Scene& s = scene();
  const PointCloud sheet = scene_sheet_over_left_ear();
  FitHeadOptions judged;
  judged.measure_stages = false;
  REQUIRE(judged.ear_refit_give_up_pairs == 0);  // off by default
  FitHeadOptions free_ears = judged;
  free_ears.bind_ear_edges = FitHeadOptions::EarBinding::FaceOnlyScans;  // a whole head: never bound
  FitHeadOptions give_up = judged;
  give_up.ear_refit_give_up_pairs = 1;
  FitHeadResult j, f, g;
  REQUIRE(fit_head(sheet, s.generic, judged, j).ok());
  REQUIRE(fit_head(sheet, s.generic, free_ears, f).ok());
  REQUIRE(fit_head(sheet, s.generic, give_up, g).ok());
  INFO("smooth ear pairs: judged at the end " << j.ear_binding.free_pairs << " free, " << j.ear_binding.bound_pairs
                                              << " bound; given up " << g.ear_binding.free_pairs << " free, "
                                              << g.ear_binding.bound_pairs << " bound after its rounds");
  REQUIRE(j.ear_binding.free_pairs > 0);  // the refit runs
  CHECK(j.ear_binding.bound);
  CHECK(g.ear_binding.free_pairs == j.ear_binding.free_pairs);
  CHECK_FALSE(g.ear_binding.bound);
  CHECK(g.ear_binding.bound_pairs > 1);
  CHECK(g.control.positions == f.control.positions);
  REQUIRE(g.level_meshes.size() == f.level_meshes.size());
  CHECK(g.level_meshes.back().positions == f.level_meshes.back().positions);
  CHECK(g.global_fit.iterations.size() == f.global_fit.iterations.size());
  CHECK(g.global_fit.fold_crease_edges == f.global_fit.fold_crease_edges);
  bool noted = false;
  for (const std::string& n : g.notes) noted = noted || n.find("given up") != std::string::npos;
  CHECK(noted);
  // Above the bound fit's count after its rounds: judged at its end.
  FitHeadOptions high = judged;
  high.ear_refit_give_up_pairs = g.ear_binding.bound_pairs;
  FitHeadResult h;
  REQUIRE(fit_head(sheet, s.generic, high, h).ok());
  CHECK(h.ear_binding.bound);
  CHECK(h.control.positions == j.control.positions);
  REQUIRE(h.level_meshes.size() == j.level_meshes.size());
  CHECK(h.level_meshes.back().positions == j.level_meshes.back().positions);
}

TEST_CASE("fit_head: the warm ear refit holds a folded ear as the cold one does, near its fit") {
  // FitHeadOptions::ear_refit_warm_rounds: the bound refit starts from the
  // free fit and runs only the last round. On the sheet over the left ear
  // (the free fit folds it) it must keep the bound fit as the cold refit
  // (the whole fit again from the local fit, the default) does, with 0 ear
  // and lip pairs at level 3 without the hold or the guard, its left ear
  // near the cold refit's, the head about as close to the truth, in fewer
  // iterations. Measured: the left ear's vertices up to 8.5 mm apart in an
  // ear 7 cm across, the truth to level 3 1.28 mm warm against 1.12 mm cold
  // (the right half, away from the sheet: 0.83 against 0.74 mm): the warm
  // refit lands in another minimum, which is why it is not the default.
  const Scene& s = scene();
  const PointCloud scan = scene_sheet_over_left_ear();
  FitHeadOptions cold;
  cold.measure_stages = false;
  cold.hold_crossing_ears = false;
  cold.guard_feature_crossings = false;  // the refit alone
  REQUIRE(cold.ear_refit_warm_rounds == 0);
  FitHeadOptions warm = cold;
  warm.ear_refit_warm_rounds = 1;
  // The warm refit is decided after the free fit's guard; so is the cold
  // one here, to compare the same free fit.
  cold.ear_refit_after_rounds = false;
  FitHeadResult warm_fit, cold_fit;
  REQUIRE(fit_head(scan, s.generic, warm, warm_fit).ok());
  REQUIRE(fit_head(scan, s.generic, cold, cold_fit).ok());
  FitQuality qw, qc;
  REQUIRE(measure_fit_quality(warm_fit, s.generic.annotations, qw).ok());
  REQUIRE(measure_fit_quality(cold_fit, s.generic.annotations, qc).ok());
  double ear_apart = 0;
  std::vector<Vec3> left_ear;
  for (int v : s.generic.annotations.regions.at("ears"))
    if (cold_fit.control.positions[v].x() > 0) {  // +x is left
      ear_apart = std::max(ear_apart, (warm_fit.control.positions[v] - cold_fit.control.positions[v]).norm());
      left_ear.push_back(cold_fit.control.positions[v]);
    }
  const double ear_size = bounding_box(left_ear).diagonal();
  const double diag = warm_fit.bbox_diagonal;
  const DistanceStats tw = point_to_surface_stats(s.truth.mesh.positions, warm_fit.level_meshes.back(), diag);
  const DistanceStats tc = point_to_surface_stats(s.truth.mesh.positions, cold_fit.level_meshes.back(), diag);
  INFO("ear pairs warm " << qw.crossings.ears << " cold " << qc.crossings.ears << "; left ear's vertices apart at most "
                         << ear_apart << " m (its box " << ear_size << " m); truth to level 3 mean warm " << tw.mean
                         << " cold " << tc.mean << "; iterations warm " << warm_fit.global_fit.iterations.size()
                         << " cold " << cold_fit.global_fit.iterations.size());
  REQUIRE(cold_fit.ear_binding.free_pairs > 0);  // the free fit folds: both refit
  CHECK(warm_fit.ear_binding.free_pairs == cold_fit.ear_binding.free_pairs);  // the same free fit
  CHECK(cold_fit.ear_binding.bound);
  CHECK(warm_fit.ear_binding.bound);
  CHECK(qw.crossings.ears == 0);
  CHECK(qw.crossings.lips == 0);
  CHECK(ear_apart < 0.2 * ear_size);
  CHECK(tw.mean < 1.25 * tc.mean);
  CHECK(warm_fit.global_fit.iterations.size() < cold_fit.global_fit.iterations.size());
  // A negative number of warm rounds is refused with its name.
  FitHeadOptions bad = cold;
  bad.ear_refit_warm_rounds = -1;
  FitHeadResult refused;
  const Status st = fit_head(scan, s.generic, bad, refused);
  CHECK(st.code == ErrorCode::InvalidInput);
  CHECK(st.message.find("ear_refit_warm_rounds") != std::string::npos);
}

TEST_CASE("fit_head: a faired generic head is aligned as its skin as cast, and fitted from its own skin") {
  // GenericHead::alignment_positions: fairing moves only how the face's
  // control vertices sample the shape, yet the alignment's choices hung on
  // that sampling (docs/design/generic_head.md). A faired head is aligned
  // on its skin as cast, so it lands exactly where the cast head does.
  const Scene& s = scene();
  GenericHeadBuildOptions cast_options, faired_options;
  cast_options.fair_iterations = 0;
  faired_options.fair_iterations = 3;
  const GenericHead cast = test::built_generic_head(cast_options);
  const GenericHead faired = test::built_generic_head(faired_options);
  REQUIRE(faired.alignment_positions == cast.mesh.positions);
  REQUIRE(cast.alignment_positions.empty());
  REQUIRE(faired.mesh.positions != cast.mesh.positions);
  FitHeadOptions o = quick_options();
  o.levels = 0;
  FitHeadResult by_cast, by_faired, by_own_skin;
  REQUIRE(fit_head(s.scan, cast, o, by_cast).ok());
  REQUIRE(fit_head(s.scan, faired, o, by_faired).ok());
  CHECK(by_faired.generic_to_head.A == by_cast.generic_to_head.A);
  CHECK(by_faired.generic_to_head.t == by_cast.generic_to_head.t);
  // The fit starts from the faired skin, placed by that alignment.
  for (size_t v = 0; v < faired.mesh.positions.size(); ++v)
    REQUIRE((by_faired.aligned.positions[v] - by_faired.generic_to_head.apply(faired.mesh.positions[v])).norm() == 0.0);
  // Aligned on its own skin instead, the same head lands elsewhere: what
  // the cast positions are there for.
  GenericHead own = faired;
  own.alignment_positions.clear();
  REQUIRE(fit_head(s.scan, own, o, by_own_skin).ok());
  CHECK(by_own_skin.generic_to_head.A != by_cast.generic_to_head.A);
}

TEST_CASE("choose_guard_step: by cost, the cheaper step that clears as many pairs is kept, not the first") {
  // A cluster's ladder as tried: step 0 does not help, step 1 clears the
  // pairs at a cost of 5, step 2 clears them at 2, step 3 clears them at 1
  // but lies beyond one extra try, step 4 costs less but leaves a pair.
  std::vector<GuardTry> tries(5);
  tries[0] = {false, 6, 0.0};
  tries[1] = {true, 0, 5.0};
  tries[2] = {true, 0, 2.0};
  tries[3] = {true, 0, 1.0};
  tries[4] = {true, 1, 0.5};
  CHECK(choose_guard_step(tries, false, 3) == 1);  // the ladder's rule: the first that helps
  CHECK(choose_guard_step(tries, true, 0) == 1);   // no extra try: the same
  CHECK(choose_guard_step(tries, true, 1) == 2);   // the cheaper within one extra try
  CHECK(choose_guard_step(tries, true, 3) == 3);   // step 4 leaves more pairs than the first
  tries[2].helps = false;                          // a cheap step that does not help is never kept
  tries[3].helps = false;
  CHECK(choose_guard_step(tries, true, 1) == 1);
  for (GuardTry& t : tries) t.helps = false;
  CHECK(choose_guard_step(tries, true, 3) == -1);
  // Equal costs: the first (the least change).
  std::vector<GuardTry> equal = {{true, 0, 1.0}, {true, 0, 1.0}};
  CHECK(choose_guard_step(equal, true, 1) == 0);
}
