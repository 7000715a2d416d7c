#include "pipeline/untangle.h"

#include "fit/global_fit.h"
#include "mesh/geometry.h"
#include "multires/multires.h"
#include "raycast/bvh.h"
#include "raycast/self_intersection.h"

#include <algorithm>
#include <cmath>

namespace lk {

Status untangle_smooth_surface(const std::vector<Vec3>& reference, const ButterflyCreases& creases, double diagonal,
                               const MeshTopology& topology, const std::vector<char>& pinned,
                               const UntangleOptions& options, TriMesh& control, UntangleResult& result) {
  result = UntangleResult{};
  const int nv = control.num_vertices();
  if (static_cast<int>(reference.size()) != nv || topology.num_vertices != nv ||
      (!pinned.empty() && static_cast<int>(pinned.size()) != nv))
    return Status::error(ErrorCode::InvalidInput, "untangling: reference, topology and pinned must match the mesh");
  if (options.level < 0 || options.level > 4 || options.iterations < 0 || !(options.erode_pct >= 0) ||
      !std::isfinite(options.erode_pct) || options.restore_rings > 8 || !(options.restore_share > 0) ||
      !(options.restore_share <= 1) || !(diagonal > 0) || !std::isfinite(diagonal))
    return Status::error(ErrorCode::InvalidInput, "untangling: level 0-4, iterations >= 0, erode_pct >= 0, "
                                                  "restore_rings <= 8, restore_share in (0, 1], diagonal > 0");
  const int K = options.level;
  const bool eroding = options.iterations > 0 && options.erode_pct > 0;
  const bool restoring = options.restore_rings >= 0;
  if (K == 0 || (!eroding && !restoring)) return Status::success();
  auto is_pinned = [&](int v) { return !pinned.empty() && pinned[v]; };

  MultiresMesh mr;
  Status st = build_multires(control, creases, K, mr);
  if (!st) return st;
  auto level_positions = [&](const std::vector<Vec3>& positions, std::vector<Vec3>& level) -> Status {
    mr.control = positions;
    Status r = evaluate(mr);
    if (!r) return r;
    level = mr.state.displaced[K];
    return Status::success();
  };
  // New pairs are those that do not cross at the reference's level
  // positions (find_new_self_intersections).
  std::vector<Vec3> reference_level;
  st = level_positions(reference, reference_level);
  if (!st) return st;
  TriMesh level;
  level.triangles = mr.triangles(K);
  std::vector<std::array<int, 2>> pairs;
  // One SAH tree for all searches, refit after each step: the steps move
  // vertices by a fraction of a percent of the diagonal, so the refit boxes
  // stay tight (James: up to seven fresh builds of level 2 cost ~44 ms).
  MeshBvh bvh;
  auto new_pairs = [&]() -> Status {
    Status r = level_positions(control.positions, level.positions);
    if (!r) return r;
    r = bvh.empty() ? build_bvh(level, bvh) : refit_bvh(level, bvh);
    if (!r) return r;
    return find_new_self_intersections(bvh, reference_level, pairs);
  };
  st = new_pairs();
  if (!st) return st;
  int best_pairs = static_cast<int>(pairs.size());
  result.pairs_before = best_pairs;
  const size_t turned_at_start = turned_triangles(reference, control).size();
  std::vector<Vec3> best = control.positions;
  // Best's level positions and new pairs, to go back to without evaluating
  // or searching again.
  std::vector<Vec3> best_level = level.positions;
  std::vector<std::array<int, 2>> best_pairs_found = pairs;
  std::vector<char> in_set(nv, 0);
  std::vector<int> set;
  const int faces_per_control = 1 << (2 * K);  // child c of triangle g is 4 g + c on every level
  // The unpinned corners of the control faces under `pairs`, into `set`.
  auto corners_under_pairs = [&]() {
    set.clear();
    std::fill(in_set.begin(), in_set.end(), 0);
    for (const auto& p : pairs)
      for (int f : p)
        for (int v : control.triangles[f / faces_per_control])
          if (!in_set[v] && !is_pinned(v)) in_set[v] = 1, set.push_back(v);
  };

  // Hinges: corners of a pair's control face that are corners of its other
  // face or next to one. Where an ear's back lies on the scalp, the back's
  // control face shares its root corners with the scalp's faces (or sits
  // one edge from them); moving those with the rest only slides the
  // crossing line along the wedge between the sheets.
  std::vector<char> hinge(nv, 0);
  auto drop_hinges = [&]() {
    std::fill(hinge.begin(), hinge.end(), 0);
    for (const auto& p : pairs)
      for (int side = 0; side < 2; ++side) {
        const Tri& other = control.triangles[p[1 - side] / faces_per_control];
        for (int v : control.triangles[p[side] / faces_per_control])
          for (int w : other) {
            if (w == v) hinge[v] = 1;
            for (int u : topology.rings[v]) hinge[v] |= u == w;
          }
      }
    size_t kept = 0;
    for (int v : set)
      if (hinge[v]) in_set[v] = 0;
      else set[kept++] = v;
    set.resize(kept);
  };

  // Trials move a few control vertices: the hierarchy is updated inside
  // their support only (update_control_vertices, bit-identical to a full
  // evaluation), and the level's new pairs at control.positions come from
  // `pairs` (the level's at `level.positions`): only the triangles whose
  // corners moved are searched again. The corners moved are `set`.
  std::vector<Vec3> now;  // level K after a trial's move
  std::vector<char> moved;
  std::vector<int> moved_list;
  std::vector<Vec3> set_positions;
  auto move_set_to = [&](const std::vector<Vec3>& positions) -> Status {
    set_positions.clear();
    for (int v : set) set_positions.push_back(positions[v]);
    return update_control_vertices(mr, set, set_positions);
  };
  auto pairs_after_move = [&](std::vector<std::array<int, 2>>& out) -> Status {
    Status r = move_set_to(control.positions);
    if (!r) return r;
    now = mr.state.displaced[K];
    moved_triangles(level.triangles, level.positions, now, moved, moved_list);
    std::swap(level.positions, now);
    r = refit_bvh(level, bvh);
    if (!r) return r;
    std::vector<std::array<int, 2>> found;
    r = find_new_self_intersections(bvh, reference_level, found, &moved_list);
    if (!r) return r;
    out = pairs_after_change(pairs, moved, found);
    return Status::success();
  };

  // 1. Erosion: two sheets pulled onto the same scan points (an ear's back
  // and the scalp behind it), which the fold limiter leaves alone
  // (shrinking displacements only returns to this surface). Each step
  // moves the corners under the pairs against their vertex normals; two
  // steps in a row without fewer pairs end a pass (each step costs a
  // search). The first pass leaves the hinges out (a corner shared by both
  // sheets has no side to move to, and moving it made more pairs;
  // docs/journal.md "Hinges"); the second, from the first's best, moves all
  // corners (a fold between neighbouring faces is all hinges).
  const double step = options.erode_pct / 100 * diagonal;
  auto erode = [&](bool without_hinges) -> Status {
    // The hierarchy, the level and its tree at control.positions (a pass
    // after another starts from that one's best, not its last step).
    if (mr.control != control.positions) {
      Status r = level_positions(control.positions, level.positions);
      if (r) r = refit_bvh(level, bvh);
      if (!r) return r;
    }
    for (int it = 0, idle = 0; it < options.iterations && !pairs.empty() && idle < 2; ++it) {
      corners_under_pairs();
      if (without_hinges) drop_hinges();
      if (set.empty()) break;
      const std::vector<Vec3> normals = vertex_normals(control);
      for (int v : set) control.positions[v] -= step * normals[v];
      // Only the level's triangles over the moved corners are searched
      // again (the same pairs as a search of the whole level).
      std::vector<std::array<int, 2>> after;
      Status r = pairs_after_move(after);
      if (!r) return r;
      pairs = std::move(after);
      // A step that turns a control triangle over against the template is
      // not kept (Fran: a lid triangle of the right eye socket turned).
      const bool turns = turned_triangles(reference, control).size() > turned_at_start;
      if (!turns && static_cast<int>(pairs.size()) < best_pairs) {
        best_pairs = static_cast<int>(pairs.size());
        best = control.positions;
        best_level = level.positions;
        best_pairs_found = pairs;
        idle = 0;
      } else {
        ++idle;
      }
    }
    control.positions = best;  // the level and its tree are brought back below
    pairs = best_pairs_found;
    return Status::success();
  };
  if (eroding) {
    if (options.hinges_last) {
      st = erode(true);
      if (!st) return st;
    }
    st = erode(false);
    if (!st) return st;
  }
  result.pairs_eroded = result.pairs_after = best_pairs;
  if (!restoring || best_pairs == 0) return Status::success();

  // 2. Restore (header comment).
  // `pairs` are best's already (each erosion pass ends there); its level
  // and tree may still be a rejected step's.
  if (level.positions != best_level) {
    level.positions = best_level;
    st = refit_bvh(level, bvh);
    if (!st) return st;
  }
  // The trials move a few control vertices: the hierarchy is updated inside
  // their support only (update_control_vertices, bit-identical to a full
  // evaluation), from best's.
  if (mr.control != best) {
    st = level_positions(best, now);
    if (!st) return st;
  }
  std::vector<std::array<int, 2>> control_pairs;
  st = find_self_intersections(control, control_pairs);
  if (!st) return st;
  const size_t crossing_at_start = control_pairs.size();
  std::vector<char> ever(nv, 0);
  std::vector<Vec3> rest(nv, Vec3::Zero());  // the reference's umbrella vectors L0(v)
  for (int v = 0; v < nv; ++v) {
    if (topology.rings[v].empty()) continue;
    Vec3 mean = Vec3::Zero();
    for (int u : topology.rings[v]) mean += reference[u];
    rest[v] = reference[v] - mean / static_cast<double>(topology.rings[v].size());
  }
  for (int rings = 0; rings <= options.restore_rings && !pairs.empty();) {
    corners_under_pairs();
    for (int r = 0; r < rings; ++r) {  // grown ring by ring
      const size_t grown = set.size();
      for (size_t i = 0; i < grown; ++i)
        for (int u : topology.rings[set[i]])
          if (!in_set[u] && !is_pinned(u)) in_set[u] = 1, set.push_back(u);
    }
    // L(v) = L0(v) on the set, the rest held: Gauss-Seidel until the
    // largest change is below 1e-9 of the diagonal (a few tens of sweeps
    // on a set three rings wide).
    std::vector<Vec3> solved = best;
    for (int sweep = 0; sweep < 1000; ++sweep) {
      double change = 0;
      for (int v : set) {
        const std::vector<int>& ring = topology.rings[v];
        if (ring.empty() || topology.is_boundary(v)) continue;
        Vec3 mean = Vec3::Zero();
        for (int u : ring) mean += solved[u];
        const Vec3 x = mean / static_cast<double>(ring.size()) + rest[v];
        change = std::max(change, (x - solved[v]).norm());
        solved[v] = x;
      }
      if (change < 1e-9 * diagonal) break;
    }
    for (int v : set) control.positions[v] = best[v] + options.restore_share * (solved[v] - best[v]);
    std::vector<std::array<int, 2>> trial;
    st = pairs_after_move(trial);
    if (!st) return st;
    bool keep = trial.size() < pairs.size() && turned_triangles(reference, control).size() <= turned_at_start;
    if (keep) {
      st = find_self_intersections(control, control_pairs);
      if (!st) return st;
      keep = control_pairs.size() <= crossing_at_start;
    }
    if (keep) {
      pairs = std::move(trial);
      best = control.positions;
      best_level = level.positions;
      for (int v : set) ever[v] = 1;
      ++result.restore_steps;
    } else {  // back to best, the level and its tree too; a wider set next
      control.positions = best;
      st = move_set_to(best);
      if (!st) return st;
      level.positions = best_level;
      st = refit_bvh(level, bvh);
      if (!st) return st;
      ++rings;
    }
  }
  control.positions = best;
  result.pairs_after = static_cast<int>(pairs.size());
  for (const auto& p : pairs)
    for (int f : p) result.crossing_faces.push_back(f / faces_per_control);
  std::sort(result.crossing_faces.begin(), result.crossing_faces.end());
  result.crossing_faces.erase(std::unique(result.crossing_faces.begin(), result.crossing_faces.end()),
                              result.crossing_faces.end());
  for (int v = 0; v < nv; ++v) result.restored_vertices += ever[v];
  return Status::success();
}

}  // namespace lk
