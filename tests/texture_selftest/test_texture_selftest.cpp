// The ground-truth texturing self-test (native_harness/texture_selftest.h):
// the renderer draws exactly where lk::Camera projects (so synthetic photos
// and their true cameras agree), and the whole Sec. 3.2 pipeline at a small
// size recovers the skin albedo in a held-out view, with the spline removing
// most of the seam between photos lit differently.
#include "texture_selftest.h"

#include "render/offscreen.h"
#include "synth/skin_field.h"

#include <catch2/catch.hpp>
#include <cmath>

using namespace lk;
using namespace lk::cli;

namespace {

// A small square facing the camera (in a plane of constant camera depth, so
// its image is an exact square centred on the projection of its centre).
void add_square(const Camera& cam, const Vec3& centre_camera, double half, TriMesh& mesh) {
  const int base = mesh.num_vertices();
  const Vec3 corners[4] = {{-half, -half, 0}, {half, -half, 0}, {half, half, 0}, {-half, half, 0}};
  for (const Vec3& c : corners) mesh.positions.push_back(cam.R.transpose() * (centre_camera + c - cam.t));
  // Counter-clockwise as seen from the camera (image y points down).
  mesh.triangles.push_back({base, base + 2, base + 1});
  mesh.triangles.push_back({base, base + 3, base + 2});
}

}  // namespace

TEST_CASE("renderer draws each point where lk::Camera projects it", "[texture_selftest]") {
  // An off-centre principal point, fx != fy, a tilted pose: every term of
  // the projection matters. A y flip or a half-pixel shift would show.
  Camera cam = look_at(Vec3(0.31, 0.12, 0.62), Vec3(0.01, -0.02, 0.0), Vec3(0.1, 1, 0).normalized(), 900, 640, 400);
  cam.fy = 960;
  cam.cx = 301.3;
  cam.cy = 214.6;
  TriMesh mesh;
  std::vector<Vec3> centres;  // in camera coordinates
  for (double x : {-0.12, 0.0, 0.11})
    for (double y : {-0.08, 0.015, 0.07}) centres.push_back(Vec3(x, y, 0.6 + 0.3 * x));
  for (const Vec3& c : centres) add_square(cam, c, 0.0035, mesh);
  mesh.colors.assign(mesh.num_vertices(), Vec3::Ones());

  OffscreenOptions options;
  options.width = cam.width;
  options.height = cam.height;
  options.supersample = 4;
  options.renderer.background_top = options.renderer.background_bottom = glm::vec3(0.0f);
  LightRig& rig = options.renderer.lights;
  rig.key_color = rig.fill_color = rig.rim_color = glm::vec3(0.0f);
  rig.ambient_sky = rig.ambient_ground = glm::vec3(1.0f);
  const CameraMatrices matrices = gl_camera_matrices(cam, 0.1, 2.0);
  Image image;
  Status s = render_offscreen(
      [&](Renderer& r) {
        DrawableHandle h;
        Status st = r.upload_mesh(mesh, h);
        if (st) r.style(h)->specular = 0.0f;
        return st;
      },
      [&](float) { return matrices; }, options, image);
  if (s.code == ErrorCode::Unsupported) {
    WARN("skipped: no OSMesa context: " << s.message);
    return;
  }
  REQUIRE(s.ok());

  // The box filter averages two levels (square, background), so a pixel's
  // value above the background is proportional to its coverage.
  int peak = 0;
  for (size_t i = 0; i < image.pixels.size(); i += 3) peak = std::max(peak, int(image.pixels[i]));
  REQUIRE(peak > 200);
  for (const Vec3& c : centres) {
    Vec2 expected;
    REQUIRE(cam.project(cam.R.transpose() * (c - cam.t), expected));
    double sum = 0, sx = 0, sy = 0;
    for (int y = int(expected.y()) - 12; y <= int(expected.y()) + 12; ++y)
      for (int x = int(expected.x()) - 12; x <= int(expected.x()) + 12; ++x) {
        if (x < 0 || y < 0 || x >= image.width || y >= image.height) continue;
        const double w = image.at(x, y)[0] / double(peak);
        sum += w;
        sx += w * (x + 0.5);  // pixel centres: top-left corner origin
        sy += w * (y + 0.5);
      }
    INFO("square at camera (" << c.transpose() << "), expected pixel " << expected.transpose());
    REQUIRE(sum > 4);  // the square is there (about 6x6 pixels)
    const Vec2 found(sx / sum, sy / sum);
    INFO("found " << found.transpose());
    CHECK((found - expected).norm() < 0.1);
  }
}

TEST_CASE("self-test at 512^2 from 3 photos recovers the albedo and the spline removes the seam",
          "[texture_selftest]") {
  SelftestOptions opt;
  opt.seed = 3;
  opt.photos = 3;
  opt.texture_size = 512;
  opt.photo_width = opt.eval_width = 600;
  opt.photo_height = opt.eval_height = 400;
  opt.subdivision_levels = 2;
  SelftestResult r;
  Status s = run_texture_selftest(opt, r);
  if (s.code == ErrorCode::Unsupported && s.message.find("OSMesa") != std::string::npos) {
    WARN("skipped: " << s.message);
    return;
  }
  INFO(s.message);
  REQUIRE(s.ok());
  INFO("PSNR " << r.with_spline.psnr_db << " dB (no spline " << r.without_spline.psnr_db << "), SSIM "
               << r.with_spline.ssim << ", seam " << r.with_spline.seam << " vs " << r.without_spline.seam
               << " without spline");
  // 28 dB, not the full-size 30 dB: at 512^2 and 600x400 photos a texel and
  // a photo pixel are each ~0.9 mm on the face, twice the full-size
  // footprint, so freckles and brows are blurred by both resamplings.
  CHECK(r.with_spline.psnr_db >= 28.0);
  CHECK(r.with_spline.ssim >= 0.85);
  CHECK(r.face_pixels > 15000);
  // The photos' lights differ by up to 12 %: a visible seam without the
  // spline, and the spline spreads it so the step between neighbours halves.
  CHECK(r.without_spline.seam > 1.0);
  CHECK(r.with_spline.seam < r.without_spline.seam / 2);
  // Calibration from ~16 clicks per photo with 0.5 px noise: the focal
  // trades off against the distance (a few % on a head-sized target), what
  // texturing needs is that the head's vertices land within a pixel.
  REQUIRE(r.calibration.size() == 3);
  for (const PhotoCalibration& c : r.calibration) {
    CHECK(c.landmarks >= 8);
    CHECK(std::abs(c.focal_error) < 0.06);
    CHECK(c.rotation_error_deg < 1.0);
    CHECK(c.vertex_error_px < 1.0);
  }
  CHECK(r.ours.width == 600);
  CHECK(r.skin.width == 512);

  // The scores must notice a bad registration: clicks with 6 px noise (30 px
  // on a 3000-pixel photo) misplace the photos on the head. How much they
  // lose depends on the draw (27.1, 30.3 and 31.4 dB have been measured, the
  // last two with the generic head before and after its eye-ring change),
  // so the bar is 1.5 dB.
  SelftestOptions sloppy = opt;
  sloppy.landmark_noise_px = 6.0;
  SelftestResult bad;
  REQUIRE(run_texture_selftest(sloppy, bad).ok());
  INFO("with 6 px clicks: PSNR " << bad.with_spline.psnr_db << " dB, seam without spline " << bad.without_spline.seam);
  CHECK(bad.with_spline.psnr_db < r.with_spline.psnr_db - 1.5);
  CHECK(bad.without_spline.seam > r.without_spline.seam);
}
