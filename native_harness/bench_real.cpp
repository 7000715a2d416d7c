// likeness bench --only fit-real: the real scans of ../shared/data (or
// --data DIR) fitted with the defaults, each with copies moved by a hair:
// shifted by 2.5e-4 of its bounding-box diagonal (0.1 mm on a head) along
// x and along y, scaled by 1.0001 and turned by 0.05 degrees about the
// vertical, all about its centroid. A fitted head's crossing count moves by
// tens of pairs under such changes (docs/fit_real.md, "False crossings,
// fold creases, and the eye sockets"), so one fit decides little; the
// copies show the spread. Skipped with a message when the data are absent.
// --fit-crease-trials N, --fit-crease-edges N, --fit-crease-angle DEG: the
// global fit's fold creases (global_fit.h); --fit-head asset|plate|ring|even|back|nape;
// --fit-surface-edges X: the spacing of the samples on the scan's triangles
// in finest-level edges (FitHeadOptions::surface_sample_edges; 0: off);
// --fit-data-level L: the global fit's last passes measure the points
// against Butterfly level L on every scan (GlobalFitOptions::data_level;
// 0: the flat control triangles; without it whole heads use level 1 and
// face captures 0, FitHeadOptions::whole_head_data_level);
// --fit-pleat-steps N: the pleat relief's sweeps (GlobalFitOptions::
// smooth_guard_pleat_steps; 0: off);
// --fit-restore-rings N: the untangling's restore (FitHeadOptions::
// untangle_restore_rings, pipeline/untangle.h; -1: off);
// --fit-hinges-last 0|1: the untangling's erosion leaves the hinges to a
// second pass (FitHeadOptions::untangle_hinges_last; 0: one pass, as
// before 2026-11-24). Each copy's line ends with the untangling's new
// smooth-surface pairs: at the start -> after the erosion -> at the end;
// --fit-real-copies N (1-13, default 5): how many of the copies to fit;
// --fit-real-dump DIR: writes each copy's fitted control mesh, its level L
// and the centroids of level L's crossing triangles (DIR/<scan>_<copy>
// _control.obj, _levelL.obj, _pairs.xyz) to look at: the copies are made in
// memory, and a copy written to a file and fitted again is another draw.
// --fit-back off|face-only|always, --fit-back-weight W: the global fit's
// scan-to-mesh term (FitHeadOptions::back_term). Beside Table 1 it prints
// the other direction: level L's face vertices to the scan's triangles
// where scanned (mean / p99 / max, and the nose's max).
#include "command.h"
#include "fit_table.h"
#include "generic_head_choice.h"
#include "timing.h"

#include "io/io.h"
#include "mesh/geometry.h"
#include "pipeline/fit_head.h"
#include "pipeline/fit_quality.h"
#include "raycast/self_intersection.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace lk::cli {
namespace {

// What --fit-real-dump writes for one copy (header comment); prefix is
// DIR/<scan>_<copy> with spaces as underscores.
Status dump_copy(const std::string& prefix, const FitHeadResult& r) {
  const TriMesh& finest = r.level_meshes.back();
  // The fold limiter's own search of this level when it has not moved
  // since (as measure_fit_quality takes it), else a search.
  std::vector<std::array<int, 2>> pairs;
  Status st;
  if (const auto* known = finest_pairs_of(r.fold_limit, finest.positions))
    pairs = *known;
  else
    st = find_self_intersections(finest, pairs);
  PointCloud centroids;
  for (const auto& p : pairs)
    for (int f : p) {
      const Tri& t = finest.triangles[f];
      centroids.positions.push_back((finest.positions[t[0]] + finest.positions[t[1]] + finest.positions[t[2]]) / 3);
    }
  if (st) st = write_file(prefix + "_control.obj", write_obj(r.control));
  if (st) st = write_file(prefix + "_level" + std::to_string(r.level_meshes.size()) + ".obj", write_obj(finest));
  if (st) st = write_file(prefix + "_pairs.xyz", write_xyz(centroids));
  return st;
}

struct Copy {
  std::string name;
  PointCloud cloud;
};

// The scan and its four nudged copies; with `count` above 5, up to eight
// more (the other directions, axes and sign), as one fit on five copies
// decides little either: a head change that moves James from 0 to 3-18
// pairs on five copies may just be another draw.
std::vector<Copy> nudged_copies(const PointCloud& scan, int count) {
  Vec3 centroid = Vec3::Zero();
  for (const Vec3& p : scan.positions) centroid += p;
  centroid /= std::max(1, scan.size());
  const double shift = 2.5e-4 * bounding_box(scan.positions).diagonal();
  const double turn = 0.05 * 3.14159265358979323846 / 180.0;
  auto turned = [&](double angle, const Vec3& axis) { return Mat3(Eigen::AngleAxisd(angle, axis)); };
  struct Nudge {
    const char* name;
    Mat3 linear;
    Vec3 offset;
  };
  const Mat3 I = Mat3::Identity();
  const Nudge nudges[] = {{"shift x", I, Vec3(shift, 0, 0)},
                          {"shift y", I, Vec3(0, shift, 0)},
                          {"scale 1.0001", 1.0001 * I, Vec3::Zero()},
                          {"turn 0.05 deg", turned(turn, Vec3::UnitY()), Vec3::Zero()},
                          {"shift -x", I, Vec3(-shift, 0, 0)},
                          {"shift -y", I, Vec3(0, -shift, 0)},
                          {"shift z", I, Vec3(0, 0, shift)},
                          {"shift -z", I, Vec3(0, 0, -shift)},
                          {"scale 0.9999", 0.9999 * I, Vec3::Zero()},
                          {"turn -0.05 deg", turned(-turn, Vec3::UnitY()), Vec3::Zero()},
                          {"tilt 0.05 deg", turned(turn, Vec3::UnitX()), Vec3::Zero()},
                          {"roll 0.05 deg", turned(turn, Vec3::UnitZ()), Vec3::Zero()}};
  // The scan itself, bit for bit (p - c + c already changes last bits).
  std::vector<Copy> copies = {Copy{"as given", scan}};
  for (const Nudge& n : nudges) {
    if (static_cast<int>(copies.size()) >= count) break;
    Copy c{n.name, scan};
    for (Vec3& p : c.cloud.positions) p = centroid + n.linear * (p - centroid) + n.offset;
    for (Vec3& q : c.cloud.normals) q = (n.linear * q).normalized();
    copies.push_back(std::move(c));
  }
  return copies;
}

int run(const Args& args) {
  const std::string data = args.get("data", "../shared/data");
  const std::vector<std::pair<std::string, std::string>> scans = {
      {"James (menpo3d face capture, mm)", data + "/head_scans/james_menpo3d/james.obj"},
      {"Fran (Cyberware face patch, m)", data + "/head_scans/fran_cyberware/fran_cut.vtk"}};
  GenericHead generic;
  Status st = choose_generic_head(args.get("fit-head", "asset"), generic);
  if (!st) {
    std::printf("   generic head: %s\n", st.message.c_str());
    return 1;
  }
  // The fold creases' knobs (GlobalFitOptions::smooth_guard_crease_*), to
  // measure them on the copies.
  FitHeadOptions options;
  int copies = 5;
  int hinges_last = options.untangle_hinges_last ? 1 : 0;
  if (!args.get_int("fit-crease-trials", options.global.smooth_guard_crease_trials,
                    options.global.smooth_guard_crease_trials) ||
      !args.get_int("fit-crease-edges", options.global.smooth_guard_crease_max_edges,
                    options.global.smooth_guard_crease_max_edges) ||
      !args.get_double("fit-crease-angle", options.global.smooth_guard_crease_min_angle_deg,
                       options.global.smooth_guard_crease_min_angle_deg) ||
      !args.get_double("fit-surface-edges", options.surface_sample_edges, options.surface_sample_edges) ||
      !args.get_int("fit-data-level", options.global.data_level, options.global.data_level) ||
      !args.get_int("fit-pleat-steps", options.global.smooth_guard_pleat_steps, options.global.smooth_guard_pleat_steps) ||
      !args.get_int("fit-restore-rings", options.untangle_restore_rings, options.untangle_restore_rings) ||
      options.untangle_restore_rings > 8 ||
      !args.get_int("fit-hinges-last", hinges_last, hinges_last) || hinges_last < 0 ||
      hinges_last > 1 ||
      !args.get_int("fit-real-copies", 5, copies) || copies < 1 || copies > 13) {
    std::printf("   --fit-crease-trials / --fit-crease-edges / --fit-data-level / --fit-pleat-steps take a whole number, "
                "--fit-restore-rings one up to 8, --fit-hinges-last 0 or 1, "
                "--fit-real-copies one from 1 to 13, --fit-crease-angle and --fit-surface-edges a number\n");
    return 1;
  }
  options.untangle_hinges_last = hinges_last == 1;
  if (!parse_back_term(args, options)) return 1;
  const std::string dump = args.get("fit-real-dump", "");
  if (args.has("fit-data-level")) options.whole_head_data_level = -1;  // on every scan, as given
  int failures = 0;
  for (const auto& [label, path] : scans) {
    PointCloud scan;
    if (!load_point_cloud_file(path, scan).ok()) {
      std::printf("   skipped %s: %s not found (the real scans live in ../shared/data; --data DIR)\n", label.c_str(),
                  path.c_str());
      continue;
    }
    std::printf("   %s, %d points; likeness fit's defaults\n", label.c_str(), scan.size());
    std::printf("   %-14s %9s %7s %7s %7s %8s %7s %8s %9s   %s\n", "copy", "Table 1 %", "pairs", "lips", "ears",
                "sockets", "rest", "smooth", "wall ms", "level L -> scan where scanned: mean / p99 / max mm, > 1 mm");
    std::vector<int> totals;
    for (const Copy& c : nudged_copies(scan, copies)) {
      double table1 = -1;
      FitStageObserver obs;
      obs.measured = [&](const FitStageReport& r) {
        if (r.name == "subdivision") table1 = r.distance.mean_pct;
      };
      FitHeadResult r;
      const double t0 = wall_clock_ms();
      st = fit_head(c.cloud, generic, options, r, obs);
      const double ms = wall_clock_ms() - t0;
      FitQuality q;
      if (st) st = measure_fit_quality(r, generic.annotations, q);
      if (!st) {
        std::printf("   %-14s failed: %s\n", c.name.c_str(), st.message.c_str());
        ++failures;
        continue;
      }
      const CrossingCounts& x = q.crossings;
      CoveredDistances back;
      double nose_max = 0;
      if (!c.cloud.faces.empty()) {
        // Once, the face; the nose's maximum from the same distances (each
        // vertex is measured on its own, whatever the region).
        std::vector<double> per_vertex;
        std::vector<char> outside_nose;
        st = measure_fit_to_scan(r, c.cloud, generic, back, "face", &per_vertex);
        if (st) st = finest_region_skip(r, generic, "nose", outside_nose);
        if (st)
          for (size_t v = 0; v < per_vertex.size(); ++v)
            if (!outside_nose[v]) nose_max = std::max(nose_max, per_vertex[v]);
        if (!st) std::printf("   %-14s level L -> scan: %s\n", c.name.c_str(), st.message.c_str());
      }
      std::printf("   %-14s %9.5f %7d %7d %7d %8d %7d %8d %9.0f   %.3f / %.2f / %.2f, %d of %d; nose max %.2f; pleats %d -> %d; untangled %d -> %d -> %d\n",
                  c.name.c_str(), table1, x.total, x.lips, x.ears, x.eye_sockets, x.rest, q.smooth_crossings.total, ms,
                  1e3 * back.mean, 1e3 * back.p99, 1e3 * back.max, back.over_1mm, back.vertices, 1e3 * nose_max,
                  r.global_fit.pleats_before, r.global_fit.pleats_after, r.untangle.pairs_before,
                  r.untangle.pairs_eroded, r.untangle.pairs_after);
      if (!dump.empty()) {
        std::string prefix = dump + "/" + label.substr(0, label.find(' ')) + "_" + c.name;
        std::replace(prefix.begin() + static_cast<long>(dump.size()), prefix.end(), ' ', '_');
        st = dump_copy(prefix, r);
        if (!st) std::printf("   %-14s --fit-real-dump: %s\n", "", st.message.c_str());
      }
      if (x.rest) {  // where the rest lie (regions overlap; "face" holds most)
        std::printf("   %-14s rest touches:", "");
        for (const auto& kv : x.rest_by_region) std::printf(" %s %d", kv.first.c_str(), kv.second);
        std::printf("\n");
      }
      totals.push_back(x.total);
    }
    if (!totals.empty()) {
      std::sort(totals.begin(), totals.end());
      std::printf("   pairs over the %zu copies: %d-%d, median %d (target 0 at lips and ears)\n\n", totals.size(),
                  totals.front(), totals.back(), totals[totals.size() / 2]);
    }
  }
  return failures ? 1 : 0;  // absent data is a skip, not a failure
}

BenchRegistrar reg({"fit-real",
                    "real scans (../shared/data) and four copies nudged by a hair: Table 1 and crossing pairs by region",
                    run});

}  // namespace
}  // namespace lk::cli
