// likeness fit: scan -> fitted control mesh + displaced Butterfly levels
// (jeong2002 Sec. 4-5), with the paper's Table 1 printed beside ours.
#include "command.h"
#include "fit_table.h"
#include "generic_head_choice.h"
#include "head/generic_head.h"
#include "io/io.h"
#include "project/export.h"
#include "project/fit_job.h"
#include "project/project_file.h"
#include "project/quality_job.h"
#include "scan_axes_option.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <sys/stat.h>

namespace lk::cli {
namespace {

int run_fit(const Args& args) {
  const std::string cmd = "fit";
  if (!only_known_options(cmd, args,
                          {"scan", "out", "levels", "up", "facing", "no-orientation-check", "face-only", "whole-head",
                           "no-eye-region", "scanned-neck", "no-scanned-neck", "neck-reach", "denoise", "no-denoise", "widen-footprints", "data-level", "dump",
                           "scan-frame", "generic-head", "project", "no-project", "thin-cells"}))
    return 2;
  const std::string scan_path = args.get("scan"), out_dir = args.get("out");
  if (scan_path.empty() || out_dir.empty()) return fail(cmd, "needs --scan FILE and --out DIR");
  FitHeadOptions opt;
  if (!args.get_int("levels", 3, opt.levels, 0, 5)) return 2;
  // Dense clouds on cell averages (FitHeadOptions::thin_cells_per_edge; off by default).
  if (!args.get_double("thin-cells", 0, opt.thin_cells_per_edge, 0, 64)) return 2;
  std::optional<Vec3> up, facing;
  if (!get_scan_axes(cmd, args, up, facing)) return 1;
  opt.up = up.value_or(opt.up);
  opt.facing = facing.value_or(opt.facing);
  // Conventions the user gave are checked, not overridden: a scan that
  // clearly fits better otherwise is refused with the flags to pass.
  if (up || facing) opt.orientation_check = FitHeadOptions::OrientationCheck::Hint;
  if (args.has("no-orientation-check")) opt.orientation_check = FitHeadOptions::OrientationCheck::Off;
  if (args.has("face-only") && args.has("whole-head")) return fail(cmd, "give --face-only or --whole-head, not both");
  if (args.has("face-only")) opt.scan_kind = FitHeadOptions::ScanKind::FaceOnly;
  if (args.has("whole-head")) opt.scan_kind = FitHeadOptions::ScanKind::WholeHead;
  if (args.has("no-eye-region")) opt.fit_eye_region = false;  // see FitHeadOptions
  // FitHeadOptions::fit_scanned_neck (on by default; --scanned-neck is accepted)
  if (args.has("scanned-neck") && args.has("no-scanned-neck"))
    return fail(cmd, "give --scanned-neck or --no-scanned-neck, not both");
  if (args.has("scanned-neck")) opt.fit_scanned_neck = true;
  if (args.has("no-scanned-neck")) opt.fit_scanned_neck = false;
  // FitHeadOptions::scanned_neck_reach (off by default)
  if (args.has("neck-reach")) opt.scanned_neck_reach = true;
  // Denoising of the finest level's displacements by smoothing over the mesh
  // (DisplacementOptions::smooth_*) is on by default; --denoise (its name
  // when it was opt-in) is accepted and changes nothing.
  if (args.has("denoise") && args.has("no-denoise")) return fail(cmd, "give --denoise or --no-denoise, not both");
  if (args.has("no-denoise")) opt.displacement.smooth_finest_levels = 0;
  // The earlier opt-in: level-L footprints widened against the scan's noise
  // (up to 128 points each; about +0.3 s, docs/journal.md).
  if (args.has("widen-footprints")) opt.displacement.max_footprint_points = 128;
  // The global fit's passes on all points measure the scan against the
  // control mesh's Butterfly level L: by default 1 on whole-head scans and
  // 0 (its flat triangles, the paper's) on face-only captures, where level
  // 1 raised the crossing pairs at James's ears (FitHeadOptions::
  // whole_head_data_level, docs/journal.md). --data-level L: L on any scan.
  if (args.has("data-level")) {
    if (!args.get_int("data-level", 0, opt.global.data_level, 0, 2)) return 2;
    opt.whole_head_data_level = -1;
  }
  const bool dump = args.has("dump"), scan_frame = args.has("scan-frame");
  // --project FILE: the whole head project as one GLB (project_file.h), for
  // `likeness project`, `likeness texture --project` and the page.
  // Written to DIR/head.likeness.glb unless --project names another file or
  // --no-project asks for none (`likeness export --head DIR` reads it).
  const std::string project_path = args.has("no-project") ? std::string()
                                   : args.get("project", out_dir + "/head.likeness.glb");
  if (args.has("project") && args.get("project").empty()) return fail(cmd, "--project needs a file name, e.g. head.likeness.glb");

  PointCloud scan;
  Status st = load_point_cloud_file(scan_path, scan);
  if (!st) return fail(cmd, st.message);
  // --generic-head plate|ring: a builder variant instead of the committed
  // asset, to measure a generic head change on real scans before shipping it.
  GenericHead generic;
  st = choose_generic_head(args.get("generic-head", "asset"), generic);
  if (!st) return fail(cmd, "generic head: " + st.message);
  ::mkdir(out_dir.c_str(), 0755);

  std::vector<TimedStage> stages;
  StageClock timer;
  FitStageObserver obs;
  HeadProject project;
  auto write_mesh = [&](const std::string& name, const TriMesh& m, bool fitted) {
    const TriMesh w = (scan_frame && fitted) ? project.frame.to_scan(m) : m;
    const Status s = write_file(out_dir + "/" + name, write_obj(w));
    if (!s) std::cerr << "likeness fit: warning: " << s.message << "\n";
  };
  obs.started = [&](const std::string& name) {
    std::printf("  %s ...\n", name.c_str());
    std::fflush(stdout);
    timer.start();
  };
  obs.finished = [&](const std::string& name, const TriMesh& surface) {
    TimedStage s;
    s.name = name;
    timer.stop(s);
    stages.push_back(s);
    if (dump && !scan_frame) write_mesh("stage_" + name + ".obj", surface, false);
  };
  obs.measured = [&](const FitStageReport& rep) {
    for (auto& s : stages)
      if (s.name == rep.name) s.distance = rep.distance;
  };

  std::printf("likeness fit: %s (%d points), %d levels\n", scan_path.c_str(), scan.size(), opt.levels);
  st = fit_project(std::move(scan), generic, opt, project, obs);
  const FitHeadResult& r = project.fit;
  for (const std::string& note : r.notes) std::printf("  note: %s\n", note.c_str());
  if (!st) {
    write_file(out_dir + "/report.json", fit_report_json(r, stages, std::string(to_string(st.code)) + ": " + st.message));
    return fail(cmd, scan_path + ": " + std::string(to_string(st.code)) + ": " + st.message);
  }
  std::printf("  unit: %s (bbox diagonal %.4g scan units = %.3f m), %d of %d points above the neck cut\n",
              r.unit_to_metres == 1 ? "m" : r.unit_to_metres == 0.01 ? "cm" : "mm", r.bbox_diagonal,
              r.bbox_diagonal * r.unit_to_metres, r.fitted_points, r.points);
  if (r.surface_samples.samples > 0)
    std::printf("  scan triangles: %d samples on %d of them measured with the points (%d dense enough, %d too long)\n",
                r.surface_samples.samples, r.surface_samples.triangles_sampled, r.surface_samples.triangles_dense,
                r.surface_samples.triangles_skipped_long);
  print_fit_table(stages);
  // Checked after the fit and outside its timed stages: the user learns
  // whether the head crosses itself before animating it, and how far the
  // face lies from the scan (a bulge away from it shows only that way).
  st = measure_project_quality(project, generic);
  if (!st) return fail(cmd, st.message);
  const ProjectQuality& q = project.quality;
  if (q.status) print_fit_quality(q.fit);
  else std::cerr << "likeness fit: warning: quality check: " << q.status.message << "\n";
  if (q.to_scan_status) print_fit_to_scan(q.to_scan, r.multires.num_levels());
  else std::cerr << "likeness fit: warning: face to scan: " << q.to_scan_status.message << "\n";

  write_mesh("control.obj", r.control, true);
  if (q.to_scan_status) {  // the finest level coloured by each vertex's distance
    Bytes map;
    Status s = export_level(project, r.multires.num_levels(), LevelFormat::DistanceMap,
                            scan_frame ? ExportFrame::Scan : ExportFrame::Head, map);
    if (s) s = write_file(out_dir + "/face_to_scan.ply", map);
    if (!s) std::cerr << "likeness fit: warning: " << s.message << "\n";
  }
  for (size_t l = 0; l < r.level_meshes.size(); ++l)
    write_mesh("level" + std::to_string(l + 1) + ".obj", r.level_meshes[l], true);
  if (dump && scan_frame) {
    write_mesh("stage_initial_alignment.obj", r.aligned, true);
    write_mesh("stage_local_fitting.obj", r.local, true);
    write_mesh("stage_global_fitting.obj", r.control, true);
  }
  st = write_file(out_dir + "/report.json", fit_report_json(r, stages, "ok", q.status ? &q.fit : nullptr,
                                                                   q.to_scan_status ? &q.to_scan : nullptr));
  if (!st) return fail(cmd, st.message);
  std::printf("  wrote %s/control.obj, level1..%d.obj, %sreport.json (%s frame)\n", out_dir.c_str(), opt.levels,
              q.to_scan_status ? "face_to_scan.ply (the finest level's distance map), " : "",
              scan_frame ? "scan" : "head: metres, +y up, +z facing");
  if (!project_path.empty()) {
    Bytes bytes;
    st = save_project(project, bytes);
    if (st) st = write_file(project_path, bytes);
    if (!st) return fail(cmd, st.message);
    std::printf("  wrote %s (the head project, %.1f MB: `likeness project info %s`)\n", project_path.c_str(),
                bytes.size() / 1e6, project_path.c_str());
  }
  return 0;
}

Registrar reg({"fit",
               "likeness fit --scan FILE --out DIR [--levels L] [--up X Y Z|+x..-z] [--facing X Y Z|+x..-z] "
               "[--no-orientation-check] [--face-only|--whole-head] [--no-eye-region] [--no-scanned-neck] [--neck-reach] [--no-denoise] [--widen-footprints] [--data-level 0|1|2] "
               "[--thin-cells X] [--dump] [--scan-frame] [--generic-head asset|plate|ring|even|back|nape|wide-mouth|nostrils|unfaired|fair-N] [--project FILE.likeness.glb | --no-project]",
               "fits the generic head to a scan (jeong2002): control.obj, level1..L.obj, report.json and the head "
               "project head.likeness.glb (--project elsewhere, --no-project none)",
               run_fit});

}  // namespace
}  // namespace lk::cli
