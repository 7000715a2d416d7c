// A head project made from photos (project/photos_project.h): the photos
// job's head as it is, with the levels `likeness photos` writes, a rig, and
// the project jobs (animate, export, checks) working on it; a session with
// too few usable photos fails with each photo's reason and no project.
#include "../photos/photos_scenario.h"
#include "head/head_creases.h"
#include "head/skin_detail.h"
#include "project/export.h"
#include "raycast/self_intersection.h"
#include "project/photos_project.h"
#include "project/pose.h"
#include "project/quality_job.h"
#include "subdiv/butterfly.h"

#include <catch2/catch.hpp>

#include <cmath>

using namespace lk;

namespace {

std::vector<LandmarkPhoto> session_photos(const test::PhotoScenario& s) { return s.session.photos; }

}  // namespace

TEST_CASE("photos project: the photos job's head, its CLI levels, a rig, and the project jobs on it") {
  SyntheticViewsOptions views;
  views.num_cameras = 5;
  const test::PhotoScenario s = test::make_photo_scenario(3, views);
  const std::vector<LandmarkPhoto> photos = session_photos(s);
  PhotosJobResult direct;
  REQUIRE(run_photos_job(s.generic, s.map, photos, PhotosJobOptions{}, direct));

  std::vector<std::vector<double>> detail;
  REQUIRE(generic_skin_detail(s.generic, 3, SkinDetailOptions{}, detail));
  HeadProject p;
  PhotosJobResult r;
  REQUIRE(photos_project(s.generic, s.map, photos, PhotosJobOptions{}, 3, p, r, &detail));
  // The same core job, bit for bit.
  CHECK(p.fit.control.positions == direct.fit.mesh.positions);
  CHECK(p.fit.control.triangles == s.generic.mesh.triangles);
  CHECK(r.calib.num_used() == 5);
  CHECK(r.calib.focal == direct.calib.focal);
  CHECK(p.fit.aligned.positions == s.generic.mesh.positions);
  // The fitted head is not the generic one (the person differs from it).
  double moved = 0;
  for (size_t i = 0; i < p.fit.control.positions.size(); ++i)
    moved = std::max(moved, (p.fit.control.positions[i] - s.generic.mesh.positions[i]).norm());
  CHECK(moved > 1e-3);
  // Without the skin detail: the levels build_butterfly_levels makes with
  // the generic head's creases (`likeness photos --no-skin-detail`).
  HeadProject plain;
  REQUIRE(project_from_photos(s.generic, direct, 3, plain));
  std::vector<ButterflyLevel> bl;
  REQUIRE(build_butterfly_levels(direct.fit.mesh, head_creases(s.generic.mesh, s.generic.annotations), 3, bl));
  std::vector<std::vector<Vec3>> cli_levels;
  REQUIRE(apply_all(bl, direct.fit.mesh.positions, cli_levels));
  REQUIRE(plain.fit.level_meshes.size() == 3);
  for (int l = 1; l <= 3; ++l) {
    CHECK(plain.fit.level_meshes[size_t(l - 1)].triangles == bl[size_t(l - 1)].fine_triangles);
    const std::vector<Vec3>& a = plain.fit.level_meshes[size_t(l - 1)].positions;
    const std::vector<Vec3>& b = cli_levels[size_t(l)];
    REQUIRE(a.size() == b.size());
    double worst = 0;
    for (size_t i = 0; i < a.size(); ++i) worst = std::max(worst, (a[i] - b[i]).norm());
    CHECK(worst < 1e-12);
  }
  // With the skin detail (`likeness photos`, the page) the levels carry it
  // as displacements: the same triangles, moved by at most its bound along
  // the normals.
  REQUIRE(p.fit.level_meshes.size() == 3);
  for (int l = 1; l <= 3; ++l) {
    CHECK(p.fit.multires.displacements[size_t(l)] == detail[size_t(l)]);
    CHECK(p.fit.level_meshes[size_t(l - 1)].triangles == plain.fit.level_meshes[size_t(l - 1)].triangles);
  }
  {
    const std::vector<Vec3>& a = p.fit.level_meshes[2].positions;
    const std::vector<Vec3>& b = plain.fit.level_meshes[2].positions;
    double worst = 0;
    for (size_t i = 0; i < a.size(); ++i) worst = std::max(worst, (a[i] - b[i]).norm());
    CHECK(worst > 1e-4);
    CHECK(worst < 3 * SkinDetailOptions{}.max_distance);
    // No crossing the plain level has not.
    std::vector<std::array<int, 2>> with_detail, without;
    REQUIRE(find_self_intersections(p.fit.level_meshes[2], with_detail));
    REQUIRE(find_self_intersections(plain.fit.level_meshes[2], without));
    CHECK(with_detail.size() <= without.size());
  }
  // Frame: what is shown is the head frame (no scan).
  CHECK(p.scan.positions.empty());
  CHECK(p.frame.to_scan(Vec3(0.1, 0.2, 0.3)) == Vec3(0.1, 0.2, 0.3));
  REQUIRE(!p.rig.moved.empty());

  // Animate: the jaw opens (level 3 moves), and back at rest it is the rest head.
  const std::vector<Vec3> rest = p.fit.multires.state.displaced[3];
  REQUIRE(pose_project(p, 1.0));
  double opened = 0;
  for (size_t i = 0; i < rest.size(); ++i) opened = std::max(opened, (p.fit.multires.state.displaced[3][i] - rest[i]).norm());
  CHECK(opened > 2e-3);
  REQUIRE(rest_pose(p));
  double back = 0;
  for (size_t i = 0; i < rest.size(); ++i) back = std::max(back, (p.fit.multires.state.displaced[3][i] - rest[i]).norm());
  CHECK(back < 1e-12);
  // Export: level 3 as OBJ, with its vertices.
  Bytes obj;
  REQUIRE(export_level(p, 3, LevelFormat::Obj, ExportFrame::Scan, obj));
  const std::string text(obj.begin(), obj.end());
  size_t vertices = 0;
  for (size_t k = text.find("\nv "); k != std::string::npos; k = text.find("\nv ", k + 1)) ++vertices;
  CHECK(vertices + (text.rfind("v ", 0) == 0 ? 1 : 0) == rest.size());
  // Checks: the head's own checks run; no vertex is measured against a scan (none).
  REQUIRE(measure_project_quality(p, s.generic));
  CHECK(p.quality.status.ok());
  CHECK(p.quality.fit.level == 3);
  CHECK((!p.quality.to_scan_status.ok() || p.quality.to_scan.vertices == 0));
}

// The canthi (the eye rims' crease corners) are the generic head's rim
// vertices furthest along x, whatever the fitted head's positions: where a
// fit draws the lid vertex next to an outer corner 1 mm beyond it, corners
// picked on the fitted head would give the exported levels other creases
// than the photos job's checks and steps used.
TEST_CASE("photos project: the levels take the generic head's creases, whatever the fitted positions") {
  const test::PhotoScenario s = test::make_photo_scenario(1, SyntheticViewsOptions{});
  PhotosJobResult r;
  r.fit.mesh = s.generic.mesh;
  r.fit.mesh.normals.clear();
  const std::vector<int>& rim = s.generic.annotations.eye_left.rim;
  REQUIRE(rim.size() > 3);
  size_t outer = 0;
  for (size_t i = 0; i < rim.size(); ++i)
    if (s.generic.mesh.positions[size_t(rim[i])].x() > s.generic.mesh.positions[size_t(rim[outer])].x()) outer = i;
  const int next = rim[(outer + 1) % rim.size()];
  r.fit.mesh.positions[size_t(next)].x() = s.generic.mesh.positions[size_t(rim[outer])].x() + 1e-3;
  const ButterflyCreases generic_creases = head_creases(s.generic.mesh, s.generic.annotations);
  const ButterflyCreases fitted_creases = head_creases(r.fit.mesh, s.generic.annotations);
  REQUIRE(fitted_creases.corners != generic_creases.corners);  // the fitted extremes are other vertices
  HeadProject p;
  REQUIRE(project_from_photos(s.generic, r, 2, p));
  CHECK(p.fit.multires.creases.corners == generic_creases.corners);
  CHECK(p.fit.multires.creases.edges == generic_creases.edges);
}

TEST_CASE("photos project: fewer than two usable photos: no project, each photo's reason") {
  SyntheticViewsOptions views;
  views.num_cameras = 3;
  const test::PhotoScenario s = test::make_photo_scenario(4, views);
  std::vector<LandmarkPhoto> photos = session_photos(s);
  // Two photos whose detector found no point at all (as for a photo with no face).
  for (size_t i = 1; i < 3; ++i) std::fill(photos[i].present.begin(), photos[i].present.end(), char(0));
  HeadProject p;
  PhotosJobResult r;
  const Status st = photos_project(s.generic, s.map, photos, PhotosJobOptions{}, 3, p, r);
  CHECK(!st.ok());
  CHECK(!st.message.empty());
  CHECK(p.fit.level_meshes.empty());
  CHECK(p.fit.multires.num_levels() == 0);
  REQUIRE(r.calib.photos.size() == 3);
  CHECK(r.calib.photos[0].refusal.empty());
  CHECK(!r.calib.photos[1].refusal.empty());
  CHECK(!r.calib.photos[2].refusal.empty());

  CHECK(!photos_project(s.generic, s.map, session_photos(s), PhotosJobOptions{}, 0, p, r).ok());
  CHECK(!photos_project(s.generic, s.map, {}, PhotosJobOptions{}, 3, p, r).ok());
}
