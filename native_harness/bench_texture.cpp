// likeness bench --only texture: the skin texture job (tarini2002 Sec. 3.2)
// at the paper's size, 2048^2 from five 3000x2000 photos, timed step by step
// (CPU time of this process, from texture_head's progress callback), beside
// the paper's figures. Head: the generic head refined twice by Butterfly
// (42k triangles, like a fit's finest level); chart: stretch-minimizing on
// the control mesh (timed), refined to the fine mesh. Photos: ground-truth
// renders of a 3-D colour field under five different light gains (their
// rendering is not timed), calibrated from 15 clicked points each.
#include "command.h"
#include "timing.h"

#include "head/generic_head.h"
#include "mesh/geometry.h"
#include "raycast/bvh.h"
#include "subdiv/butterfly.h"
#include "texture/color.h"
#include "texture/refine_uv.h"
#include "texture/synthetic_photo.h"
#include "texture/texture.h"

#include <cmath>
#include <cstdio>
#include <ctime>
#include <map>
#include <random>

namespace lk::cli {
namespace {

int run(const Args& args) {
  int size = 2048, width = 3000, height = 2000;
  if (!args.get_int("size", 2048, size, 16, 4096)) return 2;
  GenericHead head;
  if (!load_generic_head(head).ok()) {
    std::printf("texture: the generic head could not be loaded\n");
    return 1;
  }
  std::vector<ButterflyLevel> levels;
  if (!build_butterfly_levels(head.mesh, 2, levels).ok()) return 1;
  TriMesh mesh;
  mesh.triangles = levels.back().fine_triangles;
  std::vector<std::vector<Vec3>> pos;
  if (!apply_all(levels, head.mesh.positions, pos).ok()) return 1;
  mesh.positions = pos.back();

  // Ground-truth photos and their clicked points.
  const BBox box = bounding_box(mesh.positions);
  const Vec3 c = box.center();
  const double r = 4.5 * box.size().y(), angles[] = {0.0, 0.8, -0.8, 1.6, -1.6};
  const double gains[] = {1.0, 0.7, 1.25, 0.8, 1.15};
  const double scale = 0.1 * box.size().y();
  std::vector<TexturePhoto> truth(5);
  std::vector<std::vector<Correspondence>> clicks(5);
  std::vector<std::array<int, 2>> sizes(5, {width, height});
  std::mt19937 rng(99);
  std::uniform_real_distribution<double> click(-0.5, 0.5);
  for (int i = 0; i < 5; ++i) {
    const Vec3 eye = c + Vec3(r * std::sin(angles[i]), 0.05 * r, r * std::cos(angles[i]));
    truth[i].camera = look_at_camera(eye, c, Vec3::UnitY(), 0.7 * height * r / box.size().y(), width, height);
    const double g = gains[i];
    const SurfaceColorFn lit = [&](const Vec3& p, const Vec3&) { return (g * procedural_color_field(p, scale)).eval(); };
    if (!render_synthetic_photo(mesh, truth[i].camera, lit, Vec3(0.1, 0.12, 0.15), truth[i].image).ok()) return 1;
    // 15 points: control vertices that face this camera (front hemisphere).
    for (int v = 0, n = 0; v < head.mesh.num_vertices() && n < 15; v += 37) {
      const Vec3& p = head.mesh.positions[v];
      Vec2 px;
      if ((truth[i].camera.center() - p).normalized().dot(vertex_normals(head.mesh)[v]) < 0.5) continue;
      if (!truth[i].camera.project(p, px)) continue;
      clicks[i].push_back({px + Vec2(click(rng), click(rng)), p});
      ++n;
    }
  }

  std::map<std::string, double> cpu, wall;
  std::vector<CalibResult> calib;
  double c0 = cpu_clock_ms(), w0 = wall_clock_ms();
  if (!calibrate_photos(clicks, sizes, CalibOptions(), calib).ok()) {
    std::printf("texture: calibration failed\n");
    return 1;
  }
  cpu["calibrate (5 photos)"] = cpu_clock_ms() - c0;
  wall["calibrate (5 photos)"] = wall_clock_ms() - w0;
  std::vector<TexturePhoto> photos = truth;
  double rms = 0;
  for (int i = 0; i < 5; ++i) {
    photos[i].camera = calib[i].camera;
    rms = std::max(rms, calib[i].rms);
  }

  c0 = cpu_clock_ms();
  w0 = wall_clock_ms();
  std::vector<Vec2> control_uv;
  UvStats uv_stats;
  if (!parameterize_stretch(head.mesh, UvOptions(), control_uv, uv_stats).ok() ||
      !refine_chart_uvs(levels, control_uv, mesh.uvs).ok())
    return 1;
  cpu["parameterize"] = cpu_clock_ms() - c0;
  wall["parameterize"] = wall_clock_ms() - w0;

  TextureOptions opt;
  opt.size = size;
  std::string current;
  double cs = 0, ws = 0;
  const ProgressFn progress = [&](const char* step, double f) {
    if (f == 0 && current != step) {
      current = step;
      cs = cpu_clock_ms();
      ws = wall_clock_ms();
    } else if (f == 1 && current == step) {
      cpu[step] += cpu_clock_ms() - cs;
      wall[step] += wall_clock_ms() - ws;
      current.clear();
    }
    return true;
  };
  TexturedHead out;
  c0 = cpu_clock_ms();
  w0 = wall_clock_ms();
  const Status s = texture_head(mesh, photos, opt, out, progress);
  const double job_cpu = cpu_clock_ms() - c0, job_wall = wall_clock_ms() - w0;
  if (!s) {
    std::printf("texture: %s\n", s.message.c_str());
    return 1;
  }
  cpu.erase("parameterize (mesh had uvs)");
  std::printf("texture: %dx%d skin from five %dx%d photos (light gains 0.7-1.25), generic head refined twice\n"
              "  (%d vertices, %d triangles); calibration from 15 points/photo, worst rms %.2f px\n",
              size, size, width, height, mesh.num_vertices(), mesh.num_triangles(), rms);
  std::printf("  paper (tarini2002 Sec. 5, 1.7 GHz P4): parameterization ~80 min (1.6k triangles),\n"
              "  resampling 2048^2 from five photos ~1 min, multiresolution spline ~10 min\n");
  std::printf("  %-34s %10s %10s\n", "step", "CPU ms", "wall ms");
  for (const char* k : {"calibrate (5 photos)", "parameterize", "bind", "fill holes", "resample", "spline", "dilate"}) {
    if (!cpu.count(k)) continue;
    std::string label = k;
    if (label == "parameterize") label = "parameterize (control mesh + refine)";
    std::printf("  %-34s %10.1f %10.1f\n", label.c_str(), cpu[k], wall[k]);
  }
  const double total_cpu = job_cpu + cpu["parameterize"] + cpu["calibrate (5 photos)"];
  const double total_wall = job_wall + wall["parameterize"] + wall["calibrate (5 photos)"];
  std::printf("  %-34s %10.1f %10.1f   (paper: ~91 min; target < 3 s)\n", "total", total_cpu, total_wall);
  std::printf("  chart %ld texels, %d unbound vertices, triangle cases %d/%d/%d, spline levels %d\n",
              out.report.chart_texels, out.report.vertices_unbound, out.report.triangles_case[0],
              out.report.triangles_case[1], out.report.triangles_case[2], out.report.spline_levels);
  return 0;
}

BenchRegistrar reg({"texture", "skin texture 2048^2 from five 3000x2000 photos (tarini2002 3.2), per-step CPU ms", run});

}  // namespace
}  // namespace lk::cli
