// The fold limiter's incremental bookkeeping (FoldLimitOptions::incremental:
// each visit of a level recomputes only what changed since the last one,
// and the BVH refits only the moved vertices' boxes) against the reference
// that evaluates, scans and refits everything on every visit: the same
// displacements, statistics and evaluated state, bit for bit, on surfaces
// that exercise shrinking, corrections, restarts on coarser levels and the
// separation of crossing sheets.
#include "mesh/primitives.h"
#include "multires/fold_limit.h"
#include "multires/multires.h"
#include "raycast/bvh.h"
#include "displaced_crossings.h"

#include <catch2/catch.hpp>

#include <cstring>
#include <random>

using namespace lk;

namespace {

bool same_bits(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(Vec3)) == 0;
}

void require_same_run(const MultiresMesh& fast, const FoldLimitStats& fs, const MultiresMesh& full,
                      const FoldLimitStats& ss) {
  CHECK(fs.rounds == ss.rounds);
  CHECK(fs.restarts == ss.restarts);
  CHECK(fs.corrected == ss.corrected);
  CHECK(fs.remaining_bad == ss.remaining_bad);
  CHECK(fs.bad_found == ss.bad_found);
  CHECK(fs.shrunk == ss.shrunk);
  CHECK(fs.zeroed == ss.zeroed);
  CHECK(fs.intersections_found == ss.intersections_found);
  CHECK(fs.intersections_left == ss.intersections_left);
  CHECK(fs.crossing_corrected == ss.crossing_corrected);
  CHECK(fs.second_pass_before == ss.second_pass_before);
  CHECK(fs.second_pass_after == ss.second_pass_after);
  CHECK(fs.smoothed_pairs_before == ss.smoothed_pairs_before);
  CHECK(fs.smoothed_pairs_after == ss.smoothed_pairs_after);
  // The finest level's pairs handed to the quality report.
  CHECK(fs.finest_pairs_known == ss.finest_pairs_known);
  CHECK(fs.finest_pairs == ss.finest_pairs);
  REQUIRE(fast.num_levels() == full.num_levels());
  for (int l = 0; l <= fast.num_levels(); ++l) {
    INFO("level " << l);
    CHECK(std::memcmp(fast.displacements[l].data(), full.displacements[l].data(),
                      full.displacements[l].size() * sizeof(double)) == 0);
    CHECK(same_bits(fast.state.base[l], full.state.base[l]));
    CHECK(same_bits(fast.state.normals[l], full.state.normals[l]));
    CHECK(same_bits(fast.state.displaced[l], full.state.displaced[l]));
    CHECK(same_bits(fast.state.face_normals[l], full.state.face_normals[l]));
  }
  // And both are what a full evaluation of the final displacements gives.
  MultiresMesh again = fast;
  REQUIRE(evaluate(again).ok());
  for (int l = 0; l <= fast.num_levels(); ++l) {
    INFO("level " << l << " against evaluate()");
    CHECK(same_bits(fast.state.displaced[l], again.state.displaced[l]));
    CHECK(same_bits(fast.state.face_normals[l], again.state.face_normals[l]));
  }
}

void run_both(const MultiresMesh& input, FoldLimitOptions options, FoldLimitStats& fast_stats) {
  MultiresMesh fast = input, full = input;
  FoldLimitStats full_stats;
  options.incremental = true;
  REQUIRE(limit_folds(fast, options, &fast_stats).ok());
  options.incremental = false;
  REQUIRE(limit_folds(full, options, &full_stats).ok());
  // The reference searches the finest level whole every time; the
  // incremental run reuses the pairs its separation kept up to date.
  CHECK(full_stats.finest_known_reused == 0);
  require_same_run(fast, fast_stats, full, full_stats);
}

// Displacements of a few edge lengths, random in sign, on every level: the
// levels fold everywhere. Over a cap the finest level carries none, and
// over part of it level 2 neither, so bad triangles there are bent by
// coarser levels: corrections, and restarts that zero coarser displacements
// (some of them corrections made earlier, i.e. back to their old value).
MultiresMesh randomly_folded_sphere(unsigned seed) {
  std::mt19937 rng(seed);
  MultiresMesh mr;
  REQUIRE(build_multires(make_icosphere(1), 3, mr).ok());
  for (int l = 0; l <= 3; ++l) {
    const double amplitude = 0.4 / (1 + l);  // level-l edges are ~0.6 / 2^l long
    std::uniform_real_distribution<double> d(-amplitude, amplitude);
    for (double& x : mr.displacements[l]) x = d(rng);
  }
  for (int v = 0; v < mr.num_vertices(3); ++v)
    if (mr.state.base[3][v].z() > 0.3) mr.displacements[3][v] = 0;
  for (int v = 0; v < mr.num_vertices(2); ++v)
    if (mr.state.base[2][v].z() > 0.3 && mr.state.base[2][v].x() > 0) mr.displacements[2][v] = 0;
  REQUIRE(evaluate(mr).ok());
  return mr;
}

// Two spheres pushed into each other by level-0 displacements, with random
// detail (seeded) on the finer levels: the finest level crosses itself.
MultiresMesh spheres_pushed_together(unsigned seed) {
  MultiresMesh mr;
  REQUIRE(build_multires(test::two_spheres_apart(), 3, mr).ok());
  std::mt19937 rng(seed);
  for (int l = 1; l <= 3; ++l) {
    std::uniform_real_distribution<double> d(-0.04 / (1 << l), 0.04 / (1 << l));
    for (double& x : mr.displacements[l]) x = d(rng);
  }
  for (double& x : mr.displacements[0]) x = 0.15;
  REQUIRE(evaluate(mr).ok());
  return mr;
}

}  // namespace

TEST_CASE("fold limit: incremental visits equal full ones on randomly folded spheres", "[multires]") {
  for (unsigned seed : {7u, 8u, 9u, 10u}) {
    INFO("seed " << seed);
    FoldLimitStats stats;
    run_both(randomly_folded_sphere(seed), FoldLimitOptions{}, stats);
    // The paths under test were taken.
    CHECK(stats.rounds > 10);
    CHECK(stats.restarts > 0);
    CHECK(stats.corrected > 0);
    CHECK(stats.bad_found[3] > 50);
    CHECK(stats.remaining_bad == 0);
  }
}

TEST_CASE("fold limit: incremental visits equal full ones when crossing sheets are separated", "[multires]") {
  // Separation rounds, corners put on the smooth surface, parents on the
  // level above, restarts.
  const MultiresMesh mr = spheres_pushed_together(11);
  for (int restarts : {0, 3}) {
    INFO("restarts " << restarts);
    FoldLimitOptions options;
    options.max_intersection_restarts = restarts;
    options.separate_coarser_levels = false;  // the finest level's separation (coarser: test_fold_coarse.cpp)
    FoldLimitStats stats;
    run_both(mr, options, stats);
    CHECK(stats.intersections_found > 10);
    CHECK(stats.crossing_corrected > 0);
    CHECK(stats.finest_whole_searches == 1);  // the separation's start only
    CHECK(stats.finest_known_reused > 0);
  }
}

TEST_CASE("fold limit: the pairs a cut-short separation leaves are the pairs a whole search finds", "[multires]") {
  // One or two rounds leave most of the crossing pairs to the last resort
  // (smooth_region_rings): the pairs kept up to date through the rounds'
  // searches around what moved must be every pair a search of the whole
  // level finds (the reference run's), or the last resort smooths other
  // regions.
  for (unsigned seed : {11u, 13u})
    for (int rounds : {1, 2}) {
      INFO("seed " << seed << ", rounds " << rounds);
      FoldLimitOptions options;
      options.max_intersection_rounds = rounds;
      options.separate_coarser_levels = false;
      FoldLimitStats stats;
      run_both(spheres_pushed_together(seed), options, stats);
      CHECK(stats.intersections_found > 50);
      CHECK(stats.smoothed_pairs_before > 50);
      CHECK(stats.finest_whole_searches == 1);
      CHECK(stats.finest_known_reused > 0);
    }
}

TEST_CASE("fold limit: a finest-level tree taken over from elsewhere gives the run of its own tree", "[multires]") {
  // The finest level's separation searches that tree. The tree handed in
  // has its boxes at the smooth level (as the global fit's relief leaves
  // its tree), so a limiter that used it without refitting would find
  // other pairs.
  const MultiresMesh mr = spheres_pushed_together(12);
  FoldLimitOptions options;
  options.separate_coarser_levels = false;

  MultiresMesh own = mr;
  FoldLimitStats own_stats;
  REQUIRE(limit_folds(own, options, &own_stats).ok());
  CHECK(own_stats.intersections_found > 10);

  // limit_folds handed a tree over level `level`'s triangles at the smooth
  // positions; returns what it left in the tree's place.
  std::vector<std::vector<Vec3>> smooth;
  REQUIRE(smooth_positions(mr, smooth).ok());
  auto run_with_tree_of = [&](int level, MultiresMesh& run, FoldLimitStats& stats) {
    TriMesh at_smooth;
    at_smooth.positions = smooth[level];
    at_smooth.triangles = mr.triangles(level);
    MeshBvh tree;
    REQUIRE(build_bvh(at_smooth, tree).ok());
    run = mr;
    REQUIRE(limit_folds(run, options, &stats, &tree).ok());
    return tree;
  };
  MultiresMesh taken, refused;
  FoldLimitStats taken_stats, refused_stats;
  // Taken over, and handed back refitted to where the level ended.
  const MeshBvh back = run_with_tree_of(3, taken, taken_stats);
  require_same_run(taken, taken_stats, own, own_stats);
  CHECK(back.triangles == mr.triangles(3));
  CHECK(same_bits(back.positions, taken.state.displaced[3]));
  MeshBvh fresh;
  REQUIRE(build_bvh(level_mesh(taken, 3), fresh).ok());
  CHECK(same_bits({back.nodes[0].box_min, back.nodes[0].box_max}, {fresh.nodes[0].box_min, fresh.nodes[0].box_max}));
  // Other triangles: left alone.
  const MeshBvh other = run_with_tree_of(2, refused, refused_stats);
  require_same_run(refused, refused_stats, own, own_stats);
  CHECK(other.triangles == mr.triangles(2));
}
