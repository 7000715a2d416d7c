#include "fit/local_fit.h"

#include "common/parallel.h"
#include "common/sampling.h"
#include "fit/closest_point.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numeric>

namespace lk {
namespace {

using Mat12 = Eigen::Matrix<double, 12, 12>;
using Vec12 = Eigen::Matrix<double, 12, 1>;

// The box's transform about its centroid c: y -> c + A (y - c) + t, with
// parameters (A row-major, t).
struct BoxTransform {
  Mat3 A = Mat3::Identity();
  Vec3 t = Vec3::Zero();
  Vec3 c = Vec3::Zero();
  Vec3 apply(const Vec3& y) const { return c + A * (y - c) + t; }
  BoxTransform plus(const Vec12& d) const {
    BoxTransform r = *this;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) r.A(i, j) += d[3 * i + j];
    r.t += d.tail<3>();
    return r;
  }
};

// Directions in the 12 parameters (A row-major, t) that a motion may take.
Eigen::Matrix<double, 12, Eigen::Dynamic> motion_basis(RegionMotion motion) {
  Eigen::Matrix<double, 12, Eigen::Dynamic> B;
  switch (motion) {
    case RegionMotion::Affine:
      B = Mat12::Identity();
      break;
    case RegionMotion::TranslationScale:
      B = Eigen::Matrix<double, 12, 4>::Zero();
      B(0, 0) = B(4, 0) = B(8, 0) = 1;  // A = s I
      for (int k = 0; k < 3; ++k) B(9 + k, 1 + k) = 1;
      break;
    case RegionMotion::Translation:
      B = Eigen::Matrix<double, 12, 3>::Zero();
      for (int k = 0; k < 3; ++k) B(9 + k, k) = 1;
      break;
  }
  return B;
}

// The box's part of the mesh and its data, in local indices.
struct BoxProblem {
  std::vector<Vec3> rest;       // box vertices (and their outside neighbours) as aligned
  // How far each vertex follows T: y -> y + w (T(y) - y). 1 inside a box, 0
  // on the ring outside it; between 0 and 1 in a soft region's falloff.
  std::vector<double> weight;
  std::vector<Tri> triangles;   // local indices
  std::vector<std::array<int, 2>> edges;
  std::vector<double> rest_lengths;
  std::vector<Vec3> points;     // P_b
  double stretch_k = 1;
  double point_to_point = 0.1;  // conditioning share, as in global_fit

  struct Eval {
    double energy = 0;
    std::vector<SurfaceHit> hits;
    std::vector<Vec3> moved;
  };

  void evaluate(const BoxTransform& T, Eval& ev) const {
    TriMesh m;
    m.positions.resize(rest.size());
    for (size_t i = 0; i < rest.size(); ++i) m.positions[i] = rest[i] + weight[i] * (T.apply(rest[i]) - rest[i]);
    m.triangles = triangles;
    ClosestPointTree tree(m);
    ev.hits.resize(points.size());
    // Independent queries in parallel; the sum in point order (the same on
    // any number of threads).
    parallel_for(0, static_cast<int>(points.size()), 256, [&](int i, int) { ev.hits[i] = tree.closest(points[i]); });
    double dist = 0;
    for (const SurfaceHit& h : ev.hits) dist += h.squared_distance;
    double stretch = 0;
    for (size_t e = 0; e < edges.size(); ++e) {
      const double l = (m.positions[edges[e][0]] - m.positions[edges[e][1]]).norm();
      stretch += (l - rest_lengths[e]) * (l - rest_lengths[e]);
    }
    ev.energy = dist / std::max<size_t>(1, points.size()) +
                0.5 * stretch_k * stretch / std::max<size_t>(1, edges.size());
    ev.moved = std::move(m.positions);
  }

  // Gauss-Newton normal equations at T with the correspondences of ev.
  void linearize(const BoxTransform& T, const Eval& ev, Mat12& JtJ, Vec12& Jtr) const {
    JtJ.setZero();
    Jtr.setZero();
    const double wd = 1.0 / std::max<size_t>(1, points.size());
    for (size_t i = 0; i < points.size(); ++i) {
      const SurfaceHit& h = ev.hits[i];
      if (h.face < 0) continue;
      const Tri& tri = triangles[h.face];
      // Corners follow T by their weights: q collects their weighted
      // offsets from the centre, wm their total weight.
      Vec3 x = Vec3::Zero(), q = Vec3::Zero();
      double wm = 0;
      for (int k = 0; k < 3; ++k) {
        x += h.barycentric[k] * ev.moved[tri[k]];
        const double w = h.barycentric[k] * weight[tri[k]];
        q += w * (rest[tri[k]] - T.c);
        wm += w;
      }
      Vec3 n = points[i] - x;
      const double len = n.norm();
      if (len > 1e-15) {
        n /= len;
      } else {
        const Vec3& a = ev.moved[tri[0]];
        n = (ev.moved[tri[1]] - a).cross(ev.moved[tri[2]] - a);
        if (n.norm() <= 0) continue;
        n.normalize();
      }
      // Point-to-plane row: r = n . (T(y) - p).
      Vec12 j;
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) j[3 * a + b] = n[a] * q[b];
      j.tail<3>() = wm * n;
      const double r = n.dot(x - points[i]);
      JtJ.noalias() += wd * j * j.transpose();
      Jtr.noalias() += wd * r * j;
      // Point-to-point rows (one per coordinate), small weight.
      for (int a = 0; a < 3; ++a) {
        Vec12 jp = Vec12::Zero();
        for (int b = 0; b < 3; ++b) jp[3 * a + b] = q[b];
        jp[9 + a] = wm;
        JtJ.noalias() += wd * point_to_point * jp * jp.transpose();
        Jtr.noalias() += wd * point_to_point * (x[a] - points[i][a]) * jp;
      }
    }
    const double ws = 0.5 * stretch_k / std::max<size_t>(1, edges.size());
    for (size_t e = 0; e < edges.size(); ++e) {
      const Vec3 d = rest[edges[e][0]] - rest[edges[e][1]];
      const Vec3 Ad = T.A * d;
      const double l = Ad.norm();
      if (l <= 0) continue;
      Vec12 j = Vec12::Zero();
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) j[3 * a + b] = Ad[a] * d[b] / l;
      const double r = l - rest_lengths[e];
      JtJ.noalias() += ws * j * j.transpose();
      Jtr.noalias() += ws * r * j;
    }
  }
};

bool finite(const Vec3& p) { return p.allFinite(); }

// Levenberg-Marquardt on E_local within the motion's parameters; a step is
// taken only when it lowers the true energy. T starts as given.
void minimize(const BoxProblem& prob, RegionMotion motion, const LocalFitOptions& options, BoxTransform& T,
              BoxFit& fit) {
  const Eigen::Matrix<double, 12, Eigen::Dynamic> B = motion_basis(motion);
  const int k = static_cast<int>(B.cols());
  BoxProblem::Eval ev, trial;
  prob.evaluate(T, ev);
  fit.energies.push_back(ev.energy);
  double damping = 1e-4;
  for (int it = 0; it < options.max_iterations; ++it) {
    Mat12 JtJ;
    Vec12 Jtr;
    prob.linearize(T, ev, JtJ, Jtr);
    const Eigen::MatrixXd H0 = B.transpose() * JtJ * B;
    const Eigen::VectorXd g = B.transpose() * Jtr;
    bool accepted = false;
    for (int tries = 0; tries < 10 && !accepted; ++tries) {
      Eigen::MatrixXd H = H0;
      for (int j = 0; j < k; ++j) H(j, j) += damping * (H0(j, j) + 1e-12);
      const Vec12 delta = B * H.ldlt().solve(-g);
      if (!delta.allFinite()) break;
      const BoxTransform Tn = T.plus(delta);
      prob.evaluate(Tn, trial);
      if (trial.energy < ev.energy) {
        accepted = true;
        T = Tn;
        std::swap(ev, trial);
        damping = std::max(1e-7, damping / 3);
      } else {
        damping *= 4;
      }
    }
    if (!accepted) break;
    const double previous = fit.energies.back();
    fit.energies.push_back(ev.energy);
    if ((previous - ev.energy) < options.relative_tolerance * previous) break;
  }
}

Status check_mesh_and_frame(const TriMesh& mesh, const MeshTopology& topology, const AffineMap& generic_to_mesh,
                            const char* who) {
  const std::string w = who;
  if (mesh.num_vertices() == 0 || mesh.triangles.empty())
    return Status::error(ErrorCode::Empty, w + ": the mesh has no triangles");
  if (topology.num_vertices != mesh.num_vertices())
    return Status::error(ErrorCode::InvalidInput, w + ": topology does not match the mesh");
  const double det = generic_to_mesh.A.determinant();
  if (!std::isfinite(det) || std::abs(det) < 1e-12 || !generic_to_mesh.t.allFinite())
    return Status::error(ErrorCode::InvalidInput, w + ": the alignment transform is singular");
  for (const Vec3& p : mesh.positions)
    if (!finite(p)) return Status::error(ErrorCode::InvalidInput, w + ": non-finite mesh vertex");
  return Status::success();
}

}  // namespace

Status fit_local(const std::vector<Vec3>& points, const TriMesh& mesh, const MeshTopology& topology,
                 const std::vector<FeatureBox>& boxes, const AffineMap& generic_to_mesh,
                 double cloud_diagonal, const LocalFitOptions& options, TriMesh& out,
                 LocalFitResult& result, const ProgressFn& progress) {
  result = LocalFitResult{};
  const int nv = mesh.num_vertices();
  Status st = check_mesh_and_frame(mesh, topology, generic_to_mesh, "local fit");
  if (!st) return st;
  if (!(cloud_diagonal > 0) || !std::isfinite(cloud_diagonal))
    return Status::error(ErrorCode::InvalidInput, "local fit: the cloud's diagonal must be positive");
  const Mat3 A_inv = generic_to_mesh.A.inverse();
  auto to_generic = [&](const Vec3& p) { return Vec3(A_inv * (p - generic_to_mesh.t)); };

  std::vector<Vec3> generic_points;
  generic_points.reserve(points.size());
  for (const Vec3& p : points) {
    if (!finite(p)) return Status::error(ErrorCode::InvalidInput, "local fit: non-finite scan point");
    generic_points.push_back(to_generic(p));
  }
  std::vector<Vec3> generic_vertices(nv);
  for (int v = 0; v < nv; ++v) generic_vertices[v] = to_generic(mesh.positions[v]);

  std::mt19937 rng(options.seed);
  std::vector<BoxTransform> transforms(boxes.size());
  std::vector<std::vector<char>> inside(boxes.size(), std::vector<char>(nv, 0));

  // Each box's problem and start, in box order (the subsample draws from
  // one generator); then the boxes are minimized on parallel_for's threads,
  // each on its own (the same results on any number of threads).
  if (!report(progress, "local_fitting", 0.0)) return Status::error(ErrorCode::Cancelled, "local fit cancelled");
  std::vector<BoxProblem> problems(boxes.size());
  std::vector<BoxFit> fits(boxes.size());
  for (size_t bi = 0; bi < boxes.size(); ++bi) {
    const FeatureBox& box = boxes[bi];
    for (int l : box.landmarks)
      if (l < 0 || l >= nv)
        return Status::error(ErrorCode::InvalidInput, "local fit: landmark of box '" + box.name + "' out of range");
    BoxFit& fit = fits[bi];
    fit.name = box.name;

    BoxProblem& prob = problems[bi];
    prob.stretch_k = options.stretch_weight;
    std::vector<int> local(nv, -1);
    for (int v = 0; v < nv; ++v)
      if (box.contains(generic_vertices[v])) inside[bi][v] = 1;
    // G_b plus the ring of triangles that leave the box: points near the
    // box's walls belong to those, and without them the fit would stretch
    // G_b to reach them.
    for (const Tri& t : mesh.triangles) {
      if (!inside[bi][t[0]] && !inside[bi][t[1]] && !inside[bi][t[2]]) continue;
      Tri lt;
      for (int k = 0; k < 3; ++k) {
        if (local[t[k]] < 0) {
          local[t[k]] = static_cast<int>(prob.rest.size());
          prob.rest.push_back(mesh.positions[t[k]]);
          prob.weight.push_back(inside[bi][t[k]] ? 1.0 : 0.0);
        }
        lt[k] = local[t[k]];
      }
      prob.triangles.push_back(lt);
    }
    for (const Edge& e : topology.edges)
      if (inside[bi][e.v0] && inside[bi][e.v1]) {
        prob.edges.push_back({local[e.v0], local[e.v1]});
        prob.rest_lengths.push_back((mesh.positions[e.v0] - mesh.positions[e.v1]).norm());
      }
    std::vector<int> idx;
    for (size_t i = 0; i < points.size(); ++i)
      if (box.contains(generic_points[i])) idx.push_back(static_cast<int>(i));
    if (static_cast<int>(idx.size()) > options.max_points_per_box) {
      mt19937_shuffle(idx.begin(), idx.end(), rng);
      idx.resize(options.max_points_per_box);
    }
    for (int i : idx) prob.points.push_back(points[i]);
    fit.points = static_cast<int>(prob.points.size());
    BoxTransform T;
    for (size_t i = 0; i < prob.rest.size(); ++i)
      if (prob.weight[i] > 0) {
        T.c += prob.rest[i];
        ++fit.vertices;
      }
    if (fit.vertices > 0) T.c /= double(fit.vertices);

    transforms[bi] = T;
    // Nothing to fit against (a hole in the scan or a box outside it): the
    // feature keeps the shape the alignment gave it.
    fit.skipped = prob.triangles.empty() || fit.points < options.min_points_per_box;
  }
  parallel_for(0, static_cast<int>(boxes.size()), 1, [&](int bi, int) {
    if (fits[bi].skipped) return;
    const FeatureBox& box = boxes[bi];
    const BoxProblem& prob = problems[bi];
    BoxTransform& T = transforms[bi];
    BoxFit& fit = fits[bi];
    // Starts (ours): the map from the alignment, and the box shifted up and
    // down by LocalFitOptions::start_shifts of its height; each runs a few
    // iterations and the lowest E_local goes on, a shifted start only when
    // it is lower by more than LocalFitOptions::start_gain (BoxFit::energies is that
    // start's, from before its first iteration). From the alignment alone
    // the mouth can slide into the wrong basin: synthetic seed 6 (slightly
    // open mouth) with the generic head of 23 Nov moved its lip line 9 mm
    // up towards the nose (E_local 1.1e-6); started 20 % of the box lower
    // it ends 5 mm down (7.1e-7), where the previous head's fit lands too.
    // The global fit had crumpled the lips it was handed (88-125 level-3
    // pairs).
    if (!options.start_shifts.empty()) {
      LocalFitOptions screen = options;
      screen.max_iterations = options.start_screen_iterations;
      const Vec3 up = generic_to_mesh.A * Vec3::UnitY();
      const double height = box.max.y() - box.min.y();
      BoxTransform best = T;
      BoxFit best_fit = fit;
      minimize(prob, RegionMotion::Affine, screen, best, best_fit);
      for (double shift : options.start_shifts) {
        BoxTransform S = T;
        S.t += shift * height * up;
        BoxFit f = fit;
        minimize(prob, RegionMotion::Affine, screen, S, f);
        if (f.energies.back() < (1 - options.start_gain) * best_fit.energies.back()) best = S, best_fit = f;
      }
      T = best;
      fit = best_fit;  // energies: the chosen start's from its first, then on
    }
    minimize(prob, RegionMotion::Affine, options, T, fit);
  });
  for (size_t bi = 0; bi < boxes.size(); ++bi) {
    BoxFit& fit = fits[bi];
    const BoxTransform& T = transforms[bi];
    // Express about the origin for callers: c + A (y - c) + t = A y + (c - A c + t).
    fit.transform.A = T.A;
    fit.transform.t = T.c - T.A * T.c + T.t;
    result.boxes.push_back(std::move(fit));
  }
  if (!report(progress, "local_fitting", 1.0)) return Status::error(ErrorCode::Cancelled, "local fit cancelled");

  // Apply: box vertices move with their box (averaged where boxes overlap);
  // the rest follow the landmarks with exponential fall-off.
  out = mesh;
  const double kf = options.falloff_fraction * cloud_diagonal;
  std::vector<Vec3> land_pos, land_disp;
  for (size_t bi = 0; bi < boxes.size(); ++bi)
    for (int l : boxes[bi].landmarks) {
      land_pos.push_back(mesh.positions[l]);
      land_disp.push_back(transforms[bi].apply(mesh.positions[l]) - mesh.positions[l]);
    }
  for (int v = 0; v < nv; ++v) {
    const Vec3& p = mesh.positions[v];
    Vec3 sum = Vec3::Zero();
    int count = 0;
    for (size_t bi = 0; bi < boxes.size(); ++bi)
      if (inside[bi][v]) {
        sum += transforms[bi].apply(p);
        ++count;
      }
    if (count > 0) {
      out.positions[v] = sum / count;
      continue;
    }
    Vec3 disp = Vec3::Zero();
    double wsum = 0;
    for (size_t i = 0; i < land_pos.size(); ++i) {
      const double w = std::exp(-(p - land_pos[i]).norm() / kf);
      disp += w * land_disp[i];
      wsum += w;
    }
    out.positions[v] = p + disp / std::max(1.0, wsum);
  }
  report(progress, "local_fitting", 1.0);
  return Status::success();
}

double SoftRegion::radius(const Vec3& generic_point) const {
  return ((generic_point - center).array() / radii.array()).matrix().norm();
}

double SoftRegion::weight(const Vec3& generic_point) const {
  const double rho = radius(generic_point);
  if (rho <= 1) return 1;
  if (rho >= falloff) return 0;
  const double u = (rho - 1) / (falloff - 1);
  return 1 - u * u * (3 - 2 * u);
}

Status eye_region(const TriMesh& generic, const HeadAnnotations& ann, const EyeRegionOptions& options,
                  SoftRegion& out) {
  out = SoftRegion{};
  if (!(options.falloff > 1) || !std::isfinite(options.falloff) ||
      !(options.radii_per_eye_distance.array() > 0).all() || !options.radii_per_eye_distance.allFinite() ||
      !(options.data_extent > 0) || !std::isfinite(options.data_extent))
    return Status::error(ErrorCode::InvalidInput, "eye region: radii must be positive and the falloff above 1");
  Vec3 centroid[2];
  const std::vector<int>* rims[2] = {&ann.eye_left.rim, &ann.eye_right.rim};
  for (int e = 0; e < 2; ++e) {
    if (rims[e]->empty()) return Status::error(ErrorCode::InvalidInput, "eye region: the head has no eye rim");
    centroid[e] = Vec3::Zero();
    for (int v : *rims[e]) {
      if (v < 0 || v >= generic.num_vertices())
        return Status::error(ErrorCode::InvalidInput, "eye region: eye rim vertex out of range");
      centroid[e] += generic.positions[v];
    }
    centroid[e] /= double(rims[e]->size());
  }
  const double distance = (centroid[0] - centroid[1]).norm();
  if (!(distance > 0) || !std::isfinite(distance))
    return Status::error(ErrorCode::InvalidInput, "eye region: the two eye rims coincide");
  out.name = "eyes";
  out.center = 0.5 * (centroid[0] + centroid[1]);
  out.radii = distance * options.radii_per_eye_distance;
  out.falloff = options.falloff;
  out.data_extent = options.data_extent;
  out.motion = options.motion;
  return Status::success();
}

Status fit_soft_region(const std::vector<Vec3>& points, const TriMesh& mesh, const MeshTopology& topology,
                       const SoftRegion& region, const AffineMap& generic_to_mesh, const LocalFitOptions& options,
                       TriMesh& out, BoxFit& result, const ProgressFn& progress) {
  result = BoxFit{};
  result.name = region.name;
  const int nv = mesh.num_vertices();
  Status st = check_mesh_and_frame(mesh, topology, generic_to_mesh, "soft region fit");
  if (!st) return st;
  if (!(region.falloff > 1) || !(region.radii.array() > 0).all() || !region.center.allFinite() ||
      !region.radii.allFinite() || !std::isfinite(region.falloff) || !(region.data_extent > 0) ||
      !std::isfinite(region.data_extent))
    return Status::error(ErrorCode::InvalidInput, "soft region fit: region '" + region.name +
                                                      "' needs positive radii and data extent and a falloff above 1");
  if (!report(progress, "local_fitting", 0.0)) return Status::error(ErrorCode::Cancelled, "local fit cancelled");
  const Mat3 A_inv = generic_to_mesh.A.inverse();
  auto to_generic = [&](const Vec3& p) { return Vec3(A_inv * (p - generic_to_mesh.t)); };

  std::vector<double> weight(nv);
  for (int v = 0; v < nv; ++v) weight[v] = region.weight(to_generic(mesh.positions[v]));

  // The region's mesh: triangles with a moving corner (their still corners
  // are the ring outside the falloff).
  BoxProblem prob;
  prob.stretch_k = options.stretch_weight;
  std::vector<int> local(nv, -1);
  for (const Tri& t : mesh.triangles) {
    if (weight[t[0]] <= 0 && weight[t[1]] <= 0 && weight[t[2]] <= 0) continue;
    Tri lt;
    for (int k = 0; k < 3; ++k) {
      if (local[t[k]] < 0) {
        local[t[k]] = static_cast<int>(prob.rest.size());
        prob.rest.push_back(mesh.positions[t[k]]);
        prob.weight.push_back(weight[t[k]]);
      }
      lt[k] = local[t[k]];
    }
    prob.triangles.push_back(lt);
  }
  // E_stretch on the edges that move fully: it holds the scale, while the
  // falloff's edges stretch by design.
  for (const Edge& e : topology.edges)
    if (local[e.v0] >= 0 && local[e.v1] >= 0 && weight[e.v0] >= 1 && weight[e.v1] >= 1) {
      prob.edges.push_back({local[e.v0], local[e.v1]});
      prob.rest_lengths.push_back((mesh.positions[e.v0] - mesh.positions[e.v1]).norm());
    }
  std::vector<int> idx;
  for (size_t i = 0; i < points.size(); ++i) {
    if (!finite(points[i])) return Status::error(ErrorCode::InvalidInput, "soft region fit: non-finite scan point");
    if (region.radius(to_generic(points[i])) <= region.data_extent) idx.push_back(static_cast<int>(i));
  }
  if (static_cast<int>(idx.size()) > options.max_points_per_box) {
    std::mt19937 rng(options.seed);
    mt19937_shuffle(idx.begin(), idx.end(), rng);
    idx.resize(options.max_points_per_box);
  }
  for (int i : idx) prob.points.push_back(points[i]);
  result.points = static_cast<int>(prob.points.size());
  for (int v = 0; v < nv; ++v) result.vertices += weight[v] > 0;

  BoxTransform T;
  T.c = generic_to_mesh.apply(region.center);
  if (prob.triangles.empty() || result.points < options.min_points_per_box) {
    result.skipped = true;  // nothing to fit against: the region stays where the alignment put it
  } else {
    minimize(prob, region.motion, options, T, result);
  }
  result.transform.A = T.A;
  result.transform.t = T.c - T.A * T.c + T.t;
  out = mesh;
  if (!result.skipped)
    for (int v = 0; v < nv; ++v)
      if (weight[v] > 0) out.positions[v] += weight[v] * (T.apply(mesh.positions[v]) - mesh.positions[v]);
  return Status::success();  // no "done" report: fit_local follows and reports the stage from 0 to 1
}

}  // namespace lk
