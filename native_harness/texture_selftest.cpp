// The ground-truth texturing self-test (see texture_selftest.h).
#include "texture_selftest.h"

#include "calib/calibrate.h"
#include "head/generic_head.h"
#include "mesh/geometry.h"
#include "raycast/bvh.h"
#include "render/offscreen.h"
#include "subdiv/butterfly.h"
#include "common/prng.h"
#include "synth/skin_field.h"
#include "synth/synth_head.h"
#include "texture/chart_raster.h"
#include "texture/color.h"
#include "uv/stretch_param.h"

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>

namespace lk::cli {

CameraMatrices gl_camera_matrices(const Camera& c, double near_plane, double far_plane) {
  CameraMatrices m;
  // GL's eye space looks along -z with y up; lk::Camera's along +z with y
  // down: negate rows 1 and 2 of [R | t] (a rotation by 180 degrees about x,
  // so triangle winding and front faces are kept). glm is column-major: m[col][row].
  m.view = glm::mat4(1.0f);
  for (int r = 0; r < 3; ++r) {
    const double sign = r == 0 ? 1.0 : -1.0;
    for (int col = 0; col < 3; ++col) m.view[col][r] = static_cast<float>(sign * c.R(r, col));
    m.view[3][r] = static_cast<float>(sign * c.t[r]);
  }
  // Pixel u = fx x/z + cx maps to NDC 2u/W - 1 (NDC -1 is the left edge of
  // pixel 0); pixel v = fy y/z + cy (rows down) to NDC 1 - 2v/H (the
  // offscreen read-back flips rows, so NDC +1 is row 0). With eye-space
  // (xe, ye, ze) = (x, -y, -z) and w_clip = -ze these give the entries below.
  const double w = c.width, h = c.height, n = near_plane, f = far_plane;
  m.projection = glm::mat4(0.0f);
  m.projection[0][0] = static_cast<float>(2 * c.fx / w);
  m.projection[1][1] = static_cast<float>(2 * c.fy / h);
  m.projection[2][0] = static_cast<float>(1 - 2 * c.cx / w);
  m.projection[2][1] = static_cast<float>(2 * c.cy / h - 1);
  m.projection[2][2] = static_cast<float>(-(f + n) / (f - n));
  m.projection[2][3] = -1.0f;
  m.projection[3][2] = static_cast<float>(-2 * f * n / (f - n));
  return m;
}

namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// The scene's extent, for the clip planes.
struct Bounds {
  Vec3 centre = Vec3::Zero();
  double radius = 0;
};

Bounds bounds_of(const std::vector<Vec3>& points) {
  BBox box;
  for (const Vec3& p : points) box.extend(p);
  Bounds b;
  b.centre = box.center();
  for (const Vec3& p : points) b.radius = std::max(b.radius, (p - b.centre).norm());
  return b;
}

// Draws `mesh` (albedo from its colours, or from `texture` via its uvs)
// seen by `camera` under a uniform light of colour `light` (linear gains):
// hemisphere ambient with sky = ground, no key/fill/rim light, no specular,
// no occlusion, so a pixel shows albedo * light (sRGB-encoded; albedo *
// light stays under the tone-mapping shoulder at 0.8).
Status render_uniform(const TriMesh& mesh, const Image* texture, const Camera& camera, const Bounds& bounds,
                      const Vec3& light, int supersample, Image& out) {
  OffscreenOptions options;
  options.width = camera.width;
  options.height = camera.height;
  options.supersample = supersample;
  options.channels = 3;
  const glm::vec3 background(0.08f, 0.08f, 0.09f);
  options.renderer.background_top = options.renderer.background_bottom = background;
  LightRig& rig = options.renderer.lights;
  rig.key_color = rig.fill_color = rig.rim_color = glm::vec3(0.0f);
  rig.ambient_sky = rig.ambient_ground =
      glm::vec3(static_cast<float>(light.x()), static_cast<float>(light.y()), static_cast<float>(light.z()));
  rig.exposure = 1.0f;
  auto setup = [&](Renderer& r) -> Status {
    DrawableHandle h = kNoHandle;
    Status s = r.upload_mesh(mesh, h);
    if (!s) return s;
    DrawStyle& style = *r.style(h);
    style.specular = 0.0f;
    if (texture) {
      TextureHandle t = kNoHandle;
      s = r.upload_texture(*texture, t);
      if (s) s = r.attach_texture(h, t);
    }
    return s;
  };
  const double distance = (camera.center() - bounds.centre).norm();
  const double near_plane = std::max(distance - 1.5 * bounds.radius, 0.02 * distance);
  const double far_plane = distance + 1.5 * bounds.radius;
  const CameraMatrices matrices = gl_camera_matrices(camera, near_plane, far_plane);
  return render_offscreen(setup, [&](float) { return matrices; }, options, out);
}

// Is vertex p (unit normal n) seen by the camera: in front, facing it, inside
// the image with a margin, nothing of the mesh in between.
bool sees(const Camera& camera, const MeshBvh& bvh, double offset, const Vec3& p, const Vec3& n,
          double min_facing, double margin_px) {
  const Vec3 to_camera = camera.center() - p;
  const double distance = to_camera.norm();
  const Vec3 dir = to_camera / distance;
  if (n.dot(dir) < min_facing) return false;
  Vec2 px;
  if (!camera.project(p, px)) return false;
  if (px.x() < margin_px || px.y() < margin_px || px.x() > camera.width - margin_px ||
      px.y() > camera.height - margin_px)
    return false;
  Ray ray;
  ray.origin = p + offset * dir;
  ray.direction = dir;
  ray.t_max = distance;
  return !intersect_any(bvh, ray);
}

double rotation_angle_deg(const Mat3& a, const Mat3& b) {
  const Mat3 d = a * b.transpose();
  const double c = std::clamp((d.trace() - 1) / 2, -1.0, 1.0);
  return std::acos(c) * 180.0 / 3.14159265358979323846;
}

// Texture-space labels for the seam measure: texels whose triangles have
// the same set of common valid photos AND the same region (dominant photo)
// share a label. Without the spline the texture steps where the set changes
// (a photo's weight drops out of the <N,V> blend); the spline's masks switch
// where the region changes. Case 2/3 triangles (no common photo: coloured by
// interpolating vertex colours, a matter of hole filling, not of lighting)
// and background texels get -1 and are not scored. Recomputes texture_head's binding
// (same options, normals and BVH: the same answer).
Status seam_labels(const TriMesh& mesh, const std::vector<Vec3>& normals, const MeshBvh& bvh,
                   const std::vector<Camera>& cameras, const TextureOptions& options, std::vector<int>& labels,
                   ChartRaster& raster) {
  VertexBinding binding;
  Status s = bind_vertices(mesh, normals, bvh, cameras, options.binding, binding);
  if (!s) return s;
  std::vector<TriangleCase> cases;
  std::vector<int> region;
  classify_triangles(mesh, binding, cases, region);
  s = rasterize_chart(mesh.uvs, mesh.triangles, options.size, options.size, raster, options.conservative_texels);
  if (!s) return s;
  labels.assign(raster.triangle.size(), -1);
  for (size_t j = 0; j < labels.size(); ++j) {
    const int f = raster.triangle[j];
    if (f < 0) continue;
    const Tri& t = mesh.triangles[f];
    const std::uint64_t common = binding.valid[t[0]] & binding.valid[t[1]] & binding.valid[t[2]];
    if (common == 0 || region[f] < 0) continue;
    labels[j] = static_cast<int>((common & 0xFFFFFu) << 8) | region[f];
  }
  return Status::success();
}

// The true albedo in texture space: each chart texel gets the barycentric
// interpolation of its triangle's vertex albedos (linear, then sRGB-encoded),
// i.e. exactly what the truth render shows at that surface point.
Image truth_texture(const TriMesh& mesh, const std::vector<Vec3>& albedo, const ChartRaster& raster) {
  Image out = Image::make(raster.width, raster.height, 3, 0);
  for (int y = 0; y < raster.height; ++y)
    for (int x = 0; x < raster.width; ++x) {
      const int f = raster.triangle[static_cast<size_t>(y) * raster.width + x];
      if (f < 0) continue;
      const Tri& t = mesh.triangles[f];
      Vec3 w;
      if (!uv_barycentric(texel_uv(x, y, raster.width, raster.height), mesh.uvs[t[0]], mesh.uvs[t[1]],
                          mesh.uvs[t[2]], w))
        continue;
      w = w.cwiseMax(0.0);
      w /= w.sum();
      const Vec3 c = w[0] * albedo[t[0]] + w[1] * albedo[t[1]] + w[2] * albedo[t[2]];
      for (int k = 0; k < 3; ++k) out.at(x, y)[k] = linear_to_srgb8(static_cast<float>(c[k]));
    }
  return out;
}

// (texture - truth) + 128 per channel on the chart: the seam measure on it
// sees only what the pipeline got wrong, not the skin's own edges.
Image error_texture(const Image& texture, const Image& truth) {
  Image out = Image::make(truth.width, truth.height, 3, 128);
  for (size_t i = 0; i < out.pixels.size(); ++i)
    out.pixels[i] = static_cast<std::uint8_t>(std::clamp(128 + int(texture.pixels[i]) - int(truth.pixels[i]), 0, 255));
  return out;
}

// Everything the scoring of one texture needs.
struct Scene {
  TriMesh fine;              // positions, triangles, uvs (no colours)
  TriMesh fine_truth;        // the same with the albedo as vertex colours
  TriMesh fine_face;         // the same with the face region as white vertex colours
  Bounds bounds;
  Camera eval_camera;
  Image truth;
  PixelMask face_mask;
  int supersample = 2;
  Image truth_texture;  // the albedo in texture space (size x size)
};

Status score_texture(const Scene& scene, const Image& skin, SelftestScores& scores, const std::vector<int>& region,
                     Image* render) {
  Image ours;
  Status s = render_uniform(scene.fine, &skin, scene.eval_camera, scene.bounds, Vec3::Ones(), scene.supersample, ours);
  if (!s) return with_context(s, "held-out render");
  PsnrResult psnr;
  s = compute_psnr(scene.truth, ours, scene.face_mask, psnr);
  if (!s) return s;
  SsimResult ssim;
  s = compute_ssim(scene.truth, ours, scene.face_mask, SsimOptions{}, ssim);
  if (!s) return s;
  // One photo (or photos that never meet) leaves no boundary: no seam to
  // measure, reported as NaN (null in report.json).
  SeamResult seam, raw;
  s = texture_seam(error_texture(skin, scene.truth_texture), region, {}, SeamOptions{}, seam);
  if (s) s = texture_seam(skin, region, {}, SeamOptions{}, raw);
  if (s.code == ErrorCode::Empty) seam.seam = raw.seam = std::numeric_limits<double>::quiet_NaN();
  else if (!s) return with_context(s, "seam measure");
  scores.psnr_db = psnr.psnr_db;
  scores.ssim = ssim.ssim;
  scores.seam = seam.seam;
  scores.seam_texture = raw.seam;
  if (render) *render = std::move(ours);
  return Status::success();
}

// |ours - truth| x 8 (per channel, clamped) inside the face mask; the rest
// of the head dimmed, for looking at where the error sits.
Image error_image(const Image& ours, const Image& truth, const PixelMask& mask) {
  Image out = Image::make(truth.width, truth.height, 3, 0);
  for (size_t p = 0; p < mask.size(); ++p)
    for (int k = 0; k < 3; ++k) {
      const int d = std::abs(int(ours.pixels[p * 3 + k]) - int(truth.pixels[p * 3 + k]));
      out.pixels[p * 3 + k] = static_cast<std::uint8_t>(mask[p] ? std::min(255, 8 * d) : truth.pixels[p * 3 + k] / 4);
    }
  return out;
}

}  // namespace

Status run_texture_selftest(const SelftestOptions& opt, SelftestResult& result,
                            const std::function<void(const std::string&)>& log) {
  auto say = [&](const std::string& line) {
    if (log) log(line);
  };
  if (opt.photos < 1 || opt.photos > 7) return Status::error(ErrorCode::InvalidInput, "--photos must be 1..7");
  if (opt.texture_size < 64 || opt.texture_size > 8192)
    return Status::error(ErrorCode::InvalidInput, "--size must be 64..8192 texels");
  if (opt.subdivision_levels < 0 || opt.subdivision_levels > 4)
    return Status::error(ErrorCode::InvalidInput, "subdivision levels must be 0..4");
  if (opt.photo_width < 64 || opt.photo_height < 64 || opt.eval_width < 64 || opt.eval_height < 64 ||
      opt.photo_width * opt.supersample > 8192 || opt.photo_height * opt.supersample > 8192 ||
      opt.eval_width * opt.supersample > 8192 || opt.eval_height * opt.supersample > 8192)
    return Status::error(ErrorCode::InvalidInput, "image sizes must be 64.. and at most 8192 after supersampling");
  if (opt.supersample < 1 || opt.supersample > 4)
    return Status::error(ErrorCode::InvalidInput, "supersample must be 1..4");
  if (!(opt.light_spread >= 0 && opt.light_spread < 0.5) || !(opt.landmark_noise_px >= 0))
    return Status::error(ErrorCode::InvalidInput, "light spread must be in [0, 0.5) and landmark noise >= 0");
  result = SelftestResult();
  auto& timings = result.timings_ms;
  Status s;

  // 1. Head, chart, refinement, albedo.
  auto t0 = Clock::now();
  GenericHead generic, head;
  s = load_generic_head(generic);
  if (s) s = synthesize_head(generic, opt.seed, SynthHeadOptions{}, head);
  if (!s) return with_context(s, "synthetic head");
  timings.emplace_back("head", ms_since(t0));

  t0 = Clock::now();
  UvOptions uv_options;
  uv_options.view = head.annotations.look;
  std::vector<Vec2> uv;
  UvStats uv_stats;
  s = parameterize_stretch(head.mesh, uv_options, uv, uv_stats);
  if (!s) return with_context(s, "uv chart");
  timings.emplace_back("uv chart (control mesh)", ms_since(t0));

  t0 = Clock::now();
  std::vector<ButterflyLevel> levels;
  s = build_butterfly_levels(head.mesh, opt.subdivision_levels, levels);
  if (!s) return with_context(s, "subdivision");
  std::vector<Vec3> positions = head.mesh.positions;
  // Scored face: the annotated face without the eye socket pockets and the
  // mouth bag (the eyeball and teeth models cover them in use; no photo
  // sees into them, so they are hole-filled and say nothing about lighting
  // or resampling).
  std::vector<double> face(head.mesh.num_vertices(), 0.0);
  const auto& regions = head.annotations.regions;
  for (const char* name : {"face", "lips", "upper_lip", "lower_lip"})
    if (!regions.count(name)) return Status::error(ErrorCode::Internal, std::string("the head has no ") + name + " region");
  for (int v : regions.at("face")) face[v] = 1.0;
  for (int v : regions.at("lips")) face[v] = 0.0;
  for (const char* lip : {"upper_lip", "lower_lip"})
    for (int v : regions.at(lip)) face[v] = 1.0;
  for (const EyeSocket* eye : {&head.annotations.eye_left, &head.annotations.eye_right})
    for (int v = 0; v < head.mesh.num_vertices(); ++v)
      if ((head.mesh.positions[v] - eye->center).norm() < 1.3 * eye->radius) face[v] = 0.0;
  std::vector<Tri> triangles = head.mesh.triangles;
  for (const ButterflyLevel& level : levels) {
    std::vector<Vec3> fine_positions;
    s = apply(level, positions, fine_positions);
    if (!s) return s;
    positions.swap(fine_positions);
    // Linear refinement for uvs (midpoints: never flips a chart triangle)
    // and for the face label (a new vertex is face when both ends are).
    std::vector<Vec2> fine_uv(uv);
    std::vector<double> fine_face(face);
    fine_uv.resize(level.num_fine_vertices);
    fine_face.resize(level.num_fine_vertices);
    for (int k = 0; k < level.num_new_vertices(); ++k) {
      const auto& e = level.edge_endpoints[k];
      fine_uv[level.num_coarse_vertices + k] = 0.5 * (uv[e[0]] + uv[e[1]]);
      fine_face[level.num_coarse_vertices + k] = std::min(face[e[0]], face[e[1]]);
    }
    uv.swap(fine_uv);
    face.swap(fine_face);
    triangles = level.fine_triangles;
  }
  Scene scene;
  scene.supersample = opt.supersample;
  scene.fine.positions = positions;
  scene.fine.triangles = triangles;
  scene.fine.uvs = uv;
  scene.bounds = bounds_of(positions);
  result.control_triangles = head.mesh.num_triangles();
  result.vertices = scene.fine.num_vertices();
  result.triangles = scene.fine.num_triangles();
  timings.emplace_back("subdivide", ms_since(t0));
  say("head: " + std::to_string(result.control_triangles) + " control triangles -> " +
      std::to_string(result.triangles) + " (" + std::to_string(opt.subdivision_levels) + " Butterfly levels)");

  t0 = Clock::now();
  SkinField field;
  s = make_skin_field(head, opt.seed, SkinFieldOptions{}, field);
  if (!s) return s;
  scene.fine_truth = scene.fine;
  scene.fine_truth.uvs.clear();
  scene.fine_truth.colors = skin_albedo(field, positions);
  scene.fine_face = scene.fine_truth;
  for (size_t v = 0; v < face.size(); ++v) scene.fine_face.colors[v] = Vec3::Constant(face[v] >= 1.0 ? 1.0 : 0.0);
  timings.emplace_back("skin albedo", ms_since(t0));

  // 2. Cameras, lights, photos.
  t0 = Clock::now();
  const Vec3 look = head.annotations.look, up = head.annotations.up;
  CameraRingOptions ring;
  ring.width = opt.photo_width;
  ring.height = opt.photo_height;
  std::vector<Camera> true_cameras;
  s = camera_ring(positions, look, up, default_ring_views(opt.photos), opt.seed, ring, true_cameras);
  if (!s) return s;
  CameraRingOptions eval_ring = ring;
  eval_ring.width = opt.eval_width;
  eval_ring.height = opt.eval_height;
  eval_ring.jitter_deg = 0;
  eval_ring.aim_jitter_m = 0;
  std::vector<Camera> eval;
  s = camera_ring(positions, look, up, {held_out_view()}, opt.seed, eval_ring, eval);
  if (!s) return s;
  scene.eval_camera = eval[0];

  SplitMix64 light_rng(hash_mix(opt.seed, 0x11647ull));
  result.light_gains.assign(opt.photos, Vec3::Ones());
  for (int i = 1; i < opt.photos; ++i) {
    // Brighter or darker by 60-100 % of the spread: every photo differs.
    const double sign = light_rng.uniform01() < 0.5 ? -1.0 : 1.0;
    const double intensity = 1 + sign * opt.light_spread * light_rng.uniform(0.6, 1.0);
    for (int c = 0; c < 3; ++c)
      result.light_gains[i][c] = intensity * (1 + opt.light_spread / 3 * light_rng.uniform(-1, 1));
  }
  result.photos.resize(opt.photos);
  for (int i = 0; i < opt.photos; ++i) {
    s = render_uniform(scene.fine_truth, nullptr, true_cameras[i], scene.bounds, result.light_gains[i],
                       opt.supersample, result.photos[i]);
    if (!s) return with_context(s, "photo " + std::to_string(i));
  }
  timings.emplace_back("render photos", ms_since(t0));
  say("photos: " + std::to_string(opt.photos) + " at " + std::to_string(opt.photo_width) + "x" +
      std::to_string(opt.photo_height));

  // 3. Correspondences and calibration.
  t0 = Clock::now();
  const std::vector<Vec3> normals = vertex_normals(scene.fine);
  MeshBvh bvh;
  s = build_bvh(scene.fine, bvh);
  if (!s) return s;
  const double offset = 1e-3 * 2 * scene.bounds.radius;
  const std::vector<int> features = feature_vertices(head);  // control vertex i is fine vertex i
  SplitMix64 noise(hash_mix(opt.seed, 0xC11C4ull));
  std::vector<std::vector<Correspondence>> correspondences(opt.photos);
  std::vector<std::array<int, 2>> sizes(opt.photos, {opt.photo_width, opt.photo_height});
  result.calibration.assign(opt.photos, PhotoCalibration());
  for (int i = 0; i < opt.photos; ++i) {
    for (int v : features) {
      if (!sees(true_cameras[i], bvh, offset, positions[v], normals[v], 0.2, 10.0)) continue;
      Correspondence c;
      c.point = positions[v];
      true_cameras[i].project(c.point, c.pixel);
      c.pixel += opt.landmark_noise_px * Vec2(noise.gaussian(), noise.gaussian());
      correspondences[i].push_back(c);
    }
    result.calibration[i].landmarks = static_cast<int>(correspondences[i].size());
  }
  CalibOptions calib_options;
  std::vector<CalibResult> calibrated;
  if (opt.shared_focal) {
    SharedCalibResult shared;
    s = calibrate_cameras_shared(correspondences, sizes, calib_options, shared);
    calibrated = shared.photos;
    result.shared_focal = shared.focal;
  } else {
    s = calibrate_photos(correspondences, sizes, calib_options, calibrated);
  }
  if (!s) return with_context(s, "calibration");
  std::vector<Camera> cameras(opt.photos);
  for (int i = 0; i < opt.photos; ++i) {
    const Camera& t = true_cameras[i];
    const Camera& c = calibrated[i].camera;
    cameras[i] = c;
    PhotoCalibration& pc = result.calibration[i];
    pc.inliers = calibrated[i].num_inliers;
    pc.rms_px = calibrated[i].rms;
    pc.focal_true = t.fx;
    pc.focal = c.fx;
    pc.focal_error = (c.fx - t.fx) / t.fx;
    pc.rotation_error_deg = rotation_angle_deg(c.R, t.R);
    pc.centre_error_mm = 1000 * (c.center() - t.center()).norm();
    double sum = 0;
    long count = 0;
    for (int v = 0; v < scene.fine.num_vertices(); v += 7) {  // a sample is plenty
      if (normals[v].dot((t.center() - positions[v]).normalized()) < 0.1) continue;
      Vec2 a, b;
      if (!t.project(positions[v], a) || !c.project(positions[v], b)) continue;
      sum += (a - b).norm();
      ++count;
    }
    pc.vertex_error_px = count ? sum / count : 0.0;
  }
  timings.emplace_back("calibrate", ms_since(t0));

  // Misregistration on purpose (see SelftestOptions): turned cameras and a
  // surface mm off the true one.
  std::vector<Camera> texturing_cameras = cameras;
  SplitMix64 perturb_rng(hash_mix(opt.seed, 0x9E7B0ull));
  for (int i = 1; i < opt.photos && opt.perturb_deg > 0; ++i) {
    Vec3 axis(perturb_rng.gaussian(), perturb_rng.gaussian(), perturb_rng.gaussian());
    axis.normalize();
    const Mat3 turn = Eigen::AngleAxisd(opt.perturb_deg * M_PI / 180.0, axis).toRotationMatrix();
    Camera& c = texturing_cameras[i];
    const Vec3 centre = c.center();
    c.R = turn * c.R;
    c.t = -c.R * centre;
  }
  TriMesh texturing_mesh = scene.fine;
  if (opt.surface_error_mm > 0) {
    // Three plane waves of 5-8 cm wavelength in seeded directions: smooth
    // like a fitted head's error, amplitude-normalized to surface_error_mm.
    Vec3 dir[3];
    double phase[3], wavelength[3];
    for (int k = 0; k < 3; ++k) {
      dir[k] = Vec3(perturb_rng.gaussian(), perturb_rng.gaussian(), perturb_rng.gaussian()).normalized();
      phase[k] = perturb_rng.uniform(0, 2 * M_PI);
      wavelength[k] = perturb_rng.uniform(0.05, 0.08);
    }
    for (int v = 0; v < texturing_mesh.num_vertices(); ++v) {
      double d = 0;
      for (int k = 0; k < 3; ++k) d += std::sin(2 * M_PI * dir[k].dot(positions[v]) / wavelength[k] + phase[k]) / 3;
      texturing_mesh.positions[v] += 1e-3 * opt.surface_error_mm * d * normals[v];
    }
  }
  result.vertex_error_used_px.assign(opt.photos, 0.0);
  for (int i = 0; i < opt.photos; ++i) {
    double sum = 0;
    long count = 0;
    const Camera& t = true_cameras[i];
    for (int v = 0; v < scene.fine.num_vertices(); v += 7) {
      if (normals[v].dot((t.center() - positions[v]).normalized()) < 0.1) continue;
      Vec2 a, b;
      if (!t.project(positions[v], a) || !texturing_cameras[i].project(texturing_mesh.positions[v], b)) continue;
      sum += (a - b).norm();
      ++count;
    }
    result.vertex_error_used_px[i] = count ? sum / count : 0.0;
  }

  // 4. Texturing, timed per step through the progress callback.
  std::vector<TexturePhoto> photos(opt.photos);
  for (int i = 0; i < opt.photos; ++i) {
    photos[i].image = result.photos[i];
    photos[i].camera = texturing_cameras[i];
  }
  TextureOptions texture_options;
  texture_options.size = opt.texture_size;
  texture_options.keep_unblended = true;
  texture_options.register_photos = opt.register_photos;
  texture_options.label_regions = opt.label_regions;
  std::map<std::string, Clock::time_point> step_start;
  std::vector<std::pair<std::string, double>> steps;
  ProgressFn progress = [&](const char* step, double fraction) {
    if (fraction <= 0) step_start[step] = Clock::now();
    else if (fraction >= 1 && step_start.count(step)) steps.emplace_back(std::string("texture: ") + step, ms_since(step_start[step]));
    return true;
  };
  t0 = Clock::now();
  TexturedHead textured;
  s = texture_head(texturing_mesh, photos, texture_options, textured, progress);
  if (!s) return with_context(s, "texture_head");
  timings.emplace_back("texture (total)", ms_since(t0));
  timings.insert(timings.end(), steps.begin(), steps.end());
  result.texture_report = textured.report;
  result.skin = textured.skin;
  result.skin_nospline = textured.unblended;

  // 5. Held-out view: truth, face mask, ours, nospline; scores.
  t0 = Clock::now();
  s = render_uniform(scene.fine_truth, nullptr, scene.eval_camera, scene.bounds, Vec3::Ones(), opt.supersample,
                     result.truth);
  if (!s) return with_context(s, "truth render");
  s = render_uniform(scene.fine_face, nullptr, scene.eval_camera, scene.bounds, Vec3::Ones(), 1, result.face_mask);
  if (!s) return with_context(s, "face mask render");
  scene.truth = result.truth;
  scene.face_mask.assign(static_cast<size_t>(opt.eval_width) * opt.eval_height, 0);
  for (size_t p = 0; p < scene.face_mask.size(); ++p)
    if (result.face_mask.pixels[p * 3] > 127) {
      scene.face_mask[p] = 1;
      ++result.face_pixels;
    }
  if (result.face_pixels == 0) return Status::error(ErrorCode::Internal, "the face is not in the held-out view");
  std::vector<int> labels;
  ChartRaster raster;
  std::vector<Camera> used_cameras = texturing_cameras;
  if (textured.report.registered)
    for (int i = 0; i < opt.photos; ++i) used_cameras[i] = textured.report.registration.photos[i].camera;
  s = seam_labels(scene.fine, normals, bvh, used_cameras, texture_options, labels, raster);
  if (!s) return with_context(s, "seam labels");
  scene.truth_texture = truth_texture(scene.fine, scene.fine_truth.colors, raster);
  result.truth_skin = scene.truth_texture;
  s = score_texture(scene, result.skin, result.with_spline, labels, &result.ours);
  if (s) s = score_texture(scene, result.skin_nospline, result.without_spline, labels, &result.nospline);
  if (!s) return s;
  result.error = error_image(result.ours, result.truth, scene.face_mask);
  timings.emplace_back("held-out renders + metrics", ms_since(t0));
  say("scored: PSNR " + std::to_string(result.with_spline.psnr_db) + " dB on " +
      std::to_string(result.face_pixels) + " face pixels");

  // Diagnostics: neutral light everywhere (calibrated, then true cameras).
  if (opt.diagnostics) {
    t0 = Clock::now();
    for (int i = 0; i < opt.photos; ++i) {
      s = render_uniform(scene.fine_truth, nullptr, true_cameras[i], scene.bounds, Vec3::Ones(), opt.supersample,
                         photos[i].image);
      if (!s) return with_context(s, "neutral photo " + std::to_string(i));
    }
    for (int run = 0; run < 2; ++run) {
      for (int i = 0; i < opt.photos; ++i) photos[i].camera = run == 0 ? cameras[i] : true_cameras[i];
      TexturedHead diag;
      s = texture_head(scene.fine, photos, texture_options, diag);
      if (!s) return with_context(s, "diagnostic texture_head");
      std::vector<Camera> used(opt.photos);
      for (int i = 0; i < opt.photos; ++i) used[i] = photos[i].camera;
      s = seam_labels(scene.fine, normals, bvh, used, texture_options, labels, raster);
      SelftestScores* with = run == 0 ? &result.neutral_light : &result.neutral_light_true_cameras;
      SelftestScores* without = run == 0 ? &result.neutral_light_nospline : &result.neutral_light_true_cameras_nospline;
      if (s) s = score_texture(scene, diag.skin, *with, labels, nullptr);
      if (s) s = score_texture(scene, diag.unblended, *without, labels, nullptr);
      if (!s) return s;
    }
    timings.emplace_back("diagnostics", ms_since(t0));
  }
  return Status::success();
}

std::string selftest_report_json(const SelftestOptions& opt, const SelftestResult& r) {
  using nlohmann::json;
  auto num = [](double v) -> json { return std::isfinite(v) ? json(v) : json(nullptr); };
  auto scores = [&](const SelftestScores& s) {
    return json{{"psnr_db", num(s.psnr_db)}, {"ssim", num(s.ssim)}, {"seam", num(s.seam)},
                {"seam_texture", num(s.seam_texture)}};
  };
  json j;
  j["seed"] = opt.seed;
  j["options"] = {{"photos", opt.photos},
                  {"texture_size", opt.texture_size},
                  {"photo_size", {opt.photo_width, opt.photo_height}},
                  {"eval_size", {opt.eval_width, opt.eval_height}},
                  {"subdivision_levels", opt.subdivision_levels},
                  {"supersample", opt.supersample},
                  {"landmark_noise_px", opt.landmark_noise_px},
                  {"light_spread", opt.light_spread},
                  {"shared_focal", opt.shared_focal},
                  {"perturb_deg", opt.perturb_deg},
                  {"surface_error_mm", opt.surface_error_mm},
                  {"register_photos", opt.register_photos}, {"label_regions", opt.label_regions}};
  j["mesh"] = {{"control_triangles", r.control_triangles}, {"vertices", r.vertices}, {"triangles", r.triangles}};
  j["evaluation"] = "held-out view (yaw 25, pitch 6 deg), unlit albedo renders, face-region pixels; "
                    "truth albedo = photo 0's neutral light";
  j["face_pixels"] = r.face_pixels;
  j["psnr_db"] = num(r.with_spline.psnr_db);
  j["ssim"] = num(r.with_spline.ssim);
  j["seam_with_spline"] = num(r.with_spline.seam);
  j["seam_without_spline"] = num(r.without_spline.seam);
  j["with_spline"] = scores(r.with_spline);
  j["without_spline"] = scores(r.without_spline);
  if (opt.diagnostics) {
    j["diagnostics"] = {{"neutral_light", scores(r.neutral_light)},
                        {"neutral_light_nospline", scores(r.neutral_light_nospline)},
                        {"neutral_light_true_cameras", scores(r.neutral_light_true_cameras)},
                        {"neutral_light_true_cameras_nospline", scores(r.neutral_light_true_cameras_nospline)}};
  }
  json lights = json::array();
  for (const Vec3& g : r.light_gains) lights.push_back({g.x(), g.y(), g.z()});
  j["light_gains"] = lights;
  json calib = json::array();
  double worst_focal = 0, worst_rot = 0, worst_centre = 0, worst_vertex = 0;
  for (const PhotoCalibration& c : r.calibration) {
    calib.push_back({{"landmarks", c.landmarks},
                     {"inliers", c.inliers},
                     {"rms_px", num(c.rms_px)},
                     {"focal_true", c.focal_true},
                     {"focal", c.focal},
                     {"focal_error", c.focal_error},
                     {"rotation_error_deg", c.rotation_error_deg},
                     {"centre_error_mm", c.centre_error_mm},
                     {"vertex_error_px", c.vertex_error_px}});
    worst_focal = std::max(worst_focal, std::abs(c.focal_error));
    worst_rot = std::max(worst_rot, c.rotation_error_deg);
    worst_centre = std::max(worst_centre, c.centre_error_mm);
    worst_vertex = std::max(worst_vertex, c.vertex_error_px);
  }
  j["calibration"] = {{"photos", calib},
                      {"shared_focal", r.shared_focal},
                      {"max_focal_error", worst_focal},
                      {"max_rotation_error_deg", worst_rot},
                      {"max_centre_error_mm", worst_centre},
                      {"max_vertex_error_px", worst_vertex}};
  const TextureReport& t = r.texture_report;
  j["texture"] = {{"vertices_unbound", t.vertices_unbound},
                  {"triangles_case", {t.triangles_case[0], t.triangles_case[1], t.triangles_case[2]}},
                  {"texels_case", {t.texels_case[0], t.texels_case[1], t.texels_case[2]}},
                  {"chart_texels", t.chart_texels},
                  {"spline_levels", t.spline_levels}};
  j["vertex_error_used_px"] = r.vertex_error_used_px;
  if (t.registered) {
    json regs = json::array();
    for (const PhotoRegistration& p : t.registration.photos)
      regs.push_back({{"vertices", p.vertices}, {"rms_before", p.rms_before}, {"rms_after", p.rms_after},
                      {"gain", p.gain}, {"bias", p.bias}, {"rotation_deg", p.rotation_deg},
                      {"translation_mm", p.translation_mm}, {"field_max_px", p.field_max_px}});
    j["registration"] = {{"reference", t.registration.reference}, {"vertices", t.registration.vertices},
                         {"rms_before", t.registration.rms_before}, {"rms_after", t.registration.rms_after},
                         {"photos", regs}};
  }
  json timings = json::object();
  for (const auto& [name, ms] : r.timings_ms) timings[name] = ms;
  j["timings_ms"] = timings;
  return j.dump(2) + "\n";
}

}  // namespace lk::cli
