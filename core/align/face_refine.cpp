#include "align/face_refine.h"

#include "align/face_symmetry.h"
#include "common/cloud_tree.h"
#include "common/rotation.h"
#include "common/sampling.h"
#include "mesh/geometry.h"
#include "multires/surface_samples.h"
#include "raycast/bvh.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numeric>

namespace lk {

std::vector<int> upper_face_vertices(const TriMesh& generic, const HeadAnnotations& ann) {
  const int nv = generic.num_vertices();
  auto mask = [&](const char* name) {
    std::vector<char> m(nv, 0);
    if (const auto r = ann.regions.find(name); r != ann.regions.end())
      for (int v : r->second)
        if (v >= 0 && v < nv) m[v] = 1;
    return m;
  };
  const std::vector<char> face = mask("face");
  std::vector<char> out_mask(nv, 0);
  for (const char* name : {"chin", "jaw", "lips", "neck", "ears"}) {
    const std::vector<char> m = mask(name);
    for (int v = 0; v < nv; ++v) out_mask[v] = out_mask[v] || m[v];
  }
  for (int v : ann.constrained_vertices)
    if (v >= 0 && v < nv) out_mask[v] = 1;
  const std::vector<Vec3> normals = vertex_normals(generic);
  const Vec3 look = ann.look.normalized();
  std::vector<int> out;
  for (int v = 0; v < nv; ++v) {
    if (!face[v] || out_mask[v]) continue;
    if (!(normals[v].dot(look) > 0.3)) continue;  // pockets' walls, the sides of the face
    bool in_pocket = false;  // inside an eyeball's sphere: the socket behind the lids
    for (const EyeSocket* eye : {&ann.eye_left, &ann.eye_right})
      in_pocket = in_pocket || (generic.positions[v] - eye->center).norm() < 0.9 * eye->radius;
    if (!in_pocket) out.push_back(v);
  }
  return out;
}

std::vector<Vec3> upper_face_samples(const TriMesh& generic, const HeadAnnotations& ann, int count) {
  const std::vector<int> ids = upper_face_vertices(generic, ann);
  std::vector<char> keep(generic.positions.size(), 0);
  for (int v : ids) keep[v] = 1;
  // Candidates: the vertices (they cover triangles smaller than the
  // spacing) and points on the Phong surface of the triangles whose corners
  // are all upper face, some kOversample times as dense as asked; the
  // voxel grid then keeps one per cell.
  constexpr double kOversample = 4.0;
  double area = 0;
  for (int f = 0; f < generic.num_triangles(); ++f) {
    const Tri& t = generic.triangles[f];
    if (keep[t[0]] && keep[t[1]] && keep[t[2]]) area += 0.5 * face_normal_area(generic, f).norm();
  }
  PointCloud dense;
  for (int v : ids) dense.positions.push_back(generic.positions[v]);
  if (area > 0 && count > 0) {
    // An n x n split of a triangle of longest edge L = n * spacing has
    // n^2 parts of about 0.4 spacing^2 each.
    const double spacing = std::sqrt(area / (0.4 * kOversample * count));
    SurfaceSampleStats stats;
    PointCloud extra;
    if (sample_scan_surface(generic.positions, {}, generic.triangles, keep, spacing, 1e9,
                            static_cast<int>(20 * kOversample * count) + 100000, extra, stats))
      dense.positions.insert(dense.positions.end(), extra.positions.begin(), extra.positions.end());
  }
  std::vector<Vec3> out;
  for (int i : stratified_sample(dense.positions, count, 11)) out.push_back(dense.positions[i]);
  return out;
}

size_t residual_knee(const std::vector<double>& sorted) {
  const size_t n = sorted.size();
  if (n < 3) return 0;
  const double lo = sorted.front(), span = sorted.back() - sorted.front();
  if (!(span > 0)) return n - 1;
  // Normalized curve (x, y in [0, 1]); the chord is y = x. The knee is
  // where the curve lies farthest below it.
  size_t best = n - 1;
  double best_gap = 0;
  for (size_t i = 0; i < n; ++i) {
    const double x = double(i) / double(n - 1), y = (sorted[i] - lo) / span;
    if (x - y > best_gap) best_gap = x - y, best = i;
  }
  return best;
}

namespace {

struct Run {
  Mat3 linear = Mat3::Identity();
  Vec3 translation = Vec3::Zero();
  double score = 0, rms = 0, kept = 0, near = 0;
  int iterations = 0;
  // What a run needs to go on where it stopped (the same bits as running
  // through): the last trimmed RMS, whether it converged, and each
  // sample's nearest scan triangle of the last iteration.
  double previous = -1;
  bool done = false;
  std::vector<int> near_triangle;
};

// The BVH of a scan that came as a mesh (what: the caller, for messages).
Status scan_surface(const std::vector<Vec3>& cloud, const std::vector<Tri>& faces, const char* what, MeshBvh& out) {
  for (const Tri& t : faces)
    for (int v : t)
      if (v < 0 || v >= static_cast<int>(cloud.size()))
        return Status::error(ErrorCode::InvalidInput, std::string(what) + ": a scan triangle's index is out of range");
  TriMesh mesh;
  mesh.positions = cloud;
  mesh.triangles = faces;
  return build_bvh(mesh, out);
}

}  // namespace

Status upper_face_near_fraction(const TriMesh& generic, const HeadAnnotations& ann, const std::vector<Vec3>& cloud,
                                const std::vector<Tri>& faces, const Mat3& linear, const Vec3& translation,
                                double diag, double clamp_fraction, double& out, int samples) {
  out = 0;
  if (cloud.empty()) return Status::error(ErrorCode::Empty, "face near share: no scan points");
  if (!(diag > 0) || !std::isfinite(diag) || !(clamp_fraction > 0) || !linear.allFinite() || !translation.allFinite())
    return Status::error(ErrorCode::InvalidInput, "face near share: bad alignment, diagonal or distance");
  if (samples < 10) return Status::error(ErrorCode::InvalidInput, "face near share: too few samples asked");
  const std::vector<Vec3> face = upper_face_samples(generic, ann, samples);
  if (face.empty()) return Status::error(ErrorCode::Empty, "face near share: the generic head has no upper face");
  const double clamp = clamp_fraction * diag;
  int near = 0;
  if (!faces.empty()) {
    MeshBvh surface;
    const Status st = scan_surface(cloud, faces, "face near share", surface);
    if (!st) return st;
    for (const Vec3& g : face) near += closest_point(surface, linear * g + translation).distance <= clamp;
  } else {
    CloudAdaptor adaptor{cloud};
    const CloudTree tree(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16));
    for (const Vec3& g : face) {
      const Vec3 p = linear * g + translation;
      size_t idx = 0;
      double d2 = 0;
      tree.knnSearch(p.data(), 1, &idx, &d2);
      near += std::sqrt(d2) <= clamp;
    }
  }
  out = double(near) / double(face.size());
  return Status::success();
}

Status refine_alignment_on_face(const TriMesh& generic, const HeadAnnotations& ann, const std::vector<Vec3>& cloud,
                                const std::vector<Tri>& faces, const Mat3& linear, const Vec3& translation, double diag,
                                const FaceRefineOptions& o, FaceRefineResult& out, const AlignmentMeasure& whole) {
  out = FaceRefineResult{};
  if (cloud.size() < 3) return Status::error(ErrorCode::Empty, "face refinement: too few scan points");
  if (!(diag > 0) || !std::isfinite(diag) || !linear.allFinite() || !translation.allFinite())
    return Status::error(ErrorCode::InvalidInput, "face refinement: bad alignment or diagonal");
  if (o.iterations < 1 || !(o.min_keep_fraction > 0 && o.min_keep_fraction <= 1) || !(o.score_clamp_fraction > 0) ||
      o.pitch_starts_deg.empty() || o.yaw_starts_deg.empty() || o.shift_starts.empty() || o.samples < 10 ||
      o.screen_iterations < 0 || o.screen_keep < 1 ||
      (whole && (o.candidate_pitches_deg.empty() || o.candidate_iterations < 1)))
    return Status::error(ErrorCode::InvalidInput, "face refinement: bad options");
  for (const Vec3& p : cloud)
    if (!p.allFinite()) return Status::error(ErrorCode::InvalidInput, "face refinement: non-finite scan point");
  const std::vector<Vec3> face = upper_face_samples(generic, ann, o.samples);
  if (face.size() < 10) return Status::error(ErrorCode::Empty, "face refinement: the generic head has no upper face");
  const int n = static_cast<int>(face.size());
  out.samples = n;

  CloudAdaptor adaptor{cloud};
  const CloudTree tree(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  // A scan that came as a mesh is matched on its triangles: a decimated
  // scan's vertices lie millimetres apart, more than the match should err.
  MeshBvh surface;
  if (!faces.empty()) {
    const Status st = scan_surface(cloud, faces, "face refinement", surface);
    if (!st) return st;
  }
  const double clamp = o.score_clamp_fraction * diag;
  const Vec3 look = ann.look.normalized();
  const Vec3 side = ann.up.normalized().cross(look).normalized();  // the generic's horizontal axis

  // Runs `run` on until it has made `until` iterations in all or converged.
  std::vector<Vec3> model(n), target(n);
  std::vector<double> dist(n), sorted(n);
  std::vector<size_t> order(n);
  auto advance = [&](Run& run, int until) {
    // Each sample's nearest scan triangle of the last iteration: where the
    // next search starts (closest_point_near gives closest_point's answer
    // to the bit, the hint only prunes the tree).
    std::vector<int>& near_triangle = run.near_triangle;
    if (near_triangle.size() != size_t(n)) near_triangle.assign(n, -1);
    for (int it = run.iterations; it < until && !run.done; ++it) {
      for (int i = 0; i < n; ++i) {
        model[i] = run.linear * face[i] + run.translation;
        if (!surface.empty()) {
          const ClosestPoint c = closest_point_near(surface, model[i], near_triangle[i]);
          near_triangle[i] = c.triangle;
          target[i] = c.point;
          dist[i] = c.distance;
          continue;
        }
        size_t idx = 0;
        double d2 = 0;
        tree.knnSearch(model[i].data(), 1, &idx, &d2);
        target[i] = cloud[idx];
        dist[i] = std::sqrt(d2);
      }
      std::iota(order.begin(), order.end(), size_t(0));
      std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return dist[a] < dist[b]; });
      for (int i = 0; i < n; ++i) sorted[i] = dist[order[i]];
      // The pairs up to the knee of the sorted residuals pull.
      const size_t knee = residual_knee(sorted);
      const size_t keep =
          std::min<size_t>(n, std::max<size_t>(knee + 1, static_cast<size_t>(std::ceil(o.min_keep_fraction * n))));
      double sum2 = 0, score = 0;
      int near = 0;
      for (size_t k = 0; k < keep; ++k) sum2 += sorted[k] * sorted[k];
      for (double d : dist) score += std::min(d, clamp) * std::min(d, clamp), near += d <= clamp;
      run.rms = std::sqrt(sum2 / keep);
      run.kept = double(keep) / n;
      run.score = score / n;
      run.near = double(near) / n;
      run.iterations = it + 1;
      if (keep < 4 || (run.previous >= 0 && std::fabs(run.previous - run.rms) <= o.relative_tolerance * run.previous)) {
        run.done = true;
        break;
      }
      run.previous = run.rms;
      Eigen::Matrix3Xd src(3, keep), dst(3, keep);
      for (size_t k = 0; k < keep; ++k) {
        src.col(k) = model[order[k]];
        dst.col(k) = target[order[k]];
      }
      const Eigen::Matrix4d M = Eigen::umeyama(src, dst, true);
      const Mat3 sR = M.topLeftCorner<3, 3>();
      const double s = sR.col(0).norm();  // (sqrt is exact: the same in wasm)
      if (!(s > 0) || !std::isfinite(s)) {
        run.done = true;
        break;
      }
      run.linear = sR * run.linear;
      run.translation = sR * run.translation + Vec3(M.topRightCorner<3, 1>());
    }
  };
  auto run_from = [&](const Mat3& A0, const Vec3& t0, int iterations) {
    Run run;
    run.linear = A0;
    run.translation = t0;
    advance(run, iterations);
    return run;
  };

  // The starts keep the given map's rotation and mean scale but not its
  // stretch: the silhouettes of a hat or a beard stretch the head (wider,
  // shallower) where the face is not.
  const Mat3 rotation = nearest_rotation(linear);
  if (rotation.determinant() < 0)
    return Status::error(ErrorCode::InvalidInput, "face refinement: the alignment mirrors the head");
  // The mean of linear's singular values: the trace of its stretch R^T linear.
  const Mat3 isotropic = ((rotation.transpose() * linear).trace() / 3.0) * rotation;
  // The face's centre under the given map: the turns of the starts pivot there.
  Vec3 centre = Vec3::Zero();
  for (const Vec3& g : face) centre += linear * g + translation;
  centre /= n;
  const Vec3 side_world = (linear * side).normalized(), up_world = (linear * ann.up.normalized()).normalized();
  bool any = false;
  Run best;
  double width = 0;  // the face's extent across, for the starts' shifts
  {
    double lo = 1e300, hi = -1e300;
    for (const Vec3& g : face) {
      const double x = side_world.dot(linear * g);
      lo = std::min(lo, x), hi = std::max(hi, x);
    }
    width = hi - lo;
  }
  const double kDeg = 3.14159265358979323846 / 180.0;
  // The turn of a run's face to where the scan's relief in front of it is
  // most mirror-symmetric (c: the face's centre under the run's map).
  auto symmetry_of = [&](const Run& run, FaceSymmetry& symmetry, Vec3& c) {
    std::vector<Vec3> world(n);
    c = Vec3::Zero();
    for (int i = 0; i < n; ++i) world[i] = run.linear * face[i] + run.translation, c += world[i];
    c /= n;
    const Vec3 up_w = (run.linear * ann.up.normalized()).normalized();
    const Vec3 look_w = (run.linear * look).normalized();
    return bool(face_symmetry_yaw(world, look_w, up_w, surface, cloud, FaceSymmetryOptions{}, symmetry));
  };
  // The winner's face turned by that much about its vertical axis, its
  // midline onto the scan's, runs as one more start and wins by the same
  // clamped score (FaceRefineOptions::symmetry_yaw_start).
  auto symmetric_start = [&](Run& winner, int iterations) {
    FaceSymmetry symmetry;
    Vec3 c;
    if (!symmetry_of(winner, symmetry, c)) return;
    if (out.symmetry_score <= -2) out.symmetry_yaw_deg = symmetry.yaw_deg, out.symmetry_score = symmetry.score;
    if (!(std::fabs(symmetry.yaw_deg) > o.symmetry_yaw_min_deg)) return;
    const Vec3 up_w = (winner.linear * ann.up.normalized()).normalized();
    const Vec3 look_w = (winner.linear * look).normalized();
    const Vec3 u = (up_w - up_w.dot(look_w) * look_w).normalized();
    const Mat3 turn = Mat3(Eigen::AngleAxisd(symmetry.yaw_deg * kDeg, u));
    const Vec3 across = u.cross(turn * look_w);
    Run r;
    r.linear = turn * winner.linear;
    r.translation = turn * (winner.translation - c) + c + symmetry.midline_shift * across;
    advance(r, iterations);
    out.iterations += r.iterations;
    if (r.score < winner.score) winner = std::move(r);
  };
  // The best by the clamped score of the starts turned by `candidate`
  // degrees more about the horizontal axis, each run for `iterations`.
  Vec3 centre_iso = Vec3::Zero();  // the isotropic map's face centre
  for (const Vec3& g : face) centre_iso += isotropic * g;
  centre_iso /= n;
  // With screening (FaceRefineOptions::screen_iterations) every start runs
  // that far first and only the screen_keep best by the clamped score go on.
  auto best_of_starts = [&](double candidate, int iterations) {
    std::vector<Run> runs;
    for (double shift : o.shift_starts)
      for (double pitch : o.pitch_starts_deg)
        for (double yaw : o.yaw_starts_deg) {
          const Mat3 turn = Mat3(Eigen::AngleAxisd(yaw * kDeg, up_world)) *
                            Mat3(Eigen::AngleAxisd((pitch + candidate) * kDeg, side_world));
          // The isotropic map, placed so that the face's centre stays where it was.
          Run r;
          r.linear = turn * isotropic;
          r.translation = centre - turn * centre_iso + shift * width * side_world;
          runs.push_back(std::move(r));
        }
    const int count = static_cast<int>(runs.size());
    std::vector<char> goes_on(count, 1);
    if (o.screen_iterations > 0 && o.screen_iterations < iterations && o.screen_keep < count) {
      for (Run& r : runs) advance(r, o.screen_iterations);
      std::vector<int> rank(count);
      std::iota(rank.begin(), rank.end(), 0);
      std::stable_sort(rank.begin(), rank.end(), [&](int a, int b) { return runs[a].score < runs[b].score; });
      for (int k = o.screen_keep; k < count; ++k) goes_on[rank[k]] = 0;
    }
    bool found = false;
    Run winner;
    for (int k = 0; k < count; ++k) {
      if (goes_on[k]) advance(runs[k], iterations);
      out.iterations += runs[k].iterations;
      if (goes_on[k] && (!found || runs[k].score < winner.score)) winner = runs[k], found = true;
    }
    if (found && o.symmetry_yaw_start) symmetric_start(winner, iterations);
    return winner;
  };
  if (!whole) {
    best = best_of_starts(0.0, o.iterations);
    any = true;
  } else {
    // Each pitch candidate briefly. The one the whole-scan measure rates
    // highest (the first of equals) goes on, among the candidates whose
    // face looks along the scan's own (FaceRefineOptions::
    // symmetry_margin) where any does.
    std::vector<Run> runs;
    for (double candidate : o.candidate_pitches_deg) {
      runs.push_back(best_of_starts(candidate, o.candidate_iterations));
      const Run& r = runs.back();
      FaceRefineCandidate k{candidate, whole(r.linear, r.translation), r.score, r.near};
      if (!std::isfinite(k.measure)) k.measure = -1e300;
      if (o.symmetry_yaw_start) {
        FaceSymmetry symmetry;
        Vec3 c;
        if (symmetry_of(r, symmetry, c)) k.symmetry_yaw_deg = symmetry.yaw_deg, k.symmetry_score = symmetry.score;
      }
      out.candidates.push_back(k);
    }
    auto facing = [&](const FaceRefineCandidate& k) {
      return k.symmetry_score > -2 && std::fabs(k.symmetry_yaw_deg) <= o.symmetry_yaw_min_deg;
    };
    double most_symmetric = -2;
    for (const FaceRefineCandidate& k : out.candidates)
      if (facing(k)) most_symmetric = std::max(most_symmetric, k.symmetry_score);
    double best_measure = 0;
    for (size_t i = 0; i < runs.size(); ++i) {
      const FaceRefineCandidate& k = out.candidates[i];
      if (most_symmetric > -2 && !(facing(k) && k.symmetry_score >= most_symmetric - o.symmetry_margin)) continue;
      if (!any || k.measure > best_measure) {
        best = runs[i], best_measure = k.measure, any = true;
        out.chosen = static_cast<int>(i);
      }
    }
    // The winner's match goes on, and is kept where it does not move the
    // head off the scan (the knee-trimmed match can slide the face into a
    // beard or a beret: Gutenberg's turned copy, 33 % -> 15 % near).
    if (any && o.iterations > o.candidate_iterations) {
      const Run continued = run_from(best.linear, best.translation, o.iterations - o.candidate_iterations);
      out.iterations += continued.iterations;
      out.continued_measure = whole(continued.linear, continued.translation);
      if (out.continued_measure >= best_measure) best = continued;
    }
  }
  // The best start goes on until it converges (ICP's steps shrink slowly).
  if (any && o.polish_iterations > 0) {
    const Run polished = run_from(best.linear, best.translation, o.polish_iterations);
    out.iterations += polished.iterations;
    best = polished;
  }
  if (!any || !best.linear.allFinite())
    return Status::error(ErrorCode::NotConverged, "face refinement: no start converged");
  out.linear = best.linear;
  out.translation = best.translation;
  out.score = best.score;
  out.trimmed_rms = best.rms;
  out.kept_fraction = best.kept;
  out.near_fraction = best.near;
  return Status::success();
}

}  // namespace lk
