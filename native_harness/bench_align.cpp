// likeness bench --only align: the silhouette-based initial alignment
// (jeong2002 Sec. 4.1) on a virtual 300k-point scan of a synthesized head
// whose pose and units are known, at 256^2 and 512^2, beside the paper's
// figures (Sec. 7). --dump DIR writes the XOR difference images before and
// after (like the paper's Fig. 2) as align_xor_{before,after}.png.
#include "command.h"
#include "synthetic_scan.h"
#include "timing.h"

#include "align/initial_alignment.h"
#include "io/io.h"
#include "mesh/geometry.h"
#include "synth/analytic_head.h"

#if __has_include("head/generic_head.h")
#include "head/generic_head.h"
#define LK_BENCH_ALIGN_HAVE_HEAD 1
#endif

#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <string>

namespace lk::cli {
namespace {

// The scan's known pose: 7 degrees about a tilted axis, anisotropic scale,
// millimetres, and an arbitrary position (a scanner's own frame).
void known_pose(Mat3& linear, Vec3& translation) {
  const Vec3 axis = Vec3(0.3, 1.0, -0.4).normalized();
  linear = 1000.0 * Eigen::AngleAxisd(7.0 * 3.14159265358979 / 180.0, axis).toRotationMatrix() *
           Vec3(1.08, 0.94, 1.05).asDiagonal();
  translation = Vec3(312.0, 1480.0, -95.0);
}

// RMS distance of the aligned control vertices from the synthesized head's
// (same vertex ids) in the scan's frame, above the neck plane, as a
// fraction of that head's bounding-box diagonal.
double relative_rms(const GenericHead& generic, const GenericHead& truth, const Mat3& pose_l, const Vec3& pose_t,
                    const AlignResult& r) {
  double sum = 0;
  int n = 0;
  BBox box;
  for (int i = 0; i < generic.mesh.num_vertices(); ++i) {
    if (!generic.annotations.neck_clip.keeps(generic.mesh.positions[i])) continue;
    const Vec3 t = pose_l * truth.mesh.positions[i] + pose_t;
    box.extend(t);
    sum += (r.linear * generic.mesh.positions[i] + r.translation - t).squaredNorm();
    ++n;
  }
  return n ? std::sqrt(sum / n) / box.diagonal() : -1.0;
}

int run_align_bench(const Args& args) {
  const bool quick = args.has("quick");
  GenericHead generic;
  std::string generic_name = "analytic stand-in head (synth/analytic_head.h)";
#ifdef LK_BENCH_ALIGN_HAVE_HEAD
  if (load_generic_head(generic).ok()) generic_name = "generic head (head/generic_head.h)";
  else generic = analytic_head();
#else
  generic = analytic_head();
#endif
  // The person: the generic head with other proportions, scanned.
  SyntheticScan data;
  Status st = make_synthetic_scan(generic, 7, quick ? 100000 : 300000, data);
  const GenericHead& person = data.person;
  PointCloud& cloud = data.cloud;
  if (!st) {
    std::printf("   could not make the scan: %s\n", st.message.c_str());
    return 1;
  }
  Mat3 pose_l;
  Vec3 pose_t;
  known_pose(pose_l, pose_t);
  for (Vec3& p : cloud.positions) p = pose_l * p + pose_t;
  std::printf("   %s: %d vertices, %d triangles; scan: %d points (virtual structured light, holes,\n"
              "   hair junk, outliers), rotated 7 deg, scaled (1.08, 0.94, 1.05), in mm, moved\n",
              generic_name.c_str(), generic.mesh.num_vertices(), generic.mesh.num_triangles(), cloud.size());
  std::printf("   times are process CPU time (the machine is shared; wall time in brackets)\n\n");
  std::printf("   %-22s %6s %7s %7s %10s %12s %16s %9s\n", "run", "levels", "iters", "evals", "ms/eval",
              "total ms", "XOR before->after", "RMS/diag");

  struct Run { const char* name; int resolution; std::vector<int> coarse; };
  std::vector<Run> runs = {{"256^2, one level", 256, {}},
                           {"256^2, 64-128-256", 256, {64, 128}},
                           {"512^2, 64-128-256-512", 512, {64, 128, 256}}};
  if (quick) runs.pop_back();
  AlignResult dump_result;
  AlignOptions dump_options;
  int failures = 0;
  for (const Run& run : runs) {
    AlignOptions o;
    o.resolution = run.resolution;
    o.coarse_resolutions = run.coarse;
    AlignResult r;
    const double c0 = cpu_clock_ms(), w0 = wall_clock_ms();
    st = align_initial(generic.mesh, generic.annotations, cloud, o, r);
    const double cpu = cpu_clock_ms() - c0, wall = wall_clock_ms() - w0;
    if (!st) {
      std::printf("   %-22s failed: %s\n", run.name, st.message.c_str());
      ++failures;
      continue;
    }
    // One evaluation at the final resolution: rasterize the placed generic
    // into the three views and XOR-count against the cloud's masks.
    std::array<SilhouetteMask, kSilhouetteViews> cloud_masks, mesh_masks;
    rasterize_point_silhouettes(cloud.positions, r.frame.window, r.frame.clips, o.splat, cloud_masks);
    const int reps = 200;
    long long sink = 0;
    const double e0 = cpu_clock_ms();
    for (int k = 0; k < reps; ++k) {
      std::vector<Vec3> moved(generic.mesh.positions.size());
      for (size_t i = 0; i < moved.size(); ++i) moved[i] = r.linear * generic.mesh.positions[i] + r.translation;
      rasterize_mesh_silhouettes(moved, generic.mesh.triangles, r.frame.window, r.frame.clips, mesh_masks,
                                 o.cull_back_faces);
      for (int v = 0; v < kSilhouetteViews; ++v) sink += xor_count(mesh_masks[v], cloud_masks[v]);
    }
    const double per_eval = (cpu_clock_ms() - e0) / reps;
    char xor_text[48];
    std::snprintf(xor_text, sizeof xor_text, "%d -> %d", total_xor(r.xor_before), total_xor(r.xor_after));
    char total_text[40];
    std::snprintf(total_text, sizeof total_text, "%.0f (%.0f)", cpu, wall);
    std::printf("   %-22s %6zu %7d %7d %10.3f %12s %16s %8.2f%%%s\n", run.name, r.levels.size(), r.iterations,
                r.evaluations, per_eval, total_text, xor_text,
                100.0 * relative_rms(generic, person, pose_l, pose_t, r), sink < 0 ? "?" : "");
    for (const AlignLevel& level : r.levels)
      std::printf("   %24s %4d^2: %2d iterations, %4d evaluations, closing radius %.1f/%.1f/%.1f px\n", "",
                  level.resolution, level.iterations, level.evaluations, level.cloud.closing_radius_px[0],
                  level.cloud.closing_radius_px[1], level.cloud.closing_radius_px[2]);
    if (run.resolution == 256 && !run.coarse.empty()) {
      dump_result = r;
      dump_options = o;
    }
  }
  std::printf("\n   jeong2002 Sec. 7 (GeForce3 read-backs): 8-14 Powell iterations x 250-300 evaluations;\n"
              "   256^2: 6-10 min (1.7 GHz PC), 90-150 s (SGI Octane); 512^2: 20-30 min (PC), 5-8 min (Octane),\n"
              "   1-2 iterations fewer. RMS/diag: aligned generic vs the synthesized head's own control\n"
              "   vertices in the scan frame (the affine cannot absorb its different proportions).\n");

  const std::string dir = args.get("dump");
  if (!dir.empty() && !dump_result.levels.empty()) {
    std::array<Image, kSilhouetteViews> before, after;
    st = align_difference_images(generic.mesh, dump_result.initial_linear, dump_result.initial_translation, cloud,
                                 dump_result.frame, dump_options, before);
    if (st) st = align_difference_images(generic.mesh, dump_result.linear, dump_result.translation, cloud,
                                         dump_result.frame, dump_options, after);
    if (st) st = save_png_file(dir + "/align_xor_before.png", concat_views(before));
    if (st) st = save_png_file(dir + "/align_xor_after.png", concat_views(after));
    if (!st) {
      std::printf("   dump failed: %s\n", st.message.c_str());
      return 1;
    }
    std::printf("   wrote %s/align_xor_{before,after}.png (front | side | top)\n", dir.c_str());
  }
  return failures ? 1 : 0;
}

BenchRegistrar reg({"align", "silhouette-based initial alignment (jeong2002 4.1) on a virtual 300k-point scan",
                    run_align_bench});

}  // namespace
}  // namespace lk::cli
