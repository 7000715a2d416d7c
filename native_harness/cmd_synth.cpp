// likeness synth-head / synth-scan: ground-truth synthetic heads and virtual
// structured-light scans of them (core/synth), for measuring later stages.
#include "command.h"

#include "head/generic_head.h"
#include "io/io.h"
#include "synth/analytic_head.h"
#include "synth/scanner.h"
#include "synth/synth_head.h"

#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdio>
#include <iostream>
#include <sys/stat.h>

namespace lk::cli {
namespace {

int usage_error(const char* cmd, const std::string& message) {
  fail(cmd, message);
  return 2;
}

// --seed: a non-negative integer that fits 32 bits.
bool get_seed(const char* cmd, const Args& args, std::uint32_t& seed) {
  const std::string v = args.get("seed", "1");
  char* end = nullptr;
  const unsigned long long x = std::strtoull(v.c_str(), &end, 10);
  if (v.empty() || *end != '\0' || v[0] == '-' || x > 0xFFFFFFFFull) {
    fail(cmd, "--seed expects an integer in 0..4294967295, got '" + v + "'");
    return false;
  }
  seed = static_cast<std::uint32_t>(x);
  return true;
}

// The head to deform: the embedded generic head, or the analytic stand-in.
Status base_head(const std::string& which, GenericHead& out) {
  if (which == "generic") return load_generic_head(out);
  if (which == "analytic") {
    out = analytic_head();
    return Status::success();
  }
  return Status::error(ErrorCode::InvalidInput, "--base must be 'generic' or 'analytic', got '" + which + "'");
}

nlohmann::json vec(const Vec3& v) { return {v.x(), v.y(), v.z()}; }

int run_synth_head(const Args& args) {
  const char* cmd = "synth-head";
  if (!only_known_options(cmd, args, {"seed", "out", "annotations", "base", "variation"})) return 2;
  std::uint32_t seed = 0;
  if (!get_seed(cmd, args, seed)) return 2;
  const std::string out = args.get("out");
  if (out.empty()) return usage_error(cmd, "--out FILE.obj is required");
  SynthHeadOptions opt;
  if (!args.get_double("variation", 1.0, opt.variation, 0, 10)) return 2;
  GenericHead generic, head;
  Status s = base_head(args.get("base", "generic"), generic);
  if (!s) return fail(cmd, s.message);
  SynthHeadParams params;
  s = synthesize_head(generic, seed, opt, head, &params);
  if (!s) return fail(cmd, s.message);
  s = write_file(out, write_obj(head.mesh));
  if (!s) return fail(cmd, s.message);
  if (args.has("annotations")) {
    const std::string ann = args.get("annotations");
    if (ann.empty()) return usage_error(cmd, "--annotations needs a file name");
    s = write_file(ann, head_annotations_to_json(head.annotations, head.mesh.num_vertices()));
    if (!s) return fail(cmd, s.message);
  }
  std::cout << "synth-head: seed " << seed << ", " << head.mesh.num_vertices() << " vertices, "
            << head.mesh.num_triangles() << " triangles -> " << out << "\n  ";
  for (const auto& [name, v] : params.values) std::printf("%s %+.4f  ", name.c_str(), v);
  std::cout << "\n";
  return 0;
}

int run_synth_scan(const Args& args) {
  const char* cmd = "synth-scan";
  if (!only_known_options(cmd, args, {"seed", "out", "points", "noise-mm", "base", "outliers", "stations",
                               "arc", "levels", "detail-mm"}))
    return 2;
  std::uint32_t seed = 0;
  if (!get_seed(cmd, args, seed)) return 2;
  const std::string dir = args.get("out");
  if (dir.empty()) return usage_error(cmd, "--out DIR is required");
  ScannerOptions so;
  TruthOptions to;
  double noise_mm = 0, detail_mm = 0;
  if (!args.get_int("points", so.target_points, so.target_points, 1, 50000000) ||
      !args.get_double("noise-mm", so.noise_sigma_m * 1000, noise_mm, 0, 100) ||
      !args.get_double("outliers", so.outlier_fraction, so.outlier_fraction, 0, 1) ||
      !args.get_int("stations", so.stations, so.stations, 1, 64) ||
      !args.get_double("arc", so.arc_degrees, so.arc_degrees, 0, 360) ||
      !args.get_int("levels", to.subdivision_levels, to.subdivision_levels, 0, 5) ||
      !args.get_double("detail-mm", to.detail_amplitude_m * 1000, detail_mm, 0, 100))
    return 2;
  so.noise_sigma_m = noise_mm / 1000;
  to.detail_amplitude_m = detail_mm / 1000;
  ::mkdir(dir.c_str(), 0755);
  struct stat st;
  if (::stat(dir.c_str(), &st) != 0 || !S_ISDIR(st.st_mode))
    return fail(cmd, "cannot create the output folder '" + dir + "'");

  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  GenericHead generic, head;
  Status s = base_head(args.get("base", "generic"), generic);
  if (!s) return fail(cmd, s.message);
  SynthHeadParams params;
  s = synthesize_head(generic, seed, {}, head, &params);
  if (!s) return fail(cmd, s.message);
  const auto t1 = Clock::now();
  TruthSurface truth;
  s = make_truth_surface(head, seed, to, truth);
  if (!s) return fail(cmd, s.message);
  const auto t2 = Clock::now();
  so.hair_triangles = truth.hair;
  so.look = head.annotations.look;
  so.up = head.annotations.up;
  PointCloud cloud;
  ScanStats stats;
  s = scan_virtual(truth.mesh, so, seed, cloud, &stats);
  if (!s) return fail(cmd, s.message);
  const auto t3 = Clock::now();
  auto ms = [](Clock::time_point a, Clock::time_point b) {
    return std::chrono::duration<double, std::milli>(b - a).count();
  };

  const std::string p = dir + "/";
  for (const auto& [file, status] :
       {std::pair<std::string, Status>{"scan.ply", write_file(p + "scan.ply", write_ply(cloud))},
        {"truth.obj", write_file(p + "truth.obj", write_obj(truth.mesh))},
        {"truth_control.obj", write_file(p + "truth_control.obj", write_obj(head.mesh))},
        {"truth_annotations.json",
         write_file(p + "truth_annotations.json",
                    head_annotations_to_json(head.annotations, head.mesh.num_vertices()))}})
    if (!status) return fail(cmd, file + ": " + status.message);

  nlohmann::json info;
  info["seed"] = seed;
  info["base"] = args.get("base", "generic");
  info["points"] = stats.points;
  info["outliers"] = stats.outliers;
  info["hair_junk"] = stats.junk;
  info["noise_sigma_m"] = so.noise_sigma_m;
  info["outlier_fraction_requested"] = so.outlier_fraction;
  info["outlier_offset_m"] = so.outlier_offset_m;
  info["max_incidence_deg"] = so.max_incidence_deg;
  info["truth"] = {{"vertices", truth.mesh.num_vertices()},
                   {"triangles", truth.mesh.num_triangles()},
                   {"subdivision_levels", to.subdivision_levels},
                   {"detail_amplitude_m", to.detail_amplitude_m},
                   {"detail_wavelength_m", to.detail_wavelength_m}};
  nlohmann::json par = nlohmann::json::object();
  for (const auto& [name, v] : params.values) par[name] = v;
  info["head_parameters"] = par;
  nlohmann::json stations = nlohmann::json::array();
  for (const ScannerStation& t : stats.stations)
    stations.push_back({{"camera", vec(t.camera)}, {"projector", vec(t.projector)},
                        {"forward", vec(t.forward)}, {"right", vec(t.right)}, {"up", vec(t.up)},
                        {"azimuth_deg", t.azimuth_deg}, {"elevation_deg", t.elevation_deg},
                        {"half_fov_tan", t.half_fov_tan}, {"grid", t.grid},
                        {"rays", t.rays}, {"misses", t.misses}, {"back_facing", t.back_facing},
                        {"grazing", t.grazing}, {"shadowed", t.shadowed}, {"hair", t.hair},
                        {"points", t.points}, {"outliers", t.outliers}, {"junk", t.junk}});
  info["stations"] = stations;
  s = write_file(p + "scan_info.json", info.dump(2) + "\n");
  if (!s) return fail(cmd, s.message);

  std::printf("synth-scan: seed %u -> %s\n", seed, dir.c_str());
  std::printf("  head %d vertices; truth %d vertices, %d triangles (%d Loop levels, detail %.2f mm)\n",
              head.mesh.num_vertices(), truth.mesh.num_vertices(), truth.mesh.num_triangles(),
              to.subdivision_levels, to.detail_amplitude_m * 1000);
  std::printf("  scan %d points (%d misregistered, %d hair junk), noise %.3f mm, %zu stations, grid %d^2\n",
              stats.points, stats.outliers, stats.junk, so.noise_sigma_m * 1000, stats.stations.size(),
              stats.stations.empty() ? 0 : stats.stations[0].grid);
  std::printf("  time: head %.0f ms, truth %.0f ms, scan %.0f ms\n", ms(t0, t1), ms(t1, t2), ms(t2, t3));
  return 0;
}

Registrar reg_head({"synth-head",
                    "likeness synth-head --seed N --out FILE.obj [--annotations FILE.json] "
                    "[--base generic|analytic] [--variation 1.0]",
                    "a ground-truth head: the generic head deformed the way people differ (per seed)",
                    run_synth_head});
Registrar reg_scan({"synth-scan",
                    "likeness synth-scan --seed N --out DIR [--points 300000] [--noise-mm 0.2] "
                    "[--outliers 0.005] [--stations 6] [--arc 200] [--levels 2] [--detail-mm 0.5] "
                    "[--base generic|analytic]",
                    "a virtual structured-light scan of a synthetic head: DIR/scan.ply, truth.obj, "
                    "truth_control.obj, truth_annotations.json, scan_info.json",
                    run_synth_scan});

}  // namespace
}  // namespace lk::cli
