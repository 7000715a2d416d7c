// The ground-truth texturing self-test (tarini2002 Sec. 3.2 checked end to
// end; harness-level because it renders with OSMesa):
//   1. a synthetic head (core/synth), its one-chart uv map on the control
//      mesh (core/uv, Sec. 3.1), Modified Butterfly refinement of the
//      positions (core/subdiv; the uvs are refined linearly, which cannot
//      flip a triangle), a procedural skin albedo per fine vertex
//      (synth/skin_field.h);
//   2. photos: the fine mesh drawn with per-vertex albedo by the shared
//      renderer from a ring of cameras, each under its OWN uniform light
//      colour (photo 0 neutral, the others off by a seeded gain): the
//      "uncontrolled illumination" that makes seams without the spline;
//   3. calibration: ~22 feature vertices, those a photo sees, projected with
//      the true camera plus 0.5 px noise, through calibrate_cameras_shared
//      (one focal, a pose per photo);
//   4. texture_head with the spline (and its unblended texture);
//   5. evaluation in a held-out view (25 degrees front-left): the fine mesh
//      drawn UNLIT (ambient 1, no directional light, no specular), once with
//      the true albedo per vertex ("truth") and once with the texture
//      ("ours", "nospline"). The texture bakes each photo's light; unlit
//      renders compare albedo with albedo, and the neutral light of photo 0
//      is the albedo's definition. Scored on the face region (pixels of
//      annotated face triangles): PSNR, SSIM; in texture space the seam
//      measure over the photo regions, with and without the spline.
//   Diagnostics (optional) split the error: the same pipeline with all
//   photos neutrally lit (no lighting mismatch) and with the true cameras
//   (no calibration error either: resampling alone).
//
// Shapes: photos photo_width x photo_height x 3; held-out renders
// eval_width x eval_height x 3; textures size x size x 3; face mask
// eval_width * eval_height.
#pragma once
#include "calib/camera.h"
#include "common/status.h"
#include "image/image.h"
#include "image/metrics.h"
#include "render/renderer.h"
#include "texture/texture.h"

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace lk::cli {

// GL view and projection that draw exactly what lk::Camera projects
// (x_c = R X + t, pinhole, image y down, origin at the top-left pixel
// corner; distortion is ignored) into a width x height framebuffer read top
// row first (render_offscreen). near/far: clip distances along the view axis.
CameraMatrices gl_camera_matrices(const Camera& camera, double near_plane, double far_plane);

struct SelftestOptions {
  std::uint32_t seed = 1;
  int photos = 5;                    // 1..7 views of the ring (synth/skin_field.h)
  int texture_size = 1024;
  int photo_width = 1200, photo_height = 800;
  int eval_width = 1200, eval_height = 800;
  int subdivision_levels = 3;        // Butterfly levels over the 2706-triangle head: 3 = 173k triangles
  int supersample = 2;               // antialiasing of every render
  double landmark_noise_px = 0.5;    // Gaussian noise of the clicked correspondences
  double light_spread = 0.12;        // photo i > 0: intensity 1 +- (0.6..1) spread, tint +- spread/3 per channel
  bool shared_focal = true;          // calibrate_cameras_shared (one lens) vs one calibrate_camera per photo
  bool diagnostics = false;          // also run neutral light (calibrated and true cameras)
  // Misregistration as the no-click photos path has it: every photo but
  // photo 0 turned by perturb_deg about a seeded axis through its calibrated
  // centre, and the surface given to texture_head displaced along its
  // normals by a smooth seeded field of amplitude surface_error_mm (the
  // truth is still scored on the true surface, same chart).
  double perturb_deg = 0;
  double surface_error_mm = 0;
  bool register_photos = false;      // texture_head's photometric re-registration (texture/register.h)
  bool label_regions = false;        // texture_head's one-photo-per-region labelling (texture/labeling.h)
};

// What calibration recovered for one photo, against the true camera.
struct PhotoCalibration {
  int landmarks = 0;               // feature vertices the photo sees
  int inliers = 0;
  double rms_px = 0;               // reprojection RMS over the inliers
  double focal_true = 0, focal = 0;
  double focal_error = 0;          // relative, (f - f_true) / f_true
  double rotation_error_deg = 0;   // angle of R R_true^T
  double centre_error_mm = 0;      // camera centre
  double vertex_error_px = 0;      // mean |project - project_true| over vertices facing the camera
};

struct SelftestScores {
  double psnr_db = 0, ssim = 0;    // face region of the held-out view, vs truth
  // Texture-space seam measure (image/metrics.h) over the photo-set/region
  // labels (case-1 texels), 8-bit units: `seam` on the error texture
  // (texture - true albedo texture), which only steps where the pipeline's
  // colour jumps; `seam_texture` on the texture itself (what one could
  // measure without ground truth; the skin's own edges along label
  // boundaries add to it).
  double seam = 0;
  double seam_texture = 0;
};

struct SelftestResult {
  int control_triangles = 0, vertices = 0, triangles = 0;
  long long face_pixels = 0;
  std::vector<Vec3> light_gains;               // #P linear RGB gains of each photo's light
  std::vector<PhotoCalibration> calibration;   // #P
  double shared_focal = 0;
  SelftestScores with_spline, without_spline;
  // Diagnostics (when requested; psnr_db = 0 otherwise).
  SelftestScores neutral_light, neutral_light_nospline;
  SelftestScores neutral_light_true_cameras, neutral_light_true_cameras_nospline;
  TextureReport texture_report;
  std::vector<double> vertex_error_used_px;    // #P mean |project - project_true| of the cameras texture_head got
  std::vector<std::pair<std::string, double>> timings_ms;  // stage -> wall ms, in order
  // Images for people.
  std::vector<Image> photos;
  Image truth, ours, nospline, skin, skin_nospline, truth_skin, face_mask;
  Image error;  // |ours - truth| x 8 on the face region
};

// Runs everything. log (optional) gets one line per stage. Fails with the
// failing stage's status (its message names the stage).
Status run_texture_selftest(const SelftestOptions& options, SelftestResult& result,
                            const std::function<void(const std::string&)>& log = {});

// The result as report.json text (numbers only; infinities as null).
std::string selftest_report_json(const SelftestOptions& options, const SelftestResult& result);

}  // namespace lk::cli
