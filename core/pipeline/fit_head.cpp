#include "pipeline/fit_head.h"

#include "align/face_refine.h"

#include "common/parallel.h"
#include "common/rotation.h"
#include "fit/closest_point.h"
#include "head/generic_head.h"
#include "mesh/geometry.h"
#include "mesh/topology.h"
#include "pipeline/fit_quality.h"
#include "head/head_creases.h"
#include "head/head_pockets.h"
#include "pipeline/untangle.h"
#include "raycast/self_intersection.h"

#include <Eigen/Eigenvalues>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <sstream>

namespace lk {
namespace {

// The end of the refusal when too few points lie near the aligned head.
constexpr const char* kAxesHint = " (a head and shoulders lying down or facing away: pass --up and --facing, e.g. --up +z)";

ClipPlane transform_plane(const ClipPlane& c, const AffineMap& m) {
  ClipPlane out;
  out.point = m.apply(c.point);
  out.normal = (m.A.inverse().transpose() * c.normal).normalized();
  return out;
}

std::string pct(double x) {
  std::ostringstream s;
  s.precision(3);
  s << x;
  return s.str();
}

// Every stride-th point, so stats on huge scans can be capped.
std::vector<Vec3> thin(const std::vector<Vec3>& p, int max_points) {
  if (max_points <= 0 || static_cast<int>(p.size()) <= max_points) return p;
  const size_t stride = (p.size() + max_points - 1) / max_points;
  std::vector<Vec3> out;
  for (size_t i = 0; i < p.size(); i += stride) out.push_back(p[i]);
  return out;
}

// The share of pts (every stride-th, at most max_points) within near_distance
// of the surface: the check that a scan lies on the aligned head.
double near_share(const TriMesh& surface, const std::vector<Vec3>& pts, double near_distance, int max_points) {
  const std::vector<Vec3> probe = thin(pts, max_points);
  if (probe.empty()) return 0;
  ClosestPointTree tree(surface);
  const double near2 = near_distance * near_distance;
  int near = 0;
  for (const Vec3& p : probe) near += tree.closest(p, near2).face >= 0;
  return double(near) / probe.size();
}

// The eye sockets and the mouth bag are pockets the scanner never sees; a
// normal line from their vertices meets the outer skin (the lids, the lips)
// and would push the pocket out through it. Their displacements, and those
// of every finer vertex on an edge touching them, are set to zero.
Status zero_pocket_displacements(const std::vector<char>& pocket, MultiresMesh& mr, int& zeroed) {
  zeroed = 0;
  std::vector<char> inner = pocket;
  inner.resize(mr.num_vertices(0), 0);
  for (int l = 0; l <= mr.num_levels(); ++l) {
    for (size_t v = 0; v < inner.size(); ++v)
      if (inner[v] && mr.displacements[l][v] != 0) {
        mr.displacements[l][v] = 0;
        ++zeroed;
      }
    if (l == mr.num_levels()) break;
    // New vertex k of the level sits on edge_endpoints[k] (the Butterfly's
    // own edge order; a MeshTopology of the level numbers its edges
    // differently from level 2 on, which left displacements in the pockets).
    const ButterflyLevel& level = mr.levels[l];
    std::vector<char> next(level.num_fine_vertices, 0);
    std::copy(inner.begin(), inner.end(), next.begin());
    for (int k = 0; k < level.num_new_vertices(); ++k)
      next[level.num_coarse_vertices + k] = inner[level.edge_endpoints[k][0]] || inner[level.edge_endpoints[k][1]];
    inner.swap(next);
  }
  return evaluate(mr);
}

// Searches orientations (face_alignment.h) for the cloud in the head frame;
// when another fits clearly better, either rotates the cloud
// (and scan_to_head) to it with a note, or fails with the options to pass.
// as_given: the cloud before the turn, set only when it is turned.
Status check_orientation(const GenericHead& generic, const FitHeadOptions& options, const Mat3& given,
                         const std::vector<Tri>& faces, PointCloud& cloud, FitHeadResult& out, PointCloud& as_given,
                         const ProgressFn& progress) {
  if (options.orientation_check == FitHeadOptions::OrientationCheck::Off) return Status::success();
  // A mesh is searched on its surface (FitHeadOptions::orientation_surface_cell).
  PointCloud surface;
  if (!faces.empty() && options.orientation_surface_cell > 0) {
    const Status made = surface_cell_averages(
        cloud.positions, faces, options.orientation_surface_cell * bounding_box(cloud.positions).diagonal(), surface);
    if (!made) return with_context(made, "orientation check");
  }
  const Status st = guess_orientation(generic.mesh, generic.annotations, surface.positions.empty() ? cloud : surface,
                                      options.orientation, out.orientation, progress);
  if (st.code == ErrorCode::Cancelled) return st;
  if (!st) return Status::success();  // nothing aligns: the head checks below give the reason
  out.orientation_checked = true;
  if (!out.orientation.differs) return Status::success();
  // The better orientation in the scan's own frame.
  const Mat3 scan_to_upright = out.orientation.rotation * given;
  const Vec3 facing = scan_to_upright.transpose() * Vec3::UnitZ();
  const Vec3 up = scan_to_upright.transpose() * Vec3::UnitY();
  auto numbers = [](const Vec3& v) {
    std::ostringstream s;
    s.precision(2);
    for (int k = 0; k < 3; ++k) s << (k ? " " : "") << (std::abs(v[k]) < 5e-3 ? 0.0 : v[k]);
    return s.str();
  };
  const std::string what = "the scan seems to face " + axis_name(facing) + " with " + axis_name(up) +
                           " up (there its closest-point error is " + pct(out.orientation.score_given / out.orientation.score_best) +
                           "x smaller than as given)";
  const std::string flags = "--facing " + numbers(facing) + " --up " + numbers(up);
  if (options.orientation_check == FitHeadOptions::OrientationCheck::Hint)
    return Status::error(ErrorCode::NotAHead, what + "; try " + flags);
  as_given = cloud;
  for (Vec3& p : cloud.positions) p = out.orientation.rotation * p;
  out.scan_to_head.A = out.unit_to_metres * scan_to_upright;
  out.turned = true;
  out.notes.push_back(what + ": turned it that way; pass " + flags + " to say so");
  return Status::success();
}

// After check_orientation turned the scan and align_scan aligned it
// (turned_status): the scan as given is aligned as well, and the turn is
// kept only when it leaves a larger share of the scan's points within
// near_distance of the aligned head. The orientation search's closest-point
// score does not separate a bust's right pose from a wrong one by a margin
// to rely on (Demosthenes turned to a wrong pose 1.27x "better");
// this share does (docs/design/align.md, "A turn checked against the scan
// as given"). before_turn: `out` before check_orientation. Returns the kept
// one's status (turned_status by value: align_scan may write the caller's).
Status check_turn(Status turned_status, const PointCloud& as_given, const FitHeadResult& before_turn,
                  double near_distance, const std::function<Status()>& align_scan, PointCloud& cloud,
                  FitHeadResult& out) {
  auto share = [&](const Status& s) {
    return s ? near_share(out.aligned, cloud.positions, near_distance, 20000) : -1.0;
  };
  auto words = [](double s) { return s >= 0 ? pct(100 * s) + "%" : std::string("refused"); };
  const double turned_share = share(turned_status);
  FitHeadResult turned = std::move(out);
  PointCloud turned_cloud = std::move(cloud);
  out = before_turn;
  out.orientation = turned.orientation;
  out.orientation_checked = true;
  cloud = as_given;
  const Status given_status = align_scan();
  if (given_status.code == ErrorCode::Cancelled) return given_status;
  const double given_share = share(given_status);
  const std::string shares = "the share of the scan's points near the aligned head: turned " + words(turned_share) +
                             ", as given " + words(given_share);
  if (given_share > turned_share) {
    out.notes.push_back("the orientation search proposed a turn, but the scan as given lies closer to the head (" +
                        shares + "): kept as given");
    return given_status;
  }
  out = std::move(turned);
  cloud = std::move(turned_cloud);
  if (!turned_status && !given_status)
    return Status::error(turned_status.code, turned_status.message + " (as given too: " + given_status.message + ")");
  if (turned_status)
    out.notes.push_back("the turn was checked against the scan as given (" + shares + "): kept the turn");
  return turned_status;
}

// After the alignment was refused (refused: its status) in the orientation
// the first search chose, the search runs again on the scan as given with
// `search` (its options: every start run through, or a mesh's surface
// instead of its vertices). A turn it finds that differs from the one
// refused is aligned; the refusal stands when there is none, when it is
// refused too, or, with face_patch_only, when it is not aligned as a face
// patch. how: what the second search did, for the note. as_given: the scan
// before the first turn (empty when it was not turned).
Status retry_orientation(Status refused, const GenericHead& generic, const FitHeadOptions& search, const char* how,
                         bool face_patch_only, const Mat3& given, const std::vector<Tri>& faces,
                         const FitHeadResult& before_turn, const PointCloud& as_given,
                         const std::function<Status()>& align_scan, PointCloud& cloud, FitHeadResult& out,
                         const ProgressFn& progress) {
  const bool first_turned = out.turned;
  const Mat3 first_rotation = first_turned ? out.orientation.rotation : Mat3::Identity();
  FitHeadResult refused_out = std::move(out);
  const PointCloud first_cloud = cloud;  // put back with the refusal
  if (first_turned) cloud = as_given;
  out = before_turn;
  PointCloud unturned;
  Status st = check_orientation(generic, search, given, faces, cloud, out, unturned, progress);
  if (st.code == ErrorCode::Cancelled) return st;
  // The same pose as the one refused (or none found): nothing new to try
  // (the caller returns the refusal; the cloud is not put back).
  const Mat3 between = first_rotation.transpose() * out.orientation.rotation;
  const double moved_deg =
      std::acos(std::clamp((between.trace() - 1) / 2, -1.0, 1.0)) * 180.0 / 3.14159265358979323846;
  if (!st || !out.turned || moved_deg < 10) {
    out = std::move(refused_out);
    cloud = first_cloud;
    return refused;
  }
  st = align_scan();
  if (st.code == ErrorCode::Cancelled) return st;
  if (st && face_patch_only && !out.face_only) {
    // A whole head passes the near rule in wrong poses (a bust on its side
    // turned 128 deg), a face patch's match does not: the refusal stands.
    out = std::move(refused_out);
    cloud = first_cloud;
    return refused;
  }
  if (!st)
    return Status::error(refused.code, refused.message + " (" + how + ", the turn found was refused too: " +
                                           st.message + ")");
  out.notes.push_back(std::string("the orientation search left the scan ") + (first_turned ? "turned" : "as given") +
                      ", where it was refused (" + refused.message + "); " + how +
                      ", it found another orientation: aligned there");
  return st;
}

// Leaves out the points far sparser than the scan's own sampling
// (isolated_scan_points; ratio 0: none), and their entries of `index`, in
// order. Returns how many were left out.
int drop_isolated_points(double density_ratio, std::vector<Vec3>& points, std::vector<int>& index) {
  if (!(density_ratio > 0) || points.empty()) return 0;
  const std::vector<char> isolated = isolated_scan_points(points, density_ratio);
  size_t kept = 0;
  for (size_t i = 0; i < points.size(); ++i)
    if (!isolated[i]) points[kept] = points[i], index[kept] = index[i], ++kept;
  const int dropped = static_cast<int>(points.size() - kept);
  points.resize(kept);
  index.resize(kept);
  return dropped;
}

}  // namespace

Status orientation_from_conventions(const Vec3& up, const Vec3& facing, Mat3& rotation) {
  if (!up.allFinite() || !facing.allFinite() || up.norm() < 1e-12 || facing.norm() < 1e-12)
    return Status::error(ErrorCode::InvalidInput, "up and facing must be non-zero vectors");
  const Vec3 y = up.normalized();
  Vec3 z = facing - facing.dot(y) * y;
  if (z.norm() < 0.1 * facing.norm())
    return Status::error(ErrorCode::InvalidInput, "up and facing are (nearly) parallel");
  z.normalize();
  const Vec3 x = y.cross(z);
  rotation.row(0) = x.transpose();
  rotation.row(1) = y.transpose();
  rotation.row(2) = z.transpose();
  return Status::success();
}

double guess_unit_to_metres(double d) {
  const double candidates[3] = {1.0, 0.01, 0.001};
  double best = 1.0, best_err = 1e300;
  for (double u : candidates) {
    const double err = std::abs(std::log(d * u / 0.35));
    if (err < best_err) {
      best_err = err;
      best = u;
    }
  }
  return best;
}

// See fit_head.h (FitHeadOptions::guard_choose_by_cost).
int choose_guard_step(const std::vector<GuardTry>& tries, bool by_cost, int extra_tries) {
  int first = -1;
  for (int k = 0; k < static_cast<int>(tries.size()) && first < 0; ++k)
    if (tries[k].helps) first = k;
  if (first < 0 || !by_cost) return first;
  int chosen = first;
  const int last = std::min(static_cast<int>(tries.size()) - 1, first + std::max(extra_tries, 0));
  for (int k = first + 1; k <= last; ++k)
    if (tries[k].helps && tries[k].pairs_left <= tries[first].pairs_left && tries[k].cost < tries[chosen].cost)
      chosen = k;
  return chosen;
}

// See fit_head.h and FitHeadOptions::carry_mouth_bag.
Status carry_mouth_bag(const std::vector<char>& mouth_bag, const MeshTopology& topo, const TriMesh& before,
                       TriMesh& control) {
  const int nv = control.num_vertices();
  if (before.num_vertices() != nv || topo.num_vertices != nv || static_cast<int>(mouth_bag.size()) != nv)
    return Status::error(ErrorCode::InvalidInput, "carry_mouth_bag: the meshes, topology and flags differ in size");
  std::vector<int> index(nv, -1), bag;
  for (int v = 0; v < nv; ++v)
    if (mouth_bag[v]) index[v] = static_cast<int>(bag.size()), bag.push_back(v);
  if (bag.empty()) return Status::success();
  const int n = static_cast<int>(bag.size());
  std::vector<Eigen::Triplet<double>> entries;
  Eigen::MatrixXd boundary = Eigen::MatrixXd::Zero(n, 3);
  bool touches_boundary = false;
  for (int i = 0; i < n; ++i) {
    const int v = bag[i];
    entries.emplace_back(i, i, static_cast<double>(topo.rings[v].size()));
    for (int w : topo.rings[v]) {
      if (index[w] >= 0) {
        entries.emplace_back(i, index[w], -1.0);
      } else {
        boundary.row(i) += (control.positions[w] - before.positions[w]).transpose();
        touches_boundary = true;
      }
    }
  }
  if (!touches_boundary) return Status::success();  // a closed-off bag: nothing carries it
  Eigen::SparseMatrix<double> laplacian(n, n);
  laplacian.setFromTriplets(entries.begin(), entries.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(laplacian);
  if (solver.info() != Eigen::Success)
    return Status::error(ErrorCode::NotConverged, "the mouth bag has a part not joined to the lips");
  const Eigen::MatrixXd moved = solver.solve(boundary);
  if (solver.info() != Eigen::Success || !moved.allFinite())
    return Status::error(ErrorCode::NotConverged, "the mouth bag's movement could not be solved");
  for (int i = 0; i < n; ++i) control.positions[bag[i]] = before.positions[bag[i]] + moved.row(i).transpose();
  return Status::success();
}

namespace {

// FitHeadOptions::hold_crossing_ears. displace(folds, zeroed) measures the
// displacements of out.multires as built. reverted: set when an ear was held
// and then given back (the relief's tree was refitted to the held one).
template <class Displace>
Status hold_crossing_ears(const FitHeadOptions& options, const HeadAnnotations& ann, const MeshTopology& topo,
                          const ButterflyCreases& creases, FitHeadResult& out, Displace&& displace,
                          bool& reverted) {
  reverted = false;
  const auto region = ann.regions.find("ears");
  if (!options.hold_crossing_ears || region == ann.regions.end() || out.multires.num_levels() == 0)
    return Status::success();
  const int finest = out.multires.num_levels();
  auto ear_pairs = [&](const std::vector<std::vector<int>>& ears, std::vector<int>& per_ear, int& total) {
    // The fold limiter's own search of the level as it left it, when known.
    std::vector<std::array<int, 2>> pairs;
    Status s = finest_crossing_pairs(out.fold_limit, level_mesh(out.multires, finest), pairs);
    if (!s) return s;
    total = static_cast<int>(pairs.size());
    per_ear.clear();
    for (const auto& ear : ears) per_ear.push_back(count_pairs_touching(out.multires, finest, pairs, ear));
    return Status::success();
  };
  // One ear per connected part of the region.
  std::vector<std::vector<int>> ears;
  {
    const std::vector<char> in_ear = vertex_mask(region->second, topo.num_vertices);
    std::vector<char> seen(topo.num_vertices, 0);
    for (int s : region->second) {
      if (s < 0 || s >= topo.num_vertices || seen[s]) continue;
      std::vector<int> ear, stack{s};
      seen[s] = 1;
      while (!stack.empty()) {
        const int v = stack.back();
        stack.pop_back();
        ear.push_back(v);
        for (int w : topo.rings[v])
          if (in_ear[w] && !seen[w]) seen[w] = 1, stack.push_back(w);
      }
      ears.push_back(ear);
    }
  }
  std::vector<int> before;
  int total_before = 0;
  Status st = ear_pairs(ears, before, total_before);
  if (!st) return st;
  std::vector<char> held(topo.num_vertices, 0);
  int crossing = 0;
  for (size_t e = 0; e < ears.size(); ++e)
    if (before[e] > 0) {
      ++crossing;
      for (int v : ears[e]) held[v] = 1;
    }
  if (crossing == 0) return Status::success();
  // The held ears take the aligned generic ear's shape (not local fitting's
  // box, which the data had already pulled onto the hair), carried by the
  // harmonic interpolation of the movement of the head around them. Their
  // displacements are measured as elsewhere: they follow the data from the
  // generic ear (zeroed, more pairs remained: docs/design/fit_real_scans.md).
  const TriMesh control_before = out.control;
  const MultiresMesh multires_before = out.multires;
  const FoldLimitStats folds_before = out.fold_limit;
  const int zeroed_before = out.zeroed_displacements;
  st = carry_mouth_bag(held, topo, out.aligned, out.control);
  if (!st) return st;
  st = build_multires(out.control, creases, options.levels, out.multires);
  if (!st) return st;
  out.fold_limit = FoldLimitStats{};
  out.zeroed_displacements = 0;
  st = displace(out.fold_limit, out.zeroed_displacements);
  if (!st) return st;
  std::vector<int> after;
  int total_after = 0;
  st = ear_pairs(ears, after, total_after);
  if (!st) return st;
  int ears_before = 0, ears_after = 0;
  for (size_t e = 0; e < ears.size(); ++e) ears_before += before[e], ears_after += after[e];
  std::ostringstream note;
  note << crossing << " ear(s) crossed at level " << finest << " (" << ears_before << " pairs)";
  if (ears_after < ears_before && total_after - ears_after <= total_before - ears_before) {
    out.ears_held = crossing;
    note << ": kept the generic ear's shape, moved with the head around it (" << ears_after << " pairs)";
  } else {
    out.control = control_before;
    out.multires = multires_before;
    out.fold_limit = folds_before;
    out.zeroed_displacements = zeroed_before;
    reverted = true;
    note << "; holding them in the generic ear's shape did not help (" << ears_after << " pairs): left as fitted";
  }
  out.notes.push_back(note.str());
  return Status::success();
}

// The vertex mask grown by `rings` rings of neighbours (ring_distances).
std::vector<char> grown_by_rings(const MeshTopology& topo, const std::vector<char>& mask, int rings) {
  std::vector<int> sources;
  for (int v = 0; v < static_cast<int>(mask.size()); ++v)
    if (mask[v]) sources.push_back(v);
  const std::vector<int> ring = ring_distances(topo, sources, rings);
  std::vector<char> out(mask.size(), 0);
  for (size_t v = 0; v < out.size(); ++v) out[v] = ring[v] >= 0;
  return out;
}

// Whether tree was built over mesh's triangles (the relief's tree may be
// over another level when the fold limiter left it alone): refit it, else
// build one.
bool tree_over(const TriMesh& mesh, const MeshBvh& tree) {
  return !tree.empty() && tree.triangles == mesh.triangles && tree.positions.size() == mesh.positions.size();
}

// Scales the displacements of every level by a weight that is 0 on the
// control vertices in `mask` and 1 elsewhere, a new vertex taking the mean of
// its edge's endpoints: the detail fades out toward the masked area instead
// of stopping at a step.
void fade_displacements(const std::vector<char>& mask, MultiresMesh& mr) {
  std::vector<double> keep(mask.size());
  for (size_t v = 0; v < mask.size(); ++v) keep[v] = mask[v] ? 0.0 : 1.0;
  for (int l = 0; l <= mr.num_levels(); ++l) {
    for (size_t v = 0; v < keep.size(); ++v) mr.displacements[l][v] *= keep[v];
    if (l == mr.num_levels()) break;
    const ButterflyLevel& level = mr.levels[l];
    keep.resize(level.num_fine_vertices);
    for (int k = 0; k < level.num_new_vertices(); ++k)
      keep[level.num_coarse_vertices + k] =
          0.5 * (keep[level.edge_endpoints[k][0]] + keep[level.edge_endpoints[k][1]]);
  }
}

// FitHeadOptions::guard_feature_crossings. tree: a tree over the finest
// level's triangles (the relief's), refitted here and left fitted to the
// level as it ends when `searched` is set. kept: #V flags or empty, control
// vertices no step moves or relaxes (the scanned neck, fitted where it is
// scanned: the wide steps round the lips had carried it back to the
// generic neck).
Status guard_feature_crossings(const FitHeadOptions& options, const HeadAnnotations& ann, const MeshTopology& topo,
                               const std::vector<char>& kept_vertices, const std::vector<Vec3>& scan_points,
                               double cost_margin, FitHeadResult& out, MeshBvh& tree, bool& searched) {
  searched = false;
  MultiresMesh& mr = out.multires;
  const int L = mr.num_levels();
  const int nv = topo.num_vertices;
  if (!options.guard_feature_crossings || L == 0) return Status::success();
  std::vector<char> feature(nv, 0);
  for (const char* name : {"lips", "ears"})
    if (const auto r = ann.regions.find(name); r != ann.regions.end())
      for (int v : r->second)
        if (v >= 0 && v < nv) feature[v] = 1;
  const std::vector<char> feature_finest = propagate_vertex_mask(mr, feature)[L];
  TriMesh level;
  level.triangles = mr.triangles(L);
  level.positions = mr.state.displaced[L];
  auto is_feature = [&](const std::array<int, 2>& p) {
    for (int f : p)
      for (int v : level.triangles[f])
        if (feature_finest[v]) return true;
    return false;
  };
  auto split = [&](const std::vector<std::array<int, 2>>& pairs, int& features, int& others) {
    features = 0;
    for (const auto& p : pairs) features += is_feature(p);
    others = static_cast<int>(pairs.size()) - features;
  };
  std::vector<std::array<int, 2>> pairs;
  Status st = finest_crossing_pairs(out.fold_limit, level, pairs);
  if (!st) return st;
  int best_features = 0, best_others = 0;
  split(pairs, best_features, best_others);
  out.feature_guard.pairs_before = out.feature_guard.pairs_after = best_features;
  out.feature_guard.other_pairs_before = out.feature_guard.other_pairs_after = best_others;
  // Every other pair only at the finest of two or more levels: its steps
  // move control vertices toward the generic shape, and only finer levels'
  // displacements, measured again (guard_remeasure), give that detail back.
  // At one level the move is paid in the fit itself (Fran: its control mesh
  // 0.128 -> 0.172 %), so a one-level fit is guarded as before.
  const bool others_too = options.guard_other_crossings && L >= 2;
  if (best_features == 0 && (!others_too || best_others == 0)) return Status::success();

  searched = true;
  st = tree_over(level, tree) ? refit_bvh(level, tree) : build_bvh(level, tree);
  if (!st) return st;
  std::vector<Vec3> best_control = mr.control;
  std::vector<std::vector<double>> best_displacements = mr.displacements;
  std::vector<Vec3> best_level = level.positions;
  std::vector<char> relaxed(nv, 0), moved_ever(nv, 0);
  const int per_control = 1 << (2 * L);  // child c of triangle g is 4 g + c on every level
  // From the least change to the most (FitHeadOptions::guard_feature_crossings).
  struct Step {
    int rings;
    double share;  // of the way to the carried generic shape
    int smoothing; // or: sweeps of umbrella smoothing (halfway to the ring's mean) over the mask
  };
  const Step steps[] = {{0, 0.0, 0}, {1, 0.0, 0}, {2, 0.0, 0}, {1, 0.0, 2}, {1, 0.5, 0}, {1, 1.0, 0},
                        {2, 0.0, 4}, {2, 1.0, 0}, {3, 1.0, 0}, {3, 0.0, 8}, {5, 1.0, 0}};
  TriMesh target;
  target.triangles = mr.control_triangles;
  std::vector<char> moved_tris;
  std::vector<int> moved_list;
  std::vector<std::array<int, 2>> found;
  // The corners of the control faces under each crossing: pairs sharing a
  // corner make one cluster (the mouth, each ear, both sheets of a
  // crossing), tried on its own so that one giving way is not held back by
  // another that does not.
  std::vector<int> parent(nv);
  auto find = [&](int v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  // FitHeadOptions::guard_choose_by_cost: what a step loses, measured on
  // the scan's points near what it moved (their distance to the step's
  // level minus to the level before it), against a tree over that level.
  const bool by_cost = options.guard_choose_by_cost && !scan_points.empty();
  MeshBvh best_tree;
  if (by_cost) {
    st = build_bvh(level, best_tree);
    if (!st) return st;
  }
  std::vector<double> best_distance(by_cost ? scan_points.size() : 0, -1.0);  // -1: not yet measured
  auto step_cost = [&]() {
    Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    for (int t : moved_list)
      for (int v : level.triangles[t]) {
        lo = lo.cwiseMin(best_level[v]).cwiseMin(level.positions[v]);
        hi = hi.cwiseMax(best_level[v]).cwiseMax(level.positions[v]);
      }
    lo.array() -= cost_margin;
    hi.array() += cost_margin;
    double cost = 0;
    for (size_t i = 0; i < scan_points.size(); ++i) {
      const Vec3& p = scan_points[i];
      if ((p.array() < lo.array()).any() || (p.array() > hi.array()).any()) continue;
      if (best_distance[i] < 0) best_distance[i] = closest_point(best_tree, p).distance;
      cost += closest_point(tree, p).distance - best_distance[i];
    }
    return cost;
  };
  // One step on `mask` tried: the level it gives (in mr, level, tree) and
  // its pairs.
  std::vector<std::array<int, 2>> trial;
  int trial_features = 0, trial_others = 0;
  auto try_step = [&](const std::vector<char>& mask, const Step& step) -> Status {
    const double share = step.share;
    mr.control = best_control;
    if (share > 0) {
      target.positions = best_control;
      Status r = carry_mouth_bag(mask, topo, out.aligned, target);
      if (!r) return r;
      for (int v = 0; v < nv; ++v)
        if (mask[v]) mr.control[v] = best_control[v] + share * (target.positions[v] - best_control[v]);
    }
    for (int sweep = 0; sweep < step.smoothing; ++sweep)
      for (int v = 0; v < nv; ++v) {
        if (!mask[v] || topo.rings[v].empty() || topo.is_boundary(v)) continue;
        Vec3 mean = Vec3::Zero();
        for (int w : topo.rings[v]) mean += mr.control[w];
        mr.control[v] = 0.5 * (mr.control[v] + mean / static_cast<double>(topo.rings[v].size()));
      }
    mr.displacements = best_displacements;
    if (share > 0 || step.smoothing > 0) {
      // The detail over the moved vertices' Butterfly support (two rings)
      // was measured from the old surface: it goes too.
      fade_displacements(grown_by_rings(topo, mask, 2), mr);
    } else {
      fade_displacements(mask, mr);
    }
    Status r = evaluate(mr);
    if (!r) return r;
    // Only the triangles that moved are searched again.
    moved_triangles(level.triangles, best_level, mr.state.displaced[L], moved_tris, moved_list);
    level.positions = mr.state.displaced[L];
    r = refit_bvh(level, tree);
    if (!r) return r;
    find_intersections_with(tree, moved_list, found);
    trial = pairs_after_change(pairs, moved_tris, found);
    split(trial, trial_features, trial_others);
    return Status::success();
  };
  // A step is kept when it leaves fewer pairs at the lips and ears and
  // fewer in all (for_features), or fewer elsewhere and no more at the lips
  // and ears.
  auto fewer = [&](bool for_features) {
    return for_features ? trial_features < best_features && trial_features + trial_others < best_features + best_others
                        : trial_features <= best_features && trial_others < best_others;
  };
  auto keep_step = [&](const std::vector<char>& mask, const Step& step) {
    best_features = trial_features;
    best_others = trial_others;
    pairs = trial;
    best_control = mr.control;
    best_displacements = mr.displacements;
    best_level = level.positions;
    const bool moves = step.share > 0 || step.smoothing > 0;
    for (int v = 0; v < nv; ++v)
      if (mask[v]) relaxed[v] = 1, moved_ever[v] = moved_ever[v] || moves;
    ++out.feature_guard.steps;
  };
  std::ostringstream steps_note;  // which step each cluster kept
  auto describe = [](const Step& step) {
    std::ostringstream d;
    if (step.share > 0)
      d << (step.share < 1 ? "half" : "all") << " the way to the generic shape";
    else if (step.smoothing > 0)
      d << step.smoothing << " smoothing sweeps";
    else
      d << "displacements dropped";
    d << " over " << step.rings << " rings";
    return d.str();
  };
  // The lips and ears first, then (guard_other_crossings) every other pair.
  for (const bool for_features : {true, false}) {
    if (!for_features && !others_too) break;
    for (int round = 0; round < options.feature_guard_rounds; ++round) {
      if ((for_features ? best_features : best_others) == 0) break;
      for (int v = 0; v < nv; ++v) parent[v] = v;
      std::vector<char> seed(nv, 0);
      for (const auto& p : pairs)
        if (is_feature(p) == for_features) {
          const int first = mr.control_triangles[p[0] / per_control][0];
          for (int f : p)
            for (int v : mr.control_triangles[f / per_control]) seed[v] = 1, parent[find(v)] = find(first);
        }
      std::vector<std::vector<int>> clusters;
      {
        std::vector<int> index(nv, -1);
        for (int v = 0; v < nv; ++v)
          if (seed[v]) {
            int& c = index[find(v)];
            if (c < 0) c = static_cast<int>(clusters.size()), clusters.emplace_back();
            clusters[c].push_back(v);
          }
      }
      bool any = false;
      for (const std::vector<int>& cluster : clusters) {
        const std::vector<char> start = vertex_mask(cluster, nv);
        const int before = for_features ? best_features : best_others;
        // The ladder from the least change to the most; the first step
        // that leaves fewer pairs is kept, or (by_cost) the one that loses
        // least among it and the next guard_cost_extra_tries steps, leaving
        // no more pairs than it.
        const int num_steps = static_cast<int>(sizeof(steps) / sizeof(steps[0]));
        auto mask_of = [&](const Step& step) {
          std::vector<char> mask = grown_by_rings(topo, start, step.rings);
          if (!kept_vertices.empty())
            for (int v = 0; v < nv; ++v) mask[v] = mask[v] && !kept_vertices[v];
          return mask;
        };
        std::vector<GuardTry> tries;
        std::ostringstream costs;
        int first = -1;
        for (int k = 0; k < num_steps; ++k) {
          if (first >= 0 && (!by_cost || k > first + options.guard_cost_extra_tries)) break;
          st = try_step(mask_of(steps[k]), steps[k]);
          if (!st) return st;
          GuardTry t;
          t.helps = fewer(for_features);
          t.pairs_left = trial_features + trial_others;
          if (t.helps && first < 0) first = k;
          if (t.helps && by_cost) {
            t.cost = step_cost();
            costs << (costs.tellp() > 0 ? ", " : "") << k << ": " << t.pairs_left << " pairs, +"
                  << 1e6 * t.cost / static_cast<double>(scan_points.size()) << " um";
          }
          tries.push_back(t);
        }
        const int chosen = choose_guard_step(tries, by_cost, options.guard_cost_extra_tries);
        if (chosen >= 0) {
          const std::vector<char> mask = mask_of(steps[chosen]);
          if (chosen + 1 != static_cast<int>(tries.size())) {
            // Tried again: the steps are deterministic from the kept state.
            st = try_step(mask, steps[chosen]);
            if (!st) return st;
          }
          keep_step(mask, steps[chosen]);
          if (by_cost) {
            std::fill(best_distance.begin(), best_distance.end(), -1.0);
            st = refit_bvh(level, best_tree);
            if (!st) return st;
          }
          any = true;
          steps_note << (steps_note.tellp() > 0 ? "; " : "") << (for_features ? "lips/ears " : "elsewhere ")
                     << cluster.size() << " corners: " << describe(steps[chosen]) << " (" << before << " -> "
                     << (for_features ? best_features : best_others) << " pairs";
          if (by_cost) steps_note << "; step " << chosen << " of those that help: " << costs.str();
          steps_note << ")";
        }
        if ((for_features ? best_features : best_others) == 0) break;
      }
      if (!any) break;
    }
  }
  mr.control = best_control;
  mr.displacements = best_displacements;
  st = evaluate(mr);
  if (!st) return st;
  level.positions = mr.state.displaced[L];
  st = refit_bvh(level, tree);
  if (!st) return st;
  out.control.positions = best_control;
  // The pairs found are the level's (the searches around what moved find
  // what a whole search would): the quality report takes them.
  out.fold_limit.finest_pairs = pairs;
  out.fold_limit.finest_pairs_fingerprint = positions_fingerprint(level.positions);
  out.fold_limit.finest_pairs_known = true;
  out.feature_guard.pairs_after = best_features;
  out.feature_guard.other_pairs_after = best_others;
  for (int v = 0; v < nv; ++v) {
    out.feature_guard.relaxed_vertices += relaxed[v];
    out.feature_guard.moved_vertices += moved_ever[v];
  }
  std::ostringstream note;
  note << "level " << L << " crossed itself (" << out.feature_guard.pairs_before << " pairs at the lips or ears, "
       << out.feature_guard.other_pairs_before << " elsewhere): the displacements of "
       << out.feature_guard.relaxed_vertices << " control vertices there were dropped";
  if (out.feature_guard.moved_vertices)
    note << " and " << out.feature_guard.moved_vertices << " of them smoothed or moved toward the generic shape";
  note << " (" << best_features << " and " << best_others << " pairs left); steps kept: " << steps_note.str();
  out.notes.push_back(note.str());
  return Status::success();
}

}  // namespace

namespace {

Status fit_head_on(const PointCloud& scan, double scan_diagonal, const GenericHead& generic,
                   const FitHeadOptions& options, FitHeadResult& out, const FitStageObserver& observer,
                   const ProgressFn& progress);

// The result re-expressed in the head frame turned by Q (FitHeadOptions::
// face_frame): every point, vector and map in the head frame turns; the
// scan's frame and the figures do not change. The displacements are
// lengths along the normals: they stay.
void turn_result(const Mat3& Q, FitHeadResult& out) {
  if (Q == Mat3::Identity()) return;
  const Vec3 zero = Vec3::Zero();
  auto turn_map = [&](Mat3& A, Vec3& t) {
    A = Q * A;
    t = Q * t;
  };
  auto turn_all = [&](std::vector<Vec3>& v) {
    for (Vec3& p : v) p = Q * p;
  };
  turn_map(out.scan_to_head.A, out.scan_to_head.t);
  turn_map(out.generic_to_head.A, out.generic_to_head.t);
  for (TriMesh* m : {&out.aligned, &out.local, &out.control, &out.alignment.aligned}) transform(*m, Q, zero);
  for (TriMesh& m : out.level_meshes) transform(m, Q, zero);
  // The limiter's finest pairs describe the turned level as they did the
  // level (crossing is a property of the shape): their fingerprint follows.
  std::vector<Vec3>* finest = out.multires.state.displaced.empty() ? nullptr : &out.multires.state.displaced.back();
  const bool pairs_current = finest && finest_pairs_of(out.fold_limit, *finest);
  turn_all(out.multires.control);
  for (auto* arrays : {&out.multires.state.base, &out.multires.state.normals, &out.multires.state.displaced,
                       &out.multires.state.face_normals})
    for (std::vector<Vec3>& v : *arrays) turn_all(v);
  if (pairs_current) out.fold_limit.finest_pairs_fingerprint = positions_fingerprint(*finest);
  turn_map(out.alignment.linear, out.alignment.translation);
  turn_map(out.alignment.initial_linear, out.alignment.initial_translation);
  turn_map(out.face_alignment.linear, out.face_alignment.translation);
  out.face_alignment.rotation = Q * out.face_alignment.rotation;
  turn_map(out.face_refine.linear, out.face_refine.translation);
  // The boxes' maps act in the head frame: x -> A x + t becomes Q A Q^T x + Q t.
  auto turn_box = [&](BoxFit& b) {
    b.transform.A = Q * b.transform.A * Q.transpose();
    b.transform.t = Q * b.transform.t;
  };
  turn_box(out.eye_fit);
  for (BoxFit& b : out.local_fit.boxes) turn_box(b);
}

// 2000000 -> "2,000,000".
std::string with_commas(long long v) {
  std::string digits = std::to_string(v), out;
  for (size_t i = 0; i < digits.size(); ++i) {
    if (i > 0 && (digits.size() - i) % 3 == 0) out += ',';
    out += digits[i];
  }
  return out;
}

}  // namespace

Status thin_scan_for_fit(const PointCloud& scan, const GenericHead& generic, const FitHeadOptions& options,
                         PointCloud& thinned, ScanThinning& thinning) {
  thinning = ScanThinning{};
  thinning.points = thinning.kept = scan.size();
  if (!(options.thin_cells_per_edge > 0) || !scan.faces.empty() || scan.positions.empty() ||
      generic.mesh.triangles.empty() || options.levels < 0 || options.levels > 5)
    return Status::success();
  for (const Vec3& p : scan.positions)
    if (!p.allFinite()) return Status::success();  // fit_head says so
  const double diag = bounding_box(scan.positions).diagonal();
  if (!(diag > 0)) return Status::success();
  // The generic head's finest-level edge (metres) in the scan's unit.
  const double edge = mean_edge_length(generic.mesh) / double(1 << options.levels);
  const double cell = edge / options.thin_cells_per_edge / guess_unit_to_metres(diag);
  // The points fit_head would leave out as isolated (hair returns, stray
  // reflections; DisplacementOptions::isolated_density_ratio), found
  // against the full scan's own spacing: averaged in, they would not look
  // isolated among the averages and were fitted (a 2M-point synthetic
  // scan's face went 0.09 -> 0.22 mm from its truth).
  std::vector<char> isolated;
  if (options.displacement.isolated_density_ratio > 0)
    isolated = isolated_scan_points(scan.positions, options.displacement.isolated_density_ratio);
  PointCloud averaged;
  ScanThinning t;
  const Status st = thin_scan(scan, cell, averaged, t, isolated);
  if (!st) return st;
  if (t.kept > options.thin_max_share * t.points) {
    thinning.cell = t.cell;
    return Status::success();
  }
  thinned = std::move(averaged);
  thinning = t;
  thinning.bbox_diagonal = diag;
  return Status::success();
}

Status fit_head_thinned(const PointCloud& thinned, const ScanThinning& thinning, const GenericHead& generic,
                        const FitHeadOptions& options, FitHeadResult& out, const FitStageObserver& observer,
                        const ProgressFn& progress) {
  FitHeadOptions inner = options;
  inner.thin_cells_per_edge = 0;
  const Status st = fit_head_on(thinned, thinning.bbox_diagonal, generic, inner, out, observer, progress);
  out.points = thinning.points;
  out.thinning = thinning;
  if (thinning.thinned) {
    std::ostringstream cell;
    cell.precision(2);
    cell << 1000 * thinning.cell * out.unit_to_metres;
    out.notes.push_back(with_commas(thinning.points) + " points, fitted on " + with_commas(thinning.kept) +
                        " evenly spaced: the average of the points in each " + cell.str() +
                        " mm cell (the fit's finest level cannot use more)");
  }
  return st;
}

Status fit_head(const PointCloud& scan, const GenericHead& generic, const FitHeadOptions& options,
                FitHeadResult& out, const FitStageObserver& observer, const ProgressFn& progress) {
  return fit_head_on(scan, 0, generic, options, out, observer, progress);
}

namespace {

// fit_head_on in the axes of options only (no second convention).
Status fit_head_in_axes(const PointCloud& scan, double scan_diagonal, const GenericHead& generic,
                        const FitHeadOptions& options, FitHeadResult& out, const FitStageObserver& observer,
                        const ProgressFn& progress);

// fit_head with the scan's size given: a thinned cloud (its isolated points
// left out) is fitted at the full scan's bbox diagonal, which sets the
// unit, Table 1's percentages and the fit's distances in percent of it.
// scan_diagonal 0: the cloud's own. A scan refused in the default axes is
// aligned once more as Blender and CAD tools write it, for the refusal to
// name those axes where that passes (FitHeadOptions::suggest_z_up).
Status fit_head_on(const PointCloud& scan, double scan_diagonal, const GenericHead& generic,
                   const FitHeadOptions& options, FitHeadResult& out, const FitStageObserver& observer,
                   const ProgressFn& progress) {
  const Status first = fit_head_in_axes(scan, scan_diagonal, generic, options, out, observer, progress);
  if (first.code != ErrorCode::NotAHead || !options.suggest_z_up ||
      options.orientation_check != FitHeadOptions::OrientationCheck::Auto || options.up != Vec3::UnitY() ||
      options.facing != Vec3::UnitZ())
    return first;
  FitHeadOptions z_up = options;
  z_up.up = Vec3::UnitZ();
  z_up.facing = -Vec3::UnitY();
  z_up.orientation_check = FitHeadOptions::OrientationCheck::Off;  // taken as given, checked by the same shares
  bool aligned = false;  // stopped here once the alignment passed
  const ProgressFn until_aligned = [&](const char* stage, double fraction) {
    if (std::string(stage) == "initial_alignment" && fraction >= 1.0) {
      aligned = true;
      return false;
    }
    return !progress || progress(stage, fraction);
  };
  FitHeadResult second;
  const Status st = fit_head_in_axes(scan, scan_diagonal, generic, z_up, second, {}, until_aligned);
  if (st.code == ErrorCode::Cancelled && !aligned) return st;  // the user's cancel
  if (!aligned) return first;
  // The axes that pass stand where the refusal guessed at some.
  std::string message = first.message;
  const std::string guess = kAxesHint;
  const bool guessed =
      message.size() >= guess.size() && message.compare(message.size() - guess.size(), guess.size(), guess) == 0;
  if (guessed) message.resize(message.size() - guess.size());
  message += std::string(guessed ? " (" : "; ") +
             "with +z up and the face along -y, as Blender and CAD tools write scans, the alignment passes; try "
             "--facing 0 -1 0 --up 0 0 1" + (guessed ? ")" : "");
  return Status::error(first.code, message);
}

Status fit_head_in_axes(const PointCloud& scan, double scan_diagonal, const GenericHead& generic,
                        const FitHeadOptions& options, FitHeadResult& out, const FitStageObserver& observer,
                        const ProgressFn& progress) {
  out = FitHeadResult{};
  const int n = scan.size();
  out.points = n;
  out.thinning.points = out.thinning.kept = n;
  if (n == 0) return Status::error(ErrorCode::Empty, "the scan has no points");
  for (const Vec3& p : scan.positions)
    if (!p.allFinite()) return Status::error(ErrorCode::InvalidInput, "the scan has non-finite coordinates");
  if (options.levels < 0 || options.levels > 5)
    return Status::error(ErrorCode::InvalidInput, "levels must be in 0..5");
  if (!(options.scanned_neck_max_angle_deg >= 0 && options.scanned_neck_max_angle_deg <= 90))
    return Status::error(ErrorCode::InvalidInput, "scanned_neck_max_angle_deg must be in 0..90");
  if (options.ear_refit_warm_rounds < 0)
    return Status::error(ErrorCode::InvalidInput, "ear_refit_warm_rounds must be >= 0");
  if (generic.mesh.triangles.empty())
    return Status::error(ErrorCode::InvalidInput, "the generic head has no triangles");
  if (n < options.min_points)
    return Status::error(ErrorCode::NotAHead, "only " + std::to_string(n) + " points; a head scan needs at least " +
                                                  std::to_string(options.min_points));
  if (options.thin_cells_per_edge > 0) {
    PointCloud thinned;
    ScanThinning thinning;
    const Status thin = thin_scan_for_fit(scan, generic, options, thinned, thinning);
    if (!thin) return thin;
    if (thinning.thinned) return fit_head_thinned(thinned, thinning, generic, options, out, observer, progress);
  }

  // Head frame: rotate by the conventions, scale by the guessed unit.
  Mat3 R;
  Status st = orientation_from_conventions(options.up, options.facing, R);
  if (!st) return st;
  const BBox box = bounding_box(scan.positions);
  out.bbox_diagonal = scan_diagonal > 0 ? scan_diagonal : box.diagonal();
  if (!(out.bbox_diagonal > 0)) return Status::error(ErrorCode::NotAHead, "all scan points coincide");
  out.unit_to_metres = guess_unit_to_metres(out.bbox_diagonal);
  out.scan_to_head.A = out.unit_to_metres * R;
  PointCloud cloud;
  cloud.positions.reserve(n);
  for (const Vec3& p : scan.positions) cloud.positions.push_back(out.scan_to_head.apply(p));
  const double diag = out.bbox_diagonal * out.unit_to_metres;

  // A flat cloud (a wall, a sheet of paper) has one tiny principal extent.
  {
    Vec3 mean = Vec3::Zero();
    for (const Vec3& p : cloud.positions) mean += p;
    mean /= n;
    Mat3 cov = Mat3::Zero();
    for (const Vec3& p : cloud.positions) cov += (p - mean) * (p - mean).transpose();
    cov /= n;
    Eigen::SelfAdjointEigenSolver<Mat3> eig(cov);
    const Vec3 ev = eig.eigenvalues().cwiseMax(0.0);
    const double ratio = std::sqrt(ev[0] / std::max(ev[2], 1e-300));
    if (ratio < options.min_thickness_ratio)
      return Status::error(ErrorCode::NotAHead, "the points lie nearly in a plane (thickness ratio " + pct(ratio) +
                                                    "); a head scan has depth");
  }

  MeshTopology topo;
  st = build_topology(generic.mesh, topo);
  if (!st) return with_context(st, "generic head");
  const HeadAnnotations& ann = generic.annotations;
  // What the alignment matches: the skin as cast where the head was faired
  // (GenericHead::alignment_positions), else the head itself.
  GenericHead cast;
  const bool faired = generic.alignment_positions.size() == generic.mesh.positions.size();
  if (faired) {
    cast.mesh = generic.mesh;
    cast.mesh.positions = generic.alignment_positions;
    cast.mesh.normals.clear();
    cast.annotations = generic.annotations;
  }
  const GenericHead& to_align = faired ? cast : generic;

  // The scan points' distances to `surface`; tree (optional): a tree over
  // exactly `surface`, taken over for the closest points instead of building one.
  auto surface_distance = [&](const TriMesh& surface, const std::vector<Vec3>& pts, MeshBvh* tree = nullptr) {
    ClosestPointTree closest;
    if (tree) closest.build(surface, *tree);
    else closest.build(surface);
    return point_to_surface_stats(thin(pts, options.stats_max_points), closest, diag);
  };
  auto stage_done = [&](const char* name, const TriMesh& surface, const std::vector<Vec3>& pts,
                        MeshBvh* tree = nullptr) {
    if (observer.finished) {
      if (out.face_frame_turn == Mat3::Identity()) {
        observer.finished(name, surface);
      } else {  // shown as the result will be (FitHeadOptions::face_frame)
        TriMesh turned = surface;
        transform(turned, out.face_frame_turn, Vec3::Zero());
        observer.finished(name, turned);
      }
    }
    FitStageReport rep;
    rep.name = name;
    if (options.measure_stages) rep.distance = surface_distance(surface, pts, tree);
    rep.as_fitted = rep.distance;
    out.stages.push_back(rep);
    if (observer.measured) observer.measured(rep);
  };
  auto cancelled = [&] { return Status::error(ErrorCode::Cancelled, "fit cancelled"); };

  // 1. Initial alignment.
  if (observer.started) observer.started("initial_alignment");
  // The scan and the result before a turn, for check_turn below.
  PointCloud as_given;
  const FitHeadResult before_turn = out;
  st = check_orientation(to_align, options, R, scan.faces, cloud, out, as_given, progress);
  if (!st) return st;
  // The points to fit (the neck below the generic head's neck is not part
  // of the model, and would drag its boundary down) and the share of them
  // near the aligned head, for the alignment as it stands.
  std::vector<Vec3> pts;
  std::vector<int> pts_index;  // into the scan, for its normals
  ClipPlane neck;
  auto place = [&]() -> Status {
    out.generic_to_head.A = out.alignment.linear;
    out.generic_to_head.t = out.alignment.translation;
    out.aligned = to_align.mesh;
    for (Vec3& p : out.aligned.positions) p = out.generic_to_head.apply(p);
    out.aligned.normals.clear();
    pts.clear();
    pts_index.clear();
    pts.reserve(n);
    neck = transform_plane(ann.neck_clip, out.generic_to_head);
    for (int i = 0; i < n; ++i)
      if (!options.cut_neck || neck.keeps(cloud.positions[i])) pts.push_back(cloud.positions[i]), pts_index.push_back(i);
    out.fitted_points = static_cast<int>(pts.size());
    if (out.fitted_points < options.min_points)
      return Status::error(ErrorCode::NotAHead, "only " + std::to_string(out.fitted_points) +
                                                    " points above the aligned head's neck");
    out.near_fraction = near_share(out.aligned, pts, options.near_distance_pct / 100.0 * diag, 20000);
    return Status::success();
  };
  // The triangles the face is matched on: none (its vertices) on a mesh
  // finer than FitHeadOptions::face_match_vertices_edge.
  static const std::vector<Tri> no_faces;
  const std::vector<Tri>& face_match_faces =
      options.face_match_vertices_edge > 0 &&
              mean_edge_length(cloud.positions, scan.faces) < options.face_match_vertices_edge * diag
          ? no_faces
          : scan.faces;
  // The same share for another alignment, on fewer points: what chooses the
  // face's pitch (FitHeadOptions::choose_face_pitch).
  const AlignmentMeasure share_near = [&](const Mat3& linear, const Vec3& translation) {
    const AffineMap map{linear, translation};
    TriMesh moved = to_align.mesh;
    for (Vec3& p : moved.positions) p = map.apply(p);
    const ClipPlane cut = transform_plane(ann.neck_clip, map);
    std::vector<Vec3> kept;
    for (const Vec3& p : cloud.positions)
      if (!options.cut_neck || cut.keeps(p)) kept.push_back(p);
    return near_share(moved, kept, options.near_distance_pct / 100.0 * diag, options.choose_pitch_points);
  };
  // What the silhouettes and the coverage see: the cloud, or (when
  // silhouette_input is filled: FitHeadOptions::dense_mesh_retry_cell) the
  // surface's cell averages. The near rule and the face's match stay on
  // the scan itself.
  PointCloud silhouette_input;
  // The alignment of the cloud as it is now turned; NotAHead when too few
  // of its points lie near the aligned head.
  const auto align_scan = [&]() -> Status {
    const PointCloud& seen = silhouette_input.positions.empty() ? cloud : silhouette_input;
    st = estimate_coverage(seen, options.coverage, out.coverage);
    if (!st) return with_context(st, "coverage");
    out.face_only = options.scan_kind == FitHeadOptions::ScanKind::FaceOnly ||
                    (options.scan_kind == FitHeadOptions::ScanKind::Auto && out.coverage.face_only);
    if (out.face_only) {
      st = align_face(to_align.mesh, ann, cloud, options.face_align, out.face_alignment, progress);
      if (!st) return with_context(st, "initial alignment (face-only scan)");
      out.alignment.linear = out.alignment.initial_linear = out.face_alignment.linear;
      out.alignment.translation = out.alignment.initial_translation = out.face_alignment.translation;
      out.alignment.aligned = to_align.mesh;
      transform(out.alignment.aligned, out.alignment.linear, out.alignment.translation);
      out.notes.push_back("face-only scan (its upper part is " + pct(out.coverage.depth_to_width) +
                          "x as deep as wide; a whole head is 1x or more): aligned by closest points, and the "
                          "unscanned back, scalp and ears keep the generic head's shape");
    } else {
      st = align_initial(to_align.mesh, ann, seen, options.align, out.alignment, progress);
      if (!st) return with_context(st, "initial alignment");
    }
    st = place();
    if (!st) return st;
    // Sanity: a head scan lies on (near) the aligned generic head; noise,
    // furniture or a torso do not. A whole head with surfaces the generic
    // head lacks (a hat, a beard, a pedestal) may fail it because the
    // silhouettes misled the alignment: it is aligned again on the face.
    bool silhouette_face_holds = false;  // the silhouettes' own alignment, by the face's rule below
    const AlignResult silhouette_alignment = out.alignment;
    const double silhouette_near = out.near_fraction;
    double silhouette_face_near = 0;
    const size_t notes_before_face = out.notes.size();
    std::string pitches_tried;  // the face's pitch candidates and their shares, for the messages
    // The face's rule after its match: the face must lie on the scan as the
    // whole head would (the same share), and half that share of the points
    // near the whole head (the rest may be a hat, a beard, shoulders).
    auto face_rule_holds = [&] {
      return out.refined_on_face && out.face_refine.near_fraction >= options.min_near_fraction &&
             out.near_fraction >= 0.5 * options.min_near_fraction;
    };
    // The face's match with its symmetric turns first (FaceRefineOptions::
    // symmetry_yaw_start: a head turned on its bust), and again without
    // them where that leaves the scan refused (Gutenberg's copy turned by
    // 0.05 deg: docs/design/fit_real_scans.md).
    for (int attempt = 0; attempt < 2; ++attempt) {
      FaceRefineOptions face_options = options.face_refine;
      if (attempt == 1) {
        face_options.symmetry_yaw_start = false;
        out.notes.resize(notes_before_face);
        out.alignment = silhouette_alignment;
        st = place();
        if (!st) return st;
        out.refined_on_face = false;
        out.face_refine = FaceRefineResult{};
        pitches_tried.clear();
      }
      if (out.near_fraction < options.min_near_fraction && !out.face_only && options.refine_on_face) {
        st = upper_face_near_fraction(to_align.mesh, ann, cloud.positions, face_match_faces, out.alignment.linear,
                                      out.alignment.translation, diag, face_options.score_clamp_fraction,
                                      silhouette_face_near, face_options.samples);
        silhouette_face_holds = st && silhouette_face_near >= options.min_near_fraction &&
                                out.near_fraction >= 0.5 * options.min_near_fraction;
        st = refine_alignment_on_face(to_align.mesh, ann, cloud.positions, face_match_faces, out.alignment.linear,
                                      out.alignment.translation, diag, face_options, out.face_refine);
        if (st) {
          out.notes.push_back("after the silhouette alignment only " + pct(100 * out.near_fraction) +
                              "% of the points lay near the head (a hat, a beard, a pedestal?): aligned again on the face (" +
                              pct(100 * out.face_refine.near_fraction) + "% of its points on the scan)");
          out.alignment.linear = out.face_refine.linear;
          out.alignment.translation = out.face_refine.translation;
          st = place();
          if (!st) return st;
          out.refined_on_face = true;
          out.alignment.aligned = out.aligned;
        }
        // When that match (from the silhouettes' pitch) does not hold either,
        // the silhouettes' minima lie too close to choose by them or by the
        // face: other pitches are matched and the share of the points near the
        // head chooses (FitHeadOptions::choose_face_pitch; Gutenberg turned by
        // 0.05 deg: docs/design/align.md, "Choosing the pitch"). Not when the
        // silhouettes' own alignment passes the face's rule: it is kept below.
        const bool holds = face_rule_holds();
        FaceRefineResult chosen;
        if (st && !holds && !silhouette_face_holds && options.choose_face_pitch &&
            refine_alignment_on_face(to_align.mesh, ann, cloud.positions, face_match_faces, silhouette_alignment.linear,
                                     silhouette_alignment.translation, diag, face_options, chosen, share_near)) {
          for (const FaceRefineCandidate& c : chosen.candidates)
            pitches_tried += (pitches_tried.empty() ? "" : ", ") + pct(c.pitch_deg) + " deg " + pct(100 * c.measure) + "%";
          const AlignResult first = out.alignment;
          const double first_near = out.near_fraction;
          out.alignment.linear = chosen.linear;
          out.alignment.translation = chosen.translation;
          st = place();
          if (!st) return st;
          if (out.near_fraction > first_near) {
            out.face_refine = chosen;
            out.alignment.aligned = out.aligned;
            out.notes.push_back("the face's match left only " + pct(100 * first_near) +
                                "% of the points near the head: its pitch chosen again by that share (" + pitches_tried +
                                "): " + pct(chosen.candidates[chosen.chosen].pitch_deg) + " deg, " +
                                pct(100 * out.near_fraction) + "% near");
          } else {
            out.alignment = first;
            st = place();
            if (!st) return st;
          }
        }
      }
      const bool refused = out.near_fraction < options.min_near_fraction && !face_rule_holds() && !silhouette_face_holds;
      if (!refused || !options.face_refine.symmetry_yaw_start) break;
    }
    bool face_holds = face_rule_holds();
    if (out.near_fraction < options.min_near_fraction && !face_holds && silhouette_face_holds) {
      // The face's match went astray while the silhouettes' alignment passes
      // the face's rule itself (Plato with a generic head whose mouth moved a
      // few millimetres: docs/design/fit_real_scans.md): that one is kept.
      out.notes.resize(notes_before_face);  // its "aligned again on the face"
      out.alignment = silhouette_alignment;
      st = place();
      if (!st) return st;
      out.refined_on_face = false;
      out.notes.push_back("after the silhouette alignment only " + pct(100 * silhouette_near) +
                          "% of the points lay near the head, but " + pct(100 * silhouette_face_near) +
                          "% of its upper face lies on the scan (the face's own match did not hold): kept");
      face_holds = true;
    }
    if (out.near_fraction < options.min_near_fraction && !face_holds)
      return Status::error(ErrorCode::NotAHead,
                           "after alignment only " + pct(100 * out.near_fraction) + "% of the points lie within " +
                               pct(options.near_distance_pct) + "% of the diagonal of the head surface (need " +
                               pct(100 * options.min_near_fraction) + "%" +
                               (pitches_tried.empty() ? "" : "; aligned on the face from pitches " + pitches_tried) +
                               "); this does not look like a head scan" + kAxesHint);
    return Status::success();
  };
  st = align_scan();
  if (st.code == ErrorCode::Cancelled) return st;
  if (out.turned) {
    st = check_turn(st, as_given, before_turn, options.near_distance_pct / 100.0 * diag, align_scan, cloud, out);
    if (st) st = place();
  }
  const bool auto_turn = options.orientation_check == FitHeadOptions::OrientationCheck::Auto;
  if (st.code == ErrorCode::NotAHead && options.orientation_retry_unscreened && auto_turn &&
      options.orientation.screen_iterations > 0) {
    FitHeadOptions unscreened = options;
    unscreened.orientation.screen_iterations = 0;
    st = retry_orientation(st, to_align, unscreened, "searched again with every start run through", false, R,
                           scan.faces, before_turn, as_given, align_scan, cloud, out, progress);
    if (st) st = place();
  }
  if (st.code == ErrorCode::NotAHead && options.orientation_surface_retry_cell > 0 && auto_turn &&
      !scan.faces.empty() && !(options.orientation_surface_cell > 0)) {
    FitHeadOptions on_surface = options;
    on_surface.orientation_surface_cell = options.orientation_surface_retry_cell;
    st = retry_orientation(st, to_align, on_surface, "searched again on the scan's surface, not its vertices", true, R,
                           scan.faces, before_turn, as_given, align_scan, cloud, out, progress);
    if (st) st = place();
  }
  if (st.code == ErrorCode::NotAHead && options.dense_mesh_retry_cell > 0 && !scan.faces.empty() &&
      surface_cell_averages(cloud.positions, scan.faces, options.dense_mesh_retry_cell * diag, silhouette_input) &&
      silhouette_input.positions.size() < cloud.positions.size()) {
    // A dense mesh's silhouettes close fewer gaps than its decimated copy's,
    // and a bust's pitch has two basins that closing decides between
    // (Gutenberg at full density refused, decimated fitted): refused, it is
    // aligned once more with the silhouettes taken from its surface's cell
    // averages, about as many points as a decimated scan has; kept only when
    // that passes (docs/design/fit_real_scans.md, "A dense mesh aligned
    // again on its surface").
    const Status refused = st;
    FitHeadResult refused_out = out;
    st = align_scan();
    if (st.code == ErrorCode::Cancelled) return st;
    if (st) {
      out.notes.push_back("refused on its " + std::to_string(cloud.positions.size()) +
                          " vertices, the mesh was aligned again with its silhouettes taken from " +
                          std::to_string(silhouette_input.positions.size()) + " averages over its surface");
    } else {
      out = std::move(refused_out);
      st = refused;
    }
    silhouette_input = PointCloud{};
    if (st) st = place();
  }
  if (!st) return st;
  if (options.face_frame) {
    // The turn about the head frame's up to the aligned generic face's look
    // (FitHeadOptions::face_frame), applied to the result at the end
    // (turn_result): the fit itself runs in the frame it was aligned in.
    const Mat3 turn = nearest_rotation(out.generic_to_head.A);
    const Vec3 look = turn * Vec3::UnitZ();
    if (turn.determinant() > 0 && std::hypot(look.x(), look.z()) > 0.5) {
      const double yaw = std::atan2(look.x(), look.z());
      out.face_frame_turn = Mat3(Eigen::AngleAxisd(-yaw, Vec3::UnitY()));
      out.face_frame_deg = yaw * 180.0 / 3.14159265358979323846;
    }
  }
  if (faired) {  // the fit starts from the faired skin, placed as the cast one was aligned
    out.aligned = generic.mesh;
    for (Vec3& p : out.aligned.positions) p = out.generic_to_head.apply(p);
    out.aligned.normals.clear();
    out.alignment.aligned = out.aligned;
  }
  stage_done("initial_alignment", out.aligned, pts);
  if (!report(progress, "initial_alignment", 1.0)) return cancelled();

  // 2. Local fitting: the eye region (the alignment may leave the generic
  // eyes a centimetre off: James's 10 mm too high), then ears, nose, mouth.
  if (observer.started) observer.started("local_fitting");
  TriMesh eyes_placed = out.aligned;
  out.eye_fit = BoxFit{};
  out.eye_fit.skipped = true;
  if (options.fit_eye_region && !ann.eye_left.rim.empty() && !ann.eye_right.rim.empty()) {
    SoftRegion eyes;
    st = eye_region(generic.mesh, ann, options.eye_region, eyes);
    if (st)
      st = fit_soft_region(pts, out.aligned, topo, eyes, out.generic_to_head, options.local, eyes_placed,
                           out.eye_fit, progress);
    if (!st) return with_context(st, "local fitting (eyes)");
  }
  st = fit_local(pts, eyes_placed, topo, ann.boxes, out.generic_to_head, diag, options.local, out.local,
                 out.local_fit, progress);
  if (!st) return with_context(st, "local fitting");
  stage_done("local_fitting", out.local, pts);

  // 3. Global fitting.
  if (observer.started) observer.started("global_fitting");
  // The pockets (eye sockets, mouth bag) are not skin: a scanner sees the
  // eyeball or the closed lips in front of them, and points there pulled
  // the sockets out through the lids (creases from the eye corners on the
  // menpo3d James scan), so the points whose nearest surface is a pocket do
  // not pull. The mouth bag stays where local fitting put it, as the
  // paper's E_constraint keeps the inner lips. An eye socket instead keeps
  // its SHAPE and follows its rim (its edges are binding edges, E_binding
  // binds edge vectors): held in place, it made the lid margin between rim
  // and socket turn over wherever the lids moved (James: the eyes lie 10 mm
  // below where the alignment put the generic ones).
  const std::vector<char> pocket = pocket_vertices(topo, ann);
  const std::vector<char> mouth_bag = vertex_mask(ann.constrained_vertices, static_cast<int>(pocket.size()));
  GlobalFitTerms terms;
  terms.binding_edges = ann.binding_edges;
  {
    auto in_eye_socket = [&](int v) { return pocket[v] && !mouth_bag[v]; };
    for (int v = 0; v < static_cast<int>(pocket.size()); ++v)
      if (mouth_bag[v]) terms.constrained_vertices.push_back(v);
    for (const Edge& e : topo.edges)
      if (in_eye_socket(e.v0) || in_eye_socket(e.v1)) terms.binding_edges.push_back({{e.v0, e.v1}});
  }
  // The ears' edges as binding edges (FitHeadOptions::bind_ear_edges): on
  // face captures from the start; on whole heads where the free fit folds
  // an ear (below).
  std::vector<std::array<int, 2>> ear_edges;
  std::vector<int> ear_vertices;
  if (const auto ears = ann.regions.find("ears"); ears != ann.regions.end()) {
    ear_vertices = ears->second;
    const std::vector<char> in_ear = vertex_mask(ears->second, static_cast<int>(pocket.size()));
    for (const Edge& e : topo.edges)
      if (in_ear[e.v0] && in_ear[e.v1]) ear_edges.push_back({{e.v0, e.v1}});
  }
  using EarBinding = FitHeadOptions::EarBinding;
  const bool bind_ears_first = options.bind_ear_edges == EarBinding::Always ||
                               (options.bind_ear_edges != EarBinding::Off && out.face_only);
  const bool bind_ears_where_crossing = options.bind_ear_edges == EarBinding::WhereTheyCross && !out.face_only;
  if (bind_ears_first) terms.binding_edges.insert(terms.binding_edges.end(), ear_edges.begin(), ear_edges.end());
  // The template as aligned: the rest shape of E_smooth and the orientation
  // every triangle must keep (global_fit.h: local fitting's blend leaves
  // steps at the box walls and may turn triangles, which a rest shape taken
  // after it would hold).
  terms.fold_reference = out.aligned.positions;
  // The smooth-surface guard refines with the creases the levels will use.
  ButterflyCreases creases;
  if (options.rim_creases) creases = head_creases(generic.mesh, ann);
  terms.smooth_creases = creases;
  terms.smooth_guard_ignored = mouth_bag;
  // E_back leaves the pockets (their points are not fitted) and the ears
  // (seen from the side under hair on face captures, held in shape by
  // their binding edges) alone.
  terms.back_ignored = pocket;
  if (const auto ears = ann.regions.find("ears"); ears != ann.regions.end())
    for (int v : ears->second) terms.back_ignored[v] = 1;
  std::vector<Vec3> skin_pts;
  std::vector<int> skin_index;
  skin_pts.reserve(pts.size());
  const ClosestPointTree local_tree(out.local);
  {
    std::vector<char> on_pocket(pts.size(), 0);
    parallel_for(0, static_cast<int>(pts.size()), 2048, [&](int i, int) {
      const SurfaceHit c = local_tree.closest(pts[i]);
      if (c.face >= 0)
        for (int v : out.local.triangles[c.face]) on_pocket[i] = on_pocket[i] || pocket[v];
    });
    for (size_t i = 0; i < pts.size(); ++i)
      if (!on_pocket[i]) skin_pts.push_back(pts[i]), skin_index.push_back(pts_index[i]);
  }
  out.pocket_points = static_cast<int>(pts.size() - skin_pts.size());
  const auto neck_region = ann.regions.find("neck");
  // The neck's control vertices (#V flags; empty: no neck region).
  const std::vector<char> in_neck = neck_region == ann.regions.end()
                                        ? std::vector<char>{}
                                        : vertex_mask(neck_region->second, out.local.num_vertices());
  const bool scanned_neck = options.cut_neck && options.fit_scanned_neck && !out.face_only &&
                            neck_region != ann.regions.end();
  std::vector<Vec3> neck_pts;  // FitHeadOptions::fit_scanned_neck's points below the cut
  std::vector<int> neck_index;
  if (scanned_neck) {
    // FitHeadOptions::fit_scanned_neck: the scan's neck below the cut, on
    // the neck's triangles and along their normals (not beyond its rim).
    double lowest = 0;  // the aligned generic neck's lower end, below the cut
    for (const Vec3& v : out.aligned.positions) lowest = std::min(lowest, neck.normal.dot(v - neck.point));
    const double min_cos = std::cos(options.scanned_neck_max_angle_deg * 3.14159265358979323846 / 180.0);
    std::vector<char> take(n, 0);
    parallel_for(0, n, 2048, [&](int i, int) {
      const double h = neck.normal.dot(cloud.positions[i] - neck.point);
      if (h >= 0 || h < lowest) return;
      const SurfaceHit c = local_tree.closest(cloud.positions[i]);
      if (c.face < 0) return;
      const Tri& t = out.local.triangles[c.face];
      if (!in_neck[t[0]] || !in_neck[t[1]] || !in_neck[t[2]]) return;
      const Vec3 normal = (out.local.positions[t[1]] - out.local.positions[t[0]])
                              .cross(out.local.positions[t[2]] - out.local.positions[t[0]]);
      const Vec3 off = cloud.positions[i] - c.point;
      const double along = std::abs(normal.dot(off)), size = normal.norm() * off.norm();
      take[i] = size == 0 || along >= min_cos * size;
    });
    for (int i = 0; i < n; ++i)
      if (take[i]) neck_pts.push_back(cloud.positions[i]), neck_index.push_back(i);
  }
  // Points far sparser than the scan's own sampling (hair returns, stray
  // reflections) are not skin: fitted as a surface they raised bumps along
  // the hairline. They stay in the reported distances (Table 1 is over all
  // points). The neck's are dropped among themselves, as the band's below.
  out.isolated_points = drop_isolated_points(options.displacement.isolated_density_ratio, skin_pts, skin_index);
  out.isolated_points += drop_isolated_points(options.displacement.isolated_density_ratio, neck_pts, neck_index);
  out.neck_points = static_cast<int>(neck_pts.size());
  if (static_cast<int>(skin_pts.size()) < options.min_points)
    return Status::error(ErrorCode::NotAHead, "only " + std::to_string(skin_pts.size()) +
                                                  " points lie on the skin of the aligned head");
  GlobalFitOptions global_options = options.global;
  const bool smooth_guarded = options.smooth_guard == FitHeadOptions::SmoothGuard::Always ||
                              (options.smooth_guard == FitHeadOptions::SmoothGuard::FaceOnlyScans && out.face_only);
  if (!smooth_guarded) global_options.smooth_guard_level = 0;
  if (!out.face_only && options.whole_head_data_level >= 0) global_options.data_level = options.whole_head_data_level;
  const bool back_term = options.back_term == FitHeadOptions::BackTerm::Always ||
                         (options.back_term == FitHeadOptions::BackTerm::FaceOnlyScans && out.face_only);
  global_options.back_weight = back_term ? options.back_weight : 0.0;
  if (back_term && !scan.faces.empty() && global_options.back_ray_edges > 0) {
    // E_back's normal rays (global_fit.h) reach the scan's triangles over
    // fitted skin only: not below the neck cut (the collar), not pockets,
    // not isolated points.
    std::vector<char> skin(cloud.positions.size(), 0);
    for (int i : skin_index) skin[i] = 1;
    terms.back_surface.positions = cloud.positions;
    for (const Tri& t : scan.faces)
      if (skin[t[0]] && skin[t[1]] && skin[t[2]]) terms.back_surface.triangles.push_back(t);
  }
  // The relief's tree over the smooth level 3: the fold limiter refits it
  // to the displaced level instead of building one (~50 ms).
  MeshBvh relief_tree;
  const bool ear_refit = bind_ears_where_crossing && !ear_edges.empty() && options.levels > 0;
  if (!ear_refit) {
    st = fit_global(skin_pts, out.local, topo, terms, global_options, out.control, out.global_fit, progress,
                    &relief_tree);
    if (!st) return with_context(st, "global fitting");
  } else {
    // FitHeadOptions::bind_ear_edges: when the free fit's smooth finest
    // level crosses itself at an ear, the fit is made again with the ears'
    // edges bound and kept when its ears do not cross there.
    const std::vector<char> ear_mask_control = vertex_mask(ear_vertices, topo.num_vertices);
    // The ears' crossing pairs at smooth level L of `positions` (the
    // control's triangles), refined with the creases and `fold_creases`.
    // `tree`: a tree over that level's triangles at any positions (a fit's
    // relief tree), refitted here instead of building one (a refitted tree
    // finds the same pairs: raycast/self_intersection.h), and left fitted
    // to the level; empty: a tree is built there; null or over other
    // triangles: one is built for the search only.
    auto smooth_ear_pairs = [&](const std::vector<Vec3>& positions,
                                const std::vector<std::array<int, 2>>& fold_creases, int& count,
                                MeshBvh* tree) -> Status {
      ButterflyCreases c = creases;
      for (const auto& e : fold_creases) c.edges.push_back(e);
      if (!fold_creases.empty()) close_crease_ends(c);
      TriMesh control;
      control.positions = positions;
      control.triangles = out.local.triangles;
      MultiresMesh smooth;
      Status s = build_multires(control, c, options.levels, smooth);
      if (!s) return s;
      // Only the pairs with a triangle touching an ear count, so only those
      // are searched: the same pairs as a whole search's that touch one.
      const TriMesh level = level_mesh(smooth, options.levels);
      const std::vector<char> ear_mask = propagate_vertex_mask(smooth, ear_mask_control)[options.levels];
      std::vector<int> ear_triangles;
      for (int f = 0; f < level.num_triangles(); ++f) {
        const Tri& t = level.triangles[f];
        if (ear_mask[t[0]] || ear_mask[t[1]] || ear_mask[t[2]]) ear_triangles.push_back(f);
      }
      const bool refit = tree && !tree->empty() && tree->triangles == level.triangles &&
                         tree->positions.size() == level.positions.size();
      MeshBvh own;  // a given tree over other triangles is left as it is
      MeshBvh& bvh = tree && (refit || tree->empty()) ? *tree : own;
      s = refit ? refit_bvh(level, bvh) : build_bvh(level, bvh);
      if (!s) return s;
      std::vector<std::array<int, 2>> pairs;
      find_intersections_with(bvh, ear_triangles, pairs);
      count = count_pairs_touching(smooth, options.levels, pairs, ear_vertices);
      return Status::success();
    };
    // The tree the free fit's check after its rounds builds over smooth
    // level L: the next relief to search that level (the bound fit's, or
    // the free fit's own when the bound one is not kept) refits it.
    MeshBvh ear_tree;
    GlobalFitTerms bound = terms;
    bound.relief_start_tree = &ear_tree;
    bound.binding_edges.insert(bound.binding_edges.end(), ear_edges.begin(), ear_edges.end());
    GlobalFitOptions bound_options = global_options;
    const int warm_rounds = options.ear_refit_warm_rounds;
    const bool warm = warm_rounds > 0 && warm_rounds < static_cast<int>(bound_options.smooth_weights.size());
    if (warm)
      bound_options.smooth_weights.erase(bound_options.smooth_weights.begin(),
                                         bound_options.smooth_weights.end() - warm_rounds);
    // Decided after the free fit's rounds (FitHeadOptions::
    // ear_refit_after_rounds): its smooth-surface guard is not paid when the
    // bound fit is kept. The warm refit starts from the free fit's guarded
    // result: decided after.
    // Only at smooth level 3, where that was measured to agree (fit_head.h).
    const bool early = options.ear_refit_after_rounds && !warm && options.levels == 3;
    TriMesh bound_control;
    GlobalFitResult bound_fit;
    MeshBvh bound_tree;
    bool refitted = false;
    Status inner = Status::success();
    // The bound fit, whole: its guard does take ears from crossing to clean
    // (Demosthenes: 31 pairs after its rounds, 0 after the guard), so it is
    // judged only at its end.
    // FitHeadOptions::ear_refit_give_up_pairs: the bound fit ends after its
    // rounds when its ears cross there beyond what any kept one did. Its
    // count refits ear_tree (the free fit's, which the bound fit's relief
    // would take over), so a given-up fit leaves the free fit's relief a
    // tree over that level as before.
    const int give_up = !warm && options.levels == 3 ? options.ear_refit_give_up_pairs : 0;
    bool given_up = false;
    Status bound_inner = Status::success();
    if (give_up > 0)
      bound.after_rounds = [&](const std::vector<Vec3>& positions) {
        int pairs = 0;
        bound_inner = smooth_ear_pairs(positions, {}, pairs, &ear_tree);
        if (!bound_inner || pairs <= give_up) return bound_inner.ok();
        given_up = true;
        out.ear_binding.bound_pairs = pairs;
        return false;
      };
    auto refit = [&]() -> Status {
      refitted = true;
      Status s = fit_global(skin_pts, out.local, topo, bound, bound_options, bound_control, bound_fit, progress,
                            &bound_tree);
      if (!bound_inner) return with_context(bound_inner, "global fitting (ears bound)");
      if (!s) return with_context(s, "global fitting (ears bound)");
      if (given_up) return Status::success();
      return smooth_ear_pairs(bound_control.positions, bound_fit.fold_crease_edges, out.ear_binding.bound_pairs,
                              &bound_tree);
    };
    GlobalFitTerms free_terms = terms;
    free_terms.relief_start_tree = &ear_tree;
    if (early)
      free_terms.after_rounds = [&](const std::vector<Vec3>& positions) {
        int pairs = 0;
        inner = smooth_ear_pairs(positions, {}, pairs, &ear_tree);
        if (!inner) return false;
        out.ear_binding.free_pairs = out.ear_binding.bound_pairs = pairs;
        if (pairs == 0) return true;
        inner = refit();
        // The free fit's guard is paid only when the bound fit is not kept;
        // then its relief refits the bound fit's tree (the same level's
        // triangles) instead of building one.
        const bool kept = inner && !given_up && out.ear_binding.bound_pairs == 0;
        if (inner && !kept && !given_up) ear_tree = std::move(bound_tree);
        return !kept;
      };
    st = fit_global(skin_pts, out.local, topo, free_terms, global_options, out.control, out.global_fit, progress,
                    &relief_tree);
    if (!inner) return with_context(inner, "global fitting (ears)");
    if (!st) return with_context(st, "global fitting");
    if (!early) {
      int free_pairs = 0;
      st = smooth_ear_pairs(out.control.positions, out.global_fit.fold_crease_edges, free_pairs, &relief_tree);
      if (!st) return with_context(st, "global fitting (ears)");
      out.ear_binding.free_pairs = out.ear_binding.bound_pairs = free_pairs;
      if (free_pairs > 0) {
        if (warm) bound.start = out.control.positions;  // from the free fit, its last rounds only
        st = refit();
        if (!st) return with_context(st, "global fitting (ears)");
      }
    }
    if (refitted) {
      std::ostringstream note;
      note << "the fit folded the ears (" << out.ear_binding.free_pairs << " crossing pairs at smooth level "
           << options.levels << "): fitted again with their edges bound (" << out.ear_binding.bound_pairs
           << (given_up ? " pairs after its rounds)" : " pairs)");
      // Kept only when no ear folds: a bound ear that still crossed
      // (Gutenberg's, under his beret's brim) was beyond the later steps'
      // reach, where the free one's were not (docs/design/fit_real_scans.md).
      if (given_up) {
        note << ", given up";
      } else if (out.ear_binding.bound_pairs == 0) {
        out.control = std::move(bound_control);
        out.global_fit = std::move(bound_fit);
        relief_tree = std::move(bound_tree);
        out.ear_binding.bound = true;
        note << ", kept";
      } else {
        note << ", not kept";
      }
      out.notes.push_back(note.str());
    }
  }
  std::vector<Vec3> neck_shift;  // #V or empty: how far the neck's fit moved each control vertex
  if (!neck_pts.empty()) {
    // FitHeadOptions::fit_scanned_neck: the neck is fitted after the head,
    // the head held. In the head's own fit the neck's points made it another
    // fit (a bust turned by 0.05 deg: ears crossing that no later step
    // relaxed); here only the neck's control vertices move, in the last
    // round's smoothing, to all points, and the others are put back where
    // the head's fit left them, to the bit.
    GlobalFitTerms neck_terms = terms;
    neck_terms.constrained_vertices.clear();
    for (int v = 0; v < out.control.num_vertices(); ++v)
      if (!in_neck[v] || mouth_bag[v]) neck_terms.constrained_vertices.push_back(v);
    GlobalFitOptions neck_options = global_options;
    neck_options.smooth_weights = {global_options.smooth_weights.back()};
    // Only this fit's positions are used: the fold creases it would choose
    // (a search that never moves a vertex, ~0.2 s on the busts) are not
    // searched, and its relief takes over the head's relief tree and hands
    // it back refitted (the same tree, no level-3 build).
    neck_options.smooth_guard_crease_max_edges = 0;
    if (!options.scanned_neck_smooth_guard) neck_options.smooth_guard_level = 0;
    neck_terms.relief_start_tree = &relief_tree;
    std::vector<Vec3> all = skin_pts;
    all.insert(all.end(), neck_pts.begin(), neck_pts.end());
    if (options.scanned_neck_reach && !out.global_fit.iterations.empty()) {
      // FitHeadOptions::scanned_neck_reach: the held round trims every
      // residual beyond the head's trimming distance, so a neck farther off
      // than that (most of it: its median) is not pulled at all. It is then
      // fitted to its own points first, over the head's rounds (their
      // trimming from the neck's own residuals), the head held; the held
      // round below starts there.
      const double tau = out.global_fit.iterations.back().trim_distance;
      const ClosestPointTree head_tree(out.control);
      std::vector<double> d(neck_pts.size());
      parallel_for(0, static_cast<int>(neck_pts.size()), 1024,
                   [&](int i, int) { d[i] = std::sqrt(head_tree.closest(neck_pts[i]).squared_distance); });
      std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
      out.neck_reach.median_before = d[d.size() / 2];
      out.neck_reach.trim_distance = tau;
      if (out.neck_reach.median_before > tau) {
        GlobalFitOptions reach_options = neck_options;
        reach_options.smooth_weights = global_options.smooth_weights;
        reach_options.smooth_guard_level = 0;  // the held round's pass guards as it does without the reach
        GlobalFitTerms reach_terms = neck_terms;
        reach_terms.relief_start_tree = nullptr;
        TriMesh reach_control;
        GlobalFitResult reach_fit;
        st = fit_global(neck_pts, out.control, topo, reach_terms, reach_options, reach_control, reach_fit, progress);
        if (st.code == ErrorCode::Cancelled) return st;
        std::ostringstream note;
        note << "the scanned neck lay beyond the head fit's trimming distance (median " << 1e3 * out.neck_reach.median_before
             << " mm, trimmed beyond " << 1e3 * tau << " mm): ";
        if (st) {
          neck_terms.start = out.control.positions;  // the head exactly where its fit left it
          for (int v = 0; v < out.control.num_vertices(); ++v)
            if (in_neck[v] && !mouth_bag[v]) neck_terms.start[v] = reach_control.positions[v];
          out.neck_reach.reached = true;
          note << "fitted to its own points first";
        } else {
          // The held round alone, as without the option (the neck is an
          // extra; a fit of its few points that fails does not fail the head).
          note << "its fit to its own points failed (" << st.message << "): the held round alone";
        }
        out.notes.push_back(note.str());
        st = Status::success();
      }
    }
    TriMesh neck_control;
    GlobalFitResult neck_fit;
    const bool had_tree = !relief_tree.empty();
    MeshBvh neck_tree;
    st = fit_global(all, out.control, topo, neck_terms, neck_options, neck_control, neck_fit, progress, &neck_tree);
    if (!st) return with_context(st, "global fitting (scanned neck)");
    if (had_tree && relief_tree.empty()) relief_tree = std::move(neck_tree);  // taken over: back, refitted
    neck_shift.assign(out.control.num_vertices(), Vec3::Zero());
    for (int v = 0; v < out.control.num_vertices(); ++v)
      if (in_neck[v] && !mouth_bag[v]) {
        neck_shift[v] = neck_control.positions[v] - out.control.positions[v];
        out.control.positions[v] = neck_control.positions[v];
      }
  }
  if (options.carry_mouth_bag) {
    st = carry_mouth_bag(mouth_bag, topo, out.local, out.control);
    if (!st) return with_context(st, "global fitting (mouth bag)");
  }
  // The fold creases the global fit chose are refined as creases from here on.
  if (!out.global_fit.fold_crease_edges.empty()) {
    for (const auto& e : out.global_fit.fold_crease_edges) creases.edges.push_back(e);
    close_crease_ends(creases);
  }
  stage_done("global_fitting", out.control, pts);
  const std::vector<Vec3> global_control = out.control.positions;

  // 4. Displaced Butterfly levels.
  if (observer.started) observer.started("subdivision");
  UntangleOptions untangle;
  untangle.level = out.face_only ? options.face_untangle_level : options.untangle_level;
  untangle.iterations = options.untangle_iterations;
  untangle.erode_pct = options.untangle_erode_pct;
  untangle.hinges_last = options.untangle_hinges_last;
  untangle.restore_rings = options.untangle_restore_rings;
  untangle.restore_share = options.untangle_restore_share;
  const std::vector<Vec3> before_untangle = out.control.positions;
  st = untangle_smooth_surface(out.aligned.positions, creases, diag, topo, terms.smooth_guard_ignored, untangle,
                               out.control, out.untangle);
  if (!st) return with_context(st, "subdivision (untangling)");
  const std::vector<std::vector<int>>& pleat_steps = out.global_fit.pleat_step_vertices;
  const std::vector<Vec3>& pleat_shift = out.global_fit.pleat_shift;
  if (options.pleat_undo_where_crossing && out.untangle.pairs_after > 0 && !pleat_steps.empty() &&
      static_cast<int>(pleat_shift.size()) == topo.num_vertices) {
    // FitHeadOptions::pleat_undo_where_crossing: the steps near the pairs
    // left (then all of them) undone, the untangling run again from there.
    const int nv = topo.num_vertices;
    std::vector<char> under(nv, 0);
    for (int f : out.untangle.crossing_faces)
      for (int v : out.control.triangles[f]) under[v] = 1;
    const std::vector<char> near = grown_by_rings(topo, under, 2);
    // The steps touching `near`, closed over shared vertices (a vertex two
    // steps moved goes back only with both).
    std::vector<char> undo_local(pleat_steps.size(), 0), undone(nv, 0);
    for (size_t k = 0; k < pleat_steps.size(); ++k)
      for (int v : pleat_steps[k]) undo_local[k] = undo_local[k] || near[v];
    for (bool grew = true; grew;) {
      grew = false;
      for (size_t k = 0; k < pleat_steps.size(); ++k)
        if (undo_local[k])
          for (int v : pleat_steps[k]) undone[v] = 1;
      for (size_t k = 0; k < pleat_steps.size(); ++k)
        if (!undo_local[k])
          for (int v : pleat_steps[k])
            if (undone[v]) undo_local[k] = 1, grew = true;
    }
    std::vector<std::vector<char>> undos = {undo_local};
    if (const std::vector<char> undo_all(pleat_steps.size(), 1); undo_local != undo_all) undos.push_back(undo_all);
    for (const std::vector<char>& undo : undos) {
      if (std::find(undo.begin(), undo.end(), 1) == undo.end()) continue;
      std::vector<char> back(nv, 0);
      for (size_t k = 0; k < pleat_steps.size(); ++k)
        if (undo[k])
          for (int v : pleat_steps[k]) back[v] = 1;
      TriMesh trial = out.control;
      trial.positions = before_untangle;
      for (int v = 0; v < nv; ++v)
        if (back[v]) trial.positions[v] -= pleat_shift[v];
      UntangleResult trial_result;
      st = untangle_smooth_surface(out.aligned.positions, creases, diag, topo, terms.smooth_guard_ignored, untangle,
                                   trial, trial_result);
      if (!st) return with_context(st, "subdivision (untangling, pleat steps undone)");
      if (trial_result.pairs_after >= out.untangle.pairs_after) continue;
      const int left = out.untangle.pairs_after, steps = static_cast<int>(std::count(undo.begin(), undo.end(), 1));
      out.control = std::move(trial);
      out.untangle = std::move(trial_result);
      out.pleat_steps_undone = steps;
      out.notes.push_back("the smooth level " + std::to_string(untangle.level) + " still crossed itself (" +
                          std::to_string(left) + " pairs) where the global fit's pleat relief had stepped: " +
                          std::to_string(steps) + " of its " + std::to_string(pleat_steps.size()) +
                          " steps undone, untangled again (" + std::to_string(out.untangle.pairs_after) +
                          " pairs left)");
      if (out.untangle.pairs_after == 0) break;
    }
  }
  st = build_multires(out.control, creases, options.levels, out.multires);
  if (!st) return with_context(st, "subdivision");
  PointCloud fitted;
  fitted.positions = skin_pts;
  std::vector<int> measured_index = skin_index;  // into the scan
  fitted.positions.insert(fitted.positions.end(), neck_pts.begin(), neck_pts.end());
  measured_index.insert(measured_index.end(), neck_index.begin(), neck_index.end());
  if (!scanned_neck && options.cut_neck && options.displacement_below_neck_cut > 0 &&
      neck_region != ann.regions.end()) {
    // The band just below the neck cut (see FitHeadOptions) where its
    // nearest surface is the neck's (on a face scan the cut passes under
    // the ear lobes: 20 mm of band with no such test tripled James's ear
    // crossings), without its isolated returns, like the points above.
    std::vector<Vec3> band;
    std::vector<int> band_index;
    for (int i = 0; i < n; ++i) {
      const double h = neck.normal.dot(cloud.positions[i] - neck.point);
      if (h >= 0 || h < -options.displacement_below_neck_cut) continue;
      const SurfaceHit c = local_tree.closest(cloud.positions[i]);
      if (c.face < 0) continue;
      const Tri& t = out.local.triangles[c.face];
      if (in_neck[t[0]] && in_neck[t[1]] && in_neck[t[2]]) band.push_back(cloud.positions[i]), band_index.push_back(i);
    }
    drop_isolated_points(options.displacement.isolated_density_ratio, band, band_index);
    fitted.positions.insert(fitted.positions.end(), band.begin(), band.end());
    measured_index.insert(measured_index.end(), band_index.begin(), band_index.end());
  }
  std::vector<Vec3> head_normals;  // #P or empty: the scan's normals in the head frame
  if (scan.normals.size() == scan.positions.size()) {
    // The scanner's normals, in the head frame, tell thin features' two
    // sheets apart when measuring (DisplacementOptions::min_normal_agreement).
    head_normals.reserve(scan.normals.size());
    for (const Vec3& nn : scan.normals) head_normals.push_back(out.scan_to_head.A * nn);
    fitted.normals.reserve(measured_index.size());
    for (int i : measured_index) fitted.normals.push_back(head_normals[i]);
  }
  if (!scan.faces.empty() && options.surface_sample_edges > 0) {
    // A scan that came as a mesh: its triangles between the measured points.
    std::vector<char> measured(cloud.positions.size(), 0);
    for (int i : measured_index) measured[i] = 1;
    // Spaced as without the neck's fit, so that the head above the cut is
    // measured on the same samples as the head fitted without it.
    TriMesh spaced = out.control;
    for (size_t v = 0; v < neck_shift.size(); ++v) spaced.positions[v] -= neck_shift[v];
    const double spacing = options.surface_sample_edges * mean_edge_length(spaced) / double(1 << options.levels);
    st = sample_scan_surface(cloud.positions, head_normals, scan.faces, measured, spacing,
                             options.surface_sample_max_edge_ratio, options.surface_sample_max, fitted,
                             out.surface_samples);
    if (st.code == ErrorCode::TooLarge) {
      out.notes.push_back("the scan's triangles were not sampled for the displacements (" + st.message +
                          "): measured on its points only");
    } else if (!st) {
      return with_context(st, "displacements (scan triangles)");
    }
  }
  DisplacementOptions dopt = options.displacement;
  dopt.isolated_density_ratio = 0;  // already left out above
  if (dopt.max_distance <= 0) dopt.max_distance = options.displacement_max_pct / 100.0 * diag;
  // Displacements of out.multires (built), pockets zeroed, folds limited.
  auto displace = [&](FoldLimitStats& folds, int& zeroed) -> Status {
    Status s = measure_displacements(fitted, dopt, out.multires, nullptr, progress);
    if (!s) return s;
    s = zero_pocket_displacements(pocket, out.multires, zeroed);
    if (!s) return s;
    s = limit_folds(out.multires, options.fold_limit, &folds, &relief_tree);
    for (int z : folds.zeroed) zeroed += z;
    return s;
  };
  st = displace(out.fold_limit, out.zeroed_displacements);
  if (!st) return with_context(st, "displacements");
  bool ears_reverted = false;
  st = hold_crossing_ears(options, ann, topo, creases, out, displace, ears_reverted);
  if (!st) return with_context(st, "displacements (ears)");
  bool guard_searched = false;
  // The neck's control vertices stay where the neck's fit put them, when it ran.
  st = guard_feature_crossings(options, ann, topo, neck_shift.empty() ? std::vector<char>{} : in_neck,
                               fitted.positions, dopt.max_distance, out, relief_tree, guard_searched);
  if (!st) return with_context(st, "displacements (lips and ears)");
  if (options.guard_remeasure && options.levels >= 2 && out.feature_guard.moved_vertices > 0) {
    // FitHeadOptions::guard_remeasure: the detail over the control vertices
    // the guard moved is measured again from their new places, and the
    // guard gives way only where that crosses; kept when it leaves no more
    // pairs, at the lips and ears or elsewhere, than the guard alone.
    const FitHeadResult::FeatureGuard first = out.feature_guard;
    const MultiresMesh multires_guarded = out.multires;
    const FoldLimitStats folds_guarded = out.fold_limit;
    const int zeroed_guarded = out.zeroed_displacements;
    const size_t notes_guarded = out.notes.size();
    st = build_multires(out.control, creases, options.levels, out.multires);
    if (!st) return with_context(st, "displacements (measured again)");
    out.fold_limit = FoldLimitStats{};
    out.zeroed_displacements = 0;
    st = displace(out.fold_limit, out.zeroed_displacements);
    if (!st) return with_context(st, "displacements (measured again)");
    out.feature_guard = FitHeadResult::FeatureGuard{};
    bool searched_again = false;
    st = guard_feature_crossings(options, ann, topo, neck_shift.empty() ? std::vector<char>{} : in_neck,
                                 fitted.positions, dopt.max_distance, out, relief_tree, searched_again);
    if (!st) return with_context(st, "displacements (measured again)");
    if (out.feature_guard.pairs_after > first.pairs_after ||
        out.feature_guard.other_pairs_after > first.other_pairs_after) {
      out.control.positions = multires_guarded.control;
      out.multires = multires_guarded;
      out.fold_limit = folds_guarded;
      out.zeroed_displacements = zeroed_guarded;
      out.feature_guard = first;
      out.notes.resize(notes_guarded);
      TriMesh level = level_mesh(out.multires, options.levels);
      st = tree_over(level, relief_tree) ? refit_bvh(level, relief_tree) : build_bvh(level, relief_tree);
      if (!st) return with_context(st, "displacements (measured again)");
    } else {
      const FitHeadResult::FeatureGuard second = out.feature_guard;
      out.feature_guard = first;
      out.feature_guard.pairs_after = second.pairs_after;
      out.feature_guard.other_pairs_after = second.other_pairs_after;
      out.feature_guard.remeasured = true;
      out.notes.push_back("the displacements measured again over the control vertices the guard moved (" +
                          std::to_string(second.pairs_before + second.other_pairs_before) +
                          " pairs, relaxed again)");
    }
    guard_searched = true;
  }
  // The untangling, the ear hold and the guard may move control vertices
  // after the global fit's figures were taken; those figures describe the
  // control mesh the fit returns, so they are measured again on it and handed
  // to the observer again (FitStageObserver::measured); as_fitted keeps the
  // global fit's own.
  if (options.measure_stages && out.control.positions != global_control)
    for (FitStageReport& rep : out.stages)
      if (rep.name == "global_fitting") {
        rep.distance = surface_distance(out.control, pts);
        if (observer.measured) observer.measured(rep);
      }
  for (int l = 1; l <= options.levels; ++l) out.level_meshes.push_back(level_mesh(out.multires, l));
  const TriMesh finest = level_mesh(out.multires, options.levels);
  // The fold limiter (or the guard) hands back its tree (the relief's),
  // refitted to the finest level as it left it: no level-3 build for the
  // figures.
  stage_done("subdivision", finest, pts, ears_reverted && !guard_searched ? nullptr : &relief_tree);
  turn_result(out.face_frame_turn, out);
  return Status::success();
}

}  // namespace

}  // namespace lk
