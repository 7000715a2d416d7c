#include "multires/displacement.h"
#include "multires/fold_limit.h"
#include "multires/multires.h"

#include "io/io.h"
#include "mesh/geometry.h"
#include "mesh/topology.h"
#include "raycast/bvh.h"
#include "raycast/self_intersection.h"
#include "../subdiv/shapes.h"
#include "displaced_crossings.h"
#include "test_data.h"

#include <algorithm>
#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <set>

using namespace lk;
using namespace lk::test;

namespace {

// The mirrored irregular grid bent into a smooth bump: boundary, corners and
// interior vertices of valence 4..8.
TriMesh bumpy_patch(int half_width = 4, int height = 7) {
  TriMesh m = mirrored_irregular_grid(half_width, height);
  const double cy = 0.5 * height;
  for (Vec3& p : m.positions) p.z() = 1.5 * std::exp(-0.08 * ((p.x()) * (p.x()) + (p.y() - cy) * (p.y() - cy)));
  return m;
}

// Random but deterministic displacements on every level.
void random_displacements(MultiresMesh& m, unsigned seed, double amplitude) {
  std::mt19937 rng(seed);
  for (int l = 0; l <= m.num_levels(); ++l) {
    std::uniform_real_distribution<double> d(-amplitude / (1 << l), amplitude / (1 << l));
    for (double& x : m.displacements[l]) x = d(rng);
  }
}

void require_identical(const MultiresMesh& a, const MultiresMesh& b) {
  REQUIRE(a.num_levels() == b.num_levels());
  for (int l = 0; l <= a.num_levels(); ++l) {
    INFO("level " << l);
    int base = 0, normals = 0, displaced = 0;
    for (int v = 0; v < a.num_vertices(l); ++v) {
      base += a.state.base[l][v] != b.state.base[l][v];
      normals += a.state.normals[l][v] != b.state.normals[l][v];
      displaced += a.state.displaced[l][v] != b.state.displaced[l][v];
    }
    CHECK(base == 0);
    CHECK(normals == 0);
    CHECK(displaced == 0);
  }
}

// A smooth star-shaped target around the origin: radius as a function of direction.
double target_radius(const Vec3& dir) {
  return 1.0 + 0.08 * dir.x() * dir.y() + 0.06 * std::sin(3 * dir.z()) + 0.04 * dir.x() * dir.x();
}

PointCloud sample_target(int n, double noise, unsigned seed, double drop_above_z = 1e9) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0, 1);
  PointCloud c;
  while (c.size() < n) {
    Vec3 d(g(rng), g(rng), g(rng));
    d.normalize();
    if (d.z() > drop_above_z) continue;  // a hole: no data there
    c.positions.push_back(d * (target_radius(d) + noise * g(rng)));
  }
  return c;
}

double radial_error(const Vec3& p) { return std::abs(p.norm() - target_radius(p.normalized())); }

}  // namespace

TEST_CASE("multires: zero displacements give the plain butterfly hierarchy", "[multires]") {
  TriMesh m = icosphere(1);
  MultiresMesh mr;
  REQUIRE(build_multires(m, 3, mr).ok());
  REQUIRE(mr.num_levels() == 3);
  std::vector<std::vector<Vec3>> P;
  REQUIRE(apply_all(mr.levels, m.positions, P).ok());
  for (int l = 0; l <= 3; ++l) {
    REQUIRE(static_cast<int>(mr.state.displaced[l].size()) == mr.num_vertices(l));
    for (int v = 0; v < mr.num_vertices(l); ++v) CHECK(mr.state.displaced[l][v] == P[l][v]);
  }
  TriMesh out = level_mesh(mr, 2);
  CHECK(out.num_vertices() == mr.num_vertices(2));
  CHECK(out.num_triangles() == 16 * m.num_triangles());
  CHECK(out.normals.size() == out.positions.size());
}

TEST_CASE("multires: a displacement moves the vertex along its normal on its level", "[multires]") {
  TriMesh m = icosphere(1);
  MultiresMesh mr;
  REQUIRE(build_multires(m, 2, mr).ok());
  const int v = 50;  // a vertex introduced on level 1
  REQUIRE(v >= mr.num_vertices(0));
  const Vec3 before = mr.state.displaced[1][v];
  const Vec3 n = mr.state.normals[1][v];
  mr.displacements[1][v] = 0.01;
  REQUIRE(evaluate(mr).ok());
  CHECK((mr.state.displaced[1][v] - (before + 0.01 * n)).norm() < 1e-15);
  CHECK(n.dot(before.normalized()) > 0.99);  // outward normal on a sphere
  CHECK(mr.state.displaced[2][v] == mr.state.displaced[1][v]);  // interpolated by the next level
}

TEST_CASE("multires: measured displacements put every level on the scanned surface", "[multires]") {
  TriMesh m = icosphere(1);  // unit sphere; the target bulges up to ~10% away
  const double noise = 0.001;
  PointCloud cloud = sample_target(400000, noise, 11);
  MultiresMesh mr;
  REQUIRE(build_multires(m, 3, mr).ok());
  double before_mean = 0;
  for (const Vec3& p : mr.state.displaced[3]) before_mean += radial_error(p);
  before_mean /= mr.num_vertices(3);

  DisplacementStats stats;
  REQUIRE(measure_displacements(cloud, DisplacementOptions{}, mr, &stats).ok());
  for (int l = 0; l <= 3; ++l) {
    INFO("level " << l << ": " << stats.measured[l] << " of " << stats.candidates[l] << " measured, mean |d| "
                  << stats.mean_abs[l]);
    CHECK(stats.measured[l] == stats.candidates[l]);  // dense data everywhere
    double mean = 0, worst = 0;
    for (const Vec3& p : mr.state.displaced[l]) {
      mean += radial_error(p);
      worst = std::max(worst, radial_error(p));
    }
    mean /= mr.num_vertices(l);
    INFO("mean error " << mean << " max " << worst << " (before displacement " << before_mean << ")");
    CHECK(mean < 0.3 * noise);  // the quadric fit averages the noise away
    CHECK(worst < 1.5 * noise);
  }
  CHECK(before_mean > 20 * noise);
  // Displacements shrink with the level: detail is coarse-to-fine.
  CHECK(stats.mean_abs[3] < stats.mean_abs[0]);
  // Vertices inherited from the coarser level are not re-measured (jeong2002).
  for (int v = 0; v < mr.num_vertices(2); ++v) CHECK(mr.displacements[3][v] == 0.0);
  // measure + incremental evaluation equals a fresh full evaluation
  MultiresMesh again = mr;
  REQUIRE(evaluate(again).ok());
  require_identical(mr, again);
}

TEST_CASE("multires: where the scan has no data the displacement is zero", "[multires]") {
  TriMesh m = icosphere(1);
  PointCloud cloud = sample_target(200000, 0.0005, 5, /*drop_above_z=*/0.5);
  // Without the fade across the data's edge: 0 everywhere in the hole.
  // With it (the default), the hole (1 rad across its radius) lies within
  // the fade's reach (two control edges, ~1.1 rad): its displacements are
  // the edge's carried in, never larger than the largest measured one.
  DisplacementOptions no_fade;
  no_fade.edge_fade_control_edges = 0;
  for (const bool fade : {false, true}) {
    MultiresMesh mr;
    REQUIRE(build_multires(m, 3, mr).ok());
    DisplacementStats stats;
    REQUIRE(measure_displacements(cloud, fade ? DisplacementOptions{} : no_fade, mr, &stats).ok());
    int in_hole = 0, measured_elsewhere = 0, below = 0, filled = 0;
    for (int l = 0; l <= 3; ++l) {
      CHECK(stats.measured[l] < stats.candidates[l]);
      for (int v = 0; v < mr.num_vertices(l); ++v) {
        const Vec3 dir = mr.state.base[l][v].normalized();
        if (dir.z() > 0.85) {
          ++in_hole;
          if (fade) {
            CHECK(std::abs(mr.displacements[l][v]) <= stats.max_abs[l] + 1e-12);
            filled += mr.displacements[l][v] != 0.0;
          } else {
            CHECK(mr.displacements[l][v] == 0.0);
          }
        } else if (dir.z() < 0.3) {
          ++below;
          measured_elsewhere += mr.displacements[l][v] != 0.0;
        }
      }
    }
    CHECK(in_hole > 100);
    if (fade) CHECK(filled > 0);
    // Data region: new vertices are measured (inherited ones keep 0).
    CHECK(measured_elsewhere > below / 2);
  }
}

TEST_CASE("multires: local update equals a full recompute, bit for bit", "[multires]") {
  for (int shape = 0; shape < 2; ++shape) {
    TriMesh m = shape == 0 ? bumpy_patch(6, 10) : icosphere(2);
    MultiresMesh local;
    REQUIRE(build_multires(m, 3, local).ok());
    random_displacements(local, 17 + shape, 0.2);
    REQUIRE(evaluate(local).ok());
    MeshTopology topo;
    REQUIRE(build_topology(m, topo).ok());

    std::mt19937 rng(99 + shape);
    std::uniform_int_distribution<int> pick(0, m.num_vertices() - 1);
    std::uniform_int_distribution<int> how_many(1, 4);
    std::normal_distribution<double> step(0, 0.1);
    std::set<int> kinds;  // 0 boundary, 1 regular interior, 2 extraordinary interior
    for (int round = 0; round < 30; ++round) {
      std::vector<int> moved;
      std::vector<Vec3> to;
      const int n = how_many(rng);
      for (int i = 0; i < n; ++i) {
        int v = pick(rng);
        // make sure boundary and extraordinary vertices are exercised
        if (round == 0 && shape == 0) v = topo.boundary_loops[0][0];
        moved.push_back(v);
        to.push_back(local.control[v] + Vec3(step(rng), step(rng), step(rng)));
        kinds.insert(topo.is_boundary(v) ? 0 : topo.valence(v) == 6 ? 1 : 2);
      }
      UpdateFootprint fp;
      REQUIRE(update_control_vertices(local, moved, to, &fp).ok());
      MultiresMesh full = local;  // same control and displacements
      REQUIRE(evaluate(full).ok());
      INFO("shape " << shape << " round " << round);
      require_identical(local, full);
      if (n == 1) CHECK(fp.displaced_changed[3] < local.num_vertices(3));
    }
    if (shape == 0) CHECK(kinds.size() == 3);
  }
}

TEST_CASE("multires: an animation's repeated moved list is replayed from its plan, bit for bit", "[multires]") {
  // Frames move the same control vertices again and again: from the second
  // time a list is given, its per-level work lists are kept and replayed.
  // Each frame must equal a full recompute, including frames whose list
  // change (another list between), frames limited to a lower level, and a frame
  // where some listed vertices do not move.
  TriMesh m = bumpy_patch(8, 12);
  MultiresMesh local;
  REQUIRE(build_multires(m, 3, local).ok());
  random_displacements(local, 31, 0.2);
  REQUIRE(evaluate(local).ok());
  std::mt19937 rng(7);
  std::normal_distribution<double> step(0, 0.05);
  const std::vector<int> a = {40, 41, 42, 55, 56, 70}, b = {3, 90, 91};
  int replayed = 0;
  for (int frame = 0; frame < 14; ++frame) {
    const std::vector<int>& moved = frame >= 6 && frame < 9 ? b : a;
    const int limit = frame == 10 || frame == 11 ? 1 : -1;
    std::vector<Vec3> to;
    for (size_t i = 0; i < moved.size(); ++i)
      to.push_back(frame == 12 && i % 2 ? local.control[moved[i]] : local.control[moved[i]] + Vec3(step(rng), step(rng), step(rng)));
    const auto& plans = local.scratch.plans;
    const auto known = [&] {
      return std::find_if(plans.begin(), plans.end(), [&](const auto& p) { return p.moved == moved && p.top == (limit < 0 ? 3 : limit); });
    };
    const bool repeat = known() != plans.end(), built_before = repeat && known()->built;
    UpdateFootprint fp;
    REQUIRE(update_control_vertices(local, moved, to, &fp, limit).ok());
    if (repeat && plans.front().built && plans.front().moved == moved) ++replayed;
    // The first list's plan outlives the second list's frames.
    if (frame == 9) CHECK(built_before);
    REQUIRE(ensure_current(local).ok());
    MultiresMesh full = local;
    REQUIRE(evaluate(full).ok());
    INFO("frame " << frame);
    require_identical(local, full);
    // The plan covers the list's support, not the whole mesh.
    CHECK(fp.displaced_changed[limit < 0 ? 3 : limit] < local.num_vertices(limit < 0 ? 3 : limit));
  }
  CHECK(replayed >= 9);
}

TEST_CASE("multires: the update's scratch follows the hierarchy it serves", "[multires]") {
  // The marks are sized by evaluate(), so the first update after a build
  // allocates nothing; an object rebuilt on another mesh, or assigned
  // another hierarchy, must not reuse marks sized for the old one.
  MultiresMesh mr;
  REQUIRE(build_multires(icosphere(2), 3, mr).ok());
  REQUIRE(mr.scratch.base_mark.size() == 4);
  for (int l = 0; l <= 3; ++l) {
    CHECK(mr.scratch.base_mark[l].size() == static_cast<size_t>(mr.num_vertices(l)));
    CHECK(mr.scratch.face_mark[l].size() == mr.triangles(l).size());
  }
  CHECK(mr.scratch.targets.capacity() >= static_cast<size_t>(mr.num_vertices(3)));
  for (int round = 0; round < 3; ++round) {
    TriMesh m = round == 1 ? bumpy_patch(6, 10) : icosphere(round == 0 ? 1 : 2);
    MultiresMesh other;
    REQUIRE(build_multires(m, 2 + round % 2, other).ok());
    random_displacements(other, 5 + round, 0.2);
    REQUIRE(evaluate(other).ok());
    if (round == 2) {
      mr = other;  // assigned, not rebuilt
    } else {
      REQUIRE(build_multires(m, 2 + round % 2, mr).ok());
      mr.displacements = other.displacements;
      REQUIRE(evaluate(mr).ok());
    }
    const int v = m.num_vertices() / 2;
    REQUIRE(update_control_vertices(mr, {v}, {mr.control[v] + Vec3(0.05, -0.02, 0.03)}).ok());
    MultiresMesh full = mr;
    REQUIRE(evaluate(full).ok());
    INFO("round " << round);
    require_identical(mr, full);
  }
}

TEST_CASE("multires: an update touches only the support of the moved vertex", "[multires]") {
  TriMesh m = bumpy_patch(10, 20);
  MultiresMesh mr;
  REQUIRE(build_multires(m, 3, mr).ok());
  random_displacements(mr, 3, 0.1);
  REQUIRE(evaluate(mr).ok());
  double max_edge = 0;
  for (const Tri& t : m.triangles)
    for (int k = 0; k < 3; ++k) max_edge = std::max(max_edge, (m.positions[t[k]] - m.positions[t[(k + 1) % 3]]).norm());

  const int v = 10 * 21 + 10;  // an interior control vertex (centre column, row 10)
  const MultiresMesh before = mr;
  UpdateFootprint fp;
  REQUIRE(update_control_vertices(mr, {v}, {mr.control[v] + Vec3(0.05, -0.1, 0.2)}, &fp).ok());
  for (int l = 0; l <= 3; ++l) {
    int changed = 0, far_changed = 0;
    for (int u = 0; u < mr.num_vertices(l); ++u) {
      if (mr.state.displaced[l][u] == before.state.displaced[l][u]) continue;
      ++changed;
      // Butterfly stencils reach two rings per level and normals one ring, on
      // ever finer levels: the support stays within a few coarse edges.
      if ((before.state.displaced[l][u] - m.positions[v]).norm() > 6 * max_edge) ++far_changed;
    }
    INFO("level " << l << ": " << changed << " changed of " << mr.num_vertices(l) << ", recomputed "
                  << fp.displaced_changed[l]);
    CHECK(changed > 0);
    CHECK(far_changed == 0);
    CHECK(changed <= fp.displaced_changed[l]);
    CHECK(fp.displaced_changed[l] < mr.num_vertices(l));
  }
  CHECK(fp.displaced_changed[3] < mr.num_vertices(3) / 3);
}

TEST_CASE("multires: bad input gives clear errors and changes nothing", "[multires]") {
  MultiresMesh mr;
  CHECK(build_multires(TriMesh{}, 2, mr).code == ErrorCode::Empty);
  TriMesh nan_mesh = icosahedron();
  nan_mesh.positions[3].x() = std::nan("");
  CHECK(build_multires(nan_mesh, 1, mr).code == ErrorCode::InvalidInput);

  REQUIRE(build_multires(icosahedron(), 2, mr).ok());
  const MultiresMesh before = mr;
  CHECK(update_control_vertices(mr, {0, 1}, {Vec3::Zero()}).code == ErrorCode::InvalidInput);
  CHECK(update_control_vertices(mr, {12}, {Vec3::Zero()}).code == ErrorCode::InvalidInput);
  CHECK(update_control_vertices(mr, {-1}, {Vec3::Zero()}).code == ErrorCode::InvalidInput);
  CHECK(update_control_vertices(mr, {2}, {Vec3(0, std::nan(""), 0)}).code == ErrorCode::InvalidInput);
  require_identical(mr, before);
  CHECK(mr.control == before.control);

  MultiresMesh unevaluated;
  CHECK(update_control_vertices(unevaluated, {}, {}).code == ErrorCode::InvalidInput);

  CHECK(measure_displacements(PointCloud{}, DisplacementOptions{}, mr).code == ErrorCode::Empty);
  PointCloud bad;
  bad.positions = {Vec3(0, 0, std::numeric_limits<double>::infinity())};
  CHECK(measure_displacements(bad, DisplacementOptions{}, mr).code == ErrorCode::InvalidInput);
  MultiresMesh wrong = mr;
  wrong.displacements[1].pop_back();
  CHECK(evaluate(wrong).code == ErrorCode::InvalidInput);

  // Cancelling leaves zero displacements.
  PointCloud cloud = sample_target(20000, 0.0, 1);
  Status s = measure_displacements(cloud, DisplacementOptions{}, mr, nullptr,
                                   [](const char*, double f) { return f < 0.5; });
  CHECK(s.code == ErrorCode::Cancelled);
  for (const auto& d : mr.displacements)
    for (double x : d) CHECK(x == 0.0);
}

TEST_CASE("multires: displacements pull a smoothed real scan back onto the scan (fran_cut)", "[multires][shared]") {
  LK_REQUIRE_SHARED("head_scans/fran_cyberware/fran_cut.vtk");
  TriMesh fran;
  REQUIRE(load_mesh_file(shared_data_dir() + "/head_scans/fran_cyberware/fran_cut.vtk", fran).ok());
  MeshTopology topo;
  REQUIRE(build_topology(fran, topo).ok());
  // Control mesh: the scan with its detail smoothed away (uniform Laplacian,
  // boundary kept), so the displacements have real detail to recover.
  TriMesh control = fran;
  for (int it = 0; it < 10; ++it) {
    std::vector<Vec3> next = control.positions;
    for (int v = 0; v < control.num_vertices(); ++v) {
      if (topo.is_boundary(v) || topo.rings[v].empty()) continue;
      Vec3 mean = Vec3::Zero();
      for (int n : topo.rings[v]) mean += control.positions[n];
      next[v] = 0.5 * control.positions[v] + 0.5 * mean / static_cast<double>(topo.rings[v].size());
    }
    control.positions = next;
  }
  // The scan as a point cloud: its vertices plus points on its triangles.
  PointCloud cloud;
  cloud.positions = fran.positions;
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u01(0, 1);
  for (const Tri& t : fran.triangles)
    for (int i = 0; i < 12; ++i) {
      double a = u01(rng), b = u01(rng);
      if (a + b > 1) a = 1 - a, b = 1 - b;
      const Vec3& p0 = fran.positions[t[0]];
      cloud.positions.push_back(p0 + a * (fran.positions[t[1]] - p0) + b * (fran.positions[t[2]] - p0));
    }
  MeshBvh bvh;
  REQUIRE(build_bvh(fran, bvh).ok());
  MultiresMesh mr;
  REQUIRE(build_multires(control, 2, mr).ok());
  auto mean_distance = [&](const std::vector<Vec3>& pts) {
    double sum = 0;
    for (const Vec3& p : pts) sum += closest_point(bvh, p).distance;
    return sum / pts.size();
  };
  const double diag = bounding_box(fran.positions).diagonal();
  const double before = mean_distance(mr.state.displaced[2]);
  DisplacementStats stats;
  REQUIRE(measure_displacements(cloud, DisplacementOptions{}, mr, &stats).ok());
  const double after0 = mean_distance(mr.state.displaced[0]);
  const double after2 = mean_distance(mr.state.displaced[2]);
  INFO("mean distance to the scan, % of bbox diagonal: before " << 100 * before / diag << ", after: level 0 "
                                                                << 100 * after0 / diag << ", level 2 "
                                                                << 100 * after2 / diag);
  CHECK(stats.measured[0] > 0.9 * stats.candidates[0]);
  CHECK(after0 < 0.2 * before);
  CHECK(after2 < 0.2 * before);
  CHECK(after2 < 0.001 * diag);
  WARN("fran_cut: mean distance to the scan " << 100 * before / diag << "% -> " << 100 * after2 / diag
                                              << "% of the bbox diagonal (level 2)");
}

namespace {

int count_flipped(const MultiresMesh& mr, int level, int* collapsed = nullptr) {
  std::vector<std::vector<Vec3>> smooth;
  REQUIRE(smooth_positions(mr, smooth).ok());
  int flipped = 0, coll = 0;
  count_bad_triangles(mr, level, smooth[level], FoldLimitOptions{}, flipped, coll);
  if (collapsed) *collapsed = coll;
  return flipped;
}

}  // namespace

TEST_CASE("multires: the fold limiter leaves no turned-over triangle where a spike folds the surface", "[multires]") {
  TriMesh m = icosphere(1);
  MultiresMesh mr;
  REQUIRE(build_multires(m, 3, mr).ok());
  REQUIRE(measure_displacements(sample_target(150000, 0.0005, 3), DisplacementOptions{}, mr).ok());
  for (int l = 0; l <= 3; ++l) REQUIRE(count_flipped(mr, l) == 0);  // the measured target folds nothing
  const auto measured = mr.displacements;

  // A spike: one level-2 vertex pulled through the sphere, and its level-3
  // neighbourhood displaced alternately in and out by several edge lengths.
  const int spike = mr.num_vertices(1) + 7;
  const Vec3 spike_at = mr.state.base[2][spike];
  mr.displacements[2][spike] = -1.6;
  std::vector<int> touched = {spike};
  for (int v = mr.num_vertices(2); v < mr.num_vertices(3); ++v)
    if ((mr.state.base[3][v] - spike_at).norm() < 0.25) {
      mr.displacements[3][v] = (v % 2 ? 0.3 : -0.3);
      touched.push_back(v);
    }
  REQUIRE(touched.size() > 10);
  REQUIRE(evaluate(mr).ok());
  int collapsed_before = 0;
  const int flipped_before = count_flipped(mr, 3, &collapsed_before);
  INFO("before: " << flipped_before << " flipped, " << collapsed_before << " collapsed at level 3");
  REQUIRE(flipped_before > 20);

  FoldLimitStats stats;
  REQUIRE(limit_folds(mr, FoldLimitOptions{}, &stats).ok());
  CHECK(stats.remaining_bad == 0);
  CHECK(stats.rounds > 0);
  for (int l = 0; l <= 3; ++l) {
    int collapsed = 0;
    const int flipped = count_flipped(mr, l, &collapsed);
    INFO("level " << l);
    CHECK(flipped == 0);
    CHECK(collapsed == 0);
  }
  // Shrunk, not dropped: some vertices keep part of their displacement.
  CHECK(stats.shrunk[3] > stats.zeroed[3]);
  // Far from the spike nothing changed, bit for bit.
  std::vector<std::vector<Vec3>> smooth;
  REQUIRE(smooth_positions(mr, smooth).ok());
  int far = 0, far_changed = 0;
  for (int l = 0; l <= 3; ++l)
    for (int v = 0; v < mr.num_vertices(l); ++v)
      if ((smooth[l][v] - spike_at).norm() > 0.6) {
        ++far;
        far_changed += mr.displacements[l][v] != measured[l][v];
      }
  CHECK(far > 1000);
  CHECK(far_changed == 0);
  // The state is what a full evaluation gives.
  MultiresMesh again = mr;
  REQUIRE(evaluate(again).ok());
  require_identical(mr, again);
}

TEST_CASE("multires: the fold limiter changes nothing on a fold-free surface, refuses bad options", "[multires]") {
  TriMesh m = icosphere(1);
  MultiresMesh mr;
  REQUIRE(build_multires(m, 2, mr).ok());
  REQUIRE(measure_displacements(sample_target(80000, 0.0005, 4), DisplacementOptions{}, mr).ok());
  const auto before = mr.displacements;
  FoldLimitStats stats;
  REQUIRE(limit_folds(mr, FoldLimitOptions{}, &stats).ok());
  CHECK(stats.rounds == 0);
  CHECK(mr.displacements == before);
  FoldLimitOptions bad;
  bad.shrink = 1.0;  // would never end
  CHECK(limit_folds(mr, bad).code == ErrorCode::InvalidInput);
  bad = FoldLimitOptions{};
  bad.min_area_ratio = -1;
  CHECK(limit_folds(mr, bad).code == ErrorCode::InvalidInput);
  mr.displacements[1].pop_back();
  CHECK(limit_folds(mr).code == ErrorCode::InvalidInput);
}

TEST_CASE("multires: a vertex set carried down the levels keeps old vertices, takes edges inside it", "[multires]") {
  TriMesh m = icosphere(1);
  MultiresMesh mr;
  REQUIRE(build_multires(m, 3, mr).ok());
  std::vector<char> cap(mr.num_vertices(0), 0);
  for (int v = 0; v < mr.num_vertices(0); ++v) cap[v] = m.positions[v].z() > 0.2;
  const auto masks = propagate_vertex_mask(mr, cap);
  REQUIRE(masks.size() == 4);
  for (int l = 1; l <= 3; ++l) {
    REQUIRE(static_cast<int>(masks[l].size()) == mr.num_vertices(l));
    const ButterflyLevel& lv = mr.levels[l - 1];
    for (int v = 0; v < lv.num_coarse_vertices; ++v) CHECK(masks[l][v] == masks[l - 1][v]);
    int inside = 0;
    for (int k = 0; k < lv.num_new_vertices(); ++k) {
      const bool both = masks[l - 1][lv.edge_endpoints[k][0]] && masks[l - 1][lv.edge_endpoints[k][1]];
      CHECK(static_cast<bool>(masks[l][lv.num_coarse_vertices + k]) == both);
      inside += both;
    }
    CHECK(inside > 0);
    // Geometrically: members lie in the cap (z > 0.2 on the control mesh
    // shrinks a little under subdivision), non-members of the new ones outside it.
    for (int v = 0; v < mr.num_vertices(l); ++v)
      if (masks[l][v]) CHECK(mr.state.base[l][v].z() > 0.1);
  }
}

TEST_CASE("multires: the limiter separates two displaced sheets that cross", "[multires]") {
  // Two spheres 0.2 apart, each inflated by 0.15 along its normals: they
  // overlap by ~0.1 near the contact; nothing turns over.
  const TriMesh two = test::two_spheres_apart();
  MultiresMesh mr;
  REQUIRE(build_multires(two, 2, mr).ok());
  for (int l = 0; l <= 2; ++l)
    for (int v = (l == 0 ? 0 : mr.num_vertices(l - 1)); v < mr.num_vertices(l); ++v) mr.displacements[l][v] = l == 0 ? 0.15 : 0.0;
  REQUIRE(evaluate(mr).ok());
  std::vector<std::array<int, 2>> pairs;
  REQUIRE(find_self_intersections(level_mesh(mr, 2), pairs).ok());
  REQUIRE(pairs.size() > 10);
  REQUIRE(count_flipped(mr, 2) == 0);

  FoldLimitOptions opt;
  opt.max_intersection_restarts = 4;  // the crossing comes from level 0
  // The finest level's own separation is tested here (the coarser levels'
  // would remove the crossing on level 0 first: test_fold_coarse.cpp).
  opt.separate_coarser_levels = false;
  FoldLimitStats stats;
  REQUIRE(limit_folds(mr, opt, &stats).ok());
  CHECK(stats.intersections_found == static_cast<int>(pairs.size()));
  REQUIRE(find_self_intersections(level_mesh(mr, 2), pairs).ok());
  CHECK(pairs.empty());
  CHECK(stats.intersections_left == 0);
  CHECK(count_flipped(mr, 2) == 0);
  // Away from the contact the spheres keep their inflation.
  int kept = 0, far = 0;
  for (int v = 0; v < mr.num_vertices(0); ++v)
    if (std::abs(mr.control[v].x() - 1.1) > 0.8) ++far, kept += mr.displacements[0][v] == 0.15;
  CHECK(far > 10);
  CHECK(kept == far);
  // Without restarts, without putting the corners on the smooth surface
  // and without the last resort (test_fold_coarse.cpp), the finest level
  // cannot undo a crossing made on level 0.
  MultiresMesh off;
  REQUIRE(build_multires(two, 2, off).ok());
  for (int v = 0; v < off.num_vertices(0); ++v) off.displacements[0][v] = 0.15;
  MultiresMesh on = off;
  FoldLimitOptions no_correction;
  no_correction.crossing_corners_to_smooth = false;
  no_correction.separate_coarser_levels = false;
  no_correction.smooth_region_rings = -1;
  FoldLimitStats off_stats;
  REQUIRE(limit_folds(off, no_correction, &off_stats).ok());
  CHECK(off_stats.intersections_left > 0);
  for (double d : off.displacements[0]) CHECK(d == 0.15);
  // By default the finest level's corners there go onto the smooth surface
  // (the spheres do not cross): no crossing left, level 0 untouched, no
  // turned-over triangle, and the dent stays local.
  FoldLimitOptions finest_only;
  finest_only.separate_coarser_levels = false;
  FoldLimitStats on_stats;
  REQUIRE(limit_folds(on, finest_only, &on_stats).ok());
  REQUIRE(find_self_intersections(level_mesh(on, 2), pairs).ok());
  CHECK(pairs.empty());
  CHECK(on_stats.crossing_corrected > 0);
  CHECK(on_stats.restarts == 0);
  for (double d : on.displacements[0]) CHECK(d == 0.15);
  CHECK(count_flipped(on, 2) == 0);
  int moved = 0;
  for (double d : on.displacements[2]) moved += d != 0;
  CHECK(moved < on.num_vertices(2) / 4);
  // The optional step onto the level above keeps all that.
  MultiresMesh parents;
  REQUIRE(build_multires(two, 2, parents).ok());
  for (int v = 0; v < parents.num_vertices(0); ++v) parents.displacements[0][v] = 0.15;
  FoldLimitOptions with_parents;
  with_parents.crossing_parents_to_smooth = true;
  with_parents.separate_coarser_levels = false;
  REQUIRE(limit_folds(parents, with_parents).ok());
  REQUIRE(find_self_intersections(level_mesh(parents, 2), pairs).ok());
  CHECK(pairs.empty());
  CHECK(count_flipped(parents, 2) == 0);
  for (double d : parents.displacements[0]) CHECK(d == 0.15);
}

TEST_CASE("multires: crease vertices keep no displacement through the fold limiter", "[multires][crease]") {
  const int n = 6, height = 10;
  TriMesh m = bumpy_patch(n, height);
  auto id = [&](int i, int j) { return j * (2 * n + 1) + i; };
  std::vector<int> column;
  for (int j = 0; j <= height; ++j) column.push_back(id(n, j));
  ButterflyCreases creases;
  add_crease_polyline(column, false, creases);
  MultiresMesh mr;
  REQUIRE(build_multires(m, creases, 3, mr).ok());
  const auto masks = crease_vertex_masks(mr);
  // Level 0: the column; each level adds one vertex per crease edge, and
  // the column's edges double.
  int expected = height + 1, edges = height;
  for (int l = 0; l <= 3; ++l) {
    int count = 0;
    for (char c : masks[l]) count += c;
    INFO("level " << l);
    CHECK(count == expected);
    for (int v = 0; v < mr.num_vertices(l); ++v)
      if (masks[l][v]) CHECK(std::abs(mr.state.base[l][v].x()) < 1e-12);  // on the column x = 0
    expected += edges;
    edges *= 2;
  }
  random_displacements(mr, 3, 0.02);
  REQUIRE(evaluate(mr).ok());
  FoldLimitStats stats;
  REQUIRE(limit_folds(mr, FoldLimitOptions{}, &stats).ok());
  int crease_left = 0, others = 0;
  for (int l = 0; l <= 3; ++l)
    for (int v = 0; v < mr.num_vertices(l); ++v) {
      if (masks[l][v]) crease_left += mr.displacements[l][v] != 0;
      else others += mr.displacements[l][v] != 0;
    }
  CHECK(crease_left == 0);
  CHECK(stats.crease_zeroed > 0);
  CHECK(others > mr.num_vertices(3) / 2);  // the rest keeps its detail
  // The option off keeps them.
  MultiresMesh kept;
  REQUIRE(build_multires(m, creases, 3, kept).ok());
  random_displacements(kept, 3, 0.02);
  FoldLimitOptions keep;
  keep.undisplaced_creases = false;
  REQUIRE(limit_folds(kept, keep).ok());
  int crease_kept = 0;
  for (int l = 0; l <= 3; ++l)
    for (int v = 0; v < kept.num_vertices(l); ++v) crease_kept += masks[l][v] && kept.displacements[l][v] != 0;
  CHECK(crease_kept > 0);
}

TEST_CASE("multires: point normals keep a thin shell's inner sheet from pulling the outer one", "[multires]") {
  // A shell 0.02 thick: the outer unit sphere (normals out) and the inner
  // sheet (normals in), both inside every normal line's reach.
  std::mt19937 rng(21);
  std::normal_distribution<double> g(0, 1);
  PointCloud cloud;
  for (int i = 0; i < 160000; ++i) {
    Vec3 d(g(rng), g(rng), g(rng));
    d.normalize();
    const bool inner = i % 2;
    cloud.positions.push_back(d * (inner ? 0.98 : 1.0));
    cloud.normals.push_back(inner ? -d : d);
  }
  auto mean_error = [&](double agreement) {
    MultiresMesh mr;
    REQUIRE(build_multires(icosphere(1), 2, mr).ok());
    DisplacementOptions o;
    o.min_normal_agreement = agreement;
    REQUIRE(measure_displacements(cloud, o, mr).ok());
    double sum = 0;
    for (const Vec3& p : mr.state.displaced[2]) sum += std::abs(p.norm() - 1.0);
    return sum / mr.num_vertices(2);
  };
  const double with_normals = mean_error(0.0), without = mean_error(-2.0);
  INFO("mean distance to the outer sheet: with normals " << with_normals << ", without " << without);
  CHECK(with_normals < 0.001);
  CHECK(without > 3 * with_normals);
}

TEST_CASE("multires: with creases, local update equals a full recompute, and creases change the result", "[multires][crease]") {
  // A crease column and a closed crease loop on the bumpy patch: the
  // update's dependency sets come from the creased stencils, so moving
  // crease, corner, near-crease and far vertices must still match a full
  // recompute bit for bit.
  const int n = 6, height = 10;
  TriMesh m = bumpy_patch(n, height);
  auto id = [&](int i, int j) { return j * (2 * n + 1) + i; };
  std::vector<int> column, loop;
  for (int j = 0; j <= height; ++j) column.push_back(id(n, j));
  for (int i = 2; i < 5; ++i) loop.push_back(id(i, 3));
  for (int j = 3; j < 6; ++j) loop.push_back(id(5, j));
  for (int i = 5; i > 2; --i) loop.push_back(id(i, 6));
  for (int j = 6; j > 3; --j) loop.push_back(id(2, j));
  ButterflyCreases creases;
  add_crease_polyline(column, false, creases);
  add_crease_polyline(loop, true, creases);
  MultiresMesh local;
  REQUIRE(build_multires(m, creases, 3, local).ok());
  CHECK(local.creases.edges.size() == creases.edges.size());
  random_displacements(local, 5, 0.2);
  REQUIRE(evaluate(local).ok());
  MultiresMesh plain;
  REQUIRE(build_multires(m, 3, plain).ok());
  plain.displacements = local.displacements;
  REQUIRE(evaluate(plain).ok());
  double differs = 0;
  for (int v = 0; v < local.num_vertices(3); ++v)
    differs = std::max(differs, (local.state.displaced[3][v] - plain.state.displaced[3][v]).norm());
  CHECK(differs > 1e-3);

  std::mt19937 rng(7);
  std::uniform_int_distribution<int> pick(0, m.num_vertices() - 1);
  std::normal_distribution<double> step(0, 0.1);
  const std::vector<int> special = {column[0], column[height / 2], loop[0], loop[4], id(n - 1, 5), id(3, 4)};
  for (int round = 0; round < 30; ++round) {
    std::vector<int> moved = {round < static_cast<int>(special.size()) ? special[round] : pick(rng)};
    if (round % 3 == 0) moved.push_back(pick(rng));
    std::vector<Vec3> to;
    for (int v : moved) to.push_back(local.control[v] + Vec3(step(rng), step(rng), step(rng)));
    REQUIRE(update_control_vertices(local, moved, to).ok());
    MultiresMesh full = local;
    REQUIRE(evaluate(full).ok());
    INFO("round " << round);
    require_identical(local, full);
  }
}
