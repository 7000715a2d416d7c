// ICP alignment for partial scans, coverage and orientation checks; see the header.
#include "align/face_alignment.h"

#include "common/parallel.h"
#include "common/rotation.h"
#include "common/sampling.h"
#include "mesh/geometry.h"
#include "raycast/bvh.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <random>

namespace lk {
namespace {

constexpr int kMinPoints = 10;

double quantile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  const size_t k = static_cast<size_t>(std::clamp(q, 0.0, 1.0) * (values.size() - 1) + 0.5);
  std::nth_element(values.begin(), values.begin() + k, values.end());
  return values[k];
}

Status check_cloud(const PointCloud& cloud, const char* who) {
  if (cloud.positions.empty()) return Status::error(ErrorCode::Empty, std::string(who) + ": the cloud has no points");
  for (const Vec3& p : cloud.positions)
    if (!p.allFinite()) return Status::error(ErrorCode::InvalidInput, std::string(who) + ": non-finite point");
  if (cloud.size() < kMinPoints)
    return Status::error(ErrorCode::InvalidInput, std::string(who) + ": fewer than " + std::to_string(kMinPoints) +
                                                      " points");
  return Status::success();
}

// Generic frame -> world axes: look -> +z, up -> +y (as align_initial).
Status facing_matrix(const HeadAnnotations& ann, Mat3& facing) {
  Vec3 look = ann.look.normalized(), up = ann.up.normalized();
  if (!look.allFinite() || !up.allFinite() || std::fabs(look.dot(up)) > 0.5)
    return Status::error(ErrorCode::InvalidInput, "align: the generic head's look and up directions are unusable");
  up = (up - up.dot(look) * look).normalized();
  Mat3 axes;
  axes << up.cross(look), up, look;
  facing = axes.transpose();
  return Status::success();
}

// Mean of the points at or beyond the top `fraction` along +z: a nose tip
// that one stray point does not move.
Vec3 front_tip(const std::vector<Vec3>& points, double fraction) {
  std::vector<double> z(points.size());
  for (size_t i = 0; i < z.size(); ++i) z[i] = points[i].z();
  const double cut = quantile(z, 1.0 - fraction);
  Vec3 sum = Vec3::Zero();
  int n = 0;
  for (const Vec3& p : points)
    if (p.z() >= cut) {
      sum += p;
      ++n;
    }
  return n ? Vec3(sum / n) : Vec3::Zero();
}

struct Similarity {
  double s = 1;
  Mat3 R = Mat3::Identity();
  Vec3 t = Vec3::Zero();
  Vec3 apply(const Vec3& g) const { return s * (R * g) + t; }
  Vec3 inverse(const Vec3& p) const { return R.transpose() * (p - t) / s; }
};

struct IcpRun {
  Similarity T;
  double rms = 0, score = 0, inliers = 0;
  int iterations = 0;
};

// An ICP that can stop after some iterations and go on later: `next` is the
// transform the next iteration starts from, `previous` the last trimmed RMS
// (-1: none yet), `done` set when it converged or cannot go on. Going on
// gives the same bits as one uninterrupted run (the nearest-triangle hints
// only speed the searches up; closest_point_near's answer does not depend
// on them).
struct IcpProgress {
  Similarity next;
  double previous = -1;
  bool done = false;
  IcpRun run;
  std::vector<int> near;  // each sample's nearest triangle in the last iteration (-1: none yet)
};

// Point-to-point ICP of the faced generic (tree over it) onto the samples,
// until run.iterations reaches `until` (at most o.max_iterations).
// parallel: the closest points of an iteration on parallel_for's threads
// (false when the caller already runs several ICPs in parallel); the
// result does not depend on it. near (optional, one per sample): each
// sample's nearest triangle from an earlier run on the same samples, where
// this run's first searches start, updated as it goes (default: progress's
// own, so that going on starts where it stopped); the result does not
// depend on it either (closest_point_near).
void continue_icp(const MeshBvh& tree, const std::vector<Vec3>& samples, IcpProgress& progress,
                  const FaceAlignOptions& o, int until, double clamp, bool parallel,
                  std::vector<int>* near = nullptr) {
  IcpRun& run = progress.run;
  Similarity& T = progress.next;
  double& previous = progress.previous;
  std::vector<Vec3> model(samples.size());
  std::vector<double> dist(samples.size());
  if (!near) near = &progress.near;
  if (near->size() != samples.size()) near->assign(samples.size(), -1);
  std::vector<int>& face = *near;  // the last iteration's nearest triangle per sample
  const int last = std::min(until, o.max_iterations);
  if (run.iterations >= o.max_iterations) progress.done = true;
  for (int it = run.iterations; it < last && !progress.done; ++it) {
    const auto correspond = [&](int i, int) {
      const ClosestPoint c = closest_point_near(tree, T.inverse(samples[i]), face[i]);
      face[i] = c.triangle;
      model[i] = c.point;
      dist[i] = (T.apply(c.point) - samples[i]).norm();
    };
    const int n = static_cast<int>(samples.size());
    if (parallel) {
      parallel_for(0, n, 256, correspond);
    } else {
      for (int i = 0; i < n; ++i) correspond(i, 0);
    }
    const double median = quantile(dist, 0.5);
    const double trim = std::max(o.trim_factor * median, 1e-12);
    std::vector<int> keep;
    for (size_t i = 0; i < samples.size(); ++i)
      if (dist[i] <= trim) keep.push_back(static_cast<int>(i));
    run.iterations = it + 1;
    double sum2 = 0;
    for (int i : keep) sum2 += dist[i] * dist[i];
    run.rms = keep.empty() ? 0 : std::sqrt(sum2 / keep.size());
    run.inliers = double(keep.size()) / samples.size();
    double score = 0;
    for (double d : dist) score += std::min(d, clamp) * std::min(d, clamp);
    run.score = score / samples.size();
    run.T = T;
    if (keep.size() < 4 ||
        (previous >= 0 && std::fabs(previous - run.rms) <= o.relative_tolerance * previous)) {
      progress.done = true;
      break;
    }
    previous = run.rms;
    Eigen::Matrix3Xd src(3, keep.size()), dst(3, keep.size());
    for (size_t k = 0; k < keep.size(); ++k) {
      src.col(k) = model[keep[k]];
      dst.col(k) = samples[keep[k]];
    }
    const Eigen::Matrix4d M = Eigen::umeyama(src, dst, true);
    Similarity next;
    const Mat3 sR = M.topLeftCorner<3, 3>();
    // The scale as a column's length (sqrt is exact in IEEE arithmetic;
    // libm's cbrt of the determinant differs between glibc and wasm's musl).
    next.s = sR.col(0).norm();
    if (!(next.s > 0) || !std::isfinite(next.s)) {
      progress.done = true;
      break;
    }
    next.R = sR / next.s;
    next.t = M.topRightCorner<3, 1>();
    T = next;
  }
  if (run.iterations >= o.max_iterations) progress.done = true;
}

IcpRun run_icp(const MeshBvh& tree, const std::vector<Vec3>& samples, const Similarity& T, const FaceAlignOptions& o,
               double clamp, bool parallel, std::vector<int>* near = nullptr) {
  IcpProgress progress;
  progress.next = T;
  continue_icp(tree, samples, progress, o, o.max_iterations, clamp, parallel, near);
  return progress.run;
}

}  // namespace

Status estimate_coverage(const PointCloud& cloud, const CoverageOptions& o, ScanCoverage& out) {
  out = ScanCoverage{};
  Status st = check_cloud(cloud, "coverage");
  if (!st) return st;
  if (!(o.slab_fraction > 0 && o.slab_fraction <= 1) || !(o.outlier_fraction >= 0 && o.outlier_fraction < 0.2))
    return Status::error(ErrorCode::InvalidInput, "coverage: slab or outlier fraction out of range");
  const double q = o.outlier_fraction;
  std::vector<double> v(cloud.positions.size());
  Vec3 lo, hi;
  for (int a = 0; a < 3; ++a) {
    for (size_t i = 0; i < v.size(); ++i) v[i] = cloud.positions[i][a];
    lo[a] = quantile(v, q);
    hi[a] = quantile(v, 1 - q);
  }
  out.extent = hi - lo;
  const double bottom = hi.y() - o.slab_fraction * out.extent.y();
  std::vector<double> xs, zs;
  for (const Vec3& p : cloud.positions)
    if (p.y() >= bottom) {
      xs.push_back(p.x());
      zs.push_back(p.z());
    }
  if (xs.size() < 3) return Status::error(ErrorCode::NotAHead, "coverage: no points in the upper part of the cloud");
  out.slab_width = quantile(xs, 1 - q) - quantile(xs, q);
  out.slab_depth = quantile(zs, 1 - q) - quantile(zs, q);
  out.depth_to_width = out.slab_width > 0 ? out.slab_depth / out.slab_width : 0;
  out.face_only = out.depth_to_width < o.face_only_depth_ratio;
  return Status::success();
}

namespace {

struct Searcher {
  MeshBvh tree;
  Mat3 facing = Mat3::Identity();
  std::vector<Vec3> faced;  // generic positions, faced
  Vec3 tip_g = Vec3::Zero();
  double clamp = 0;

  Status build(const TriMesh& generic, const HeadAnnotations& ann, const PointCloud& cloud, double clamp_fraction) {
    Status st = facing_matrix(ann, facing);
    if (!st) return st;
    TriMesh m;
    m.triangles = generic.triangles;
    m.positions.reserve(generic.positions.size());
    for (const Vec3& p : generic.positions) m.positions.push_back(facing * p);
    faced = m.positions;
    st = build_bvh(m, tree);
    if (!st) return with_context(st, "align_face");
    tip_g = front_tip(faced, 0.002);
    clamp = clamp_fraction * bounding_box(cloud.positions).diagonal();
    return Status::success();
  }

  // The start for a cloud seen through Q (cloud -> a frame where it is
  // upright and faces +z): nose tips together, and the scale that makes the
  // generic's part inside the cloud's nose-relative box as wide as the cloud
  // (a fixed point: that box in generic units shrinks as the scale grows).
  bool start(const std::vector<Vec3>& cloud, const Mat3& Q, double relative_scale, Similarity& T) const {
    std::vector<Vec3> turned;
    turned.reserve(cloud.size());
    for (const Vec3& p : cloud) turned.push_back(Q * p);
    const Vec3 tip_c = front_tip(turned, 0.002);
    const BBox box = bounding_box(turned);
    const Vec3 lo = box.min - tip_c, hi = box.max - tip_c;
    const double width_c = box.size().x();
    double s = width_c / std::max(1e-300, bounding_box(faced).size().x());
    for (int iter = 0; iter < 20; ++iter) {
      double x0 = 1e300, x1 = -1e300;
      for (const Vec3& p : faced) {
        const Vec3 r = s * (p - tip_g);
        if (r.y() < lo.y() || r.y() > hi.y() || r.z() < lo.z()) continue;
        x0 = std::min(x0, r.x());
        x1 = std::max(x1, r.x());
      }
      if (!(x1 > x0)) break;
      const double s_new = s * width_c / (x1 - x0);
      const bool settled = std::fabs(s_new - s) < 1e-4 * s;
      s = s_new;
      if (settled) break;
    }
    if (!(s > 0) || !std::isfinite(s)) return false;
    // In the turned frame: x' = s g + (tip_c - s tip_g); back: x = Q^T x'.
    T.s = s * relative_scale;
    T.R = Q.transpose();
    T.t = Q.transpose() * (tip_c - T.s * tip_g);
    return true;
  }
};

// n random points of the cloud (all when it has no more), the same subset
// as std::shuffle under libstdc++ gave before, on any standard library.
std::vector<Vec3> random_subset(const std::vector<Vec3>& points, int n, std::uint32_t seed) {
  std::vector<Vec3> out = points;
  if (static_cast<int>(out.size()) > n) {
    std::mt19937 rng(seed);
    mt19937_shuffle(out.begin(), out.end(), rng);
    out.resize(n);
  }
  return out;
}

// About n points of the cloud, stratified (common/sampling.h).
std::vector<Vec3> subset(const std::vector<Vec3>& points, int n, std::uint64_t seed) {
  std::vector<Vec3> out;
  for (int i : stratified_sample(points, n, seed)) out.push_back(points[i]);
  return out;
}

// cos and sin of an angle in degrees; exact for multiples of 45 degrees (the
// starts), where libm's sin and cos of a rounded pi/4 may differ in the last
// bit between native and wasm.
void cos_sin_deg(double degrees, double& c, double& s) {
  const double eighths = degrees / 45.0;
  if (eighths == std::floor(eighths) && std::fabs(eighths) < 1e6) {
    const long k = ((static_cast<long>(eighths) % 8) + 8) % 8;
    const double h = std::sqrt(0.5);
    const double cs[8] = {1, h, 0, -h, -1, -h, 0, h};
    c = cs[k];
    s = cs[(k + 6) % 8];
    return;
  }
  const double r = degrees * 3.14159265358979323846 / 180.0;
  c = std::cos(r);
  s = std::sin(r);
}

// Rotation by `degrees` about the unit axis (Rodrigues).
Mat3 rotation_about(const Vec3& axis, double degrees) {
  double c, s;
  cos_sin_deg(degrees, c, s);
  Mat3 K;
  K << 0, -axis.z(), axis.y(), axis.z(), 0, -axis.x(), -axis.y(), axis.x(), 0;
  return Mat3::Identity() + s * K + (1 - c) * (K * K);
}

Mat3 yaw(double degrees) { return rotation_about(Vec3::UnitY(), degrees); }

double rotation_angle_deg(const Mat3& a, const Mat3& b) {
  const double c = 0.5 * ((a.transpose() * b).trace() - 1);
  return std::acos(std::clamp(c, -1.0, 1.0)) * 180.0 / 3.14159265358979323846;
}

// Indices of the runs (those with inliers) in order of score, then index.
std::vector<int> ranked(const std::vector<IcpRun>& runs, const std::vector<char>& valid) {
  std::vector<int> order;
  for (int k = 0; k < static_cast<int>(runs.size()); ++k)
    if (valid[k] && runs[k].inliers > 0) order.push_back(k);
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    return runs[a].score < runs[b].score || (runs[a].score == runs[b].score && a < b);
  });
  return order;
}

// Up to `count` runs from `order` whose results differ from those before.
std::vector<int> distinct_best(const std::vector<IcpRun>& runs, const std::vector<int>& order, int count,
                               double distinct_deg, double distinct_scale) {
  std::vector<int> picked;
  for (int k : order) {
    if (static_cast<int>(picked.size()) >= count) break;
    bool distinct = true;
    for (int j : picked)
      if (rotation_angle_deg(runs[k].T.R, runs[j].T.R) <= distinct_deg &&
          std::fabs(runs[k].T.s / runs[j].T.s - 1) <= distinct_scale)
        distinct = false;
    if (distinct) picked.push_back(k);
  }
  return picked;
}

}  // namespace

Status align_face(const TriMesh& generic, const HeadAnnotations& ann, const PointCloud& cloud,
                  const FaceAlignOptions& o, FaceAlignResult& out, const ProgressFn& progress) {
  out = FaceAlignResult{};
  Status st = check_cloud(cloud, "align_face");
  if (!st) return st;
  if (generic.triangles.empty()) return Status::error(ErrorCode::Empty, "align_face: the generic head has no triangles");
  if (o.max_points < kMinPoints || o.coarse_points < kMinPoints || o.max_iterations < 1 ||
      o.coarse_iterations < 1 || o.start_scales.empty() || o.start_yaws_deg.empty() || !(o.trim_factor > 1) ||
      !(o.score_clamp_fraction > 0) || o.final_points < kMinPoints || !(o.distinct_deg >= 0) ||
      !(o.distinct_scale >= 0) || !(o.polish_tolerance >= 0) ||
      std::any_of(o.scale_hops.begin(), o.scale_hops.end(), [](double h) { return !(h > 0 && h < 0.5); }) ||
      !(o.scale_hop_gain >= 0 && o.scale_hop_gain < 1))
    return Status::error(ErrorCode::InvalidInput, "align_face: an option is out of range");
  Searcher search;
  st = search.build(generic, ann, cloud, o.score_clamp_fraction);
  if (!st) return st;

  const std::vector<Vec3> coarse = subset(cloud.positions, o.coarse_points, o.seed);
  FaceAlignOptions coarse_options = o;
  coarse_options.max_iterations = o.coarse_iterations;
  bool have = false;
  IcpRun best;
  // The starts are independent: run in one loop on parallel_for's threads,
  // one start each (one loop per yaw left a thread idle at each yaw's
  // third start), then compared in their fixed order (the same choice on
  // any number of threads). Progress is reported per yaw after the loop.
  const int num_scales = static_cast<int>(o.start_scales.size());
  const int total = static_cast<int>(o.start_yaws_deg.size()) * num_scales;
  std::vector<IcpRun> runs(total);
  std::vector<char> started(total);
  parallel_for(0, total, 1, [&](int k, int) {
    Similarity T0;
    const Mat3 Q = yaw(o.start_yaws_deg[k / num_scales]);
    started[k] = search.start(cloud.positions, Q, o.start_scales[k % num_scales], T0);
    if (started[k]) runs[k] = run_icp(search.tree, coarse, T0, coarse_options, search.clamp, false);
  });
  for (int k = 0; k < total; ++k) {
    if (started[k]) {
      const IcpRun& run = runs[k];
      out.iterations += run.iterations;
      ++out.starts;
      if (run.inliers > 0 && (!have || run.score < best.score)) {
        best = run;
        have = true;
      }
    }
    if ((k + 1) % num_scales == 0 && !report(progress, "align", 0.7 * (k + 1) / total))
      return Status::error(ErrorCode::Cancelled, "align_face: cancelled");
  }
  if (!have) return Status::error(ErrorCode::NotAHead, "align_face: no scan point corresponds to the head");
  // Refine the best distinct coarse results, polish each on the (nearly)
  // full cloud and keep the one that fits it best: the choice between
  // nearly equal basins is made on the full cloud, and each polish ends
  // near its basin's minimum whatever the samples were. (Scoring the
  // refined results on the full cloud and polishing only the best chose
  // different basins for different seeds: James 3 mm apart.)
  const std::vector<int> candidates = distinct_best(runs, ranked(runs, started), std::max(1, o.refine_candidates),
                                                    o.distinct_deg, o.distinct_scale);
  const std::vector<Vec3> refine_set = subset(cloud.positions, o.max_points, o.seed + 1ull);
  const std::vector<Vec3> final_set = subset(cloud.positions, o.final_points, o.seed + 2ull);
  FaceAlignOptions polish_options = o;
  polish_options.relative_tolerance = o.polish_tolerance;
  // Each set's nearest triangles carried from run to run (a polish starts
  // where its refinement ended, a hop next to the polish): the searches
  // start there, the same answers.
  std::vector<int> refine_near(refine_set.size(), -1), final_near(final_set.size(), -1);
  have = false;
  for (size_t c = 0; c < candidates.size(); ++c) {
    const IcpRun refined = run_icp(search.tree, refine_set, runs[candidates[c]].T, o, search.clamp, true, &refine_near);
    const IcpRun polished =
        run_icp(search.tree, final_set, refined.T, polish_options, search.clamp, true, &final_near);
    out.iterations += refined.iterations + polished.iterations;
    if (polished.inliers > 0 && (!have || polished.score < best.score)) {
      best = polished;
      have = true;
    }
    if (!report(progress, "align", 0.7 + 0.3 * (c + 1) / candidates.size()))
      return Status::error(ErrorCode::Cancelled, "align_face: cancelled");
  }
  if (!have || !(best.inliers > 0))
    return Status::error(ErrorCode::NotAHead, "align_face: no scan point corresponds to the head");
  // Near a scale of 1 the trimmed score has shallow minima a percent or two
  // apart (a one-station capture of a synthetic head: 0.996, 1.005 and
  // 1.020, which basin depending on the samples). The polished best is
  // polished again from scale_hops larger and smaller scales; a score
  // better by more than scale_hop_gain wins (smaller gains are the samples'
  // noise, and jumping for them moved James's alignment by a hair for
  // 0.01 %, which put 22 crossing pairs on one of his ears).
  for (double hop : o.scale_hops) {
    for (double f : {1 + hop, 1 - hop}) {
      Similarity T = best.T;
      T.s *= f;
      const IcpRun hopped = run_icp(search.tree, final_set, T, polish_options, search.clamp, true, &final_near);
      out.iterations += hopped.iterations;
      if (hopped.inliers > 0 && hopped.score < (1 - o.scale_hop_gain) * best.score) best = hopped;
    }
  }
  out.scale = best.T.s;
  out.rotation = best.T.R;
  out.linear = best.T.s * best.T.R * search.facing;
  out.translation = best.T.t;
  out.facing = best.T.R * Vec3::UnitZ();
  out.up = best.T.R * Vec3::UnitY();
  out.rms = best.rms;
  out.score = best.score;
  out.inlier_fraction = best.inliers;
  return report(progress, "align", 1.0) ? Status::success()
                                        : Status::error(ErrorCode::Cancelled, "align_face: cancelled");
}

namespace {

double angle_deg(const Vec3& a, const Vec3& b) {
  return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)) * 180.0 / 3.14159265358979323846;
}

Vec3 snap(const Vec3& d, double snap_deg) {
  for (int a = 0; a < 3; ++a)
    for (int sign : {1, -1}) {
      Vec3 e = Vec3::Zero();
      e[a] = sign;
      if (angle_deg(d, e) <= snap_deg) return e;
    }
  return d.normalized();
}

}  // namespace

Status guess_orientation(const TriMesh& generic, const HeadAnnotations& ann, const PointCloud& cloud,
                         const OrientationOptions& o, OrientationGuess& out, const ProgressFn& progress) {
  out = OrientationGuess{};
  Status st = check_cloud(cloud, "guess_orientation");
  if (!st) return st;
  if (!(o.better_ratio > 0 && o.better_ratio <= 1) || o.points < kMinPoints || o.iterations < 1 ||
      o.final_points < kMinPoints || o.candidates < 1 || o.screen_iterations < 0 || o.screen_keep < 1 ||
      (o.screen_points != 0 && o.screen_points < kMinPoints))
    return Status::error(ErrorCode::InvalidInput, "guess_orientation: an option is out of range");
  if (generic.triangles.empty())
    return Status::error(ErrorCode::Empty, "guess_orientation: the generic head has no triangles");
  Searcher search;
  FaceAlignOptions fo;
  fo.max_iterations = o.iterations;
  st = search.build(generic, ann, cloud, fo.score_clamp_fraction);
  if (!st) return st;
  // Random (not stratified) coarse samples: the given orientation's score
  // on them decides whether the search can stop (accept_given_fraction),
  // and stratified samples weigh the neck and the back of a synthetic head
  // more, which made every whole-head fit run all 48 starts (+1.6 s CPU).
  const std::vector<Vec3> samples = random_subset(cloud.positions, o.points, o.seed);
  // The screening's samples (OrientationOptions::screen_points): the first
  // of the same shuffle, so a subset of `samples`.
  const bool fewer = o.screen_iterations > 0 && o.screen_iterations < o.iterations && o.screen_points > 0 &&
                     o.screen_points < static_cast<int>(samples.size());
  const std::vector<Vec3> screen_samples =
      fewer ? std::vector<Vec3>(samples.begin(), samples.begin() + o.screen_points) : samples;
  // +y first: its first yaw is the given orientation (see accept_given_fraction).
  const std::vector<Vec3> axes = {Vec3::UnitY(), Vec3::UnitX(), -Vec3::UnitX(), -Vec3::UnitY(),
                                  Vec3::UnitZ(), -Vec3::UnitZ()};
  const double diagonal = search.clamp / fo.score_clamp_fraction;
  bool have_best = false, have_given = false;
  IcpRun best;
  // The given orientation (the first start) runs alone, as it may end the
  // search; then the other 47 starts run in ONE parallel loop (independent;
  // one loop per up axis left the threads waiting at each axis's slowest
  // start, 6 joins per search) and are compared in their fixed order, so
  // the outcome does not depend on the number of threads.
  constexpr int kYaws = 8;
  const int num_starts = static_cast<int>(axes.size()) * kYaws;
  std::vector<IcpProgress> icps(num_starts);
  std::vector<IcpRun> runs(num_starts);
  std::vector<char> ran(num_starts, 0);
  std::vector<Similarity> initial(num_starts);  // each start's pose, for screen_points
  // Screening (OrientationOptions::screen_iterations): the first
  // `first_stage` iterations of every start, then only the best go on.
  const int first_stage = o.screen_iterations > 0 ? std::min(o.screen_iterations, o.iterations) : o.iterations;
  const auto run_start = [&](int start, int) {
    const Vec3& up = axes[start / kYaws];
    // A facing axis perpendicular to up, then yaws about up in 45 degree steps.
    const Vec3 look0 = std::fabs(up.z()) < 0.5 ? Vec3(Vec3::UnitZ()) : Vec3(Vec3::UnitX());
    const Vec3 look = rotation_about(up, 45.0 * (start % kYaws)) * look0;
    Mat3 Q;  // cloud -> candidate upright frame
    Q.row(0) = up.cross(look).transpose();
    Q.row(1) = up.transpose();
    Q.row(2) = look.transpose();
    IcpProgress& icp = icps[start];
    ran[start] = search.start(samples, Q, 1.0, icp.next);
    if (!ran[start]) return;
    initial[start] = icp.next;
    if (start == 0)
      continue_icp(search.tree, samples, icp, fo, o.iterations, search.clamp, false);
    else
      continue_icp(search.tree, screen_samples, icp, fo, first_stage, search.clamp, false);
    runs[start] = icp.run;
  };
  const auto is_consistent = [&](const IcpRun& run) {
    return angle_deg(run.T.R * Vec3::UnitY(), Vec3::UnitY()) <= o.up_tolerance_deg &&
           angle_deg(run.T.R * Vec3::UnitZ(), Vec3::UnitZ()) <= o.facing_tolerance_deg;
  };
  run_start(0, 0);
  if (!report(progress, "orientation", 0.5 / num_starts))
    return Status::error(ErrorCode::Cancelled, "guess_orientation: cancelled");
  if (ran[0] && runs[0].inliers > 0 && is_consistent(runs[0]) &&
      std::sqrt(runs[0].score) < o.accept_given_fraction * diagonal) {
    out.score_given = out.score_best = runs[0].score;
    return Status::success();  // up +y, facing +z, identity rotation, differs = false
  }
  parallel_for(1, num_starts, 1, run_start);
  // Likewise when the given orientation is clearly best (OrientationOptions::
  // stop_when_given_clearly_best; the given start's score over the best
  // turned one's: the real James 0.49, Fran and the busts 1.01-1.33). Only
  // the given start is then scored on the dense samples, for the scores.
  const std::vector<Vec3> dense = subset(cloud.positions, o.final_points, o.seed + 1ull);
  std::vector<int> dense_near(dense.size(), -1);  // nearest triangles carried from run to run (continue_icp)
  FaceAlignOptions score_only = fo;
  score_only.max_iterations = 1;  // (run_icp's first iteration scores its start)
  if (o.stop_when_given_clearly_best && ran[0] && runs[0].inliers > 0 && is_consistent(runs[0])) {
    bool clearly_best = true;
    for (int k = 1; k < num_starts; ++k)
      if (ran[k] && runs[k].inliers > 0 && !is_consistent(runs[k]) && !(runs[0].score <= o.better_ratio * runs[k].score))
        clearly_best = false;
    const IcpRun given =
        clearly_best ? run_icp(search.tree, dense, runs[0].T, score_only, search.clamp, true, &dense_near) : IcpRun{};
    if (given.inliers > 0) {
      out.score_given = out.score_best = given.score;
      out.given_clearly_best = true;
      return report(progress, "orientation", 1.0) ? Status::success()
                                                  : Status::error(ErrorCode::Cancelled, "guess_orientation: cancelled");
    }
  }
  if (first_stage < o.iterations) {
    // The screen_keep best screened starts, and the screen_keep best of
    // those consistent with the given orientation, go on to o.iterations
    // (the same bits as running them through at once); the others are out
    // of the choice below. On James and Fran the starts kept this way
    // include every start the full search picked (docs/journal.md).
    std::vector<char> screened(num_starts, 0);
    for (int k = 1; k < num_starts; ++k) screened[k] = ran[k];
    const std::vector<int> by_screen = ranked(runs, screened);
    std::vector<int> go_on;
    int consistent_kept = 0;
    for (int k : by_screen) {
      const bool best_few = static_cast<int>(go_on.size()) < o.screen_keep;
      const bool consistent_few = consistent_kept < o.screen_keep && is_consistent(runs[k]);
      if (!best_few && !consistent_few) continue;
      go_on.push_back(k);
      consistent_kept += is_consistent(runs[k]);
    }
    parallel_for(0, static_cast<int>(go_on.size()), 1, [&](int i, int) {
      IcpProgress& icp = icps[go_on[i]];
      if (fewer) {  // run again from its start on all samples: the full search's bits for this start
        icp = IcpProgress{};
        icp.next = initial[go_on[i]];
      }
      continue_icp(search.tree, samples, icp, fo, o.iterations, search.clamp, false);
      runs[go_on[i]] = icp.run;
    });
    std::vector<char> kept(num_starts, 0);
    kept[0] = ran[0];
    for (int k : go_on) kept[k] = 1;
    ran.swap(kept);
  }
  if (!report(progress, "orientation", 0.7))
    return Status::error(ErrorCode::Cancelled, "guess_orientation: cancelled");
  // The best distinct results and the best consistent one are scored on
  // the (nearly) full cloud, where the decision is made; the best is
  // polished there, so that its facing does not depend on the 600 samples.
  const std::vector<int> order = ranked(runs, ran);
  if (order.empty()) return Status::error(ErrorCode::NotAHead, "guess_orientation: no orientation could be aligned");
  std::vector<int> picked = distinct_best(runs, order, o.candidates, fo.distinct_deg, fo.distinct_scale);
  for (int k : order)
    if (is_consistent(runs[k])) {
      if (std::find(picked.begin(), picked.end(), k) == picked.end()) picked.push_back(k);
      break;
    }
  std::vector<int> best_near;  // the best's nearest triangles on the dense samples, for its polish
  for (size_t c = 0; c < picked.size(); ++c) {
    std::fill(dense_near.begin(), dense_near.end(), -1);
    const IcpRun run = run_icp(search.tree, dense, runs[picked[c]].T, score_only, search.clamp, true, &dense_near);
    if (!(run.inliers > 0)) continue;
    if (is_consistent(run) && (!have_given || run.score < out.score_given)) {
      out.score_given = run.score;
      have_given = true;
    }
    if (!have_best || run.score < best.score) {
      best = run;
      have_best = true;
      best_near = dense_near;
    }
  }
  // A best result consistent with the given orientation leaves the scan as
  // given (differs is false whatever its polish does short of turning it
  // 40 degrees away), so its facing is never used: polished only when it
  // would turn the scan (James: 0.2 s CPU of the 0.6 s check saved).
  if (have_best && !is_consistent(best)) {
    FaceAlignOptions polish_options = fo;
    polish_options.max_iterations = 4 * o.iterations;
    polish_options.relative_tolerance = 0.1 * fo.polish_tolerance;
    const IcpRun polished = run_icp(search.tree, dense, best.T, polish_options, search.clamp, true, &best_near);
    if (polished.inliers > 0) {
      best = polished;
      if (is_consistent(best) && best.score < out.score_given) out.score_given = best.score;
    }
  }
  if (!report(progress, "orientation", 1.0))
    return Status::error(ErrorCode::Cancelled, "guess_orientation: cancelled");
  if (!have_best) return Status::error(ErrorCode::NotAHead, "guess_orientation: no orientation could be aligned");
  out.score_best = best.score;
  const Vec3 facing = best.T.R * Vec3::UnitZ(), up = best.T.R * Vec3::UnitY();
  const bool consistent = is_consistent(best);
  out.differs = !consistent && (!have_given || best.score < o.better_ratio * out.score_given);
  out.up = snap(up, o.snap_deg);
  // Facing: perpendicular to the (snapped) up, then snapped, then made
  // exactly perpendicular again (a snapped up and an unsnapped facing).
  out.facing = snap(facing - facing.dot(out.up) * out.up, o.snap_deg);
  out.facing = (out.facing - out.facing.dot(out.up) * out.up).normalized();
  out.rotation.row(0) = out.up.cross(out.facing).transpose();
  out.rotation.row(1) = out.up.transpose();
  out.rotation.row(2) = out.facing.transpose();
  return Status::success();
}

Status fit_scaled_rotation_icp(const TriMesh& surface, const std::vector<Vec3>& samples, const Mat3& axes,
                               const FaceAlignOptions& o, double clamp, ScaledRotationFit& out, IcpLoss loss) {
  out = ScaledRotationFit{};
  if (samples.size() < static_cast<size_t>(kMinPoints) || surface.triangles.empty())
    return Status::error(ErrorCode::Empty, "fit_scaled_rotation_icp: too few samples or no triangles");
  if (!axes.allFinite() || !(std::fabs(axes.determinant()) > 0.5))
    return Status::error(ErrorCode::InvalidInput, "fit_scaled_rotation_icp: the axes are not a rotation");
  MeshBvh tree;
  Status st = build_bvh(surface, tree);
  if (!st) return with_context(st, "fit_scaled_rotation_icp");
  // Point-to-plane Gauss-Newton (Chen & Medioni 1992): each step linearizes
  // x -> x + sum_k sigma_k u_k u_k^T (x - c) + omega x (x - c) + tau about
  // the samples' centroid c, u_k the surface's axes as turned so far.
  // Point-to-point ICP slides along a head's flat directions (its pitch) by
  // a fraction of a degree per iteration and stops wherever its tolerance
  // is met; this converges to the minimum. The map stays
  // R * (axes diag(d) axes^T) * x + t.
  Vec3 c = Vec3::Zero();
  for (const Vec3& p : samples) c += p;
  c /= double(samples.size());
  const int n = static_cast<int>(samples.size());
  Mat3 R = Mat3::Identity();
  Vec3 d = Vec3::Ones(), t = Vec3::Zero();
  std::vector<int> face(n, -1);
  std::vector<Vec3> q(n), nrm(n);
  std::vector<double> dist(n);
  const double extent = bounding_box(samples).diagonal();
  for (int it = 0; it < o.max_iterations; ++it) {
    const Mat3 M = R * axes * d.asDiagonal() * axes.transpose();
    const Mat3 Minv = M.inverse(), normal_map = Minv.transpose();
    parallel_for(0, n, 256, [&](int i, int) {
      const ClosestPoint cp = closest_point_near(tree, Minv * (samples[i] - t), face[i]);
      face[i] = cp.triangle;
      const Tri& f = surface.triangles[cp.triangle];
      const Vec3 fn = (surface.positions[f[1]] - surface.positions[f[0]])
                          .cross(surface.positions[f[2]] - surface.positions[f[0]]);
      q[i] = M * cp.point + t;
      nrm[i] = (normal_map * fn).normalized();
      dist[i] = (q[i] - samples[i]).norm();
    });
    // Pairs beyond the clamp do not pull either: the steps lower the same
    // clamped score that chooses between poses (a beard or a pedestal
    // farther than the clamp from the head would pull it off the face).
    const double trim = std::max(std::min(o.trim_factor * quantile(dist, 0.5), clamp), 1e-12 * extent);
    // The M-estimators' scale: from the pairs within the clamp (the junk
    // beyond it must not widen it), floored so a perfect fit cannot
    // divide by zero.
    double s = 0;
    if (loss != IcpLoss::Trim) {
      std::vector<double> within;
      within.reserve(n);
      for (int i = 0; i < n; ++i)
        if (dist[i] <= clamp) within.push_back(dist[i]);
      s = std::max(1.4826 * quantile(within, 0.5), 1e-9 * extent);
      out.loss_scale = s;
    }
    auto weight = [&](double di) -> double {
      if (!(di <= clamp)) return 0.0;
      if (loss == IcpLoss::Trim) return di <= trim ? 1.0 : 0.0;
      const double u = di / s;
      if (loss == IcpLoss::Tukey) {
        const double v = u / 4.685;
        return v < 1 ? (1 - v * v) * (1 - v * v) : 0.0;
      }
      return 1.0 / ((1 + u * u) * (1 + u * u));
    };
    const Mat3 U = R * axes;
    Eigen::Matrix<double, 9, 9> H = Eigen::Matrix<double, 9, 9>::Zero();
    Eigen::Matrix<double, 9, 1> g = Eigen::Matrix<double, 9, 1>::Zero();
    int kept = 0;
    double sum2 = 0, score = 0;
    for (int i = 0; i < n; ++i) {
      score += std::min(dist[i], clamp) * std::min(dist[i], clamp);
      const double w = weight(dist[i]);
      if (!(w > 0) || !nrm[i].allFinite()) continue;
      const Vec3 r = q[i] - c;
      Eigen::Matrix<double, 9, 1> J;
      for (int k = 0; k < 3; ++k) J[k] = nrm[i].dot(U.col(k)) * U.col(k).dot(r);
      J.segment<3>(3) = r.cross(nrm[i]);
      J.segment<3>(6) = nrm[i];
      const double e = nrm[i].dot(q[i] - samples[i]);
      H += w * J * J.transpose();
      g += w * J * e;
      sum2 += dist[i] * dist[i];
      ++kept;
    }
    out.iterations = it + 1;
    out.rms = kept ? std::sqrt(sum2 / kept) : 0;
    out.inlier_fraction = double(kept) / n;
    out.score = score / n;
    if (kept < 9) break;
    const Eigen::Matrix<double, 9, 1> step = H.ldlt().solve(-g);
    if (!step.allFinite() || !((Vec3::Ones() + step.head<3>()).minCoeff() > 0.5)) break;
    // The step composed onto the map: x -> dR S (M x + t - c) + c + tau.
    const Mat3 dR = rotation_from_vector(step.segment<3>(3));
    const Vec3 grow = Vec3::Ones() + step.head<3>();
    const Mat3 S = U * grow.asDiagonal() * U.transpose();
    t = dR * (S * (t - c)) + c + step.segment<3>(6);
    R = dR * R;
    d = d.cwiseProduct(grow);
    if (step.head<6>().cwiseAbs().maxCoeff() < 1e-7 && step.segment<3>(6).norm() < 1e-7 * extent) break;
  }
  out.linear = R * axes * d.asDiagonal() * axes.transpose();
  out.rotation = R;
  out.scales = d;
  out.translation = t;
  if (!(out.inlier_fraction > 0)) return Status::error(ErrorCode::NotConverged, "fit_scaled_rotation_icp: no pairs kept");
  return Status::success();
}

std::string axis_name(const Vec3& d) {
  const char* names[3] = {"x", "y", "z"};
  for (int a = 0; a < 3; ++a)
    for (int sign : {1, -1}) {
      Vec3 e = Vec3::Zero();
      e[a] = sign;
      if ((d.normalized() - e).norm() < 1e-9) return std::string(sign > 0 ? "+" : "-") + names[a];
    }
  char buf[96];
  std::snprintf(buf, sizeof buf, "(%.3g, %.3g, %.3g)", d.x(), d.y(), d.z());
  return buf;
}

}  // namespace lk
