// The head project's jobs (core/project) driven directly on a synthetic
// scan: each must give what the stages it composes give, and fail with a
// message, never a crash, on a project that cannot do it yet.
#include "io/io.h"
#include "mesh/geometry.h"
#include "pipeline/fit_quality.h"
#include "project/export.h"
#include "project/fit_job.h"
#include "project/pose.h"
#include "project/quality_job.h"
#include "project_scene.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <set>

using namespace lk;

namespace {

bool same(const std::vector<Vec3>& a, const std::vector<Vec3>& b) { return a == b; }

}  // namespace

TEST_CASE("project fit: the fit job's head is fit_head's, bit for bit, with its frame and rig") {
  const test::ProjectScene& s = test::project_scene();
  REQUIRE(s.direct_status.ok());
  HeadProject p = test::fitted_project();
  CHECK(same(p.fit.control.positions, s.direct.control.positions));
  REQUIRE(p.fit.level_meshes.size() == s.direct.level_meshes.size());
  for (size_t l = 0; l < s.direct.level_meshes.size(); ++l)
    CHECK(same(p.fit.level_meshes[l].positions, s.direct.level_meshes[l].positions));
  CHECK(p.fit.scan_to_head.A == s.direct.scan_to_head.A);
  CHECK(p.scan.positions == s.person.scan.positions);
  CHECK(p.scan.faces == s.person.scan.faces);
  // The frame undoes scan_to_head.
  for (int i = 0; i < 50; ++i) {
    const Vec3& q = s.person.scan.positions[static_cast<size_t>(i) * 97];
    CHECK((p.frame.to_scan(p.fit.scan_to_head.apply(q)) - q).norm() < 1e-12);
  }
  // The rig moves the jaw regions and the brow, nothing twice.
  const auto& regions = s.generic.annotations.regions;
  std::set<int> jaw(regions.at("jaw").begin(), regions.at("jaw").end());
  CHECK(p.rig.moved.size() == std::set<int>(p.rig.moved.begin(), p.rig.moved.end()).size());
  int jaw_moved = 0, brow_moved = 0;
  for (size_t i = 0; i < p.rig.moved.size(); ++i) {
    if (p.rig.kind[i] == AnimationRig::Kind::Jaw) ++jaw_moved;
    else ++brow_moved;
    CHECK(p.rig.rest[i] == p.fit.control.positions[p.rig.moved[i]]);
    CHECK(p.rig.weight[i] > 0);
    CHECK(p.rig.weight[i] <= 1);
  }
  CHECK(jaw_moved >= static_cast<int>(jaw.size()));
  CHECK(brow_moved >= static_cast<int>(regions.at("brow").size()));
}

TEST_CASE("project fit: a scan that is no head fails with fit_head's code and a message") {
  HeadProject p;
  PointCloud few;
  for (int i = 0; i < 10; ++i) few.positions.push_back(Vec3(i, 0, 0));
  const Status st = fit_project(few, test::project_scene().generic, test::quick_options(), p);
  CHECK(st.code == ErrorCode::NotAHead);
  CHECK(!st.message.empty());
  CHECK(p.fit.multires.num_levels() == 0);
}

TEST_CASE("project refit: the kept scan is fitted again with the project's options, and no scan means no refit") {
  const test::ProjectScene& s = test::project_scene();
  const HeadProject p = test::fitted_project();
  // What the project keeps of its scan: positions and faces (its normals,
  // which the displacements read, are dropped by fit_project).
  PointCloud kept;
  kept.positions = s.person.scan.positions;
  kept.faces = s.person.scan.faces;
  FitHeadResult expect;
  REQUIRE(fit_head(kept, s.generic, test::quick_options(), expect).ok());
  HeadProject r;
  const Status st = refit_project(p, s.generic, {}, r);
  INFO(st.message);
  REQUIRE(st.ok());
  CHECK(r.options.levels == test::quick_options().levels);
  CHECK(same(r.fit.control.positions, expect.control.positions));
  REQUIRE(r.fit.level_meshes.size() == expect.level_meshes.size());
  for (size_t l = 0; l < expect.level_meshes.size(); ++l) CHECK(same(r.fit.level_meshes[l].positions, expect.level_meshes[l].positions));
  CHECK(r.scan.positions == p.scan.positions);
  CHECK(r.scan.faces == p.scan.faces);

  // levels > 0 replaces the project's.
  HeadProject one;
  REQUIRE(refit_project(p, s.generic, {1}, one).ok());
  CHECK(one.options.levels == 1);
  CHECK(one.fit.multires.num_levels() < r.fit.multires.num_levels());

  // A head without a scan (from photos) is refused; the target is untouched.
  HeadProject no_scan = p;
  no_scan.scan = PointCloud{};
  HeadProject target = one;
  const Status refused = refit_project(no_scan, s.generic, {}, target);
  CHECK(refused.code == ErrorCode::InvalidInput);
  CHECK(refused.message.find("no scan") != std::string::npos);
  CHECK(same(target.fit.control.positions, one.fit.control.positions));
  CHECK(target.options.levels == 1);
}

TEST_CASE("project refit: new axes fit a kept scan that lies with +z up as the same scan upright") {
  // The scene's scan turned +y -> +z (a bust exported with Blender's axes:
  // +z up, the face along -y), kept by a project fitted with +y up; told
  // its axes (the page's "Scan's axes"), the refit sees the upright scan
  // again: the same head in the head frame, not turned by the search.
  HeadProject p = test::fitted_project();
  const std::vector<Vec3> control = p.fit.control.positions;
  for (Vec3& q : p.scan.positions) q = Vec3(q.x(), -q.z(), q.y());
  RefitChanges axes;
  axes.up = Vec3::UnitZ();
  axes.facing = -Vec3::UnitY();
  HeadProject r;
  const Status st = refit_project(p, test::project_scene().generic, axes, r);
  INFO(st.message);
  REQUIRE(st.ok());
  CHECK(r.options.up == Vec3::UnitZ());
  CHECK(r.options.facing == -Vec3::UnitY());
  CHECK_FALSE(r.fit.turned);
  // The given axes, less the turn to the aligned face's frame (FitHeadOptions::face_frame).
  CHECK((r.fit.face_frame_turn.transpose() * r.fit.scan_to_head.A * Vec3::UnitZ()).normalized().isApprox(Vec3::UnitY(), 1e-12));
  REQUIRE(r.fit.control.positions.size() == control.size());
  double worst = 0;  // the scan's box diagonal sums its sides in another order: ulps apart at most
  for (size_t i = 0; i < control.size(); ++i) worst = std::max(worst, (r.fit.control.positions[i] - control[i]).norm());
  CHECK(worst < 1e-6);
}

TEST_CASE("project pose: 0 is the rest pose, 1 opens the jaw by its angle and lifts the brows") {
  HeadProject p = test::fitted_project();
  const MultiresMesh& mr = p.fit.multires;
  const int L = mr.num_levels();
  const std::vector<Vec3> rest_level = mr.state.displaced[L];
  // Pose 0 re-evaluates the levels: the fit's own state came another way,
  // and differs from it by rounding only (2.8e-17 m here).
  REQUIRE(pose_project(p, 0.0).ok());
  const std::vector<Vec3> rest_evaluated = mr.state.displaced[L];
  double worst = 0;
  for (size_t i = 0; i < rest_level.size(); ++i) worst = std::max(worst, (rest_evaluated[i] - rest_level[i]).norm());
  CHECK(worst < 1e-15);

  REQUIRE(pose_project(p, 1.0).ok());
  CHECK(p.pose == 1.0);
  const std::vector<Vec3>& posed = mr.control;  // P_0, the control vertices the rig moves
  const double lift = 0.02 * p.rig.head_size;
  for (size_t i = 0; i < p.rig.moved.size(); ++i) {
    const Vec3 now = posed[p.rig.moved[i]], was = p.rig.rest[i];
    if (p.rig.kind[i] == AnimationRig::Kind::Brow) {
      CHECK((now - was - Vec3(0, lift * p.rig.weight[i], 0)).norm() < 1e-12);
    } else {
      // Rotated about the x axis through the pivot by jaw_angle(1) (~8 deg):
      // same distance to the hinge line, x unchanged, the chin down.
      const Vec3 a = was - p.rig.jaw_pivot, b = now - p.rig.jaw_pivot;
      CHECK(now.x() == Approx(was.x()).margin(1e-12));
      const double ra = std::hypot(a.y(), a.z()), rb = std::hypot(b.y(), b.z());
      CHECK(rb == Approx(ra).margin(1e-12));
      if (ra > 1e-3) {
        const double turned = std::atan2(a.y() * b.z() - a.z() * b.y(), a.y() * b.y() + a.z() * b.z());
        CHECK(turned == Approx(jaw_angle(1.0)).margin(1e-9));
      }
    }
  }
  CHECK(jaw_angle(1.0) == Approx(0.14));
  // The scan-frame jaw matrix moves a jaw vertex's rest point (scan frame)
  // where the pose put it.
  const Mat4 m = jaw_motion(p, 1.0);
  for (size_t i = 0; i < p.rig.moved.size(); ++i) {
    if (p.rig.kind[i] != AnimationRig::Kind::Jaw) continue;
    const Vec3 from = p.frame.to_scan(p.rig.rest[i]), to = p.frame.to_scan(posed[p.rig.moved[i]]);
    const Vec3 moved = m.topLeftCorner<3, 3>() * from + m.topRightCorner<3, 1>();
    CHECK((moved - to).norm() < 1e-9);
  }
  // Out of range amounts are clamped, and back at rest every level is the
  // rest pose again, bit for bit.
  REQUIRE(pose_project(p, 7.0, 1).ok());
  CHECK(p.pose == 1.0);
  REQUIRE(rest_pose(p).ok());
  CHECK(p.pose == 0.0);
  CHECK(same(mr.state.displaced[L], rest_evaluated));
  CHECK(pose_project(p, 0.5, L + 1).code == ErrorCode::InvalidInput);
}

TEST_CASE("project quality: the checks are the fit's own, measured at rest") {
  const test::ProjectScene& s = test::project_scene();
  HeadProject p = test::fitted_project();
  FitQuality direct;
  REQUIRE(measure_fit_quality(s.direct, s.generic.annotations, direct).ok());
  CoveredDistances to_scan;
  std::vector<double> per_vertex;
  REQUIRE(measure_fit_to_scan(s.direct, s.person.scan, s.generic, to_scan, "face", &per_vertex).ok());

  REQUIRE(pose_project(p, 1.0).ok());  // measured on the rest pose whatever the pose was
  REQUIRE(measure_project_quality(p, s.generic).ok());
  CHECK(p.pose == 0.0);
  const ProjectQuality& q = p.quality;
  REQUIRE(q.status.ok());
  REQUIRE(q.to_scan_status.ok());
  CHECK(q.fit.level == direct.level);
  CHECK(q.fit.triangles == direct.triangles);
  CHECK(q.fit.flipped == direct.flipped);
  CHECK(q.fit.crossings.total == direct.crossings.total);
  CHECK(q.fit.smooth_crossings.total == direct.smooth_crossings.total);
  CHECK(q.fit.control_crossings == direct.control_crossings);
  CHECK(q.to_scan.vertices == to_scan.vertices);
  CHECK(q.to_scan.vertices > 100);
  CHECK(q.to_scan.mean == to_scan.mean);
  CHECK(q.to_scan.max == to_scan.max);
  CHECK(q.to_scan_colors == distance_colors(per_vertex));
}

TEST_CASE("project export: level bytes read back give the level's mesh") {
  HeadProject p = test::fitted_project();
  const int L = p.fit.multires.num_levels();
  REQUIRE(pose_project(p, 0.6, 1).ok());  // levels above 1 stale: the export brings them up to date
  TriMesh level;
  REQUIRE(project_level_mesh(p, L, ExportFrame::Scan, level).ok());
  for (size_t i = 0; i < level.positions.size(); i += 37)
    CHECK((level.positions[i] - p.frame.to_scan(p.fit.multires.state.displaced[L][i])).norm() == 0);

  Bytes ply;
  REQUIRE(export_level(p, L, LevelFormat::Ply, ExportFrame::Scan, ply).ok());
  TriMesh back;
  GeometryKind kind;
  REQUIRE(read_ply(ply.data(), ply.size(), back, kind).ok());
  REQUIRE(kind == GeometryKind::Mesh);
  CHECK(back.triangles == level.triangles);
  REQUIRE(back.positions.size() == level.positions.size());
  double worst_ply = 0;
  for (size_t i = 0; i < level.positions.size(); ++i)
    worst_ply = std::max(worst_ply, (back.positions[i] - level.positions[i]).norm());
  CHECK(worst_ply < 1e-6);  // float32 of a ~0.2 m head

  Bytes obj;
  REQUIRE(export_level(p, 0, LevelFormat::Obj, ExportFrame::Head, obj).ok());
  REQUIRE(read_obj(obj.data(), obj.size(), back, kind).ok());
  CHECK(back.triangles == p.fit.multires.triangles(0));
  REQUIRE(back.positions.size() == p.fit.multires.state.displaced[0].size());
  double worst_obj = 0;
  for (size_t i = 0; i < back.positions.size(); ++i)
    worst_obj = std::max(worst_obj, (back.positions[i] - p.fit.multires.state.displaced[0][i]).norm());
  CHECK(worst_obj < 1e-6);
}

TEST_CASE("project export: the distance map comes with the checks, at rest, on the finest level") {
  const test::ProjectScene& s = test::project_scene();
  HeadProject p = test::fitted_project();
  Bytes map;
  CHECK(export_level(p, 0, LevelFormat::DistanceMap, ExportFrame::Scan, map).code == ErrorCode::InvalidInput);
  REQUIRE(measure_project_quality(p, s.generic).ok());
  REQUIRE(pose_project(p, 1.0).ok());
  REQUIRE(export_level(p, 0, LevelFormat::DistanceMap, ExportFrame::Head, map).ok());
  CHECK(p.pose == 0.0);
  // What `likeness fit` wrote before the project: the finest level mesh
  // with the map's colours, normals and uvs dropped.
  TriMesh before = s.direct.level_meshes.back();
  before.colors = p.quality.to_scan_colors;
  before.normals.clear();
  before.uvs.clear();
  CHECK(map == write_ply(before));
}

TEST_CASE("project jobs: a project without a fit or texture gives errors, not crashes") {
  HeadProject empty;
  CHECK(pose_project(empty, 0.5).code == ErrorCode::InvalidInput);
  CHECK(measure_project_quality(empty, test::project_scene().generic).code == ErrorCode::InvalidInput);
  Bytes bytes;
  CHECK(export_level(empty, 0, LevelFormat::Obj, ExportFrame::Scan, bytes).code == ErrorCode::InvalidInput);
  TexturedFiles files;
  CHECK(export_textured(empty, 0, "head", ExportFrame::Scan, files).code == ErrorCode::InvalidInput);
  HeadProject p = test::fitted_project();
  CHECK(export_level(p, 9, LevelFormat::Obj, ExportFrame::Scan, bytes).code == ErrorCode::InvalidInput);
  CHECK(export_level(p, -1, LevelFormat::Ply, ExportFrame::Scan, bytes).code == ErrorCode::InvalidInput);
  const Status st = export_textured(p, 1, "head", ExportFrame::Scan, files);
  CHECK(st.code == ErrorCode::InvalidInput);
  CHECK(st.message.find("not textured") != std::string::npos);
}

TEST_CASE("project landmarks: each lies in its region, on its side") {
  const GenericHead& g = test::project_scene().generic;
  const std::vector<TextureLandmark> marks = texture_landmarks(g);
  REQUIRE(marks.size() == 14);
  auto at = [&](const std::string& id) {
    for (const TextureLandmark& m : marks)
      if (id == m.id) return g.mesh.positions[m.vertex];
    FAIL("no landmark " << id);
    return Vec3(Vec3::Zero());
  };
  auto in = [&](const std::string& id, const std::vector<int>& set) {
    for (const TextureLandmark& m : marks)
      if (id == m.id) return std::find(set.begin(), set.end(), m.vertex) != set.end();
    return false;
  };
  const auto& r = g.annotations.regions;
  CHECK(in("nose_tip", r.at("nose")));
  CHECK(in("chin", r.at("chin")));
  CHECK(in("ear_left_top", r.at("ear_left")));
  CHECK(in("eye_right_outer", g.annotations.eye_right.rim));
  // +x is the person's left.
  CHECK(at("eye_right_outer").x() < at("eye_right_inner").x());
  CHECK(at("eye_right_inner").x() < at("eye_left_inner").x());
  CHECK(at("eye_left_inner").x() < at("eye_left_outer").x());
  CHECK(at("mouth_right").x() < 0);
  CHECK(at("mouth_left").x() > 0);
  CHECK(at("ear_left_lobe").y() < at("ear_left_top").y());
  CHECK(at("nose_tip").z() > at("upper_lip").z());
}
