// The project's texture job on synthetic photos of the fitted head: the
// skin is the one the worker's flow of stages made before the job existed
// (calibrate each photo, then jointly; the control mesh's chart refined to
// the level; texture_head), and it holds the photographed colours.
#include "project/export.h"
#include "project/pose.h"
#include "project/texture_job.h"
#include "project_photos.h"
#include "project_scene.h"

#include "io/io.h"
#include "mesh/geometry.h"
#include "raycast/bvh.h"
#include "texture/binding.h"
#include "texture/refine_uv.h"
#include "texture/synthetic_photo.h"

#include <catch2/catch.hpp>

#include <cmath>

using namespace lk;
using test::photograph;
using test::Photos;

TEST_CASE("project texture: the job's skin is the composed stages' skin, and holds the photos' colours") {
  HeadProject p = test::fitted_project();
  const int L = p.fit.multires.num_levels();
  REQUIRE(pose_project(p, 0.0).ok());  // the worker's flow textured the re-evaluated rest pose
  TriMesh level;
  REQUIRE(project_level_mesh(p, L, ExportFrame::Scan, level).ok());
  const Photos shots = photograph(level);

  // The stages as the worker composed them before the job.
  std::vector<CalibResult> calib(3);
  std::vector<std::array<int, 2>> sizes;
  for (int i = 0; i < 3; ++i) {
    const Image& im = shots.photos[i].image;
    sizes.push_back({im.width, im.height});
    REQUIRE(calibrate_camera(shots.points[i], im.width, im.height, CalibOptions{}, calib[i]).ok());
  }
  REQUIRE(photos_look_like_one_camera(sizes));
  REQUIRE(calibrate_photos(shots.points, sizes, CalibOptions{}, calib, true).ok());
  std::vector<TexturePhoto> photos = shots.photos;
  for (int i = 0; i < 3; ++i) photos[i].camera = calib[i].camera;
  TriMesh control;
  control.positions = p.fit.control.positions;
  control.triangles = p.fit.control.triangles;
  std::vector<Vec2> control_uv, finest_uv;
  UvStats stats;
  REQUIRE(parameterize_stretch(control, UvOptions{}, control_uv, stats).ok());
  REQUIRE(refine_chart_uvs(p.fit.multires.levels, control_uv, finest_uv).ok());
  TriMesh mesh = level;
  mesh.uvs.assign(finest_uv.begin(), finest_uv.begin() + mesh.positions.size());
  TextureOptions topt;
  topt.size = 256;
  TexturedHead before;
  REQUIRE(texture_head(mesh, photos, topt, before).ok());

  // The job, on a posed project (it textures the rest pose), with its steps.
  REQUIRE(pose_project(p, 1.0).ok());
  TextureJobInput input = test::job_input(shots, 256);
  TextureJobResult out;
  std::vector<std::string> started, finished;
  StepObserver observer;
  observer.started = [&](const std::string& s) { started.push_back(s); };
  observer.finished = [&](const std::string& s) { finished.push_back(s); };
  const Status st = texture_project(p, input, out, observer);
  INFO(st.message);
  REQUIRE(st.ok());
  CHECK(out.calibration.shared);
  CHECK(out.level == L);
  CHECK(p.texture.uvs == finest_uv);
  CHECK(p.texture.skin.pixels == before.skin.pixels);
  CHECK(out.chart.l2_stretch == stats.l2_stretch);
  const std::vector<std::string> steps = {"calibrate", "chart", "parameterize", "bind", "fill holes",
                                          "resample", "spline", "dilate"};
  CHECK(started == steps);
  CHECK(finished == steps);
  for (const std::string& s : steps) CHECK(texture_job_step_index(s) > 0);

  // The colours: at each vertex the front photo sees head-on, the skin
  // (at its uv) is the photo's pixel where the vertex projects.
  const Image& skin = p.texture.skin;
  const Image& front = shots.photos[0].image;
  const Vec3 view = (calib[0].camera.center() - bounding_box(level.positions).center()).normalized();
  const std::vector<Vec3> normals = vertex_normals(level);
  double diff = 0;
  int count = 0;
  for (int v = 0; v < level.num_vertices(); ++v) {
    if (normals[v].dot(view) < 0.9) continue;
    Vec2 px;
    if (!calib[0].camera.project(level.positions[v], px)) continue;
    const Vec2& uv = p.texture.uvs[v];
    const int tx = std::min(skin.width - 1, static_cast<int>(uv.x() * skin.width));
    const int ty = std::min(skin.height - 1, static_cast<int>((1 - uv.y()) * skin.height));
    const int fx = static_cast<int>(px.x()), fy = static_cast<int>(px.y());
    for (int k = 0; k < 3; ++k) diff += std::abs(int(skin.at(tx, ty)[k]) - int(front.at(fx, fy)[k]));
    count += 3;
  }
  REQUIRE(count > 300);
  CHECK(diff / count < 10.0);  // of 255: the field varies within a texel and a pixel

  // The textured files carry the same skin and the level's uvs.
  TexturedFiles files;
  REQUIRE(export_textured(p, L, "head", ExportFrame::Scan, files).ok());
  CHECK(files.obj.find("mtllib head.mtl") != std::string::npos);
  CHECK(files.mtl.find("map_Kd head.png") != std::string::npos);
  Image png;
  REQUIRE(read_image(files.png.data(), files.png.size(), png).ok());
  CHECK(png.pixels == skin.pixels);
}

TEST_CASE("project texture: bad photos and points give errors that name the photo") {
  HeadProject empty;
  TextureJobInput input;
  TextureJobResult out;
  CHECK(texture_project(empty, input, out).code == ErrorCode::InvalidInput);

  HeadProject p = test::fitted_project();
  CHECK(texture_project(p, input, out).message.find("no photo") != std::string::npos);
  TriMesh level;
  REQUIRE(project_level_mesh(p, p.fit.multires.num_levels(), ExportFrame::Scan, level).ok());
  const Photos shots = photograph(level);
  input.photos = shots.photos;
  input.points = shots.points;
  input.names = shots.names;
  input.level = 7;
  CHECK(texture_project(p, input, out).code == ErrorCode::InvalidInput);
  input.level = -1;
  // Points that no camera can explain: the second photo's clicks all on one spot.
  for (Correspondence& c : input.points[1]) c.pixel = Vec2(10, 10);
  const Status st = texture_project(p, input, out);
  CHECK(!st.ok());
  CHECK(st.message.find("left.png") != std::string::npos);
  REQUIRE(out.calibration.status.size() == 3);
  CHECK(out.calibration.status[0].ok());
  CHECK(!out.calibration.status[1].ok());
  CHECK(p.texture.empty());
}

TEST_CASE("project texture: with the cameras given (a head from photos) nothing is calibrated and those cameras are used") {
  HeadProject p = test::fitted_project();
  const int L = p.fit.multires.num_levels();
  REQUIRE(pose_project(p, 0.0).ok());
  TriMesh level;
  REQUIRE(project_level_mesh(p, L, ExportFrame::Scan, level).ok());
  const Photos shots = photograph(level);

  // texture_head with the true cameras on the job's chart.
  TriMesh mesh = level;
  UvStats stats;
  std::vector<Vec2> finest_uv;
  REQUIRE(level_chart(p.fit.control, p.fit.multires.levels, UvOptions{}, finest_uv, stats).ok());
  mesh.uvs.assign(finest_uv.begin(), finest_uv.begin() + mesh.positions.size());
  TextureOptions topt;
  topt.size = 256;
  TexturedHead direct;
  REQUIRE(texture_head(mesh, shots.photos, topt, direct).ok());

  TextureJobInput input;
  input.photos = shots.photos;  // cameras set, no points
  input.names = shots.names;
  input.cameras_given = true;
  input.options = topt;
  TextureJobResult out;
  const Status st = texture_project(p, input, out);
  INFO(st.message);
  REQUIRE(st.ok());
  CHECK(out.calibration.status.empty());
  CHECK(p.texture.skin.pixels == direct.skin.pixels);

  // The given cameras are what is used: the front one moved 3 cm sideways
  // gives another skin.
  input.photos = shots.photos;
  input.photos[0].camera.t.x() += 0.03;
  REQUIRE(texture_project(p, input, out).ok());
  CHECK(p.texture.skin.pixels != direct.skin.pixels);
}
