// likeness bench --only synth: the BVH (build, rays, closest points) and the
// virtual scanner on a synthetic head, in CPU time (the machine is shared).
#include "command.h"
#include "timing.h"

#include "head/generic_head.h"
#include "raycast/bvh.h"
#include "common/prng.h"
#include "synth/scanner.h"
#include "synth/synth_head.h"

#include <cstdio>
#include <ctime>

namespace lk::cli {
namespace {

int run_bench_synth(const Args& args) {
  const bool quick = args.has("quick");
  GenericHead generic, head;
  Status s = load_generic_head(generic);
  if (s) s = synthesize_head(generic, 1, {}, head);
  if (!s) {
    std::printf("   synth: %s\n", s.message.c_str());
    return 1;
  }
  std::printf("   %-34s %10s %12s %14s\n", "truth mesh", "triangles", "BVH build", "per query");
  for (int levels : {2, 3}) {
    TruthOptions to;
    to.subdivision_levels = levels;
    TruthSurface truth;
    double t0 = cpu_clock_ms();
    if (!(s = make_truth_surface(head, 1, to, truth))) return 1;
    const double t_truth = cpu_clock_ms() - t0;
    MeshBvh bvh;
    t0 = cpu_clock_ms();
    if (!(s = build_bvh(truth.mesh, bvh))) return 1;
    const double t_build = cpu_clock_ms() - t0;
    const int n = quick ? 50000 : 200000;
    SplitMix64 rng(42);
    const Vec3 c = Vec3(0, 0, 0.3);
    int hits = 0;
    t0 = cpu_clock_ms();
    for (int i = 0; i < n; ++i) {
      Ray r;
      r.origin = c + Vec3(rng.uniform(-0.3, 0.3), rng.uniform(-0.3, 0.3), 0.3);
      r.direction = Vec3(rng.uniform(-0.1, 0.1), rng.uniform(-0.1, 0.1), 0) - r.origin;
      hits += intersect_first(bvh, r).hit();
    }
    const double t_rays = cpu_clock_ms() - t0;
    double sum = 0;
    t0 = cpu_clock_ms();
    for (int i = 0; i < n; ++i)
      sum += closest_point(bvh, Vec3(rng.uniform(-0.12, 0.12), rng.uniform(-0.15, 0.15),
                                     rng.uniform(-0.12, 0.12)))
                 .distance;
    const double t_cp = cpu_clock_ms() - t0;
    char name[64];
    std::snprintf(name, sizeof name, "Loop x%d (truth %.0f ms)", levels, t_truth);
    std::printf("   %-34s %10d %9.0f ms   ray %5.2f us (%d%% hit), closest %5.2f us (mean %.0f mm)\n",
                name, truth.mesh.num_triangles(), t_build, 1000.0 * t_rays / n, 100 * hits / n,
                1000.0 * t_cp / n, 1000.0 * sum / n);
  }
  TruthSurface truth;
  if (!(s = make_truth_surface(head, 1, {}, truth))) return 1;
  ScannerOptions so;
  so.hair_triangles = truth.hair;
  std::printf("   %-34s %10s %12s %14s\n", "virtual scan (2 Loop levels)", "points", "CPU time", "outliers");
  for (int target : {100000, 300000}) {
    if (quick && target > 100000) break;
    so.target_points = target;
    PointCloud cloud;
    ScanStats st;
    const double t0 = cpu_clock_ms();
    if (!(s = scan_virtual(truth.mesh, so, 1, cloud, &st))) {
      std::printf("   scan: %s\n", s.message.c_str());
      return 1;
    }
    std::printf("   %-34s %10d %9.0f ms %14d\n", "", cloud.size(), cpu_clock_ms() - t0, st.outliers);
  }
  return 0;
}

BenchRegistrar reg({"synth", "BVH rays/closest points and the virtual scanner (CPU time)",
                    run_bench_synth});

}  // namespace
}  // namespace lk::cli
