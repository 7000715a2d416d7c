// likeness texture: skin texture from photographs (tarini2002 Sec. 3.2).
// Reads a `likeness fit` output (or one mesh), photos and one points file per
// photo, calibrates each photo, textures the head and writes textured.obj +
// textured.mtl + skin.png + report.json. With --make-synthetic it instead
// writes ground-truth photos and points files of a head to try it on.
#include "command.h"
#include "timing.h"

#include "components/components.h"
#include "head/generic_head.h"
#include "io/io.h"
#include "mesh/geometry.h"
#include "photos/ground_truth.h"
#include "project/export.h"
#include "project/pose.h"
#include "project/project_file.h"
#include "project/texture_job.h"
#include "raycast/bvh.h"
#include "subdiv/butterfly.h"
#include "synth/skin_field.h"
#include "texture/binding.h"
#include "texture/color.h"
#include "texture/correspondences.h"
#include "texture/synthetic_photo.h"
#include "texture/texture.h"

#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <sys/stat.h>

namespace lk::cli {
namespace {

const char* kName = "texture";

int usage_error(const std::string& message) {
  fail(kName, message);
  return 2;
}

bool is_directory(const std::string& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}
bool is_file(const std::string& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode);
}

// The head to texture and, when it is a fit's finest level, the chart
// computed on the control mesh and refined to it (refine_uv.h).
struct HeadInput {
  TriMesh mesh;
  TriMesh control;  // the control mesh when the head has the generic head's topology (else empty)
  std::string description;
  bool uv_from_control = false;
  UvStats control_uv;
  double control_uv_ms = 0;  // parameterizing the control mesh
};

Status load_head(const std::string& spec, const UvOptions& uv_options, HeadInput& out) {
  if (spec == "generic") {
    GenericHead head;
    Status s = load_generic_head(head);
    if (!s) return s;
    out.mesh = head.mesh;
    out.mesh.uvs.clear();
    out.control = out.mesh;
    out.description = "the generic head";
    return Status::success();
  }
  if (is_file(spec)) {
    out.description = spec;
    Status s = with_context(load_mesh_file(spec, out.mesh), spec);
    if (s && out.mesh.uv_per_corner) {
      // A scanner's atlas (seams, several charts): the paper wants one chart.
      std::printf("note: %s has per-corner uvs (an atlas with seams); making one chart instead\n", spec.c_str());
      out.mesh.uvs.clear();
      out.mesh.uv_per_corner = false;
    }
    return s;
  }
  if (!is_directory(spec))
    return Status::error(ErrorCode::InvalidInput,
                         spec + ": no such directory (give a `likeness fit` output, a mesh file or 'generic')");
  const std::string control_path = spec + "/control.obj";
  if (!is_file(control_path))
    return Status::error(ErrorCode::InvalidInput, spec + ": no control.obj (is it a `likeness fit` output?)");
  int finest = 0;
  while (is_file(spec + "/level" + std::to_string(finest + 1) + ".obj")) ++finest;
  TriMesh control;
  Status s = with_context(load_mesh_file(control_path, control), control_path);
  if (!s) return s;
  out.control = control;
  if (finest == 0) {
    out.mesh = control;
    out.description = control_path;
    return Status::success();
  }
  const std::string fine_path = spec + "/level" + std::to_string(finest) + ".obj";
  s = with_context(load_mesh_file(fine_path, out.mesh), fine_path);
  if (!s) return s;
  out.description = fine_path;
  // The chart: on the control mesh, refined to the finest level when the
  // level is the control mesh's Butterfly refinement (same triangles).
  std::vector<ButterflyLevel> levels;
  if (build_butterfly_levels(control, finest, levels).ok() &&
      levels.back().fine_triangles == out.mesh.triangles &&
      levels.back().num_fine_vertices == out.mesh.num_vertices()) {
    const double t0 = wall_clock_ms();
    s = level_chart(control, levels, uv_options, out.mesh.uvs, out.control_uv);
    out.control_uv_ms = wall_clock_ms() - t0;
    if (!s) return with_context(s, control_path);
    out.mesh.uv_per_corner = false;
    out.uv_from_control = true;
  } else {
    out.mesh.uvs.clear();  // parameterized on the fine mesh itself
  }
  return Status::success();
}

// The synthetic person's skin of `likeness synth-photos` (tone, blotches,
// freckles, red lips, dark brows), placed on a head with the generic head's
// topology: its annotations carried to the control mesh (the head's frame by
// the best similarity, the eyes as place_components puts them).
Status person_skin(const TriMesh& control, std::uint32_t seed, SkinField& out) {
  GenericHead generic;
  Status s = load_generic_head(generic);
  if (!s) return s;
  if (control.num_vertices() != generic.mesh.num_vertices())
    return Status::error(ErrorCode::InvalidInput, "--field person needs a head with the generic head's topology "
                                                  "(a `likeness fit` output, a project or 'generic')");
  GenericHead person = generic;
  person.mesh.positions = control.positions;
  std::vector<int> all(std::size_t(control.num_vertices()));
  for (int v = 0; v < control.num_vertices(); ++v) all[std::size_t(v)] = v;
  const Similarity frame = fit_similarity(generic.mesh.positions, control.positions, all);
  person.annotations.look = frame.R * generic.annotations.look;
  person.annotations.up = frame.R * generic.annotations.up;
  ComponentPlacement placed;
  s = place_components(person, generic, placed);
  if (!s) return s;
  EyeSocket* eyes[2] = {&person.annotations.eye_left, &person.annotations.eye_right};
  for (int e = 0; e < 2; ++e) {
    eyes[e]->center = placed.eye_center[e];
    eyes[e]->radius = placed.eye_radius[e];
  }
  return make_skin_field(person, seed, SkinFieldOptions{}, out);
}

nlohmann::json vec3(const Vec3& v) { return {v.x(), v.y(), v.z()}; }

// Writes five ground-truth photos (3000 x 2000 by default, a different
// light gain each unless even) and their points files: 15 visible vertices
// spread over each photo, clicked with up to half a pixel of error.
int make_synthetic(const Args& args, const HeadInput& head, const std::string& dir) {
  int width = 3000, height = 2000;
  if (!args.get_int("photo-width", 3000, width, 64, 8000) || !args.get_int("photo-height", 2000, height, 64, 8000))
    return 2;
  ::mkdir(dir.c_str(), 0755);
  const TriMesh& mesh = head.mesh;
  const BBox box = bounding_box(mesh.positions);
  const double scale = 0.1 * box.size().y();  // the colour field's finest wavelength
  // "bands": the colourful test field; "skin": one skin tone with faint
  // mottling, on which a lighting seam is as visible as on a real face;
  // "person": synth-photos' person (seed 1), whose brows and lips show what
  // texturing does.
  const std::string kind = args.get("field", "bands");
  if (kind != "bands" && kind != "skin" && kind != "person")
    return usage_error("--field must be 'bands', 'skin' or 'person'");
  const bool skin = kind == "skin", person = kind == "person";
  SkinField person_field;
  if (person) {
    const Status ps = person_skin(head.control, 1, person_field);
    if (!ps) return fail(kName, ps.message);
  }
  const SurfaceColorFn field = [scale, skin, person, &person_field](const Vec3& p, const Vec3&) {
    if (person) return skin_albedo(person_field, p);
    const Vec3 f = procedural_color_field(p, scale);
    if (!skin) return f;
    const double mottle = 0.92 + 0.35 * (f.x() - 0.45) + 0.15 * (f.z() - 0.25);
    return Vec3(Vec3(0.58, 0.36, 0.27) * mottle);
  };
  const double even[] = {1, 1, 1, 1, 1}, uneven[] = {1.0, 0.7, 1.25, 0.8, 1.15};
  const double* gains = args.has("even-light") ? even : uneven;
  const Vec3 c = box.center();
  const double r = 4.5 * box.size().y(), angles[] = {0.0, 0.8, -0.8, 1.6, -1.6};
  MeshBvh bvh;
  Status s = build_bvh(mesh, bvh);
  if (!s) return fail(kName, s.message);
  const std::vector<Vec3> normals = vertex_normals(mesh);
  std::mt19937 rng(1234);
  for (int i = 0; i < 5; ++i) {
    const Vec3 eye = c + Vec3(r * std::sin(angles[i]), 0.05 * r, r * std::cos(angles[i]));
    const Camera cam = look_at_camera(eye, c, Vec3::UnitY(), 0.7 * height * r / box.size().y(), width, height);
    const double gain = gains[i];
    // The person is shaded (Lambert, light from the camera's upper left) as
    // synth-photos' renders are; the test fields stay unshaded.
    const Vec3 to_eye = (eye - c).normalized(), left = Vec3::UnitY().cross(to_eye).normalized();
    const Vec3 light = (to_eye + 0.6 * Vec3::UnitY() + 0.4 * left).normalized();
    const SurfaceColorFn lit = [&](const Vec3& p, const Vec3& n) {
      const double shade = person ? 0.45 + 0.65 * std::max(0.0, n.dot(light)) : 1.0;
      return (gain * shade * field(p, n)).eval();
    };
    Image photo;
    s = render_synthetic_photo(mesh, cam, lit, Vec3(0.1, 0.12, 0.15), photo);
    if (!s) return fail(kName, s.message);
    const std::string photo_path = dir + "/photo" + std::to_string(i) + ".png";
    s = save_png_file(photo_path, photo);
    if (!s) return fail(kName, s.message);
    // Visible vertices, then 15 of them by farthest-point sampling in the image.
    VertexBinding b;
    BindingOptions bo;
    bo.min_facing = 0.4;  // points a user would click: well inside the view
    s = bind_vertices(mesh, normals, bvh, {cam}, bo, b);
    if (!s) return fail(kName, s.message);
    std::vector<int> visible;
    for (int v = 0; v < mesh.num_vertices(); ++v)
      if (b.bound(v)) visible.push_back(v);
    if (visible.size() < 15) return fail(kName, "the synthetic photo " + photo_path + " sees too few vertices");
    std::vector<Vec2> px(visible.size());
    for (size_t j = 0; j < visible.size(); ++j) cam.project(mesh.positions[visible[j]], px[j]);
    std::vector<size_t> chosen = {0};
    std::vector<double> dist(visible.size(), 1e300);
    while (chosen.size() < 15) {
      size_t best = 0;
      for (size_t j = 0; j < visible.size(); ++j) {
        dist[j] = std::min(dist[j], (px[j] - px[chosen.back()]).norm());
        if (dist[j] > dist[best]) best = j;
      }
      chosen.push_back(best);
    }
    std::uniform_real_distribution<double> click(-0.5, 0.5);
    std::vector<Correspondence> points;
    for (size_t j : chosen) points.push_back({px[j] + Vec2(click(rng), click(rng)), mesh.positions[visible[j]]});
    const std::string points_path = dir + "/points" + std::to_string(i) + ".txt";
    s = write_file(points_path, format_correspondences(points));
    if (!s) return fail(kName, s.message);
    std::printf("wrote %s (%dx%d, light gain %.2f) and %s (15 points)\n", photo_path.c_str(), width, height, gain,
                points_path.c_str());
  }
  return 0;
}

int run_texture(const Args& args) {
  if (!only_known_options(kName, args,
                          {"head", "photos", "points", "size", "focal", "out", "no-spline", "dump",
                           "make-synthetic", "photo-width", "photo-height", "even-light", "field",
                           "same-camera", "separate-cameras", "project", "project-out"}))
    return 2;
  const double t_start = wall_clock_ms();
  const std::string head_spec = args.get("head"), out_dir = args.get("out");
  // --project FILE: the head is a saved project's finest level (scan frame,
  // as the points are), textured by the project's job as in the page;
  // --project-out FILE saves the textured project.
  const std::string project_path = args.get("project"), project_out = args.get("project-out");
  const bool use_project = args.has("project");
  if (use_project && project_path.empty()) return usage_error("--project needs a project file");
  if (use_project && !head_spec.empty()) return usage_error("give --head or --project, not both");
  if (args.has("project-out") && (!use_project || project_out.empty()))
    return usage_error("--project-out FILE goes with --project FILE");
  if (head_spec.empty() && !use_project)
    return usage_error("--head DIR (a `likeness fit` output), a mesh file or 'generic' is required, or --project FILE");
  TextureOptions opt;
  double focal = 0;
  if (!args.get_int("size", 2048, opt.size, 16, 4096) || !args.get_double("focal", 0, focal, 0)) return 2;
  opt.multiresolution_spline = !args.has("no-spline");

  HeadInput head;
  HeadProject project;
  std::map<std::string, double> timings;
  double t0 = wall_clock_ms();
  Status s;
  if (use_project) {
    Bytes bytes;
    s = read_file(project_path, bytes);
    if (s) s = with_context(load_project(bytes.data(), bytes.size(), project), project_path);
    if (s) s = rest_pose(project);
    if (s) s = project_level_mesh(project, project.fit.multires.num_levels(), ExportFrame::Scan, head.mesh);
    if (s) s = project_level_mesh(project, 0, ExportFrame::Scan, head.control);
    head.description = project_path;
  } else {
    s = load_head(head_spec, opt.uv, head);
  }
  if (!s) return fail(kName, s.message);
  timings["load head"] = wall_clock_ms() - t0 - head.control_uv_ms;

  if (args.has("make-synthetic")) {
    const std::string dir = args.get("make-synthetic");
    if (dir.empty()) return usage_error("--make-synthetic needs a directory");
    return make_synthetic(args, head, dir);
  }

  const std::vector<std::string> photo_paths = args.get_all("photos"), point_paths = args.get_all("points");
  if (out_dir.empty()) return usage_error("--out DIR is required");
  if (photo_paths.empty()) return usage_error("--photos P1 [P2 ...] is required");
  if (photo_paths.size() != point_paths.size())
    return usage_error(std::to_string(photo_paths.size()) + " photos but " + std::to_string(point_paths.size()) +
                       " points files: give one points file per photo, in the same order");

  // Photos and points.
  t0 = wall_clock_ms();
  std::vector<TexturePhoto> photos(photo_paths.size());
  std::vector<std::vector<Correspondence>> points(photo_paths.size());
  std::vector<std::array<int, 2>> sizes;
  for (size_t i = 0; i < photo_paths.size(); ++i) {
    s = load_image_file(photo_paths[i], photos[i].image, 3);
    if (!s) return fail(kName, s.message);  // names the file
    sizes.push_back({photos[i].image.width, photos[i].image.height});
    Bytes bytes;
    s = read_file(point_paths[i], bytes, kMaxCorrespondenceBytes);
    if (!s) return fail(kName, s.message);
    s = parse_correspondences(std::string(bytes.begin(), bytes.end()), points[i]);
    if (!s) return fail(kName, point_paths[i] + ": " + s.message);
    if (points[i].size() < 6)
      return fail(kName, point_paths[i] + ": " + std::to_string(points[i].size()) +
                             " points; calibrating a photo needs at least 6 (the paper clicks 12-15)");
  }
  timings["load photos"] = wall_clock_ms() - t0;

  // Calibration: each photo alone, then jointly with one focal length when
  // they share a camera (core/project/texture_job.h).
  t0 = wall_clock_ms();
  CalibOptions copt;
  copt.known_focal = focal;
  const CameraSharing sharing = args.has("same-camera")        ? CameraSharing::Same
                                : args.has("separate-cameras") ? CameraSharing::Separate
                                                               : CameraSharing::Auto;
  PhotoCalibration calibration;
  TexturedHead out;
  opt.keep_unblended = args.has("dump");
  if (use_project) {
    // The project's texture job: calibration, the chart, texture_head.
    TextureJobInput input;
    input.photos = photos;
    input.points = points;
    input.names = photo_paths;
    input.options = opt;
    input.calibration = copt;
    input.sharing = sharing;
    TextureJobResult result;
    std::map<std::string, double> started;
    StepObserver observer;
    observer.started = [&](const std::string& step) { started[step] = wall_clock_ms(); };
    observer.finished = [&](const std::string& step) { timings[step] += wall_clock_ms() - started[step]; };
    s = texture_project(project, input, result, observer);
    if (!s) return fail(kName, head.description + ": " + s.message);
    calibration = std::move(result.calibration);
    out = std::move(result.head);
    timings["parameterize"] += timings["chart"];
    timings.erase("chart");
    head.uv_from_control = true;
    head.control_uv = result.chart;
    if (!project_out.empty()) {
      ::mkdir(out_dir.c_str(), 0755);  // the project may go inside --out
      Bytes bytes;
      s = save_project(project, bytes);
      if (s) s = write_file(project_out, bytes);
      if (!s) return fail(kName, s.message);
      std::printf("wrote %s (the textured head project)\n", project_out.c_str());
    }
  } else {
    s = calibrate_texture_photos(points, sizes, photo_paths, copt, sharing, calibration);
    if (!s) return fail(kName, s.message);
  }
  const std::vector<CalibResult>& calib = calibration.results;
  if (calibration.shared)
    std::printf("calibration: one focal length shared by all photos (same camera)%s\n",
                args.has("same-camera") ? "" : "; --separate-cameras calibrates each photo alone");
  for (size_t i = 0; i < photos.size(); ++i) photos[i].camera = calib[i].camera;
  if (!use_project) timings["calibrate"] = wall_clock_ms() - t0;

  // Texturing, timed step by step from the progress callback.
  std::string current;
  double step_start = 0;
  const ProgressFn progress = [&](const char* step, double f) {
    if (f == 0 && current != step) {
      current = step;
      step_start = wall_clock_ms();
    } else if (f == 1 && current == step) {
      timings[step] = wall_clock_ms() - step_start;
      current.clear();
    }
    return true;
  };
  if (!use_project) {
    s = texture_head(head.mesh, photos, opt, out, progress);
    if (!s) return fail(kName, head.description + ": " + name_photos(s, photo_paths).message);
  }
  // The chart of a fit's finest level is made on its control mesh while loading.
  if (head.uv_from_control && !use_project) timings["parameterize"] += head.control_uv_ms;

  // Outputs.
  t0 = wall_clock_ms();
  ::mkdir(out_dir.c_str(), 0755);
  s = write_file(out_dir + "/textured.obj", write_obj(out.mesh, "textured.mtl"));
  if (s) s = write_file(out_dir + "/textured.mtl", write_mtl("skin.png"));
  if (s) s = save_png_file(out_dir + "/skin.png", out.skin);
  if (s && args.has("dump")) {
    if (!out.unblended.empty()) s = save_png_file(out_dir + "/skin_unblended.png", out.unblended);
    // Regions: one colour per photo, grey = interpolated, black = background.
    const Vec3 palette[] = {{0.9, 0.3, 0.3}, {0.3, 0.8, 0.3}, {0.3, 0.4, 0.9}, {0.9, 0.8, 0.2},
                            {0.8, 0.3, 0.9}, {0.2, 0.8, 0.9}, {0.9, 0.6, 0.3}, {0.6, 0.6, 0.3}};
    Image regions = Image::make(opt.size, opt.size, 3, 0);
    for (size_t j = 0; j < out.region.size(); ++j) {
      const int r = out.region[j];
      const Vec3 c = r >= 0 ? palette[r % 8] : (r == kRegionFilled ? Vec3(0.5, 0.5, 0.5) : Vec3(0, 0, 0));
      for (int k = 0; k < 3; ++k) regions.pixels[j * 3 + k] = static_cast<std::uint8_t>(255 * c[k]);
    }
    if (s) s = save_png_file(out_dir + "/regions.png", regions);
  }
  if (!s) return fail(kName, s.message);
  timings["write"] = wall_clock_ms() - t0;
  timings["total"] = wall_clock_ms() - t_start;

  const TextureReport& rep = out.report;
  nlohmann::json j;
  j["head"] = head.description;
  j["vertices"] = rep.vertices;
  j["triangles"] = rep.triangles;
  j["size"] = opt.size;
  j["multiresolution_spline"] = opt.multiresolution_spline;
  j["photos"] = nlohmann::json::array();
  for (size_t i = 0; i < photos.size(); ++i) {
    nlohmann::json p;
    p["file"] = photo_paths[i];
    p["points_file"] = point_paths[i];
    p["width"] = photos[i].image.width;
    p["height"] = photos[i].image.height;
    p["calibration"] = {{"rms_px", calib[i].rms},
                        {"inliers", calib[i].num_inliers},
                        {"focal_px", calib[i].camera.fx},
                        {"camera_center", vec3(calib[i].camera.center())}};
    nlohmann::json pts = nlohmann::json::array();
    for (size_t k = 0; k < points[i].size(); ++k)
      pts.push_back({{"u", points[i][k].pixel.x()},
                     {"v", points[i][k].pixel.y()},
                     {"point", vec3(points[i][k].point)},
                     {"error_px", std::isfinite(calib[i].errors[k]) ? nlohmann::json(calib[i].errors[k]) : nlohmann::json(nullptr)},
                     {"outlier", calib[i].outlier[k] != 0}});
    p["calibration"]["points"] = pts;
    p["vertices_valid"] = rep.photos[i].vertices_valid;
    p["vertices_main"] = rep.photos[i].vertices_main;
    p["texels_colored"] = rep.photos[i].texels_colored;
    p["texels_seen"] = rep.photos[i].texels_seen;
    j["photos"].push_back(p);
  }
  const UvStats& uv = head.uv_from_control ? head.control_uv : rep.uv;
  j["uv"] = {{"computed_on", head.uv_from_control ? "control mesh, refined to the finest level"
                                                  : (rep.parameterized ? "the textured mesh" : "given with the mesh")},
             {"l2_stretch", uv.l2_stretch},
             {"l2_stretch_unweighted", uv.l2_stretch_unweighted},
             {"linf_stretch", uv.linf_stretch},
             {"textured_mesh_l2_stretch", rep.uv.l2_stretch},
             {"textured_mesh_linf_stretch", rep.uv.linf_stretch},
             {"flipped", rep.uv.flipped}};
  j["vertices_unbound"] = rep.vertices_unbound;
  j["triangle_cases"] = {rep.triangles_case[0], rep.triangles_case[1], rep.triangles_case[2]};
  j["texel_cases"] = {rep.texels_case[0], rep.texels_case[1], rep.texels_case[2]};
  j["hole_fill"] = {{"filled_per_pass", rep.hole_fill.filled_per_pass},
                    {"sweeps", rep.hole_fill.sweeps},
                    {"uncolorable", rep.hole_fill.uncolorable}};
  j["chart_texels"] = rep.chart_texels;
  j["background_filled"] = rep.background_filled;
  j["spline_levels"] = rep.spline_levels;
  j["timings_ms"] = timings;
  s = write_file(out_dir + "/report.json", j.dump(2) + "\n");
  if (!s) return fail(kName, s.message);

  std::printf("likeness texture: %s (%d vertices), %zu photos -> %s/skin.png (%dx%d)\n", head.description.c_str(),
              rep.vertices, photos.size(), out_dir.c_str(), opt.size, opt.size);
  for (size_t i = 0; i < photos.size(); ++i)
    std::printf("  %s: calibration rms %.2f px (%d/%zu inliers), %d vertices bound, %ld texels\n",
                photo_paths[i].c_str(), calib[i].rms, calib[i].num_inliers, points[i].size(),
                rep.photos[i].vertices_valid, rep.photos[i].texels_colored);
  std::printf("  unbound vertices %d (hole-filled), triangle cases %d/%d/%d, spline levels %d\n", rep.vertices_unbound,
              rep.triangles_case[0], rep.triangles_case[1], rep.triangles_case[2], rep.spline_levels);
  std::printf("  ms:");
  for (const char* k : {"load head", "load photos", "calibrate", "parameterize", "bind", "fill holes", "resample",
                        "spline", "dilate", "write", "total"})
    if (timings.count(k)) std::printf(" %s %.0f,", k, timings[k]);
  std::printf("\n  wrote textured.obj, textured.mtl, skin.png, report.json%s\n",
              args.has("dump") ? ", skin_unblended.png, regions.png" : "");
  return 0;
}

const Registrar reg({kName,
                     "likeness texture --head DIR|MESH|generic | --project FILE [--project-out FILE] "
                     "--photos P1 P2 ... --points F1 F2 ... --out DIR "
                     "[--size 2048] [--focal PX] [--same-camera | --separate-cameras] [--no-spline] [--dump] | --head ... --make-synthetic DIR "
                     "[--photo-width 3000 --photo-height 2000] [--even-light] [--field bands|skin|person]",
                     "skin texture from calibrated photos (tarini2002 Sec. 3.2): binding, resampling, hole filling, "
                     "multiresolution spline",
                     run_texture});

}  // namespace
}  // namespace lk::cli
