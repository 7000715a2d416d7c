// likeness make-generic-head: regenerates the generic head asset
// (core/head/data/generic_head.{obj,json}) from core/head/generic_head_builder.
#include "command.h"

#include "head/generic_head.h"
#include "head/generic_head_builder.h"
#include "io/io.h"
#include "mesh/geometry.h"
#include "mesh/topology.h"

#include <sys/stat.h>

#include <cstdio>
#include <iostream>

namespace lk::cli {
namespace {

const char* kName = "make-generic-head";

int run_make_generic_head(const Args& args) {
  if (!only_known_options(kName, args, {"out", "ring-ear", "plate-ear", "even-eye-corners", "face-rows-at-back", "nape-by-shape"})) return 2;
  const std::string out_dir = args.get("out");
  if (out_dir.empty()) {
    fail(kName, "--out DIR is required (the asset lives in core/head/data)");
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
  // asset's rows behind the ears before they were evened (docs/generic_head.md).
  if (args.has("face-rows-at-back")) options.even_back_rows = false;
  // --nape-by-shape: GenericHeadBuildOptions::regular_nape off, the asset's
  // nape and neck before they were made regular (quads split by shape).
  if (args.has("nape-by-shape")) options.regular_nape = false;
  ::mkdir(out_dir.c_str(), 0755);  // as `likeness fit` does; an existing one is kept
  GenericHead head;
  Status s = build_generic_head(options, head);
  if (!s) return fail(kName, s.message);

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

Registrar reg({kName, "likeness make-generic-head --out DIR [--ring-ear|--plate-ear] [--even-eye-corners] [--face-rows-at-back] [--nape-by-shape]",
               "builds the generic head control mesh + annotations (writes generic_head.obj/.json)",
               run_make_generic_head});

}  // namespace
}  // namespace lk::cli
