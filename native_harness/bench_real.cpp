// likeness bench --only fit-real: every real scan under ../shared/data/
// head_scans (or --data DIR; --fit-real-scan NAME: those whose folder/file
// holds NAME) fitted with the defaults. Per scan: Table 1 (mean, max), the
// scan's own noise floor in the same measure (fit/scan_noise.h: what its
// true surface would score), the finest level's crossing pairs by region,
// the face of the finest level to the scan where scanned (mean / p99 /
// max), the scanned neck below the cut to the fitted neck (points, median /
// p90), and the fit's CPU time (all threads); then one summary line per
// scan (docs/design/fit_real_scans.md). Skipped with a message when the data are
// absent.
// --fit-real-copies N (1-13, default 1): the scan and copies moved by a
// hair: shifted by 2.5e-4 of its bounding-box diagonal (0.1 mm on a head)
// along x and along y, scaled by 1.0001, turned by 0.05 degrees about the
// vertical, ..., all about its centroid. A fitted head's crossing count
// moves by tens of pairs under such changes (docs/journal.md, "False
// crossings, fold creases, and the eye sockets"), so one fit decides
// little; the copies show the spread.
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
// second pass (FitHeadOptions::untangle_hinges_last);
// --fit-real-dump DIR: writes each copy's fitted control mesh, its level L
// and the centroids of level L's crossing triangles (DIR/<folder>_<copy>
// _control.obj, _levelL.obj, _pairs.xyz) to look at: the copies are made in
// memory, and a copy written to a file and fitted again is another draw.
// --fit-back off|face-only|always, --fit-back-weight W: the global fit's
// scan-to-mesh term (FitHeadOptions::back_term).
// --fit-real-no-scanned-neck: the scanned neck below the cut is not fitted
// (FitHeadOptions::fit_scanned_neck off: the figures before it was the
// default); --fit-real-scanned-neck: on (the default).
// --fit-real-stages: per copy, Table 1 after each stage, the local fit's
// points per box, the global fit's guards, the untangling, the crossing
// guard and the control faces the untangling left crossing (to find where
// two generic heads' fits part: docs/design/generic_head.md, session 50).
// --fit-real-copy NAME: only the copies whose name holds NAME ("turn").
// --fit-real-dense: the copies of dense_copies instead (the same surface
// sampled 4 and 16 times as densely; with --fit-real-dense-x64 also 64
// times, a full-resolution scan's 0.4-0.6 million vertices: slow).
// --fit-real-surface-cells F: every
// copy fitted on its surface's cell averages over cells of F times its
// diagonal (pipeline/scan_thinning.h), an input nearly free of how the
// surface was tessellated.
// --fit-real-sweep: the copies of swept_copies instead (shifts along each
// axis, turns of 0.05-5 deg about each axis); every copy prints where its
// alignment put the head against the as-given copy's (turn, scale,
// vertices apart) and which path it took. --fit-real-cube: the scan in
// each of the 24 right-angle orientations about its centroid (which way
// its up and facing point), as a held-out scan may come; with
// --fit-real-align-only each says whether the pose found is the as-given
// copy's. --fit-real-align-only: stops
// each fit once its alignment is final (the alignment's figures only).
// --fit-ear-refit-rounds N: the ear refit's warm rounds
// (FitHeadOptions::ear_refit_warm_rounds; 0: the whole fit again, cold).
// --fit-ear-refit-late: the ear refit decided after each fit's guard
// (FitHeadOptions::ear_refit_after_rounds off), to compare.
// --fit-neck-guard 0|1: the scanned neck's fit with the smooth-surface
// guard (FitHeadOptions::scanned_neck_smooth_guard).
// --fit-neck-reach 0|1: a scanned neck beyond the head fit's trimming
// distance fitted to its own points first (FitHeadOptions::scanned_neck_reach).
// --fit-ear-give-up N: the bound ear refit given up after its rounds when
// its ears cross there in more than N pairs
// (FitHeadOptions::ear_refit_give_up_pairs; 0: judged at its end).
// --fit-untangle-level K: the whole heads' untangling level
// (FitHeadOptions::untangle_level; 0: off); --fit-guard-others 0|1: the
// guard's steps for the pairs away from the lips and ears
// (FitHeadOptions::guard_other_crossings); --fit-guard-remeasure 0|1:
// the detail measured again where the guard moved control vertices
// (FitHeadOptions::guard_remeasure); --fit-pleat-undo 0|1: pleat steps
// undone where the untangled level still crosses
// (FitHeadOptions::pleat_undo_where_crossing); --fit-guard-by-cost 0|1
// and --fit-guard-cost-tries N: the guard's step chosen by what it loses
// among the first that helps and N after it
// (FitHeadOptions::guard_choose_by_cost, guard_cost_extra_tries).
// --fit-face-screen I,K: the face refinement's starts screened after I
// iterations, the K best going on (FaceRefineOptions::screen_iterations,
// screen_keep; 0: off); --fit-face-symmetry 0|1: the face's symmetric
// turn as a start and in the choice of its pitch
// (FaceRefineOptions::symmetry_yaw_start; off by default); --fit-face-frame 0|1: the result turned to
// the aligned face's look (FitHeadOptions::face_frame; off by default); --fit-orient-screen-points N: the orientation
// check's screening on N of its samples (OrientationOptions::screen_points);
// --fit-orient-screen-keep K: the K best screened starts go on
// (OrientationOptions::screen_keep); --fit-orient-retry 0|1: the search run
// again unscreened when the alignment is refused
// (FitHeadOptions::orientation_retry_unscreened); --fit-orient-surface-retry
// X: the second search on a refused mesh's surface, cells of X of its
// diagonal (FitHeadOptions::orientation_surface_retry_cell; 0: off);
// --fit-dense-retry X: a dense mesh still refused aligned again on cells
// of X of its diagonal (FitHeadOptions::dense_mesh_retry_cell; 0: off);
// --fit-face-match-edge X: the face matched to the vertices of a mesh whose
// mean edge is under X of its diagonal (FitHeadOptions::
// face_match_vertices_edge; 0: always its triangles); --fit-z-up-hint 0|1: a
// scan refused in the default axes aligned again with +z up, for the
// refusal to name those axes (FitHeadOptions::suggest_z_up).
// With --fit-real-align-only each copy's pose line also prints the final
// map and the orientation check's outcome, to compare two runs to the bit.
#include "command.h"
#include "fit_table.h"
#include "generic_head_choice.h"
#include "timing.h"

#include "align/face_symmetry.h"
#include "fit/scan_noise.h"
#include "io/io.h"
#include "mesh/geometry.h"
#include "mesh/midpoint_split.h"
#include "pipeline/fit_head.h"
#include "pipeline/fit_quality.h"
#include "pipeline/scan_thinning.h"
#include "raycast/self_intersection.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

namespace lk::cli {
namespace {

// Issue 35: the fit of a real scan (about 200k points with its triangles
// sampled) in under 2 s of process CPU.
constexpr double kRealCpuTargetS = 2.0;

// What --fit-real-dump writes for one copy (header comment); prefix is
// DIR/<scan>_<copy> with spaces as underscores.
Status dump_copy(const std::string& prefix, const FitHeadResult& r) {
  const TriMesh& finest = r.level_meshes.back();
  std::vector<std::array<int, 2>> pairs;
  Status st = finest_crossing_pairs(r.fold_limit, finest, pairs);
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
  Mat3 linear = Mat3::Identity();  // copy point = centroid + linear * (p - centroid) + offset
  Vec3 offset = Vec3::Zero();
  Vec3 centroid = Vec3::Zero();
};

// --fit-real-sweep: the scan, shifted by 2.5e-4 of its diagonal along each
// axis, and turned by 0.05, 0.5, 2 and 5 degrees about x (tilt), y (turn)
// and z (roll), about its centroid: a fit must land in the same basin on
// all of them (issue 35).
std::vector<Copy> swept_copies(const PointCloud& scan) {
  Vec3 centroid = Vec3::Zero();
  for (const Vec3& p : scan.positions) centroid += p;
  centroid /= std::max(1, scan.size());
  const double shift = 2.5e-4 * bounding_box(scan.positions).diagonal();
  std::vector<Copy> copies = {Copy{"as given", scan, Mat3::Identity(), Vec3::Zero(), centroid}};
  auto add = [&](const std::string& name, const Mat3& linear, const Vec3& offset) {
    Copy c{name, scan, linear, offset, centroid};
    for (Vec3& p : c.cloud.positions) p = centroid + linear * (p - centroid) + offset;
    for (Vec3& q : c.cloud.normals) q = (linear * q).normalized();
    copies.push_back(std::move(c));
  };
  const char* axes[3] = {"tilt", "turn", "roll"};
  for (int a = 0; a < 3; ++a) {
    Vec3 off = Vec3::Zero();
    off[a] = shift;
    add(std::string("shift ") + "xyz"[a], Mat3::Identity(), off);
  }
  for (double deg : {0.05, 0.5, 2.0, 5.0})
    for (int a = 0; a < 3; ++a) {
      char name[32];
      std::snprintf(name, sizeof name, "%s %g deg", axes[a], deg);
      add(name, Mat3(Eigen::AngleAxisd(deg * 3.14159265358979323846 / 180.0, Vec3::Unit(a))), Vec3::Zero());
    }
  return copies;
}

// --fit-real-cube: the scan turned about its centroid so that its +y
// points along each axis and its +z along each axis perpendicular to it:
// the 24 right-angle orientations, the as-given one first.
std::vector<Copy> cube_copies(const PointCloud& scan) {
  Vec3 centroid = Vec3::Zero();
  for (const Vec3& p : scan.positions) centroid += p;
  centroid /= std::max(1, scan.size());
  const char* names[6] = {"+x", "-x", "+y", "-y", "+z", "-z"};
  auto axis = [](int k) { return Vec3((k / 2 == 0) * (k % 2 ? -1.0 : 1.0), (k / 2 == 1) * (k % 2 ? -1.0 : 1.0),
                                      (k / 2 == 2) * (k % 2 ? -1.0 : 1.0)); };
  std::vector<Copy> copies = {Copy{"as given", scan, Mat3::Identity(), Vec3::Zero(), centroid}};
  for (int u = 0; u < 6; ++u)
    for (int f = 0; f < 6; ++f) {
      if (u / 2 == f / 2 || (u == 2 && f == 4)) continue;  // parallel, or the as-given one
      Mat3 linear;  // +y -> up, +z -> facing
      linear.col(1) = axis(u);
      linear.col(2) = axis(f);
      linear.col(0) = axis(u).cross(axis(f));
      Copy c{std::string("up ") + names[u] + " face " + names[f], scan, linear, Vec3::Zero(), centroid};
      for (Vec3& p : c.cloud.positions) p = centroid + linear * (p - centroid);
      for (Vec3& q : c.cloud.normals) q = linear * q;
      copies.push_back(std::move(c));
    }
  return copies;
}

// --fit-real-dense: the scan (a mesh) and the same surface sampled 4 and 16
// times as densely: each triangle split 1:4 at its edges' midpoints, once
// and twice (normals and colours averaged). The surface does not change, so
// a fit that depends on how densely it is sampled shows it (real scans come
// with 10^4 to 10^6 points; docs/design/fit_real_scans.md, "The same
// surface, sampled more densely"). A raw cloud gets no dense copies.
std::vector<Copy> dense_copies(const PointCloud& scan, bool x64) {
  Vec3 centroid = Vec3::Zero();
  for (const Vec3& p : scan.positions) centroid += p;
  centroid /= std::max(1, scan.size());
  std::vector<Copy> copies = {Copy{"as given", scan, Mat3::Identity(), Vec3::Zero(), centroid}};
  if (scan.faces.empty()) return copies;
  PointCloud finer = split_at_midpoints(scan);
  copies.push_back(Copy{"dense x4", finer, Mat3::Identity(), Vec3::Zero(), centroid});
  copies.push_back(Copy{"dense x16", split_at_midpoints(finer), Mat3::Identity(), Vec3::Zero(), centroid});
  if (x64) copies.push_back(Copy{"dense x64", split_at_midpoints(copies.back().cloud), Mat3::Identity(), Vec3::Zero(), centroid});
  return copies;
}

// The aligned generic head's vertices in the ORIGINAL scan's frame and
// units (the copy's nudge undone), so copies' alignments compare.
std::vector<Vec3> aligned_in_scan(const FitHeadResult& r, const Copy& c) {
  const Mat3 to_scan = r.scan_to_head.A.inverse();
  const Mat3 undo = c.linear.inverse();
  std::vector<Vec3> out;
  for (const Vec3& p : r.aligned.positions) {
    const Vec3 q = to_scan * (p - r.scan_to_head.t);
    out.push_back(c.centroid + undo * (q - c.offset - c.centroid));
  }
  return out;
}

// How far the scan's face is turned from the aligned generic face, in the
// fit's frame (align/face_symmetry.h): near 0 where the face match found
// the face's own axis.
bool face_symmetry_turn(const FitHeadResult& r, const Copy& c, const GenericHead& generic, double& yaw, double& score) {
  std::vector<Vec3> scan;
  for (const Vec3& p : c.cloud.positions) scan.push_back(r.scan_to_head.apply(p));
  FaceSymmetry s;
  if (!face_symmetry_of_alignment(generic.mesh, generic.annotations, scan, c.cloud.faces, r.generic_to_head.A,
                                  r.generic_to_head.t, FaceSymmetryOptions{}, s))
    return false;
  yaw = s.yaw_deg, score = s.score;
  return true;
}

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
  std::vector<Copy> copies = {Copy{"as given", scan, I, Vec3::Zero(), centroid}};
  for (const Nudge& n : nudges) {
    if (static_cast<int>(copies.size()) >= count) break;
    Copy c{n.name, scan, n.linear, n.offset, centroid};
    for (Vec3& p : c.cloud.positions) p = centroid + n.linear * (p - centroid) + n.offset;
    for (Vec3& q : c.cloud.normals) q = (n.linear * q).normalized();
    copies.push_back(std::move(c));
  }
  return copies;
}

// Every scan file (OBJ, PLY, VTK, XYZ) in the folders under head_scans/,
// by folder name: James and Fran, the statues' busts, and whatever is put
// there next.
std::vector<std::pair<std::string, std::string>> find_real_scans(const std::string& data) {
  namespace fs = std::filesystem;
  std::vector<std::pair<std::string, std::string>> scans;
  std::error_code ec;
  const fs::path root = fs::path(data) / "head_scans";
  if (!fs::is_directory(root, ec)) return scans;
  for (const auto& folder : fs::directory_iterator(root, ec)) {
    if (!folder.is_directory(ec)) continue;
    for (const auto& file : fs::directory_iterator(folder.path(), ec)) {
      std::string ext = file.path().extension().string();
      std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
      if (ext == ".obj" || ext == ".ply" || ext == ".vtk" || ext == ".xyz")
        scans.emplace_back(folder.path().filename().string() + "/" + file.path().filename().string(),
                           file.path().string());
    }
  }
  std::sort(scans.begin(), scans.end());
  return scans;
}

// The scanned neck below the neck cut (the cut is where fitting's points
// end): the scan's points between the cut and the lowest point of the
// aligned generic neck whose nearest point of the finest level is on the
// neck, and their distances to it. A neck that was not fitted stands
// beside them (centimetres); a fitted one lies on them.
struct NeckFigures {
  int points = 0;
  double median = 0, p90 = 0;  // metres
};
Status measure_neck(const FitHeadResult& r, const PointCloud& scan, const GenericHead& generic, NeckFigures& out) {
  out = NeckFigures{};
  if (r.level_meshes.empty()) return Status::success();
  std::vector<char> not_neck;
  Status st = finest_region_skip(r, generic, "neck", not_neck);
  if (!st) return st;
  const ClipPlane& c = generic.annotations.neck_clip;
  const Vec3 point = r.generic_to_head.apply(c.point);
  const Vec3 normal = (r.generic_to_head.A.inverse().transpose() * c.normal).normalized();
  double lowest = 0;
  for (const Vec3& v : r.aligned.positions) lowest = std::min(lowest, normal.dot(v - point));
  const TriMesh& finest = r.level_meshes.back();
  const ClosestPointTree tree(finest);
  std::vector<double> d;
  for (const Vec3& p0 : scan.positions) {
    const Vec3 p = r.scan_to_head.apply(p0);
    const double h = normal.dot(p - point);
    if (h >= 0 || h < lowest) continue;
    const SurfaceHit s = tree.closest(p);
    if (s.face < 0) continue;
    const Tri& t = finest.triangles[s.face];
    if (not_neck[t[0]] && not_neck[t[1]] && not_neck[t[2]]) continue;
    d.push_back(std::sqrt(s.squared_distance));
  }
  out.points = static_cast<int>(d.size());
  if (d.empty()) return Status::success();
  std::sort(d.begin(), d.end());
  out.median = d[d.size() / 2];
  out.p90 = d[std::min(d.size() - 1, d.size() * 9 / 10)];
  return Status::success();
}

// The scan's noise floor (fit/scan_noise.h) over the points Table 1
// measures (above the neck cut), in percent of the diagonal as Table 1.
Status noise_floor_pct(const FitHeadResult& r, const PointCloud& scan, const GenericHead& generic, double& pct,
                       double& sigma_mm) {
  const ClipPlane& c = generic.annotations.neck_clip;
  ClipPlane neck;
  neck.point = r.generic_to_head.apply(c.point);
  neck.normal = (r.generic_to_head.A.inverse().transpose() * c.normal).normalized();
  std::vector<Vec3> head(scan.positions.size());
  std::vector<char> measured(head.size());
  for (size_t i = 0; i < head.size(); ++i) {
    head[i] = r.scan_to_head.apply(scan.positions[i]);
    measured[i] = neck.keeps(head[i]);
  }
  ScanNoise noise;
  const Status st = estimate_scan_noise(head, measured, 16, noise);
  if (!st) return st;
  pct = 100.0 * noise.floor / (r.bbox_diagonal * r.unit_to_metres);
  sigma_mm = 1e3 * noise.sigma_median;
  return Status::success();
}

int run(const Args& args) {
  const std::string data = args.get("data", "../shared/data");
  std::vector<std::pair<std::string, std::string>> scans = find_real_scans(data);
  if (scans.empty()) {
    std::printf("   skipped: no scans under %s/head_scans (the real scans live in ../shared/data; --data DIR)\n",
                data.c_str());
    return 0;
  }
  // --fit-real-scan NAME: only the scans whose folder/file contains NAME.
  if (args.has("fit-real-scan")) {
    const std::string only = args.get("fit-real-scan", "");
    scans.erase(std::remove_if(scans.begin(), scans.end(),
                               [&](const auto& s) { return s.first.find(only) == std::string::npos; }),
                scans.end());
  }
  GenericHead generic;
  Status st = choose_generic_head(args.get("fit-head", "asset"), generic);
  if (!st) {
    std::printf("   generic head: %s\n", st.message.c_str());
    return 1;
  }
  // The fold creases' knobs (GlobalFitOptions::smooth_guard_crease_*), to
  // measure them on the copies.
  FitHeadOptions options;
  int copies = 1;
  int hinges_last = options.untangle_hinges_last ? 1 : 0;
  int guard_others = options.guard_other_crossings ? 1 : 0;
  int guard_remeasure = options.guard_remeasure ? 1 : 0;
  int pleat_undo = options.pleat_undo_where_crossing ? 1 : 0;
  int guard_by_cost = options.guard_choose_by_cost ? 1 : 0;
  double surface_cells = 0;  // --fit-real-surface-cells: a fraction of the diagonal
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
      !args.get_int("fit-ear-refit-rounds", options.ear_refit_warm_rounds, options.ear_refit_warm_rounds) ||
      options.ear_refit_warm_rounds < 0 ||
      !args.get_int("fit-real-copies", 1, copies) || copies < 1 || copies > 13 ||
      !args.get_int("fit-untangle-level", options.untangle_level, options.untangle_level) ||
      options.untangle_level < 0 || options.untangle_level > 3 ||
      !args.get_int("fit-guard-others", guard_others, guard_others) || guard_others < 0 || guard_others > 1 ||
      !args.get_int("fit-guard-remeasure", guard_remeasure, guard_remeasure) || guard_remeasure < 0 ||
      guard_remeasure > 1 || !args.get_int("fit-pleat-undo", pleat_undo, pleat_undo) || pleat_undo < 0 ||
      pleat_undo > 1 || !args.get_int("fit-guard-by-cost", guard_by_cost, guard_by_cost) || guard_by_cost < 0 ||
      guard_by_cost > 1 ||
      !args.get_int("fit-guard-cost-tries", options.guard_cost_extra_tries, options.guard_cost_extra_tries) ||
      options.guard_cost_extra_tries < 0 || !args.get_double("fit-real-surface-cells", 0, surface_cells) ||
      !(surface_cells >= 0 && surface_cells <= 0.1)) {
    std::printf("   --fit-crease-trials / --fit-crease-edges / --fit-data-level / --fit-pleat-steps take a whole number, "
                "--fit-restore-rings one up to 8, --fit-hinges-last 0 or 1, --fit-ear-refit-rounds one >= 0, "
                "--fit-real-copies one from 1 to 13, --fit-untangle-level one from 0 to 3, --fit-guard-others / --fit-guard-remeasure / --fit-pleat-undo / --fit-guard-by-cost 0 or 1, "
                "--fit-guard-cost-tries one >= 0, --fit-real-surface-cells one from 0 to 0.1, "
                "--fit-crease-angle and --fit-surface-edges a number\n");
    return 1;
  }
  options.untangle_hinges_last = hinges_last == 1;
  options.guard_other_crossings = guard_others == 1;
  options.guard_remeasure = guard_remeasure == 1;
  options.pleat_undo_where_crossing = pleat_undo == 1;
  options.guard_choose_by_cost = guard_by_cost == 1;
  if (args.has("fit-real-scanned-neck")) options.fit_scanned_neck = true;
  if (args.has("fit-real-no-scanned-neck")) options.fit_scanned_neck = false;
  const std::string only_copy = args.get("fit-real-copy", "");
  const bool sweep = args.has("fit-real-sweep"), align_only = args.has("fit-real-align-only"),
             cube = args.has("fit-real-cube"), dense = args.has("fit-real-dense");
  const bool stages = args.has("fit-real-stages");
  // --fit-align-pitches A,B,...: the silhouettes' pitch starts (deg);
  // --fit-align-polish 0|1: the ICP polish (AlignOptions).
  if (args.has("fit-align-pitches")) {
    options.align.pitch_starts_deg.clear();
    for (const std::string& item : split_list(args.get("fit-align-pitches", "0")))
      options.align.pitch_starts_deg.push_back(std::atof(item.c_str()));
  }
  if (args.has("fit-align-polish")) options.align.polish = args.get("fit-align-polish", "1") != "0";
  // --fit-align-loss trim|tukey|gm: the polish's weights (AlignOptions::polish_loss);
  // --fit-align-choose polish|face: what chooses between polished starts
  // (the polished score, or the face's distance: AlignOptions::choose_by_face).
  if (args.has("fit-align-loss")) {
    const std::string loss = args.get("fit-align-loss", "trim");
    if (loss != "trim" && loss != "tukey" && loss != "gm") {
      std::printf("   --fit-align-loss takes trim, tukey or gm\n");
      return 1;
    }
    options.align.polish_loss = loss == "tukey" ? IcpLoss::Tukey : loss == "gm" ? IcpLoss::GemanMcClure : IcpLoss::Trim;
  }
  if (args.has("fit-align-choose")) {
    const std::string choose = args.get("fit-align-choose", "polish");
    if (choose != "polish" && choose != "face") {
      std::printf("   --fit-align-choose takes polish or face\n");
      return 1;
    }
    options.align.choose_by_face = choose == "face";
  }
  // --fit-align-smooth 0|1: the outlines' chamfer score instead of D (AlignOptions::smooth_score).
  if (args.has("fit-align-smooth")) options.align.smooth_score = args.get("fit-align-smooth", "1") != "0";
  // --fit-align-coarse A,B,...: the coarse resolutions (AlignOptions; "none": the final one only).
  if (args.has("fit-align-coarse")) {
    options.align.coarse_resolutions.clear();
    for (const std::string& item : split_list(args.get("fit-align-coarse", "none")))
      if (item != "none") options.align.coarse_resolutions.push_back(std::atoi(item.c_str()));
  }
  // --fit-face-screen, --fit-orient-screen-points: see the header comment.
  if (args.has("fit-face-screen")) {
    const std::vector<std::string> items = split_list(args.get("fit-face-screen", "0"));
    options.face_refine.screen_iterations = items.empty() ? 0 : std::atoi(items[0].c_str());
    if (items.size() > 1) options.face_refine.screen_keep = std::atoi(items[1].c_str());
  }
  if (args.has("fit-face-symmetry"))
    options.face_refine.symmetry_yaw_start = args.get("fit-face-symmetry", "1") != "0";
  if (args.has("fit-face-frame")) options.face_frame = args.get("fit-face-frame", "1") != "0";
  if (!args.get_int("fit-orient-screen-points", options.orientation.screen_points, options.orientation.screen_points))
    return 1;
  if (!args.get_int("fit-orient-screen-keep", options.orientation.screen_keep, options.orientation.screen_keep, 1))
    return 1;
  {
    int retry = options.orientation_retry_unscreened ? 1 : 0;
    if (!args.get_int("fit-orient-retry", retry, retry, 0, 1)) return 1;
    options.orientation_retry_unscreened = retry == 1;
    if (!args.get_double("fit-orient-surface-retry", options.orientation_surface_retry_cell,
                         options.orientation_surface_retry_cell, 0, 0.1) ||
        !args.get_double("fit-dense-retry", options.dense_mesh_retry_cell, options.dense_mesh_retry_cell, 0, 0.1) ||
        !args.get_double("fit-face-match-edge", options.face_match_vertices_edge, options.face_match_vertices_edge, 0,
                         0.1))
      return 1;
    int z_up = options.suggest_z_up ? 1 : 0;
    if (!args.get_int("fit-z-up-hint", z_up, z_up, 0, 1)) return 1;
    options.suggest_z_up = z_up == 1;
  }
  // --fit-align-tolerance T: Powell's relative decrease per sweep (AlignOptions::tolerance).
  if (args.has("fit-align-tolerance")) options.align.tolerance = std::atof(args.get("fit-align-tolerance", "1e-4").c_str());
  if (args.has("fit-ear-refit-late")) options.ear_refit_after_rounds = false;
  if (!args.get_int("fit-ear-give-up", options.ear_refit_give_up_pairs, options.ear_refit_give_up_pairs, 0)) return 1;
  {
    int neck_guard = options.scanned_neck_smooth_guard ? 1 : 0;
    if (!args.get_int("fit-neck-guard", neck_guard, neck_guard, 0, 1)) return 1;
    options.scanned_neck_smooth_guard = neck_guard == 1;
    int neck_reach = options.scanned_neck_reach ? 1 : 0;
    if (!args.get_int("fit-neck-reach", neck_reach, neck_reach, 0, 1)) return 1;
    options.scanned_neck_reach = neck_reach == 1;
  }
  if (!parse_back_term(args, options)) return 1;
  const std::string dump = args.get("fit-real-dump", "");
  if (args.has("fit-data-level")) options.whole_head_data_level = -1;  // on every scan, as given
  int failures = 0;
  struct Summary {
    std::string scan;
    double table1 = 0, floor = 0, back_mean = 0, neck_median = 0, cpu_s = 0;
    int lips = 0, ears = 0, rest = 0, neck_points = 0;
    bool face_only = false;
  };
  std::vector<Summary> summary;
  for (const auto& [label, path] : scans) {
    PointCloud scan;
    st = load_point_cloud_file(path, scan);
    if (!st) {
      std::printf("   skipped %s: %s\n", label.c_str(), st.message.c_str());
      continue;
    }
    std::printf("   %s, %d points%s; likeness fit's defaults\n", label.c_str(), scan.size(),
                scan.faces.empty() ? "" : " (a mesh)");
    std::printf("   %-14s %9s %9s %9s %6s %5s %5s %6s %5s %7s %7s   %s\n", "copy", "Table 1 %", "max %", "floor %",
                "pairs", "lips", "ears", "socket", "rest", "smooth", "cpu s",
                "face -> scan mean / p99 / max mm; neck: points, median / p90 mm");
    std::vector<int> totals;
    std::vector<Vec3> given_pose;  // the as-given copy's aligned head, scan frame
    const std::vector<Copy> all_copies = cube    ? cube_copies(scan)
                                         : sweep ? swept_copies(scan)
                                         : dense ? dense_copies(scan, args.has("fit-real-dense-x64"))
                                                 : nudged_copies(scan, copies);
    for (Copy c : all_copies) {
      if (!only_copy.empty() && c.name.find(only_copy) == std::string::npos) continue;
      if (surface_cells > 0) {
        const int before = c.cloud.size();
        // The copy fitted on its surface's cell averages (a raw cloud on
        // its points' averages): what depends on the vertices, not the surface.
        PointCloud averages;
        ScanThinning thinned;
        const double cell = surface_cells * bounding_box(c.cloud.positions).diagonal();
        st = c.cloud.faces.empty() ? thin_scan(c.cloud, cell, averages, thinned)
                                   : surface_cell_averages(c.cloud.positions, c.cloud.faces, cell, averages);
        if (!st) {
          std::printf("   %-14s surface cell averages: %s\n", c.name.c_str(), st.message.c_str());
          ++failures;
          continue;
        }
        c.cloud = std::move(averages);
        std::printf("   %-14s surface cell averages: %d points (of %d)\n", c.name.c_str(), c.cloud.size(), before);
      }
      DistanceStats table1;
      FitStageObserver obs;
      obs.measured = [&](const FitStageReport& r) {
        if (r.name == "subdivision") table1 = r.distance;
      };
      // CPU per stage, from its start to its end (the stats measured after
      // each stage are in the total only).
      std::vector<std::pair<std::string, double>> stage_cpu;
      double stage0 = 0;
      obs.started = [&](const std::string&) { stage0 = cpu_clock_ms(); };
      obs.finished = [&](const std::string& name, const TriMesh&) {
        stage_cpu.emplace_back(name, 1e-3 * (cpu_clock_ms() - stage0));
      };
      FitHeadResult r;
      const double cpu0 = cpu_clock_ms();
      // --fit-real-align-only: stopped once the alignment is final.
      const ProgressFn stop_after_alignment = [&](const char* stage, double f) {
        return !(align_only && std::string(stage) == "initial_alignment" && f >= 1.0);
      };
      st = fit_head(c.cloud, generic, options, r, obs, stop_after_alignment);
      const double cpu_s = 1e-3 * (cpu_clock_ms() - cpu0);
      if ((st || (align_only && st.code == ErrorCode::Cancelled)) && !r.aligned.positions.empty()) {
        // Where this copy's alignment put the head against the as-given
        // copy's, in the scan's frame: turn (deg), scale ratio, vertices
        // apart (mm); and which path it took.
        const std::vector<Vec3> pose = aligned_in_scan(r, c);
        if (c.name == "as given") given_pose = pose;
        std::printf("   %-14s pose: %s", c.name.c_str(), r.face_only ? "face patch" : r.refined_on_face ? "face match" : "silhouettes");
        if (!r.face_only)
          std::printf(", D %d, turn %.4f %.4f %.4f, log scales %.4f %.4f %.4f", total_xor(r.alignment.xor_after),
                      r.alignment.parameters[3], r.alignment.parameters[4], r.alignment.parameters[5],
                      r.alignment.parameters[6], r.alignment.parameters[7], r.alignment.parameters[8]);
        if (!r.face_only && r.alignment.polished)
          std::printf(", polished by %.2f deg, scale %.4f (D %d)", r.alignment.polish_turn_deg, r.alignment.polish_scale,
                      total_xor(r.alignment.xor_polished));
        if (!r.face_only && r.alignment.starts.size() > 1)
          for (size_t k = 0; k < r.alignment.starts.size(); ++k) {
            const AlignResult::Start& a = r.alignment.starts[k];
            std::printf("%s%s%+.0f: D %d", k ? ", " : "; starts ", int(k) == r.alignment.chosen ? "*" : "", a.pitch_deg,
                        a.xor_final);
            if (a.polish_score >= 0) std::printf(" score %.4g", a.polish_score);
            if (a.face_distance >= 0) std::printf(" face %.4g", a.face_distance);
          }
        std::printf(", near %.1f %%", 100 * r.near_fraction);
        if (options.face_frame) std::printf(", head frame turned %+.1f deg about up to the face's look", r.face_frame_deg);
        if (align_only) {  // the final map and the orientation check's outcome, to compare runs to the bit
          const Mat3& A = r.generic_to_head.A;
          const Vec3& t = r.generic_to_head.t;
          std::printf("; map %.12g %.12g %.12g %.12g %.12g %.12g %.12g %.12g %.12g | %.12g %.12g %.12g", A(0, 0),
                      A(0, 1), A(0, 2), A(1, 0), A(1, 1), A(1, 2), A(2, 0), A(2, 1), A(2, 2), t.x(), t.y(), t.z());
          std::printf("; orientation %s %s, scores %.6g / %.6g", r.turned ? "turned" : "kept",
                      r.orientation.given_clearly_best ? "(given clearly best)" : "", r.orientation.score_best,
                      r.orientation.score_given);
        }
        {
          double yaw = 0, score = 0;
          if (face_symmetry_turn(r, c, generic, yaw, score))
            std::printf("; the scan's face most symmetric %+.1f deg about the aligned face's up (%.2f)", yaw, score);
        }
        for (const FaceRefineCandidate& k : r.face_refine.candidates)
          std::printf("%s%+.0f: %.1f (face most symmetric %+.1f deg, %.2f)",
                      &k == &r.face_refine.candidates.front() ? "; pitches " : ", ", k.pitch_deg, 100 * k.measure,
                      k.symmetry_yaw_deg, k.symmetry_score);
        if (!given_pose.empty() && given_pose.size() == pose.size()) {
          Mat3 A = Mat3::Zero(), B = Mat3::Zero();  // least squares: pose ~ M * given (centred)
          Vec3 ca = Vec3::Zero(), cb = Vec3::Zero();
          for (size_t i = 0; i < pose.size(); ++i) ca += given_pose[i], cb += pose[i];
          ca /= pose.size();
          cb /= pose.size();
          double rms = 0, worst = 0;
          for (size_t i = 0; i < pose.size(); ++i) {
            A += (pose[i] - cb) * (given_pose[i] - ca).transpose();
            B += (given_pose[i] - ca) * (given_pose[i] - ca).transpose();
            const double d = (pose[i] - given_pose[i]).norm();
            rms += d * d;
            worst = std::max(worst, d);
          }
          const Mat3 M = A * B.inverse();
          Eigen::JacobiSVD<Mat3> svd(M, Eigen::ComputeFullU | Eigen::ComputeFullV);
          const Mat3 R = svd.matrixU() * svd.matrixV().transpose();
          const double angle = std::acos(std::clamp(0.5 * (R.trace() - 1), -1.0, 1.0)) * 180 / 3.14159265358979323846;
          const double pct = 100 / r.bbox_diagonal;
          std::printf("; against as given: turned %.3f deg, scale %.4f, vertices %.3f %% of the diagonal rms, %.3f max",
                      angle, std::cbrt(M.determinant()), pct * std::sqrt(rms / pose.size()), pct * worst);
        }
        std::printf(", %.2f s\n", cpu_s);
      }
      if (align_only) {
        if (!(st.code == ErrorCode::Cancelled)) std::printf("   %-14s %s\n", c.name.c_str(), st ? "not stopped" : st.message.c_str());
        continue;
      }
      FitQuality q;
      if (st) st = measure_fit_quality(r, generic.annotations, q);
      if (!st) {
        std::printf("   %-14s failed: %s\n", c.name.c_str(), st.message.c_str());
        ++failures;
        continue;
      }
      for (const std::string& note : r.notes)
        std::printf("   %-14s note: %s\n", "", note.c_str());
      if (stages) {  // --fit-real-stages: Table 1 after each stage (mean / max %)
        std::printf("   %-14s stages:", "");
        for (const FitStageReport& s : r.stages) {
          std::printf(" %s %.4f / %.3f", s.name.c_str(), s.distance.mean_pct, s.distance.max_pct);
          if (s.as_fitted.mean_pct != s.distance.mean_pct) std::printf(" (as fitted %.4f)", s.as_fitted.mean_pct);
          std::printf(";");
        }
        std::printf(" local fit:");
        for (const BoxFit& b : r.local_fit.boxes) std::printf(" %s %d pts", b.name.c_str(), b.points);
        std::printf("; global: smooth pairs %d -> %d, relief folds %d -> %d, pleats %d -> %d (%d steps), creases %zu, "
                    "untangle %d -> %d, guard %d+%d -> %d+%d, pleats undone %d, ears %s\n",
                    r.global_fit.smooth_crossing_before, r.global_fit.smooth_crossing_after,
                    r.global_fit.relief_folds_before, r.global_fit.relief_folds_after, r.global_fit.pleats_before,
                    r.global_fit.pleats_after, r.global_fit.pleat_steps, r.global_fit.fold_crease_edges.size(),
                    r.untangle.pairs_before, r.untangle.pairs_after, r.feature_guard.pairs_before,
                    r.feature_guard.other_pairs_before, r.feature_guard.pairs_after,
                    r.feature_guard.other_pairs_after, r.pleat_steps_undone,
                    r.ear_binding.bound ? "bound" : "free");
        if (!r.untangle.crossing_faces.empty()) {
          std::printf("   %-14s untangle left faces:", "");
          for (int f : r.untangle.crossing_faces) {
            const Tri& t = r.control.triangles[f];
            std::printf(" %d(%d %d %d)", f, t[0], t[1], t[2]);
          }
          std::printf("\n");
        }
      }
      const CrossingCounts& x = q.crossings;
      CoveredDistances back;
      st = measure_fit_to_scan(r, c.cloud, generic, back, "face");
      if (!st) std::printf("   %-14s face -> scan: %s\n", c.name.c_str(), st.message.c_str());
      NeckFigures neck;
      st = measure_neck(r, c.cloud, generic, neck);
      if (!st) std::printf("   %-14s neck: %s\n", c.name.c_str(), st.message.c_str());
      double floor_pct = -1, sigma_mm = -1;
      st = noise_floor_pct(r, c.cloud, generic, floor_pct, sigma_mm);
      if (!st) std::printf("   %-14s noise floor: %s\n", c.name.c_str(), st.message.c_str());
      std::printf("   %-14s %9.4f %9.3f %9.4f %6d %5d %5d %6d %5d %7d %7.2f   %.3f / %.2f / %.2f; %d, %.1f / %.1f\n",
                  c.name.c_str(), table1.mean_pct, table1.max_pct, floor_pct, x.total, x.lips, x.ears,
                  x.eye_sockets, x.rest, q.smooth_crossings.total, cpu_s, 1e3 * back.mean, 1e3 * back.p99,
                  1e3 * back.max, neck.points, 1e3 * neck.median, 1e3 * neck.p90);
      std::printf("   %-14s cpu s by stage:", "");
      for (const auto& [name, s] : stage_cpu) std::printf(" %s %.2f", name.c_str(), s);
      std::printf("\n");
      if (!dump.empty()) {
        std::string prefix = dump + "/" + label.substr(0, label.find('/')) + "_" + c.name;
        std::replace(prefix.begin() + static_cast<long>(dump.size()), prefix.end(), ' ', '_');
        st = dump_copy(prefix, r);
        if (!st) std::printf("   %-14s --fit-real-dump: %s\n", "", st.message.c_str());
      }
      if (!r.face_only)  // the silhouette alignment's answer: a nudge that changes it changes the fit
        std::printf("   %-14s alignment: D %d after %d evaluations; log scales %.4f %.4f %.4f, turn %.4f %.4f %.4f\n", "",
                    total_xor(r.alignment.xor_after), r.alignment.evaluations, r.alignment.parameters[6],
                    r.alignment.parameters[7], r.alignment.parameters[8], r.alignment.parameters[3],
                    r.alignment.parameters[4], r.alignment.parameters[5]);
      if (x.rest) {  // where the rest lie (regions overlap; "face" holds most)
        std::printf("   %-14s rest touches:", "");
        for (const auto& kv : x.rest_by_region) std::printf(" %s %d", kv.first.c_str(), kv.second);
        std::printf("\n");
      }
      totals.push_back(x.total);
      if (c.name == "as given")
        summary.push_back({label, table1.mean_pct, floor_pct, 1e3 * back.mean, 1e3 * neck.median, cpu_s, x.lips,
                           x.ears, x.rest, neck.points, r.face_only});
    }
    if (totals.size() > 1) {
      std::sort(totals.begin(), totals.end());
      std::printf("   pairs over the %zu copies: %d-%d, median %d (target 0 at lips and ears)\n", totals.size(),
                  totals.front(), totals.back(), totals[totals.size() / 2]);
    }
    std::printf("\n");
  }
  // One line per scan (as given), so a change that helps one head and hurts
  // another shows at once. Targets (issue 35): Table 1 within 0.02 % of the
  // floor, 0 pairs at lips and ears, under 2 s of CPU.
  std::printf("   %-44s %9s %9s %8s %5s %5s %5s %9s %7s %7s\n", "scan (as given)", "Table 1 %", "floor %", "gap %",
              "lips", "ears", "rest", "face mm", "neck mm", "cpu s");
  int over_cpu = 0;
  for (const Summary& s : summary) {
    std::printf("   %-44s %9.4f %9.4f %8.4f %5d %5d %5d %9.3f %7.1f %7.2f%s%s\n", s.scan.c_str(), s.table1, s.floor,
                s.table1 - s.floor, s.lips, s.ears, s.rest, s.back_mean, s.neck_median, s.cpu_s,
                s.cpu_s > kRealCpuTargetS ? " > 2 s" : "", s.face_only ? "  (face-only)" : "");
    over_cpu += s.cpu_s > kRealCpuTargetS;
  }
  if (!summary.empty())
    std::printf("   cpu: process CPU of the fit, all threads (LK_THREADS=1 for one); target %.1f s per real scan "
                "(issue 35; the synthetic seeds' target is 1.3 s, bench --only fit): %d of %zu over\n",
                kRealCpuTargetS, over_cpu, summary.size());
  return failures ? 1 : 0;  // absent data is a skip, not a failure
}

BenchRegistrar reg({"fit-real",
                    "every real scan in ../shared/data/head_scans: Table 1 beside its noise floor, crossing pairs by "
                    "region, face to scan, the neck, CPU time",
                    run});

}  // namespace
}  // namespace lk::cli
