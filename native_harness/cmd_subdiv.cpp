// likeness subdiv: builds the displaced Modified Butterfly hierarchy of a
// control mesh (jeong2002 Sec. 5), optionally measuring displacements from a
// scan, and writes every level's mesh so it can be looked at
// (`likeness render --mesh PREFIX_level2.ply`).
#include "command.h"
#include "timing.h"

#include "io/io.h"
#include "mesh/geometry.h"
#include "multires/displacement.h"
#include "multires/fold_limit.h"
#include "multires/multires.h"
#include "raycast/self_intersection.h"

#include <cstdio>
#include <ctime>

namespace lk::cli {
namespace {

const char* kName = "subdiv";

int usage_error(const std::string& message) {
  fail(kName, message);
  return 2;
}

int run_subdiv(const Args& args) {
  if (!only_known_options(kName, args,
                          {"mesh", "points", "levels", "radius", "max-distance", "min-points", "out", "crossings"}))
    return 2;
  const std::string mesh_path = args.get("mesh"), points_path = args.get("points"), out = args.get("out");
  if (mesh_path.empty()) return usage_error("--mesh FILE is required");
  if (out.empty()) return usage_error("--out PREFIX is required (writes PREFIX_level<l>.ply)");
  int levels = 2, min_points = 3;
  DisplacementOptions options;
  if (!args.get_int("levels", 2, levels, 0, 5) || !args.get_int("min-points", 3, min_points, 1, 1000000) ||
      !args.get_double("radius", 0.0, options.radius, 0) || !args.get_double("max-distance", 0.0, options.max_distance, 0))
    return 2;
  options.min_points = min_points;

  TriMesh control;
  Status s = load_mesh_file(mesh_path, control);
  if (!s) return fail(kName, s.message);
  MultiresMesh mr;
  double t0 = cpu_clock_ms();
  s = build_multires(control, levels, mr);
  if (!s) return fail(kName, mesh_path + ": " + s.message);
  std::printf("built %d levels over %d vertices / %d triangles in %.1f ms\n", levels, control.num_vertices(),
              control.num_triangles(), cpu_clock_ms() - t0);

  if (!points_path.empty()) {
    PointCloud cloud;
    s = load_point_cloud_file(points_path, cloud);
    if (!s) return fail(kName, s.message);
    DisplacementStats stats;
    t0 = cpu_clock_ms();
    s = measure_displacements(cloud, options, mr, &stats);
    if (!s) return fail(kName, points_path + ": " + s.message);
    std::printf("measured displacements from %d points in %.1f ms\n", cloud.size(), cpu_clock_ms() - t0);
    for (int l = 0; l <= levels; ++l)
      std::printf("  level %d: %d of %d vertices had data, mean |d| %.4g, max |d| %.4g\n", l, stats.measured[l],
                  stats.candidates[l], stats.mean_abs[l], stats.max_abs[l]);
  }
  for (int l = 0; l <= levels; ++l) {
    const TriMesh m = level_mesh(mr, l);
    const std::string path = out + "_level" + std::to_string(l) + ".ply";
    s = write_file(path, write_ply(m));
    if (!s) return fail(kName, s.message);
    std::printf("wrote %s (%d vertices, %d triangles)\n", path.c_str(), m.num_vertices(), m.num_triangles());
    // --crossings: each level's self-intersecting triangle pairs (a fitted
    // control mesh's smooth levels are where a fit's folds show first).
    if (args.has("crossings")) {
      std::vector<std::array<int, 2>> pairs;
      s = find_self_intersections(m, pairs);
      if (!s) return fail(kName, s.message);
      std::printf("  level %d: %zu self-intersecting triangle pairs\n", l, pairs.size());
    }
  }
  return 0;
}

Registrar reg({kName,
               "likeness subdiv --mesh FILE [--points FILE] [--levels N] [--radius R] [--max-distance D] "
               "[--min-points N] [--crossings] --out PREFIX",
               "Modified Butterfly hierarchy of a control mesh, displaced onto a scan when --points is given "
               "(jeong2002 Sec. 5); writes PREFIX_level<l>.ply",
               run_subdiv});

}  // namespace
}  // namespace lk::cli
