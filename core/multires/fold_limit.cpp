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

namespace {

using PairList = std::vector<std::array<int, 2>>;

// Indices where now differs bit-wise from before; before is brought up to date.
template <class T>
void differences(const std::vector<T>& now, std::vector<T>& before, std::vector<int>& out) {
  out.clear();
  for (int i = 0; i < static_cast<int>(now.size()); ++i)
    if (std::memcmp(&now[i], &before[i], sizeof(now[i])) != 0) {
      out.push_back(i);
      before[i] = now[i];
    }
}

// The vertices whose position differs from the one the BVH's boxes were
// fitted to (bvh.positions).
void moved_since_fit(const MeshBvh& bvh, const std::vector<Vec3>& positions, std::vector<int>& out) {
  out.clear();
  for (int v = 0; v < static_cast<int>(bvh.positions.size()); ++v)
    if (positions[v] != bvh.positions[v]) out.push_back(v);
}

// The distinct triangles of `pairs` and then of `extra`, in the order first
// met; returns how many came from the pairs. `mark` (#F, all 0) is all 0 again
// on return.
size_t distinct_triangles(const PairList& pairs, const std::vector<int>& extra, std::vector<char>& mark,
                          std::vector<int>& out) {
  out.clear();
  for (const auto& p : pairs)
    for (int f : p)
      if (!mark[f]) mark[f] = 1, out.push_back(f);
  const size_t from_pairs = out.size();
  for (int f : extra)
    if (!mark[f]) mark[f] = 1, out.push_back(f);
  for (int f : out) mark[f] = 0;
  return from_pairs;
}

// One run of limit_folds over an evaluated mesh: the state its passes share
// (what each level last saw, the per-vertex shrink counts and visit marks)
// and the passes themselves. Stats accumulate in `st`.
class FoldLimiter {
 public:
  FoldLimiter(MultiresMesh& mesh, const FoldLimitOptions& options, const std::vector<std::vector<Vec3>>& smooth,
              FoldLimitStats& st);

  // 1. Folds, level by level, coarse to fine; each coarser level's
  // crossings are separated on its visit. At most round_limit rounds in
  // all (st.rounds).
  Status fold_pass(int round_limit);
  // 2. The finest level's crossings, then fold passes for what that turned
  // over (FoldLimitOptions::separation_repeats).
  Status separate_finest();
  // Bad triangles left on the finest level.
  int count_finest_bad() const;
  int given_up_still_crossing() const;
  // Every crossing pair of the finest level as it is now: a full search on
  // separate_finest's tree, refitted to the current positions (the same
  // sorted pairs as a search on a fresh tree, without its build).
  Status finest_pairs(PairList& out);
  // Takes over `other`'s finest-level tree (refitted, not rebuilt, at the
  // start of separate_finest) when this run starts where `other` ended.
  void adopt_finest_tree(FoldLimiter& other);
  // Takes over a tree built over the finest level's triangles elsewhere
  // (moved out of `tree`; a tree over other triangles is left alone).
  void adopt_finest_tree(MeshBvh& tree);
  // That tree (boxes at whatever positions it was last refitted to), or
  // null when it was never built. The caller may refit it elsewhere: the
  // pairs known at its positions (below) are dropped.
  MeshBvh* finest_tree() {
    finest_known_valid_ = false;
    return finest_built_ ? &finest_bvh_ : nullptr;
  }

 private:
  bool is_bad(int l, int f) const {
    return bad_triangle(face_normal(mesh_.triangles(l), state_.displaced[l], f), smooth_normals_[l][f], options_);
  }
  void bad_among(int l, const std::vector<int>& faces, std::vector<int>& out) const {
    out.clear();
    for (int f : faces)
      if (is_bad(l, f)) out.push_back(f);
  }
  void evaluate_changes(int l);
  void refine_changes(int l);
  void all_bad(int l, std::vector<int>& out);
  bool shrink_one(int k, int v, bool to_zero = false);
  bool shrink_corners(int l, int f, const std::vector<char>* hold = nullptr);
  bool correct_corners(int l, int f);
  int shrink_above(int l, int f);
  void around_changed(int l, std::vector<int>& out);
  void drop_smooth_crossings(int l, PairList& pairs, std::set<PairList::value_type>* left_alone) const;
  Status separate_level(int l);
  void restore_held_heights(int l);
  void hold_finer_heights(int l);
  bool fold_rounds(int l, int round_limit, int& restart);
  void separate_from_coarser(const PairList::value_type& pair, std::vector<char>& held,
                             std::vector<char>& parent_done, int full_searches,
                             std::set<PairList::value_type>& unfixable, int& restart);
  void reevaluate_from(int level);

  MultiresMesh& mesh_;
  MultiresState& state_;
  const FoldLimitOptions& options_;
  const std::vector<std::vector<Vec3>>& smooth_;
  FoldLimitStats& st_;
  const int L_;

  std::vector<std::vector<Vec3>> smooth_normals_;        // L+1, #F_l
  std::vector<std::vector<std::uint8_t>> shrinks_;       // L+1, #V_l: times shrunk
  std::vector<std::vector<int>> shrunk_in_round_;        // L+1, #V_l: stamp of the last shrink
  std::vector<std::vector<int>> face_checked_;           // L+1, #F_l: stamp of the last visit
  std::vector<char> checked_;                            // L+1: bad_found counted
  // Corners without displacement put on the smooth surface (once each).
  std::vector<std::vector<char>> corrected_;             // L+1, #V_l
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
  std::vector<SeenLevel> seen_;  // L+1 when incremental, else empty
  std::vector<int> moved_base_, moved_displaced_;
  // Visit marks of the rounds (fold, separation): a fresh value per round.
  int stamp_ = 0;
  // keep_finer_heights: a vertex of the two finest levels holding its height
  // (below) is first let go (its displacement as measured, over the new
  // base) when a fold or a crossing needs it to move; shrinking follows from
  // there. Shrinking from the held height instead left synthetic seed 1 with
  // 72 ear pairs (12 when letting go on the finest level only); letting go
  // on every level left James 678 level-3 pairs (640 this way, 646 without
  // holding).
  const int let_go_from_;
  std::vector<std::vector<double>> let_go_;  // L+1, #V_l, NaN: not holding
  // The vertices moved in the current round (re-displaced at once: N_l does
  // not depend on d_l, so nothing else on level l moves).
  std::vector<int> changed_;
  std::vector<int> around_;
  // Crossings of the coarser levels (FoldLimitOptions::separate_coarser_levels).
  struct LevelSeparation {
    bool built = false;
    MeshBvh bvh;  // bvh.positions: where the boxes were fitted
    BvhRefitIndex refit_index;
  };
  std::vector<LevelSeparation> separation_;  // L
  std::vector<int> moved_total_;             // separate_level: the vertices it moved
  PairList level_pairs_;
  std::vector<int> pair_tris_;
  std::vector<char> in_pair_set_;
  // FoldLimitOptions::keep_finer_heights: per level, the vertices whose base
  // moved because a coarser displacement changed, with the displaced
  // position each had before (marks #V_l, and the list); and each coarser
  // level's displaced positions as last refined into the next.
  std::vector<std::vector<char>> held_mark_;                       // L+1
  std::vector<std::vector<std::pair<int, Vec3>>> held_heights_;   // L+1
  std::vector<std::vector<Vec3>> refined_from_;                    // L
  std::vector<int> moved_level_;
  std::vector<int> bad_, stuck_;
  // separate_finest: the pairs it gave up on (incl. those that cross on the
  // smooth surface too).
  std::set<PairList::value_type> given_up_;
  // separate_finest's tree over the finest level (bvh.positions: where its
  // boxes were last fitted), kept for finest_pairs and a second run: a
  // level-3 build is about half the cost of a full search.
  bool finest_built_ = false;
  MeshBvh finest_bvh_;
  BvhRefitIndex finest_refit_index_;
  // Incremental runs: every crossing pair of the finest level at
  // finest_bvh_.positions (sorted, a < b), from its last whole search kept
  // up to date by every search around moved triangles since (a pair
  // between two unmoved triangles crosses as it did). A later whole search
  // of the level at the same positions is then not needed (finest_pairs,
  // and separate_finest at the start of a run that continues this one).
  bool finest_known_valid_ = false;
  PairList finest_known_;
  std::vector<char> finest_mark_;  // #F_L, all 0 between uses
  // The pairs around `around` (finest-level triangles, distinct) were
  // searched again at the tree's positions: `found` replaces every known
  // pair with a triangle in it.
  void update_finest_known(const std::vector<int>& around, const PairList& found);
  // Every crossing pair of the finest level at the tree's positions, given
  // `moved` (the vertices that moved since the tree's last refit, now
  // refitted): the known pairs when nothing moved, else a whole search.
  // (On the synthetic seeds and James and Fran nothing ever moved between
  // the separation's last search and the searches after it.)
  void search_finest(const std::vector<int>& moved, PairList& out);
};

FoldLimiter::FoldLimiter(MultiresMesh& mesh, const FoldLimitOptions& options,
                         const std::vector<std::vector<Vec3>>& smooth, FoldLimitStats& st)
    : mesh_(mesh), state_(mesh.state), options_(options), smooth_(smooth), st_(st), L_(mesh.num_levels()),
      let_go_from_(std::max(mesh.num_levels() - 1, 0)) {
  const int L = L_;
  st_.bad_found.assign(L + 1, 0);
  st_.shrunk.assign(L + 1, 0);
  st_.zeroed.assign(L + 1, 0);
  st_.coarse_intersections_found.assign(L, 0);
  st_.coarse_intersections_left.assign(L, 0);
  smooth_normals_.resize(L + 1);
  shrinks_.resize(L + 1);
  shrunk_in_round_.resize(L + 1);
  face_checked_.resize(L + 1);
  checked_.assign(L + 1, 0);
  corrected_.resize(L + 1);
  for (int l = 0; l <= L; ++l) {
    const auto& tris = mesh_.triangles(l);
    smooth_normals_[l].resize(tris.size());
    for (int f = 0; f < static_cast<int>(tris.size()); ++f) smooth_normals_[l][f] = face_normal(tris, smooth_[l], f);
    shrinks_[l].assign(mesh_.num_vertices(l), 0);
    shrunk_in_round_[l].assign(mesh_.num_vertices(l), -1);
    face_checked_[l].assign(tris.size(), -1);
    corrected_[l].assign(mesh_.num_vertices(l), 0);
  }
  seen_.resize(options_.incremental ? L + 1 : 0);
  for (int l = 0; l < static_cast<int>(seen_.size()); ++l) {
    SeenLevel& sl = seen_[l];
    sl.base = state_.base[l];
    sl.refined = sl.flagged = state_.displaced[l];
    sl.bad.resize(mesh_.triangles(l).size());
    for (int f = 0; f < static_cast<int>(sl.bad.size()); ++f) sl.bad[f] = is_bad(l, f);
  }
  let_go_.resize(L + 1);
  separation_.resize(L);
  held_mark_.resize(L + 1);
  held_heights_.resize(L + 1);
  refined_from_.resize(L);
  for (int l = 0; l < L; ++l) refined_from_[l] = state_.displaced[l];
}

// = evaluate_level(mesh, l)
void FoldLimiter::evaluate_changes(int l) {
  if (!options_.incremental) return evaluate_level(mesh_, l);
  differences(state_.base[l], seen_[l].base, moved_base_);
  update_level(mesh_, l, moved_base_);
}

// = apply(mesh.levels[l], state.displaced[l], state.base[l + 1])
void FoldLimiter::refine_changes(int l) {
  if (!options_.incremental) {
    apply(mesh_.levels[l], state_.displaced[l], state_.base[l + 1]);  // sizes match (check_sizes)
    return;
  }
  differences(state_.displaced[l], seen_[l].refined, moved_displaced_);
  update_refinement(mesh_, l, moved_displaced_);
}

// = every bad triangle of level l, ascending
void FoldLimiter::all_bad(int l, std::vector<int>& out) {
  out.clear();
  if (!options_.incremental) {
    for (int f = 0; f < static_cast<int>(mesh_.triangles(l).size()); ++f)
      if (is_bad(l, f)) out.push_back(f);
    return;
  }
  SeenLevel& sl = seen_[l];
  differences(state_.displaced[l], sl.flagged, moved_displaced_);
  const IndexRows& vf = mesh_.links[l].vertex_faces;
  for (int v : moved_displaced_)
    for (int i = vf.offsets[v]; i < vf.offsets[v + 1]; ++i) sl.bad[vf.items[i]] = is_bad(l, vf.items[i]);
  for (int f = 0; f < static_cast<int>(sl.bad.size()); ++f)
    if (sl.bad[f]) out.push_back(f);
}

// Scales d_k[v] once per round; true when v carries a displacement.
bool FoldLimiter::shrink_one(int k, int v, bool to_zero) {
  double& d = mesh_.displacements[k][v];
  if (k >= let_go_from_ && !let_go_[k].empty() && !std::isnan(let_go_[k][v])) {
    const double measured = let_go_[k][v];
    let_go_[k][v] = std::nan("");
    if (!to_zero) {
      if (shrunk_in_round_[k][v] == stamp_) return true;
      shrunk_in_round_[k][v] = stamp_;
      d = measured;
      return true;
    }
    if (d == 0) return false;
  }
  if (d == 0) return false;
  if (shrunk_in_round_[k][v] == stamp_) return true;
  shrunk_in_round_[k][v] = stamp_;
  if (shrinks_[k][v]++ == 0) ++st_.shrunk[k];
  if (to_zero || shrinks_[k][v] >= options_.max_shrinks) {
    d = 0;
    ++st_.zeroed[k];
  } else {
    d *= options_.shrink;
  }
  return true;
}

// A triangle's own corners on its level (but those `hold` marks); the
// changed ones are re-displaced at once (N_l does not depend on d_l, so
// nothing else on level l moves).
bool FoldLimiter::shrink_corners(int l, int f, const std::vector<char>* hold) {
  bool any = false;
  for (int v : mesh_.triangles(l)[f])
    if ((!hold || !(*hold)[v]) && shrink_one(l, v)) {
      any = true;
      changed_.push_back(v);
      state_.displaced[l][v] = displace(state_.base[l][v], mesh_.displacements[l][v], state_.normals[l][v]);
    }
  return any;
}

// Corners without displacement (pockets, holes): the coarser levels bent
// the triangle. First their displacement is set to reach the smooth
// surface along the normal (what the smooth levels would have there);
// shrinking coarser levels (shrink_above) is the last resort.
bool FoldLimiter::correct_corners(int l, int f) {
  bool any = false;
  for (int v : mesh_.triangles(l)[f]) {
    if (corrected_[l][v] || mesh_.displacements[l][v] != 0) continue;
    corrected_[l][v] = 1;
    const double d = (smooth_[l][v] - state_.base[l][v]).dot(state_.normals[l][v]);
    if (d == 0) continue;
    mesh_.displacements[l][v] = d;
    shrunk_in_round_[l][v] = stamp_;  // not shrunk again in this round
    ++st_.corrected;
    any = true;
    changed_.push_back(v);
    state_.displaced[l][v] = displace(state_.base[l][v], d, state_.normals[l][v]);
  }
  return any;
}

// Corners without displacement: the coarser levels bent the triangle.
// Shrinks the neighbourhood of its parent (the Butterfly stencils of the
// parent's edges) on the first level above that has displacement there;
// returns that level, or -1.
int FoldLimiter::shrink_above(int l, int f) {
  for (int k = l, g = f; k > 0;) {
    g /= 4;  // child c of coarse triangle g is 4 g + c
    --k;
    // The parent's own corners first; their neighbourhood only when they
    // carry nothing (less detail lost for the same effect).
    // Zeroed at once: each step up costs a re-evaluation of the levels below.
    bool any = false;
    for (int c : mesh_.triangles(k)[g]) any |= shrink_one(k, c, true);
    const MultiresLevelLinks& links = mesh_.links[k];
    if (!any)
      for (int c : mesh_.triangles(k)[g])
        for (int i = links.vertex_faces.offsets[c]; i < links.vertex_faces.offsets[c + 1]; ++i)
          for (int v : mesh_.triangles(k)[links.vertex_faces.items[i]]) any |= shrink_one(k, v, true);
    if (any) return k;
  }
  return -1;
}

// Triangles of level l around the changed vertices, each once per round.
void FoldLimiter::around_changed(int l, std::vector<int>& out) {
  out.clear();
  const IndexRows& vf = mesh_.links[l].vertex_faces;
  for (int v : changed_)
    for (int i = vf.offsets[v]; i < vf.offsets[v + 1]; ++i) {
      const int f = vf.items[i];
      if (face_checked_[l][f] == stamp_) continue;
      face_checked_[l][f] = stamp_;
      out.push_back(f);
    }
}

// A pair that crosses on the smooth level l too is not the displacements'
// doing: shrinking would only lose detail. Such pairs leave `pairs` (into
// `left_alone` when given, to be counted).
void FoldLimiter::drop_smooth_crossings(int l, PairList& pairs, std::set<PairList::value_type>* left_alone) const {
  size_t kept = 0;
  for (const auto& p : pairs) {
    if (mesh_triangles_cross(smooth_[l], mesh_.triangles(l)[p[0]], mesh_.triangles(l)[p[1]])) {
      if (left_alone) left_alone->insert(p);
      continue;
    }
    pairs[kept++] = p;
  }
  pairs.resize(kept);
}

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
// Returns with moved_total_ = the level-l vertices it moved (repeats allowed).
Status FoldLimiter::separate_level(int l) {
  moved_total_.clear();
  LevelSeparation& sep = separation_[l];
  if (!sep.built) {
    TriMesh level;
    level.positions = state_.displaced[l];
    level.triangles = mesh_.triangles(l);
    Status r = build_bvh(level, sep.bvh);
    if (!r.ok()) return r;
    build_refit_index(sep.bvh, sep.refit_index);
    sep.built = true;
    find_self_intersections(sep.bvh, level_pairs_);
    st_.coarse_intersections_found[l] = static_cast<int>(level_pairs_.size());
  } else {
    moved_since_fit(sep.bvh, state_.displaced[l], changed_);
    if (changed_.empty()) return Status::success();
    Status r = refit_bvh_vertices(sep.bvh, sep.refit_index, state_.displaced[l], changed_);
    if (!r.ok()) return r;
    ++stamp_;  // for around_changed
    around_changed(l, around_);
    find_intersections_with(sep.bvh, around_, level_pairs_);
  }
  in_pair_set_.assign(mesh_.triangles(l).size(), 0);
  for (int round = 0; round < options_.max_intersection_rounds && !level_pairs_.empty(); ++round) {
    ++stamp_;  // separation rounds are not counted in st.rounds (the fold rounds' limit)
    drop_smooth_crossings(l, level_pairs_, nullptr);
    distinct_triangles(level_pairs_, {}, in_pair_set_, pair_tris_);
    changed_.clear();
    for (int f : pair_tris_)
      if (!shrink_corners(l, f)) correct_corners(l, f);
    if (changed_.empty()) break;
    moved_total_.insert(moved_total_.end(), changed_.begin(), changed_.end());
    Status r = refit_bvh_vertices(sep.bvh, sep.refit_index, state_.displaced[l], changed_);
    if (!r.ok()) return r;
    around_changed(l, around_);
    find_intersections_with(sep.bvh, around_, level_pairs_);
  }
  st_.coarse_intersections_left[l] = static_cast<int>(level_pairs_.size());
  return Status::success();
}

// Shrinking on the coarser levels (separation, fold restarts) moved level
// l's base: its vertices that carry a displacement get back the position
// they had before (the height they were measured for).
void FoldLimiter::restore_held_heights(int l) {
  for (const auto& [w, target] : held_heights_[l]) {
    held_mark_[l][w] = 0;
    double& d = mesh_.displacements[l][w];
    if (d == 0) continue;
    if (l >= let_go_from_) {
      if (let_go_[l].empty()) let_go_[l].assign(mesh_.num_vertices(l), std::nan(""));
      if (std::isnan(let_go_[l][w])) let_go_[l][w] = d;
    }
    d = (target - state_.base[l][w]).dot(state_.normals[l][w]);
    state_.displaced[l][w] = displace(state_.base[l][w], d, state_.normals[l][w]);
  }
  held_heights_[l].clear();
}

// What moved on level l < L since it was last refined: the level-(l+1)
// vertices refined from it keep their displaced positions as targets
// (their displacements were measured from the old base).
void FoldLimiter::hold_finer_heights(int l) {
  differences(state_.displaced[l], refined_from_[l], moved_level_);
  if (held_mark_[l + 1].empty()) held_mark_[l + 1].assign(mesh_.num_vertices(l + 1), 0);
  const IndexRows& reach = mesh_.links[l].refine_reach;
  for (int v : moved_level_)
    for (int i = reach.offsets[v]; i < reach.offsets[v + 1]; ++i) {
      const int w = reach.items[i];
      if (held_mark_[l + 1][w]) continue;
      held_mark_[l + 1][w] = 1;
      held_heights_[l + 1].emplace_back(w, state_.displaced[l + 1][w]);
    }
}

// Shrink rounds on level l until bad_ is empty or the round limit is
// reached; false with `restart` set to the coarsest level whose
// displacements changed when a bad triangle needed the levels above.
bool FoldLimiter::fold_rounds(int l, int round_limit, int& restart) {
  while (!bad_.empty() && st_.rounds < round_limit) {
    ++st_.rounds, ++stamp_;
    changed_.clear();
    stuck_.clear();
    for (int f : bad_)
      if (!shrink_corners(l, f) && !correct_corners(l, f)) stuck_.push_back(f);
    if (!options_.shrink_coarser_levels) stuck_.clear();
    for (int f : stuck_) {
      const int k = shrink_above(l, f);
      if (k >= 0) restart = restart < 0 ? k : std::min(restart, k);
    }
    if (restart >= 0) return false;  // the coarser levels changed: evaluate again from there
    around_changed(l, around_);
    bad_among(l, around_, bad_);
  }
  return true;
}

Status FoldLimiter::fold_pass(int round_limit) {
  int l = 0;
  while (l <= L_) {
    evaluate_changes(l);
    restore_held_heights(l);
    all_bad(l, bad_);
    if (!checked_[l]) {
      checked_[l] = 1;
      st_.bad_found[l] = static_cast<int>(bad_.size());
    }
    int restart = -1;
    for (int sweep = 0;; ++sweep) {
      if (!fold_rounds(l, round_limit, restart)) break;
      // Then this level's crossings; what that shrank may turn triangles
      // over: the fold loop again around it (a few sweeps at most).
      if (l == L_ || !options_.separate_coarser_levels || options_.max_intersection_rounds == 0 ||
          sweep >= options_.separation_repeats + 1 || st_.rounds >= round_limit)
        break;
      const Status r = separate_level(l);
      if (!r.ok()) return r;
      if (moved_total_.empty()) break;
      changed_.swap(moved_total_);
      ++stamp_;
      around_changed(l, around_);
      bad_among(l, around_, bad_);
      if (bad_.empty()) break;
    }
    if (restart >= 0) {
      ++st_.restarts;
      l = restart;  // levels above it are unchanged, so its base P is current
      continue;
    }
    if (l < L_) {
      if (options_.keep_finer_heights) hold_finer_heights(l);
      refine_changes(l);
    }
    ++l;
  }
  return Status::success();
}

// Evaluates and refines the levels from `level` down to the finest after
// coarser displacements were set on purpose (nothing held).
void FoldLimiter::reevaluate_from(int level) {
  for (int k = level; k <= L_; ++k) {
    evaluate_changes(k);
    if (k < L_) {
      refine_changes(k);
      refined_from_[k] = state_.displaced[k];  // meant to move the finer levels: nothing held
    }
  }
}

// A finest-level pair none of whose corners moved this round: coarser
// levels crossed it. `restart` (the round's, -1: none yet) becomes the
// coarsest level whose displacements were changed for it (then everything
// is evaluated again from there); while the round has no restart, a pair
// that cannot be helped goes into `unfixable`.
void FoldLimiter::separate_from_coarser(const PairList::value_type& p, std::vector<char>& held,
                                        std::vector<char>& parent_done, int full_searches,
                                        std::set<PairList::value_type>& unfixable, int& restart) {
  const int L = L_;
  // Coarser levels crossed it, but the smooth surface does not: the
  // corners go onto the smooth surface along their normals (a local
  // dent; no re-evaluation of the levels above, no detail lost
  // elsewhere).
  // When the corners already are there, their neighbourhood (the
  // triangles around them) follows, one ring per round.
  if (options_.crossing_corners_to_smooth) {
    const size_t before = changed_.size();
    bool any = false;
    for (int f : p) any |= correct_corners(L, f);
    if (!any) {
      const IndexRows& vf = mesh_.links[L].vertex_faces;
      for (int f : p)
        for (int c : mesh_.triangles(L)[f])
          for (int i = vf.offsets[c]; i < vf.offsets[c + 1]; ++i) any |= correct_corners(L, vf.items[i]);
    }
    for (size_t i = before; i < changed_.size(); ++i) held[changed_[i]] = 1, ++st_.crossing_corrected;
    if (any) return;
    // Still crossing with everything around on the smooth surface
    // along the normals: the level above moved it sideways. Its
    // parent triangle's corners go onto the smooth surface there
    // (once each), and the two finest levels are evaluated again.
    if (options_.crossing_parents_to_smooth && L > 0) {
      bool moved_parent = false;
      for (int f : p)
        for (int c : mesh_.triangles(L - 1)[f / 4]) {
          if (parent_done[c]) continue;
          parent_done[c] = 1;
          const double d = (smooth_[L - 1][c] - state_.base[L - 1][c]).dot(state_.normals[L - 1][c]);
          if (d == mesh_.displacements[L - 1][c]) continue;
          mesh_.displacements[L - 1][c] = d;
          ++st_.crossing_corrected;
          moved_parent = true;
          restart = restart < 0 ? L - 1 : std::min(restart, L - 1);
        }
      if (moved_parent) return;
    }
  }
  if (full_searches < options_.max_intersection_restarts)
    for (int f : p) {
      const int k = shrink_above(L, f);
      if (k >= 0) restart = restart < 0 ? k : std::min(restart, k);
    }
  if (restart < 0) unfixable.insert(p);
}

// Self-intersections of the finest level: the triangles of each crossing
// pair are shrunk towards the smooth surface like bad ones.
Status FoldLimiter::separate_finest() {
  const int L = L_;
  TriMesh finest;
  finest.positions = state_.displaced[L];
  finest.triangles = mesh_.triangles(L);
  MeshBvh& bvh = finest_bvh_;
  // Rounds move a few hundred of the finest level's vertices: only the
  // boxes holding them are refitted (bvh.positions are the positions the
  // boxes were fitted to).
  BvhRefitIndex& refit_index = finest_refit_index_;
  Status s;
  std::vector<int> moved;  // since the tree's last refit (known pairs: see search_finest)
  if (finest_built_) {
    // A tree taken over from the run this one continues: every box
    // refitted to where the level is now (searches give the same pairs on
    // any tree over the same positions).
    if (finest_known_valid_) moved_since_fit(bvh, state_.displaced[L], moved);
    s = refit_bvh(finest, bvh);
  } else {
    s = build_bvh(finest, bvh);
    if (s.ok()) build_refit_index(bvh, refit_index);
    finest_built_ = s.ok();
    finest_known_valid_ = false;
  }
  if (!s.ok()) return s;
  // The reference path: the moved vertices copied, every box refitted.
  auto refit_changed = [&]() {
    if (options_.incremental) return refit_bvh_vertices(bvh, refit_index, state_.displaced[L], changed_);
    for (int v : changed_) finest.positions[v] = state_.displaced[L][v];
    return refit_bvh(finest, bvh);
  };
  PairList pairs;
  search_finest(moved, pairs);
  st_.intersections_found = static_cast<int>(pairs.size());
  std::vector<int> tris, next_bad;
  std::vector<char> in_set(finest.triangles.size(), 0);
  int rounds = 0, full_searches = 0;
  std::set<PairList::value_type> unfixable;
  std::vector<char> held(finest.positions.size(), 0);
  std::vector<char> parent_done(L > 0 ? mesh_.num_vertices(L - 1) : 0, 0);
  // After changed_ moved on the finest level: crossings and bad triangles
  // are searched again around it only.
  auto search_around_changed = [&]() -> Status {
    Status r = refit_changed();
    if (!r.ok()) return r;
    around_changed(L, around_);
    find_intersections_with(bvh, around_, pairs);
    update_finest_known(around_, pairs);
    bad_among(L, around_, next_bad);
    return Status::success();
  };
  for (int pass = 0;; ++pass) {
    while ((!pairs.empty() || !next_bad.empty()) && rounds < options_.max_intersection_rounds) {
      ++rounds;
      ++st_.rounds, ++stamp_;
      drop_smooth_crossings(L, pairs, &unfixable);
      const size_t crossing_tris = distinct_triangles(pairs, next_bad, in_set, tris);
      changed_.clear();
      // Corners put on the smooth surface (below) are not shrunk back
      // towards the crossing; a fold they cause may shrink them.
      for (size_t i = 0; i < tris.size(); ++i) shrink_corners(L, tris[i], i < crossing_tris ? &held : nullptr);
      // A pair whose triangles carry no displacement on this level was
      // crossed by the coarser levels (separate_from_coarser). What still
      // crosses then is the smooth Butterfly surface's own doing (a control
      // mesh with sheets ~0.3 mm apart crosses itself at eye and mouth
      // corners): counted.
      int restart = -1;
      for (const auto& p : pairs) {
        bool movable = false;
        for (int f : p)
          for (int v : mesh_.triangles(L)[f]) movable |= shrunk_in_round_[L][v] == stamp_;
        if (movable) continue;
        separate_from_coarser(p, held, parent_done, full_searches, unfixable, restart);
      }
      if (restart >= 0) {
        ++st_.restarts;
        ++full_searches;
        reevaluate_from(restart);
        // Only what moved is searched again (the levels' evaluation is
        // cheap, a full search is not).
        moved_since_fit(bvh, state_.displaced[L], changed_);
      }
      s = search_around_changed();
      if (!s.ok()) return s;
    }
    for (const auto& p : pairs) unfixable.insert(p);
    st_.intersections_left = static_cast<int>(unfixable.size());
    given_up_ = unfixable;
    // Shrinking towards the smooth surface can turn a triangle over
    // against its neighbours: one more fold pass.
    all_bad(L, bad_);
    if (bad_.empty()) break;
    const std::vector<Vec3> before_folds = state_.displaced[L];
    std::fill(checked_.begin(), checked_.end(), 1);  // keep the first pass's counts
    s = fold_pass(st_.rounds + options_.max_rounds);
    if (!s.ok()) return s;
    if (pass >= options_.separation_repeats) break;
    // The fold pass may shrink corners back into a crossing: separate again
    // around what it moved (a local search, not a full one).
    changed_.clear();
    for (int v = 0; v < static_cast<int>(before_folds.size()); ++v)
      if (state_.displaced[L][v] != before_folds[v]) changed_.push_back(v);
    if (changed_.empty()) break;
    s = refit_changed();
    if (!s.ok()) return s;
    ++st_.rounds, ++stamp_;  // a fresh round stamp for the visit marks
    around_changed(L, around_);
    find_intersections_with(bvh, around_, pairs);
    update_finest_known(around_, pairs);
    next_bad.clear();
    rounds = 0;
  }
  return Status::success();
}

// Pairs separate_finest gave up on that still cross at the end, but not on
// the smooth surface (see limit_folds' second pass).
int FoldLimiter::given_up_still_crossing() const {
  const std::vector<Tri>& tris = mesh_.triangles(L_);
  int n = 0;
  for (const auto& p : given_up_)
    n += !mesh_triangles_cross(smooth_[L_], tris[p[0]], tris[p[1]]) &&
         mesh_triangles_cross(state_.displaced[L_], tris[p[0]], tris[p[1]]);
  return n;
}

Status FoldLimiter::finest_pairs(PairList& out) {
  out.clear();
  std::vector<int> moved;
  if (!finest_built_) {
    TriMesh finest;
    finest.positions = state_.displaced[L_];
    finest.triangles = mesh_.triangles(L_);
    Status s = build_bvh(finest, finest_bvh_);
    if (!s.ok()) return s;
    build_refit_index(finest_bvh_, finest_refit_index_);
    finest_built_ = true;
    finest_known_valid_ = false;
  } else {
    moved_since_fit(finest_bvh_, state_.displaced[L_], moved);
    Status s = refit_bvh_vertices(finest_bvh_, finest_refit_index_, state_.displaced[L_], moved);
    if (!s.ok()) return s;
  }
  search_finest(moved, out);
  return Status::success();
}

void FoldLimiter::update_finest_known(const std::vector<int>& around, const PairList& found) {
  if (!finest_known_valid_) return;
  for (int f : around) finest_mark_[f] = 1;
  finest_known_ = pairs_after_change(finest_known_, finest_mark_, found);
  for (int f : around) finest_mark_[f] = 0;
}

void FoldLimiter::search_finest(const std::vector<int>& moved, PairList& out) {
  if (options_.incremental && finest_known_valid_ && moved.empty()) {
    out = finest_known_;
    ++st_.finest_known_reused;
    return;
  }
  find_self_intersections(finest_bvh_, out);
  ++st_.finest_whole_searches;
  if (options_.incremental) {
    finest_known_ = out;
    finest_known_valid_ = true;
    finest_mark_.assign(mesh_.triangles(L_).size(), 0);
  }
}

void FoldLimiter::adopt_finest_tree(MeshBvh& tree) {
  if (tree.empty() || tree.triangles != mesh_.triangles(L_) || tree.positions.size() != state_.displaced[L_].size())
    return;
  finest_bvh_ = std::move(tree);
  tree = MeshBvh{};
  build_refit_index(finest_bvh_, finest_refit_index_);
  finest_built_ = true;
  finest_known_valid_ = false;
}

void FoldLimiter::adopt_finest_tree(FoldLimiter& other) {
  if (!other.finest_built_) return;
  finest_bvh_ = std::move(other.finest_bvh_);
  finest_refit_index_ = std::move(other.finest_refit_index_);
  finest_built_ = true;
  other.finest_built_ = false;
  // The pairs known at the tree's positions go with it.
  finest_known_valid_ = other.finest_known_valid_;
  finest_known_ = std::move(other.finest_known_);
  finest_mark_ = std::move(other.finest_mark_);
  other.finest_known_valid_ = false;
}

int FoldLimiter::count_finest_bad() const {
  int bad = 0;
  for (int f = 0; f < static_cast<int>(mesh_.triangles(L_).size()); ++f) bad += is_bad(L_, f);
  return bad;
}

// FoldLimitOptions::undisplaced_creases: returns how many were set to 0.
int zero_crease_displacements(MultiresMesh& mesh) {
  int zeroed = 0;
  const auto crease = crease_vertex_masks(mesh);
  for (int l = 0; l <= mesh.num_levels(); ++l)
    for (int v = 0; v < mesh.num_vertices(l); ++v)
      if (crease[l][v] && mesh.displacements[l][v] != 0) {
        mesh.displacements[l][v] = 0;
        ++zeroed;
      }
  return zeroed;
}

// FoldLimitOptions::smooth_region_rings: the smooth surface over the
// control faces of the finest level's crossing pairs that the smooth
// surface does not have. `pairs` are the finest level's pairs at the
// evaluated mesh (sorted, a < b) and become those of the result; the mesh
// is left as it was unless the result is kept. `tree` (may be null): a BVH
// over the finest level's triangles at any positions, refitted here
// instead of building one.
Status smooth_crossing_regions(MultiresMesh& mesh, const FoldLimitOptions& options,
                               const std::vector<std::vector<Vec3>>& smooth, MeshBvh* tree, PairList& pairs,
                               FoldLimitStats& st) {
  const int L = mesh.num_levels();
  const std::vector<Tri>& finest = mesh.triangles(L);
  auto new_pairs = [&](const PairList& ps) {
    int n = 0;
    for (const auto& p : ps) n += !mesh_triangles_cross(smooth[L], finest[p[0]], finest[p[1]]);
    return n;
  };
  // The pairs' control faces (a level-l triangle f lies in control face
  // f >> 2l), counting them on the way.
  const int F0 = static_cast<int>(mesh.control_triangles.size());
  std::vector<char> region(F0, 0);
  int before = 0;
  for (const auto& p : pairs)
    if (!mesh_triangles_cross(smooth[L], finest[p[0]], finest[p[1]])) {
      ++before;
      for (int f : p) region[f >> (2 * L)] = 1;
    }
  st.smoothed_pairs_before = before;
  st.smoothed_pairs_after = static_cast<int>(pairs.size());
  if (before == 0 || options.smooth_region_rings < 0 || L < 1) return Status::success();

  // Control faces around a vertex: one ring of growth.
  std::vector<std::vector<int>> vertex_faces(mesh.control.size());
  for (int f = 0; f < F0; ++f)
    for (int v : mesh.control_triangles[f]) vertex_faces[v].push_back(f);

  const std::vector<std::vector<double>> original = mesh.displacements;
  const MultiresState original_state = mesh.state;
  TriMesh level;
  level.positions = mesh.state.displaced[L];
  level.triangles = finest;
  MeshBvh own;
  MeshBvh& bvh = tree ? *tree : own;
  Status s = tree ? Status::success() : build_bvh(level, own);
  if (!s.ok()) return s;

  PairList best_pairs = pairs, trial;
  std::vector<std::vector<double>> best_displacements;
  int best_total = static_cast<int>(pairs.size()), best_faces = 0, best_level = -1;
  const std::vector<char> seed_region = region;
  // Tries, from the least change to the most: the finest levels first
  // (the coarser ones carry every finer level's base over tens of mm on
  // level 0), each from the pairs' own faces outwards.
  const int rings = options.smooth_region_rings;
  for (int t = 0; t < L * (rings + 1); ++t) {
    const int first_level = L - 1 - t / (rings + 1), ring = t % (rings + 1);
    if (ring == 0) {
      region = seed_region;
    } else {
      const std::vector<char> grown = region;
      for (int f = 0; f < F0; ++f)
        if (grown[f])
          for (int v : mesh.control_triangles[f])
            for (int g : vertex_faces[v]) region[g] = 1;
    }
    mesh.displacements = original;
    for (int l = first_level; l <= L; ++l) {
      const std::vector<Tri>& tris = mesh.triangles(l);
      for (int f = 0; f < static_cast<int>(tris.size()); ++f)
        if (region[f >> (2 * l)])
          for (int v : tris[f]) mesh.displacements[l][v] = 0;
    }
    // The levels above first_level are as they were (tries only go
    // coarser): the rest is evaluated with evaluate()'s kernels.
    for (int l = first_level; l <= L; ++l) {
      evaluate_level(mesh, l);
      if (l < L) {
        s = apply(mesh.levels[l], mesh.state.displaced[l], mesh.state.base[l + 1]);
        if (!s.ok()) return s;
      }
    }
    // The finest level moved only around the region: its pairs elsewhere
    // stay, those of the moved triangles are searched again.
    const std::vector<Vec3>& now = mesh.state.displaced[L];
    std::vector<char> moved_tri(finest.size(), 0);
    std::vector<int> moved;
    for (int f = 0; f < static_cast<int>(finest.size()); ++f)
      for (int v : finest[f])
        if (now[v] != original_state.displaced[L][v]) moved_tri[f] = 1;
    for (int f = 0; f < static_cast<int>(finest.size()); ++f)
      if (moved_tri[f]) moved.push_back(f);
    level.positions = now;
    s = refit_bvh(level, bvh);
    if (!s.ok()) return s;
    find_intersections_with(bvh, moved, trial);
    for (const auto& p : pairs)
      if (!moved_tri[p[0]] && !moved_tri[p[1]]) trial.push_back(p);
    std::sort(trial.begin(), trial.end());
    trial.erase(std::unique(trial.begin(), trial.end()), trial.end());
    // Only a moved triangle can have turned or collapsed.
    const bool bad = std::any_of(moved.begin(), moved.end(), [&](int f) {
      return bad_triangle(face_normal(finest, now, f), face_normal(finest, smooth[L], f), options);
    });
    if (!bad && static_cast<int>(trial.size()) < best_total) {
      best_total = static_cast<int>(trial.size());
      best_pairs = trial;
      best_displacements = mesh.displacements;
      best_faces = static_cast<int>(std::count(region.begin(), region.end(), 1));
      best_level = first_level;
    }
    if (!bad && new_pairs(trial) == 0) break;
  }
  if (best_displacements.empty()) {
    mesh.displacements = original;
    mesh.state = original_state;
    return Status::success();
  }
  mesh.displacements.swap(best_displacements);
  s = evaluate(mesh);  // all levels: the last try need not be the kept one
  if (!s.ok()) return s;
  pairs.swap(best_pairs);
  st.smoothed_control_faces = best_faces;
  st.smoothed_from_level = best_level;
  st.smoothed_pairs_after = best_total;
  return Status::success();
}

}  // namespace

std::uint64_t positions_fingerprint(const std::vector<Vec3>& positions) {
  std::uint64_t h = 14695981039346656037ull;
  for (const Vec3& p : positions)
    for (int k = 0; k < 3; ++k) {
      unsigned char bytes[sizeof(double)];
      const double x = p[k];
      std::memcpy(bytes, &x, sizeof x);
      for (unsigned char b : bytes) h = (h ^ b) * 1099511628211ull;
    }
  return h;
}

const std::vector<std::array<int, 2>>* finest_pairs_of(const FoldLimitStats& stats,
                                                       const std::vector<Vec3>& finest_positions) {
  if (!stats.finest_pairs_known || positions_fingerprint(finest_positions) != stats.finest_pairs_fingerprint)
    return nullptr;
  return &stats.finest_pairs;
}

Status finest_crossing_pairs(const FoldLimitStats& stats, const TriMesh& finest,
                             std::vector<std::array<int, 2>>& pairs) {
  if (const auto* known = finest_pairs_of(stats, finest.positions)) {
    pairs = *known;
    return Status::success();
  }
  return find_self_intersections(finest, pairs);
}

Status limit_folds(MultiresMesh& mesh, const FoldLimitOptions& options, FoldLimitStats* stats,
                   MeshBvh* finest_tree) {
  if (!(options.shrink >= 0 && options.shrink < 1) || options.min_area_ratio < 0 || options.max_shrinks < 0 ||
      options.max_rounds < 0 || options.max_intersection_rounds < 0 || options.max_intersection_restarts < 0 ||
      options.separation_repeats < 0 ||
      !(std::abs(options.min_normal_cos) <= 1))
    return Status::error(ErrorCode::InvalidInput,
                         "multires fold limit: shrink must be in [0, 1), the cosine in [-1, 1], ratios and counts >= 0");
  Status s = check_sizes(mesh);
  if (!s.ok()) return s;
  std::vector<std::vector<Vec3>> smooth;
  s = smooth_positions(mesh, smooth);
  if (!s.ok()) return s;
  FoldLimitStats st;
  if (options.undisplaced_creases) st.crease_zeroed = zero_crease_displacements(mesh);
  s = evaluate(mesh);
  if (!s.ok()) return s;
  FoldLimiter limiter(mesh, options, smooth, st);
  // The caller's tree slot receives the limiter's tree at the end unless it
  // holds a tree over other triangles (left alone).
  bool hand_back = false;
  if (finest_tree) {
    if (!finest_tree->empty()) limiter.adopt_finest_tree(*finest_tree);
    hand_back = finest_tree->empty();  // taken over, or none given
  }
  s = limiter.fold_pass(options.max_rounds);
  if (!s.ok()) return s;
  if (options.max_intersection_rounds > 0) {
    s = limiter.separate_finest();
    if (!s.ok()) return s;
  }
  st.remaining_bad = limiter.count_finest_bad();
  // The separation gives a pair up when no corner of it can move: its
  // corners and its parents' were put on the smooth surface. Restarts and
  // fold passes later re-evaluate the coarser levels and move the finest
  // level's base under those held heights, so a given-up pair may cross
  // again where nothing looks any more (the demo sample's right ear: a
  // corner 1.3 mm off the smooth surface, 10 pairs). When one does, the
  // whole limiter runs once more on its own result, with nothing held (it
  // sees the pairs from the start), and that is kept when it leaves fewer
  // crossing pairs (those that cross on the smooth surface too included:
  // what the user sees).
  // Both full searches below run on the first run's finest-level tree,
  // refitted (the second run takes it over): the same pairs as searches on
  // fresh trees, without three level-L builds; the pairs of the result
  // are handed to the quality report (FoldLimitStats::finest_pairs).
  if (options.max_intersection_rounds > 0 && options.second_pass && limiter.given_up_still_crossing() > 0) {
    PairList before_pairs, after_pairs;
    s = limiter.finest_pairs(before_pairs);
    if (!s.ok()) return s;
    const int before = static_cast<int>(before_pairs.size());
    const std::vector<std::vector<double>> displacements = mesh.displacements;
    const MultiresState state = mesh.state;
    s = evaluate(mesh);
    if (!s.ok()) return s;
    FoldLimitStats again_st;
    again_st.crease_zeroed = st.crease_zeroed;
    FoldLimiter again(mesh, options, smooth, again_st);
    again.adopt_finest_tree(limiter);
    s = again.fold_pass(options.max_rounds);
    if (s.ok()) s = again.separate_finest();
    if (s.ok()) s = again.finest_pairs(after_pairs);
    if (!s.ok()) return s;
    const int after = static_cast<int>(after_pairs.size());
    st.second_pass_before = before;
    st.second_pass_after = after;
    if (after < before && again.count_finest_bad() == 0) {
      again_st.remaining_bad = 0;
      again_st.second_pass_before = before;
      again_st.second_pass_after = after;
      again_st.second_pass_kept = true;
      again_st.rounds += st.rounds;
      again_st.finest_whole_searches += st.finest_whole_searches;
      again_st.finest_known_reused += st.finest_known_reused;
      st = again_st;
      st.finest_pairs.swap(after_pairs);
    } else {
      mesh.displacements = displacements;
      mesh.state = state;
      st.finest_pairs.swap(before_pairs);
      st.finest_whole_searches += again_st.finest_whole_searches;
      st.finest_known_reused += again_st.finest_known_reused;
    }
    st.finest_pairs_known = true;
    st.finest_pairs_fingerprint = positions_fingerprint(mesh.state.displaced[mesh.num_levels()]);
    limiter.adopt_finest_tree(again);  // for the last resort below
  }
  // The last resort (smooth_region_rings) needs the finest level's pairs:
  // the second pass's, or one whole search here (the quality report then
  // takes them instead of searching again).
  if (options.max_intersection_rounds > 0 && options.smooth_region_rings >= 0 && mesh.num_levels() > 0) {
    const std::vector<Vec3>& finest = mesh.state.displaced[mesh.num_levels()];
    PairList pairs;
    if (const auto* known = finest_pairs_of(st, finest)) {
      pairs = *known;
    } else {
      s = limiter.finest_pairs(pairs);
      if (!s.ok()) return s;
    }
    s = smooth_crossing_regions(mesh, options, smooth, limiter.finest_tree(), pairs, st);
    if (!s.ok()) return s;
    st.finest_pairs.swap(pairs);
    st.finest_pairs_known = true;
    st.finest_pairs_fingerprint = positions_fingerprint(mesh.state.displaced[mesh.num_levels()]);
  }
  if (stats) *stats = st;
  if (hand_back) {
    if (MeshBvh* tree = limiter.finest_tree()) {
      TriMesh finest;
      finest.positions = mesh.state.displaced[mesh.num_levels()];
      finest.triangles = mesh.triangles(mesh.num_levels());
      s = refit_bvh(finest, *tree);
      if (!s.ok()) return s;
      *finest_tree = std::move(*tree);
    }
  }
  return Status::success();
}

}  // namespace lk
