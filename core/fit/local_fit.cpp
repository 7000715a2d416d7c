#include "fit/local_fit.h"

#include "fit/closest_point.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

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

// The box's part of the mesh and its data, in local indices.
struct BoxProblem {
  std::vector<Vec3> rest;       // box vertices (and their outside neighbours) as aligned
  std::vector<char> moving;     // 1 for vertices inside the box (they follow T)
  std::vector<Tri> triangles;   // local indices
  std::vector<std::array<int, 2>> edges;
  std::vector<double> rest_lengths;
  std::vector<Vec3> points;     // P_b
  double stretch_k = 1;
  double point_to_point = 0.1;  // conditioning share, as in global_fit

  struct Eval {
    double energy = 0;
    std::vector<SurfacePoint> hits;
    std::vector<Vec3> moved;
  };

  void evaluate(const BoxTransform& T, Eval& ev) const {
    TriMesh m;
    m.positions.resize(rest.size());
    for (size_t i = 0; i < rest.size(); ++i) m.positions[i] = moving[i] ? T.apply(rest[i]) : rest[i];
    m.triangles = triangles;
    ClosestPointTree tree(m);
    ev.hits.resize(points.size());
    double dist = 0;
    for (size_t i = 0; i < points.size(); ++i) {
      ev.hits[i] = tree.closest(points[i]);
      dist += ev.hits[i].squared_distance;
    }
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
      const SurfacePoint& h = ev.hits[i];
      if (h.face < 0) continue;
      const Tri& tri = triangles[h.face];
      // Only corners inside the box follow T: q collects their weighted
      // offsets from the centre, wm their total weight.
      Vec3 x = Vec3::Zero(), q = Vec3::Zero();
      double wm = 0;
      for (int k = 0; k < 3; ++k) {
        x += h.barycentric[k] * ev.moved[tri[k]];
        if (moving[tri[k]]) {
          q += h.barycentric[k] * (rest[tri[k]] - T.c);
          wm += h.barycentric[k];
        }
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

}  // namespace

Status fit_local(const std::vector<Vec3>& points, const TriMesh& mesh, const MeshTopology& topology,
                 const std::vector<FeatureBox>& boxes, const AffineMap& generic_to_mesh,
                 double cloud_diagonal, const LocalFitOptions& options, TriMesh& out,
                 LocalFitResult& result, const ProgressFn& progress) {
  result = LocalFitResult{};
  const int nv = mesh.num_vertices();
  if (nv == 0 || mesh.triangles.empty())
    return Status::error(ErrorCode::Empty, "local fit: the mesh has no triangles");
  if (topology.num_vertices != nv)
    return Status::error(ErrorCode::InvalidInput, "local fit: topology does not match the mesh");
  if (!(cloud_diagonal > 0) || !std::isfinite(cloud_diagonal))
    return Status::error(ErrorCode::InvalidInput, "local fit: the cloud's diagonal must be positive");
  const double det = generic_to_mesh.A.determinant();
  if (!std::isfinite(det) || std::abs(det) < 1e-12)
    return Status::error(ErrorCode::InvalidInput, "local fit: the alignment transform is singular");
  for (const Vec3& p : mesh.positions)
    if (!finite(p)) return Status::error(ErrorCode::InvalidInput, "local fit: non-finite mesh vertex");
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

  for (size_t bi = 0; bi < boxes.size(); ++bi) {
    const FeatureBox& box = boxes[bi];
    if (!report(progress, "local_fitting", double(bi) / boxes.size()))
      return Status::error(ErrorCode::Cancelled, "local fit cancelled");
    for (int l : box.landmarks)
      if (l < 0 || l >= nv)
        return Status::error(ErrorCode::InvalidInput, "local fit: landmark of box '" + box.name + "' out of range");
    BoxFit fit;
    fit.name = box.name;

    BoxProblem prob;
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
          prob.moving.push_back(inside[bi][t[k]]);
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
      std::shuffle(idx.begin(), idx.end(), rng);
      idx.resize(options.max_points_per_box);
    }
    for (int i : idx) prob.points.push_back(points[i]);
    fit.points = static_cast<int>(prob.points.size());
    BoxTransform T;
    for (size_t i = 0; i < prob.rest.size(); ++i)
      if (prob.moving[i]) {
        T.c += prob.rest[i];
        ++fit.vertices;
      }
    if (fit.vertices > 0) T.c /= double(fit.vertices);

    if (prob.triangles.empty() || fit.points < options.min_points_per_box) {
      // Nothing to fit against (a hole in the scan or a box outside it): the
      // feature keeps the shape the alignment gave it.
      fit.skipped = true;
    } else {
      BoxProblem::Eval ev, trial;
      prob.evaluate(T, ev);
      fit.energies.push_back(ev.energy);
      double damping = 1e-4;
      for (int it = 0; it < options.max_iterations; ++it) {
        Mat12 JtJ;
        Vec12 Jtr;
        prob.linearize(T, ev, JtJ, Jtr);
        bool accepted = false;
        for (int tries = 0; tries < 10 && !accepted; ++tries) {
          Mat12 H = JtJ;
          for (int k = 0; k < 12; ++k) H(k, k) += damping * (JtJ(k, k) + 1e-12);
          const Vec12 delta = H.ldlt().solve(-Jtr);
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
    transforms[bi] = T;
    // Express about the origin for callers: c + A (y - c) + t = A y + (c - A c + t).
    fit.transform.A = T.A;
    fit.transform.t = T.c - T.A * T.c + T.t;
    result.boxes.push_back(fit);
  }

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

}  // namespace lk
