// likeness make-generic-head: regenerates the generic head asset
// (core/head/data/generic_head.{obj,json}) from core/head/generic_head_builder.
#include <cstdlib>
#include "command.h"

#include "head/generic_head.h"
#include "head/generic_head_builder.h"
#include "head/head_creases.h"
#include "head/skin_detail.h"
#include "head/surface_quality.h"
#include "io/io.h"
#include "mesh/geometry.h"
#include "mesh/topology.h"
#include "multires/multires.h"

#include <sys/stat.h>

#include <cstdio>
#include <iostream>

namespace lk::cli {
namespace {

const char* kName = "make-generic-head";

int run_make_generic_head(const Args& args) {
  if (!only_known_options(kName, args, {"out", "report", "level3", "ring-ear", "plate-ear", "even-eye-corners", "face-rows-at-back", "nape-by-shape", "wide-mouth-ring", "diagonals-by-side", "fair", "fair-rim-rings", "nostrils", "teeth-mouth-bag", "skin-detail"})) return 2;
  const std::string out_dir = args.get("out");
  const bool report = args.has("report");
  const std::string level3_path = args.get("level3");
  if (out_dir.empty() && !report && level3_path.empty()) {
    fail(kName, "--out DIR is required (the asset lives in core/head/data), or --report / --level3 FILE");
    return 2;
  }
  // --ring-ear / --plate-ear: the builder's ear choice instead of its
  // default (GenericHeadBuildOptions::ring_ear), to look at or measure one.
  if (args.has("ring-ear") && args.has("plate-ear")) {
    fail(kName, "give --ring-ear or --plate-ear, not both");
    return 2;
  }
  GenericHeadBuildOptions options;
  if (args.has("ring-ear")) options.ring_ear = true;
  if (args.has("plate-ear")) options.ring_ear = false;
  // --even-eye-corners: GenericHeadBuildOptions::even_eye_corners, the
  // builder's default and the asset's since 3a8dc46 (the flag is kept so
  // older command lines still run).
  if (args.has("even-eye-corners")) options.even_eye_corners = true;
  // --face-rows-at-back: GenericHeadBuildOptions::even_back_rows off, the
  // asset's rows behind the ears before they were evened (docs/journal.md).
  if (args.has("face-rows-at-back")) options.even_back_rows = false;
  // --nape-by-shape: GenericHeadBuildOptions::regular_nape off, the asset's
  // nape and neck before they were made regular (quads split by shape).
  if (args.has("nape-by-shape")) options.regular_nape = false;
  // --wide-mouth-ring: GenericHeadBuildOptions::wide_mouth_ring on (not
  // the asset's yet); --diagonals-by-side: mirror_diagonals off, the
  // asset's triangles before issue 35.
  if (args.has("wide-mouth-ring")) options.wide_mouth_ring = true;
  if (args.has("diagonals-by-side")) options.mirror_diagonals = false;
  // --nostrils: GenericHeadBuildOptions::nostrils (open nostrils with
  // shallow pockets; not the asset's yet).
  if (args.has("nostrils")) options.nostrils = true;
  // --teeth-mouth-bag: GenericHeadBuildOptions::teeth_mouth_bag (the bag
  // round the placed teeth; not the asset's).
  if (args.has("teeth-mouth-bag")) options.teeth_mouth_bag = true;
  // --fair N: GenericHeadBuildOptions::fair_iterations (0, the asset's:
  // the skin as cast; 3 measured for issue 35, not landed).
  if (args.has("fair")) {
    options.fair_iterations = std::atoi(args.get("fair").c_str());
    if (options.fair_iterations < 0 || options.fair_iterations > 100) return fail(kName, "--fair needs 0..100 passes");
  }
  // --fair-rim-rings K: GenericHeadBuildOptions::fair_keep_rim_rings (the
  // K rings round the eye rims and lip lines kept as cast; session 50).
  if (args.has("fair-rim-rings")) {
    options.fair_keep_rim_rings = std::atoi(args.get("fair-rim-rings").c_str());
    if (options.fair_keep_rim_rings < 0 || options.fair_keep_rim_rings > 10)
      return fail(kName, "--fair-rim-rings needs 0..10 rings");
  }
  GenericHead head;
  Status s = build_generic_head(options, head);
  if (!s) return fail(kName, s.message);
  if (!out_dir.empty()) ::mkdir(out_dir.c_str(), 0755);  // as `likeness fit` does; an existing one is kept
  // --skin-detail: the report and level 3 with the head's skin detail
  // (head/skin_detail.h) as displacements, the surface a photos head starts from.
  const ButterflyCreases creases = head_creases(head.mesh, head.annotations);
  std::vector<std::vector<double>> detail;
  if (args.has("skin-detail") && (report || !level3_path.empty())) {
    s = generic_skin_detail(head, 3, SkinDetailOptions{}, detail);
    if (!s) return fail(kName, s.message);
  }
  const std::vector<std::vector<double>>* with_detail = detail.empty() ? nullptr : &detail;
  // --report: the smooth level 3's roughness per region and every level's
  // crossing pairs (head/surface_quality.h), the issue-35 figures.
  if (report) {
    HeadSurfaceQuality q;
    s = measure_head_surface(head, creases, 3, q, with_detail);
    if (!s) return fail(kName, s.message);
    std::printf("smooth level %d with the head's creases (rims, canthi, socket rings), angle between adjacent triangles' normals (deg):\n", q.level);
    std::printf("  %-7s %6s %6s %6s %6s %6s\n", "region", "edges", "mean", "p95", "p99", "max");
    for (const RegionRoughness& r : q.regions)
      std::printf("  %-7s %6d %6.2f %6.2f %6.2f %6.2f\n", r.region.c_str(), r.edges, r.mean_deg, r.p95_deg,
                  r.p99_deg, r.max_deg);
    std::printf("self-intersecting triangle pairs, level 0..%d:", q.level);
    for (int n : q.crossing_pairs) std::printf(" %d", n);
    std::printf("\n");
  }
  // --level3 FILE: that smooth level 3 as a mesh, to render and look at.
  if (!level3_path.empty()) {
    MultiresMesh smooth;
    s = build_multires(head.mesh, creases, 3, smooth);
    if (s && with_detail) s = apply_skin_detail(detail, smooth);
    if (s) s = write_file(level3_path, write_obj(level_mesh(smooth, 3)));
    if (!s) return fail(kName, s.message);
    std::printf("wrote %s\n", level3_path.c_str());
  }
  if (out_dir.empty()) return 0;

  const std::string obj_path = out_dir + "/generic_head.obj";
  const std::string json_path = out_dir + "/generic_head.json";
  s = write_file(obj_path, write_obj(head.mesh));
  if (!s) return fail(kName, s.message);
  s = write_file(json_path, head_annotations_to_json(head.annotations, head.mesh.num_vertices()));
  if (!s) return fail(kName, s.message);

  MeshTopology topo;
  s = build_topology(head.mesh, topo);
  if (!s) return fail(kName, s.message);
  const BBox box = bounding_box(head.mesh.positions);
  std::printf("generic head: %d vertices, %d triangles, %zu boundary loop(s), Euler characteristic %d\n",
              head.mesh.num_vertices(), head.mesh.num_triangles(), topo.boundary_loops.size(),
              euler_characteristic(topo, head.mesh.num_triangles()));
  std::printf("bounding box (m): x %.3f..%.3f  y %.3f..%.3f  z %.3f..%.3f\n", box.min.x(), box.max.x(),
              box.min.y(), box.max.y(), box.min.z(), box.max.z());
  std::printf("wrote %s and %s\n", obj_path.c_str(), json_path.c_str());
  return 0;
}

Registrar reg({kName, "likeness make-generic-head --out DIR [--report] [--level3 FILE.obj] [--ring-ear|--plate-ear] [--even-eye-corners] [--face-rows-at-back] [--nape-by-shape] [--wide-mouth-ring] [--diagonals-by-side] [--fair N [--fair-rim-rings K]] [--nostrils] [--teeth-mouth-bag] [--skin-detail]",
               "builds the generic head control mesh + annotations (writes generic_head.obj/.json; --report: smooth level 3 roughness by region, crossing pairs by level; --level3: that level as a mesh; --skin-detail: both with the skin detail a photos head starts from)",
               run_make_generic_head});

}  // namespace
}  // namespace lk::cli
