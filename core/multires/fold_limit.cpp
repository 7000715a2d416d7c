#include "multires/fold_limit.h"

#include "multires/multires_detail.h"
#include "raycast/bvh.h"
#include "raycast/self_intersection.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numeric>
#include <set>

namespace lk {

using namespace multires_detail;

namespace {

// Bad against the smooth triangle: turned over or collapsed. Arguments are
// unnormalised (2 x area) normals. A smooth triangle of zero area gives no
// reference and is never bad.
inline bool bad_triangle(const Vec3& displaced, const Vec3& smooth, const FoldLimitOptions& o) {
  const double ls = smooth.norm();
  if (ls == 0) return false;
  const double ld = displaced.norm();
  if (!(ld > o.min_area_ratio * ls)) return true;
  return displaced.dot(smooth) <= o.min_normal_cos * ld * ls;
}

}  // namespace

std::vector<std::vector<char>> crease_vertex_masks(const MultiresMesh& mesh) {
  const int L = mesh.num_levels();
  std::vector<std::vector<char>> out(L + 1);
  for (int l = 0; l <= L; ++l) out[l].assign(mesh.num_vertices(l), 0);
  for (int l = 0; l < L; ++l) {
    const ButterflyLevel& lv = mesh.levels[l];
    for (int k = 0; k < lv.num_new_vertices(); ++k) {
      if (k >= static_cast<int>(lv.crease_edges.size()) || !lv.crease_edges[k]) continue;
      for (int v : lv.edge_endpoints[k]) out[l][v] = 1;
      out[l + 1][lv.num_coarse_vertices + k] = 1;
    }
    for (int v = 0; v < lv.num_coarse_vertices; ++v) out[l + 1][v] |= out[l][v];
  }
  return out;
}

Status smooth_positions(const MultiresMesh& mesh, std::vector<std::vector<Vec3>>& out) {
  return apply_all(mesh.levels, mesh.control, out);
}

void count_bad_triangles(const MultiresMesh& mesh, int level, const std::vector<Vec3>& smooth,
                         const FoldLimitOptions& options, int& flipped, int& collapsed) {
  flipped = collapsed = 0;
  if (level < 0 || level > mesh.num_levels() || static_cast<int>(mesh.state.displaced.size()) <= level) return;
  const auto& tris = mesh.triangles(level);
  const auto& P = mesh.state.displaced[level];
  if (P.size() != smooth.size()) return;
  for (int f = 0; f < static_cast<int>(tris.size()); ++f) {
    const Vec3 nd = face_normal(tris, P, f), ns = face_normal(tris, smooth, f);
    const double ls = ns.norm(), ld = nd.norm();
    if (ls == 0) continue;
    if (!(ld > options.min_area_ratio * ls)) ++collapsed;
    if (nd.dot(ns) <= options.min_normal_cos * ld * ls) ++flipped;
  }
}

Status limit_folds(MultiresMesh& mesh, const FoldLimitOptions& options, FoldLimitStats* stats) {
  if (!(options.shrink >= 0 && options.shrink < 1) || options.min_area_ratio < 0 || options.max_shrinks < 0 ||
      options.max_rounds < 0 || options.max_intersection_rounds < 0 || options.max_intersection_restarts < 0 ||
      options.separation_repeats < 0 ||
      !(std::abs(options.min_normal_cos) <= 1))
    return Status::error(ErrorCode::InvalidInput,
                         "multires fold limit: shrink must be in [0, 1), the cosine in [-1, 1], ratios and counts >= 0");
  Status s = check_sizes(mesh);
  if (!s.ok()) return s;
  const int L = mesh.num_levels();
  std::vector<std::vector<Vec3>> smooth;
  s = smooth_positions(mesh, smooth);
  if (!s.ok()) return s;
  FoldLimitStats st;
  if (options.undisplaced_creases) {
    const auto crease = crease_vertex_masks(mesh);
    for (int l = 0; l <= L; ++l)
      for (int v = 0; v < mesh.num_vertices(l); ++v)
        if (crease[l][v] && mesh.displacements[l][v] != 0) {
          mesh.displacements[l][v] = 0;
          ++st.crease_zeroed;
        }
  }
  s = evaluate(mesh);
  if (!s.ok()) return s;
  MultiresState& state = mesh.state;

  st.bad_found.assign(L + 1, 0);
  st.shrunk.assign(L + 1, 0);
  st.zeroed.assign(L + 1, 0);
  std::vector<std::vector<Vec3>> smooth_normals(L + 1);
  std::vector<std::vector<std::uint8_t>> shrinks(L + 1);
  std::vector<std::vector<int>> shrunk_in_round(L + 1), face_checked(L + 1);
  std::vector<char> checked(L + 1, 0);
  for (int l = 0; l <= L; ++l) {
    const auto& tris = mesh.triangles(l);
    smooth_normals[l].resize(tris.size());
    for (int f = 0; f < static_cast<int>(tris.size()); ++f) smooth_normals[l][f] = face_normal(tris, smooth[l], f);
    shrinks[l].assign(mesh.num_vertices(l), 0);
    shrunk_in_round[l].assign(mesh.num_vertices(l), -1);
    face_checked[l].assign(tris.size(), -1);
  }
  auto is_bad = [&](int l, int f) {
    return bad_triangle(face_normal(mesh.triangles(l), state.displaced[l], f), smooth_normals[l][f], options);
  };
  // Rounds and restarts change a few hundred vertices, yet every visit of a
  // level used to evaluate it whole, scan all its triangles and refine all
  // of the next level. Instead, what each of those last saw is kept, and a
  // visit recomputes only where the inputs differ bit-wise from it, with
  // the same kernels (multires_detail.h): the same bits as the full passes.
  struct SeenLevel {
    std::vector<Vec3> base;       // base positions the normals were computed from
    std::vector<Vec3> refined;    // displaced positions the next level was refined from
    std::vector<Vec3> flagged;    // displaced positions the bad flags were computed from
    std::vector<char> bad;        // #F_l: is_bad at `flagged`
  };
  std::vector<SeenLevel> seen(options.incremental ? L + 1 : 0);
  for (int l = 0; l < static_cast<int>(seen.size()); ++l) {
    SeenLevel& sl = seen[l];
    sl.base = state.base[l];
    sl.refined = sl.flagged = state.displaced[l];
    sl.bad.resize(mesh.triangles(l).size());
    for (int f = 0; f < static_cast<int>(sl.bad.size()); ++f) sl.bad[f] = is_bad(l, f);
  }
  // Indices where now differs bit-wise from before; before is brought up to date.
  auto differences = [](const auto& now, auto& before, std::vector<int>& out) {
    out.clear();
    for (int i = 0; i < static_cast<int>(now.size()); ++i)
      if (std::memcmp(&now[i], &before[i], sizeof(now[i])) != 0) {
        out.push_back(i);
        before[i] = now[i];
      }
  };
  std::vector<int> moved_base, moved_displaced;
  // = evaluate_level(mesh, l)
  auto evaluate_changes = [&](int l) {
    if (!options.incremental) return evaluate_level(mesh, l);
    differences(state.base[l], seen[l].base, moved_base);
    update_level(mesh, l, moved_base);
  };
  // = apply(mesh.levels[l], state.displaced[l], state.base[l + 1])
  auto refine_changes = [&](int l) {
    if (!options.incremental) {
      apply(mesh.levels[l], state.displaced[l], state.base[l + 1]);  // sizes match (check_sizes)
      return;
    }
    differences(state.displaced[l], seen[l].refined, moved_displaced);
    update_refinement(mesh, l, moved_displaced);
  };
  // = every bad triangle of level l, ascending
  auto all_bad = [&](int l, std::vector<int>& out) {
    out.clear();
    if (!options.incremental) {
      for (int f = 0; f < static_cast<int>(mesh.triangles(l).size()); ++f)
        if (is_bad(l, f)) out.push_back(f);
      return;
    }
    SeenLevel& sl = seen[l];
    differences(state.displaced[l], sl.flagged, moved_displaced);
    const IndexRows& vf = mesh.links[l].vertex_faces;
    for (int v : moved_displaced)
      for (int i = vf.offsets[v]; i < vf.offsets[v + 1]; ++i) sl.bad[vf.items[i]] = is_bad(l, vf.items[i]);
    out.clear();
    for (int f = 0; f < static_cast<int>(sl.bad.size()); ++f)
      if (sl.bad[f]) out.push_back(f);
  };
  // Visit marks of the rounds below (fold, separation): a fresh value per round.
  int stamp = 0;
  // keep_finer_heights: a vertex of the two finest levels holding its height
  // (below) is first let go (its displacement as measured, over the new
  // base) when a fold or a crossing needs it to move; shrinking follows from
  // there. Shrinking from the held height instead left synthetic seed 1 with
  // 72 ear pairs (12 when letting go on the finest level only); letting go
  // on every level left James 678 level-3 pairs (640 this way, 646 without
  // holding).
  const int let_go_from = std::max(L - 1, 0);
  std::vector<std::vector<double>> let_go(L + 1);  // #V_l, NaN: not holding
  // Scales d_k[v] once per round; true when v carries a displacement.
  auto shrink_one = [&](int k, int v, bool to_zero = false) {
    double& d = mesh.displacements[k][v];
    if (k >= let_go_from && !let_go[k].empty() && !std::isnan(let_go[k][v])) {
      const double measured = let_go[k][v];
      let_go[k][v] = std::nan("");
      if (!to_zero) {
        if (shrunk_in_round[k][v] == stamp) return true;
        shrunk_in_round[k][v] = stamp;
        d = measured;
        return true;
      }
      if (d == 0) return false;
    }
    if (d == 0) return false;
    if (shrunk_in_round[k][v] == stamp) return true;
    shrunk_in_round[k][v] = stamp;
    if (shrinks[k][v]++ == 0) ++st.shrunk[k];
    if (to_zero || shrinks[k][v] >= options.max_shrinks) {
      d = 0;
      ++st.zeroed[k];
    } else {
      d *= options.shrink;
    }
    return true;
  };
  // A triangle's own corners on its level; the changed ones are re-displaced
  // at once (N_l does not depend on d_l, so nothing else on level l moves).
  std::vector<int> changed;
  auto shrink_corners = [&](int l, int f, const std::vector<char>* hold = nullptr) {
    bool any = false;
    for (int v : mesh.triangles(l)[f])
      if ((!hold || !(*hold)[v]) && shrink_one(l, v)) {
        any = true;
        changed.push_back(v);
        state.displaced[l][v] = displace(state.base[l][v], mesh.displacements[l][v], state.normals[l][v]);
      }
    return any;
  };
  // Corners without displacement (pockets, holes): the coarser levels bent
  // the triangle. First their displacement is set to reach the smooth
  // surface along the normal (what the smooth levels would have there);
  // shrinking coarser levels (below) is the last resort.
  std::vector<std::vector<char>> corrected(L + 1);
  for (int k = 0; k <= L; ++k) corrected[k].assign(mesh.num_vertices(k), 0);
  auto correct_corners = [&](int l, int f) {
    bool any = false;
    for (int v : mesh.triangles(l)[f]) {
      if (corrected[l][v] || mesh.displacements[l][v] != 0) continue;
      corrected[l][v] = 1;
      const double d = (smooth[l][v] - state.base[l][v]).dot(state.normals[l][v]);
      if (d == 0) continue;
      mesh.displacements[l][v] = d;
      shrunk_in_round[l][v] = stamp;  // not shrunk again in this round
      ++st.corrected;
      any = true;
      changed.push_back(v);
      state.displaced[l][v] = displace(state.base[l][v], d, state.normals[l][v]);
    }
    return any;
  };
  // Corners without displacement: the coarser levels bent the triangle.
  // Shrinks the neighbourhood of its parent (the Butterfly stencils of the
  // parent's edges) on the first level above that has displacement there;
  // returns that level, or -1.
  auto shrink_above = [&](int l, int f) {
    for (int k = l, g = f; k > 0;) {
      g /= 4;  // child c of coarse triangle g is 4 g + c
      --k;
      // The parent's own corners first; their neighbourhood only when they
      // carry nothing (less detail lost for the same effect).
      // Zeroed at once: each step up costs a re-evaluation of the levels below.
      bool any = false;
      for (int c : mesh.triangles(k)[g]) any |= shrink_one(k, c, true);
      const MultiresLevelLinks& links = mesh.links[k];
      if (!any)
        for (int c : mesh.triangles(k)[g])
          for (int i = links.vertex_faces.offsets[c]; i < links.vertex_faces.offsets[c + 1]; ++i)
            for (int v : mesh.triangles(k)[links.vertex_faces.items[i]]) any |= shrink_one(k, v, true);
      if (any) return k;
    }
    return -1;
  };
  // Triangles of level l around the changed vertices, each once per round.
  auto around_changed = [&](int l, std::vector<int>& out) {
    out.clear();
    const IndexRows& vf = mesh.links[l].vertex_faces;
    for (int v : changed)
      for (int i = vf.offsets[v]; i < vf.offsets[v + 1]; ++i) {
        const int f = vf.items[i];
        if (face_checked[l][f] == stamp) continue;
        face_checked[l][f] = stamp;
        out.push_back(f);
      }
  };
  // Crossings of the coarser levels (FoldLimitOptions::separate_coarser_levels).
  // A level-l displacement that pushes one sheet through another is refined
  // into every finer level, where the finest level's separation (step 2
  // below) can only put corners back on the surface refined from the crossed
  // level l, not on the smooth one: on the menpo3d James scan levels 0-2
  // crossed at the ears in 25 / 235 / 627 pairs and 750 of level 3's 950
  // pairs were left. So every visit of a level l < L in the fold pass also
  // separates its crossings, with step 2's rules: the corners of both
  // triangles are shrunk, corners without displacement of their own go onto
  // the smooth surface along their normals, and pairs that cross on the
  // smooth level l too are left alone. The first visit searches the whole
  // level, later visits only around what moved since (restarts zero coarser
  // displacements, which moves sheets too).
  // A pair that crosses on the smooth level l too is not the displacements'
  // doing: shrinking would only lose detail. Such pairs leave `pairs` (into
  // `left_alone` when given, to be counted).
  auto drop_smooth_crossings = [&](int l, std::vector<std::array<int, 2>>& pairs,
                                   std::set<std::array<int, 2>>* left_alone) {
    size_t kept = 0;
    for (const auto& p : pairs) {
      if (mesh_triangles_cross(smooth[l], mesh.triangles(l)[p[0]], mesh.triangles(l)[p[1]])) {
        if (left_alone) left_alone->insert(p);
        continue;
      }
      pairs[kept++] = p;
    }
    pairs.resize(kept);
  };
  struct LevelSeparation {
    bool built = false;
    MeshBvh bvh;  // bvh.positions: where the boxes were fitted
    BvhRefitIndex refit_index;
  };
  std::vector<LevelSeparation> separation(L);
  std::vector<int> around, moved_total;
  std::vector<std::array<int, 2>> level_pairs;
  std::vector<int> pair_tris;
  std::vector<char> in_pair_set;
  st.coarse_intersections_found.assign(L, 0);
  st.coarse_intersections_left.assign(L, 0);
  // FoldLimitOptions::keep_finer_heights: per level, the vertices whose base
  // moved because a coarser displacement changed, with the displaced
  // position each had before (marks #V_l, and the list); and each coarser
  // level's displaced positions as last refined into the next.
  std::vector<std::vector<char>> held_mark(L + 1);
  std::vector<std::vector<std::pair<int, Vec3>>> held_heights(L + 1);
  std::vector<std::vector<Vec3>> refined_from(L);
  for (int l = 0; l < L; ++l) refined_from[l] = state.displaced[l];
  std::vector<int> moved_level;
  // Returns with moved_total = the level-l vertices it moved (repeats allowed).
  auto separate_level = [&](int l) -> Status {
    moved_total.clear();
    LevelSeparation& sep = separation[l];
    if (!sep.built) {
      TriMesh level;
      level.positions = state.displaced[l];
      level.triangles = mesh.triangles(l);
      Status r = build_bvh(level, sep.bvh);
      if (!r.ok()) return r;
      build_refit_index(sep.bvh, sep.refit_index);
      sep.built = true;
      find_self_intersections(sep.bvh, level_pairs);
      st.coarse_intersections_found[l] = static_cast<int>(level_pairs.size());
    } else {
      changed.clear();
      for (int v = 0; v < static_cast<int>(sep.bvh.positions.size()); ++v)
        if (state.displaced[l][v] != sep.bvh.positions[v]) changed.push_back(v);
      if (changed.empty()) return Status::success();
      Status r = refit_bvh_vertices(sep.bvh, sep.refit_index, state.displaced[l], changed);
      if (!r.ok()) return r;
      ++stamp;  // for around_changed
      around_changed(l, around);
      find_intersections_with(sep.bvh, around, level_pairs);
    }
    in_pair_set.assign(mesh.triangles(l).size(), 0);
    for (int round = 0; round < options.max_intersection_rounds && !level_pairs.empty(); ++round) {
      ++stamp;  // separation rounds are not counted in st.rounds (the fold rounds' limit)
      drop_smooth_crossings(l, level_pairs, nullptr);
      pair_tris.clear();
      for (const auto& p : level_pairs)
        for (int f : p)
          if (!in_pair_set[f]) in_pair_set[f] = 1, pair_tris.push_back(f);
      for (int f : pair_tris) in_pair_set[f] = 0;
      changed.clear();
      for (int f : pair_tris)
        if (!shrink_corners(l, f)) correct_corners(l, f);
      if (changed.empty()) break;
      moved_total.insert(moved_total.end(), changed.begin(), changed.end());
      Status r = refit_bvh_vertices(sep.bvh, sep.refit_index, state.displaced[l], changed);
      if (!r.ok()) return r;
      around_changed(l, around);
      find_intersections_with(sep.bvh, around, level_pairs);
    }
    st.coarse_intersections_left[l] = static_cast<int>(level_pairs.size());
    return Status::success();
  };
  // 1. Folds, level by level (again after step 2 if that turned any over).
  std::vector<int> bad, stuck;
  auto fold_pass = [&](int round_limit) -> Status {
    int l = 0;
    while (l <= L) {
      evaluate_changes(l);
      // Shrinking on the coarser levels (separation, fold restarts) moved
      // this level's base: its vertices that carry a displacement get back
      // the position they had before (the height they were measured for).
      for (const auto& [w, target] : held_heights[l]) {
        held_mark[l][w] = 0;
        double& d = mesh.displacements[l][w];
        if (d == 0) continue;
        if (l >= let_go_from) {
          if (let_go[l].empty()) let_go[l].assign(mesh.num_vertices(l), std::nan(""));
          if (std::isnan(let_go[l][w])) let_go[l][w] = d;
        }
        d = (target - state.base[l][w]).dot(state.normals[l][w]);
        state.displaced[l][w] = displace(state.base[l][w], d, state.normals[l][w]);
      }
      held_heights[l].clear();
      all_bad(l, bad);
      if (!checked[l]) {
        checked[l] = 1;
        st.bad_found[l] = static_cast<int>(bad.size());
      }
      int restart = -1;
      for (int sweep = 0;; ++sweep) {
        while (!bad.empty() && st.rounds < round_limit) {
          ++st.rounds, ++stamp;
          changed.clear();
          stuck.clear();
          for (int f : bad)
            if (!shrink_corners(l, f) && !correct_corners(l, f)) stuck.push_back(f);
          if (!options.shrink_coarser_levels) stuck.clear();
          for (int f : stuck) {
            const int k = shrink_above(l, f);
            if (k >= 0) restart = restart < 0 ? k : std::min(restart, k);
          }
          if (restart >= 0) break;  // the coarser levels changed: evaluate again from there
          around_changed(l, around);
          bad.clear();
          for (int f : around)
            if (is_bad(l, f)) bad.push_back(f);
        }
        // Then this level's crossings; what that shrank may turn triangles
        // over: the fold loop again around it (a few sweeps at most).
        if (restart >= 0 || l == L || !options.separate_coarser_levels || options.max_intersection_rounds == 0 ||
            sweep >= options.separation_repeats + 1 || st.rounds >= round_limit)
          break;
        const Status r = separate_level(l);
        if (!r.ok()) return r;
        if (moved_total.empty()) break;
        changed.swap(moved_total);
        ++stamp;
        around_changed(l, around);
        bad.clear();
        for (int f : around)
          if (is_bad(l, f)) bad.push_back(f);
        if (bad.empty()) break;
      }
      if (restart >= 0) {
        ++st.restarts;
        l = restart;  // levels above it are unchanged, so its base P is current
        continue;
      }
      if (l < L) {
        if (options.keep_finer_heights) {
          // What moved on level l since it was last refined: the level-(l+1)
          // vertices refined from it keep their displaced positions as
          // targets (their displacements were measured from the old base).
          differences(state.displaced[l], refined_from[l], moved_level);
          if (held_mark[l + 1].empty()) held_mark[l + 1].assign(mesh.num_vertices(l + 1), 0);
          const IndexRows& reach = mesh.links[l].refine_reach;
          for (int v : moved_level)
            for (int i = reach.offsets[v]; i < reach.offsets[v + 1]; ++i) {
              const int w = reach.items[i];
              if (held_mark[l + 1][w]) continue;
              held_mark[l + 1][w] = 1;
              held_heights[l + 1].emplace_back(w, state.displaced[l + 1][w]);
            }
        }
        refine_changes(l);
      }
      ++l;
    }
    return Status::success();
  };
  s = fold_pass(options.max_rounds);
  if (!s.ok()) return s;

  // 2. Self-intersections of the finest level: the triangles of each
  // crossing pair are shrunk towards the smooth surface like bad ones.
  if (options.max_intersection_rounds > 0) {
    TriMesh finest;
    finest.positions = state.displaced[L];
    finest.triangles = mesh.triangles(L);
    MeshBvh bvh;
    s = build_bvh(finest, bvh);
    if (!s.ok()) return s;
    // Rounds move a few hundred of the finest level's vertices: only the
    // boxes holding them are refitted (bvh.positions are the positions the
    // boxes were fitted to).
    BvhRefitIndex refit_index;
    build_refit_index(bvh, refit_index);
    // The reference path: the moved vertices copied, every box refitted.
    auto refit_moved = [&](const std::vector<int>& moved) {
      for (int v : moved) finest.positions[v] = state.displaced[L][v];
      return refit_bvh(finest, bvh);
    };
    std::vector<std::array<int, 2>> pairs;
    find_self_intersections(bvh, pairs);
    st.intersections_found = static_cast<int>(pairs.size());
    std::vector<int> tris, next_bad;
    std::vector<char> in_set(finest.triangles.size(), 0);
    int rounds = 0, full_searches = 0;
    std::set<std::array<int, 2>> unfixable;
    std::vector<char> held(finest.positions.size(), 0);
    std::vector<char> parent_done(L > 0 ? mesh.num_vertices(L - 1) : 0, 0);
    // After `changed` moved on the finest level: crossings and bad triangles
    // are searched again around it only.
    auto search_around_changed = [&]() -> Status {
      Status r = options.incremental ? refit_bvh_vertices(bvh, refit_index, state.displaced[L], changed)
                                     : refit_moved(changed);
      if (!r.ok()) return r;
      around_changed(L, around);
      find_intersections_with(bvh, around, pairs);
      next_bad.clear();
      for (int f : around)
        if (is_bad(L, f)) next_bad.push_back(f);
      return Status::success();
    };
    for (int pass = 0;; ++pass) {
      while ((!pairs.empty() || !next_bad.empty()) && rounds < options.max_intersection_rounds) {
        ++rounds;
        ++st.rounds, ++stamp;
        drop_smooth_crossings(L, pairs, &unfixable);
        tris.clear();
        for (const auto& p : pairs)
          for (int f : p)
            if (!in_set[f]) in_set[f] = 1, tris.push_back(f);
        const size_t crossing_tris = tris.size();
        for (int f : next_bad)
          if (!in_set[f]) in_set[f] = 1, tris.push_back(f);
        for (int f : tris) in_set[f] = 0;
        changed.clear();
        // Corners put on the smooth surface (below) are not shrunk back
        // towards the crossing; a fold they cause may shrink them.
        for (size_t i = 0; i < tris.size(); ++i) shrink_corners(L, tris[i], i < crossing_tris ? &held : nullptr);
        // A pair whose triangles carry no displacement on this level was
        // crossed by the coarser levels: their parents' displacements are
        // zeroed and everything is evaluated and searched again (a few times
        // at most: each costs a full search). What still crosses then is the
        // smooth Butterfly surface's own doing (a control mesh with sheets
        // ~0.3 mm apart crosses itself at eye and mouth corners): counted.
        int restart = -1;
        for (const auto& p : pairs) {
          bool movable = false;
          for (int f : p)
            for (int v : mesh.triangles(L)[f]) movable |= shrunk_in_round[L][v] == stamp;
          if (movable) continue;
          // Coarser levels crossed it, but the smooth surface does not: the
          // corners go onto the smooth surface along their normals (a local
          // dent; no re-evaluation of the levels above, no detail lost
          // elsewhere).
          // When the corners already are there, their neighbourhood (the
          // triangles around them) follows, one ring per round.
          if (options.crossing_corners_to_smooth) {
            const size_t before = changed.size();
            bool any = false;
            for (int f : p) any |= correct_corners(L, f);
            if (!any) {
              const IndexRows& vf = mesh.links[L].vertex_faces;
              for (int f : p)
                for (int c : mesh.triangles(L)[f])
                  for (int i = vf.offsets[c]; i < vf.offsets[c + 1]; ++i) any |= correct_corners(L, vf.items[i]);
            }
            for (size_t i = before; i < changed.size(); ++i) held[changed[i]] = 1, ++st.crossing_corrected;
            if (any) continue;
            // Still crossing with everything around on the smooth surface
            // along the normals: the level above moved it sideways. Its
            // parent triangle's corners go onto the smooth surface there
            // (once each), and the two finest levels are evaluated again.
            if (options.crossing_parents_to_smooth && L > 0) {
              bool moved_parent = false;
              for (int f : p)
                for (int c : mesh.triangles(L - 1)[f / 4]) {
                  if (parent_done[c]) continue;
                  parent_done[c] = 1;
                  const double d = (smooth[L - 1][c] - state.base[L - 1][c]).dot(state.normals[L - 1][c]);
                  if (d == mesh.displacements[L - 1][c]) continue;
                  mesh.displacements[L - 1][c] = d;
                  ++st.crossing_corrected;
                  moved_parent = true;
                  restart = restart < 0 ? L - 1 : std::min(restart, L - 1);
                }
              if (moved_parent) continue;
            }
          }
          if (full_searches < options.max_intersection_restarts)
            for (int f : p) {
              const int k = shrink_above(L, f);
              if (k >= 0) restart = restart < 0 ? k : std::min(restart, k);
            }
          if (restart < 0) unfixable.insert(p);
        }
        if (restart >= 0) {
          ++st.restarts;
          ++full_searches;
          for (int k = restart; k <= L; ++k) {
            evaluate_changes(k);
            if (k < L) {
              refine_changes(k);
              refined_from[k] = state.displaced[k];  // meant to move the finer levels: nothing held
            }
          }
          // Only what moved is searched again (the levels' evaluation is
          // cheap, a full search is not).
          changed.clear();
          for (int v = 0; v < static_cast<int>(bvh.positions.size()); ++v)
            if (state.displaced[L][v] != bvh.positions[v]) changed.push_back(v);
          s = search_around_changed();
          if (!s.ok()) return s;
          continue;
        }
        s = search_around_changed();
        if (!s.ok()) return s;
      }
      for (const auto& p : pairs) unfixable.insert(p);
      st.intersections_left = static_cast<int>(unfixable.size());
      // Shrinking towards the smooth surface can turn a triangle over
      // against its neighbours: one more fold pass.
      all_bad(L, bad);
      if (bad.empty()) break;
      const std::vector<Vec3> before_folds = state.displaced[L];
      std::fill(checked.begin(), checked.end(), 1);  // keep the first pass's counts
      s = fold_pass(st.rounds + options.max_rounds);
      if (!s.ok()) return s;
      if (pass >= options.separation_repeats) break;
      // The fold pass may shrink corners back into a crossing: separate again
      // around what it moved (a local search, not a full one).
      changed.clear();
      for (int v = 0; v < static_cast<int>(before_folds.size()); ++v)
        if (state.displaced[L][v] != before_folds[v]) changed.push_back(v);
      if (changed.empty()) break;
      s = options.incremental ? refit_bvh_vertices(bvh, refit_index, state.displaced[L], changed)
                              : refit_moved(changed);
      if (!s.ok()) return s;
      ++st.rounds, ++stamp;  // a fresh round stamp for the visit marks
      around_changed(L, around);
      find_intersections_with(bvh, around, pairs);
      next_bad.clear();
      rounds = 0;
    }
  }
  for (int f = 0; f < static_cast<int>(mesh.triangles(L).size()); ++f) st.remaining_bad += is_bad(L, f);
  if (stats) *stats = st;
  return Status::success();
}

}  // namespace lk
