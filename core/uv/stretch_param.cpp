#include "uv/stretch_param.h"

#include "mesh/topology.h"

#include <Eigen/Sparse>
#include <Eigen/SparseLU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace lk {
namespace {

const double kInf = std::numeric_limits<double>::infinity();

double signed_area(const Vec2& a, const Vec2& b, const Vec2& c) {
  return 0.5 * ((b.x() - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (b.y() - a.y()));
}

// Sander et al. 2001, Sec. 3: for the map texture -> 3-D, S_s and S_t are
// its partial derivatives; a = S_s.S_s, c = S_t.S_t, b = S_s.S_t.
// Returns (a + c) / 2 = L2(T)^2 and, via out-params, Gamma and gamma.
// Infinite when the texture triangle is flipped or degenerate.
double stretch_sq(const Vec3& q1, const Vec3& q2, const Vec3& q3, const Vec2& p1, const Vec2& p2,
                  const Vec2& p3, double* big = nullptr, double* small = nullptr) {
  const double A = signed_area(p1, p2, p3);
  if (!(A > 0)) {
    if (big) *big = kInf;
    if (small) *small = kInf;
    return kInf;
  }
  const Vec3 Ss = (q1 * (p2.y() - p3.y()) + q2 * (p3.y() - p1.y()) + q3 * (p1.y() - p2.y())) / (2 * A);
  const Vec3 St = (q1 * (p3.x() - p2.x()) + q2 * (p1.x() - p3.x()) + q3 * (p2.x() - p1.x())) / (2 * A);
  const double a = Ss.squaredNorm(), b = Ss.dot(St), c = St.squaredNorm();
  if (big || small) {
    const double root = std::sqrt((a - c) * (a - c) + 4 * b * b);
    if (big) *big = std::sqrt(0.5 * (a + c + root));
    if (small) *small = std::sqrt(std::max(0.0, 0.5 * (a + c - root)));
  }
  return 0.5 * (a + c);
}

// Everything the solver needs about the mesh, computed once.
struct Problem {
  const TriMesh* mesh = nullptr;
  MeshTopology topo;
  std::vector<double> area3d;   // #F, A'(T)
  std::vector<double> weight;   // #F, w(T) * A'(T)
  std::vector<std::vector<int>> vertex_faces;  // #V
  std::vector<int> boundary;    // the boundary loop
  double total_area3d = 0, total_weight = 0;
};

// Measuring needs only the per-triangle areas and weights; the solvers also
// need the topology (a disk: one boundary loop), which is the costly part on
// a 171k-triangle level 3 (a hash map of every edge), so it is optional.
Status setup(const TriMesh& mesh, const UvOptions& options, Problem& pb, bool with_topology = true) {
  pb.mesh = &mesh;
  if (mesh.num_vertices() < 3 || mesh.num_triangles() < 1)
    return Status::error(ErrorCode::Empty, "parameterization needs a mesh with triangles");
  for (const auto& p : mesh.positions)
    if (!p.allFinite()) return Status::error(ErrorCode::InvalidInput, "mesh has a NaN or infinite vertex");
  if (options.view_weighted && !(std::isfinite(options.k) && options.k > 1))
    return Status::error(ErrorCode::InvalidInput,
                         "k must be finite and above 1 so every weight 1/(<N,V>+k) is positive (the paper uses 1.01..2)");
  if (!(options.margin >= 0 && options.margin < 0.5))
    return Status::error(ErrorCode::InvalidInput, "margin must be in [0, 0.5)");
  if (with_topology) {
    Status s = build_topology(mesh, pb.topo);
    if (!s.ok()) return s;
    if (pb.topo.boundary_loops.size() != 1)
      return Status::error(ErrorCode::InvalidInput,
                           "one-chart parameterization needs a disk (exactly one boundary loop), this mesh has " +
                               std::to_string(pb.topo.boundary_loops.size()));
    if (euler_characteristic(pb.topo, mesh.num_triangles()) != 1)
      return Status::error(ErrorCode::InvalidInput, "mesh is not a topological disk (it has handles)");
    pb.boundary = pb.topo.boundary_loops[0];
    for (int v = 0; v < mesh.num_vertices(); ++v)
      if (pb.topo.valence(v) == 0)
        return Status::error(ErrorCode::InvalidInput, "vertex " + std::to_string(v) + " is in no triangle");
    pb.vertex_faces.assign(mesh.num_vertices(), {});
  }
  const Vec3 view = options.view.normalized();
  const int nf = mesh.num_triangles();
  pb.area3d.resize(nf);
  pb.weight.resize(nf);
  double mean_area = 0;
  for (int f = 0; f < nf; ++f) {
    const Tri& t = mesh.triangles[f];
    const Vec3 n = (mesh.positions[t[1]] - mesh.positions[t[0]]).cross(mesh.positions[t[2]] - mesh.positions[t[0]]);
    pb.area3d[f] = 0.5 * n.norm();
    mean_area += pb.area3d[f] / nf;
    // V in the paper's w = 1/(<N,V> + k) is taken as the direction a viewer
    // looks AT the face (= -look): with Sander's stretch of the texture ->
    // surface map, only then are face triangles weighted up and become
    // larger in the texture, the effect the paper states and shows (Fig. 2).
    const double w = options.view_weighted && n.norm() > 0 ? 1.0 / (options.k - n.normalized().dot(view)) : 1.0;
    pb.weight[f] = w * pb.area3d[f];
    pb.total_area3d += pb.area3d[f];
    pb.total_weight += pb.weight[f];
    if (with_topology)
      for (int k = 0; k < 3; ++k) pb.vertex_faces[t[k]].push_back(f);
  }
  for (int f = 0; f < nf; ++f)
    if (!(pb.area3d[f] > 1e-12 * mean_area))
      return Status::error(ErrorCode::InvalidInput, "triangle " + std::to_string(f) + " has zero area");
  return Status::success();
}

double face_energy(const Problem& pb, const std::vector<Vec2>& uv, int f) {
  const Tri& t = pb.mesh->triangles[f];
  const auto& P = pb.mesh->positions;
  return pb.weight[f] * stretch_sq(P[t[0]], P[t[1]], P[t[2]], uv[t[0]], uv[t[1]], uv[t[2]]);
}

double face_uv_area(const Problem& pb, const std::vector<Vec2>& uv, int f) {
  const Tri& t = pb.mesh->triangles[f];
  return signed_area(uv[t[0]], uv[t[1]], uv[t[2]]);
}

// Scale-invariant weighted L2(M): sqrt(E / W * A_uv / A_3d).
double objective(double energy, double uv_area, const Problem& pb) {
  return std::sqrt(energy / pb.total_weight * uv_area / pb.total_area3d);
}

double total_l2(const Problem& pb, const std::vector<Vec2>& uv) {
  double e = 0, a = 0;
  for (int f = 0; f < pb.mesh->num_triangles(); ++f) {
    e += face_energy(pb, uv, f);
    a += face_uv_area(pb, uv, f);
  }
  return objective(e, a, pb);
}

// Floater's mean-value weight of edge (i, j) seen from i: (tan(a/2) + tan(b/2)) / |ij|
// with a, b the angles at i next to the edge. Always positive, so the
// solution with a convex boundary has no flipped triangles (Floater 2003).
double tan_half(const Vec3& at, const Vec3& a, const Vec3& b) {
  const Vec3 u = (a - at).normalized(), w = (b - at).normalized();
  const double cosang = std::clamp(u.dot(w), -1.0, 1.0);
  return std::sqrt(std::max(0.0, (1 - cosang) / (1 + cosang)));
}

// Solves sum_j w_ij (u_i - u_j) = 0 for interior i with the boundary fixed.
bool solve_interior(const Problem& pb, const std::vector<std::vector<double>>& w, std::vector<Vec2>& uv) {
  const int nv = pb.mesh->num_vertices();
  std::vector<int> index(nv, -1);
  int n = 0;
  for (int v = 0; v < nv; ++v)
    if (!pb.topo.is_boundary(v)) index[v] = n++;
  if (n == 0) return true;
  std::vector<Eigen::Triplet<double>> trip;
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(n, 2);
  for (int v = 0; v < nv; ++v) {
    if (index[v] < 0) continue;
    const auto& ring = pb.topo.rings[v];
    double sum = 0;
    for (size_t k = 0; k < ring.size(); ++k) {
      const int j = ring[k];
      sum += w[v][k];
      if (index[j] >= 0) trip.emplace_back(index[v], index[j], -w[v][k]);
      else rhs.row(index[v]) += w[v][k] * uv[j].transpose();
    }
    trip.emplace_back(index[v], index[v], sum);
  }
  Eigen::SparseMatrix<double> L(n, n);
  L.setFromTriplets(trip.begin(), trip.end());
  Eigen::SparseLU<Eigen::SparseMatrix<double>> lu;
  lu.compute(L);
  if (lu.info() != Eigen::Success) return false;
  const Eigen::MatrixXd x = lu.solve(rhs);
  if (lu.info() != Eigen::Success || !x.allFinite()) return false;
  for (int v = 0; v < nv; ++v)
    if (index[v] >= 0) uv[v] = x.row(index[v]).transpose();
  return true;
}

Status tutte(const Problem& pb, std::vector<std::vector<double>>& w, std::vector<Vec2>& uv) {
  const TriMesh& mesh = *pb.mesh;
  const int nv = mesh.num_vertices();
  uv.assign(nv, Vec2::Zero());
  // Boundary on the unit circle with arc-length spacing.
  const auto& loop = pb.boundary;
  std::vector<double> arc(loop.size() + 1, 0.0);
  for (size_t i = 0; i < loop.size(); ++i)
    arc[i + 1] = arc[i] + (mesh.positions[loop[(i + 1) % loop.size()]] - mesh.positions[loop[i]]).norm();
  for (size_t i = 0; i < loop.size(); ++i) {
    const double a = 2 * 3.14159265358979323846 * arc[i] / arc.back();
    uv[loop[i]] = Vec2(std::cos(a), std::sin(a));
  }
  w.assign(nv, {});
  for (int v = 0; v < nv; ++v) {
    const auto& ring = pb.topo.rings[v];
    const auto& rf = pb.topo.ring_faces[v];
    w[v].assign(ring.size(), 0.0);
    // Face k lies between ring[k] and ring[k+1]; the angle at v in it
    // borders both edges.
    for (size_t k = 0; k < rf.size(); ++k) {
      const int a = ring[k], b = ring[(k + 1) % ring.size()];
      const double th = tan_half(mesh.positions[v], mesh.positions[a], mesh.positions[b]);
      w[v][k] += th;
      w[v][(k + 1) % ring.size()] += th;
    }
    for (size_t k = 0; k < ring.size(); ++k)
      w[v][k] = std::max(w[v][k], 1e-12) / std::max((mesh.positions[ring[k]] - mesh.positions[v]).norm(), 1e-300);
  }
  if (!solve_interior(pb, w, uv))
    return Status::error(ErrorCode::NotConverged, "the initial (mean-value) system could not be solved");
  // The loop direction decides the chart's orientation: make triangles CCW.
  double area = 0;
  for (int f = 0; f < mesh.num_triangles(); ++f) area += face_uv_area(pb, uv, f);
  if (area < 0)
    for (auto& p : uv) p.x() = -p.x();
  return Status::success();
}

void normalize_to_unit_square(std::vector<Vec2>& uv, double margin) {
  Vec2 lo = Vec2::Constant(kInf), hi = Vec2::Constant(-kInf);
  for (const auto& p : uv) { lo = lo.cwiseMin(p); hi = hi.cwiseMax(p); }
  const double extent = std::max((hi - lo).maxCoeff(), 1e-300);
  const double s = (1 - 2 * margin) / extent;
  const Vec2 centre = 0.5 * (lo + hi);
  for (auto& p : uv) p = Vec2::Constant(0.5) + s * (p - centre);
}

int count_flipped(const Problem& pb, const std::vector<Vec2>& uv) {
  int n = 0;
  for (int f = 0; f < pb.mesh->num_triangles(); ++f) n += !(face_uv_area(pb, uv, f) > 0);
  return n;
}

}  // namespace

std::vector<Vec2> triangle_stretch(const TriMesh& mesh, const std::vector<Vec2>& uv) {
  std::vector<Vec2> out(mesh.num_triangles(), Vec2::Constant(kInf));
  if (uv.size() != mesh.positions.size()) return out;
  double a3 = 0, a2 = 0;
  for (const Tri& t : mesh.triangles) {
    a3 += 0.5 * (mesh.positions[t[1]] - mesh.positions[t[0]]).cross(mesh.positions[t[2]] - mesh.positions[t[0]]).norm();
    a2 += signed_area(uv[t[0]], uv[t[1]], uv[t[2]]);
  }
  const double scale = a3 > 0 && a2 > 0 ? std::sqrt(a2 / a3) : 1.0;
  for (int f = 0; f < mesh.num_triangles(); ++f) {
    const Tri& t = mesh.triangles[f];
    double big, small;
    stretch_sq(mesh.positions[t[0]], mesh.positions[t[1]], mesh.positions[t[2]], uv[t[0]], uv[t[1]], uv[t[2]], &big, &small);
    out[f] = Vec2(big * scale, small * scale);
  }
  return out;
}

Status measure_stretch(const TriMesh& mesh, const std::vector<Vec2>& uv, const UvOptions& options,
                       UvStats& stats) {
  stats = UvStats{};
  Problem pb;
  Status s = setup(mesh, options, pb, /*with_topology=*/false);
  if (!s.ok()) return s;
  if (uv.size() != mesh.positions.size())
    return Status::error(ErrorCode::InvalidInput, "uv must have one entry per vertex");
  stats.flipped = count_flipped(pb, uv);
  // Flipped charts from other tools are measured with |area| so the numbers
  // stay comparable; the flipped count says what happened.
  double e = 0, eu = 0, a2 = 0;
  const auto& P = mesh.positions;
  std::vector<char> is_face(mesh.num_vertices(), 0);
  for (int v : options.face_vertices)
    if (v >= 0 && v < mesh.num_vertices()) is_face[v] = 1;
  double face2 = 0, face3 = 0;
  double big_max = 0;
  for (int f = 0; f < mesh.num_triangles(); ++f) {
    const Tri& t = mesh.triangles[f];
    Vec2 p1 = uv[t[0]], p2 = uv[t[1]], p3 = uv[t[2]];
    if (signed_area(p1, p2, p3) < 0) std::swap(p2, p3);  // measure mirrored triangles as they are
    Vec3 q2 = P[t[1]], q3 = P[t[2]];
    if (!(signed_area(uv[t[0]], uv[t[1]], uv[t[2]]) > 0)) std::swap(q2, q3);
    double big = 0;
    const double l2 = stretch_sq(P[t[0]], q2, q3, p1, p2, p3, &big);
    e += pb.weight[f] * l2;
    eu += pb.area3d[f] * l2;
    big_max = std::max(big_max, big);
    const double a = std::abs(signed_area(p1, p2, p3));
    a2 += a;
    if (is_face[t[0]] && is_face[t[1]] && is_face[t[2]]) { face2 += a; face3 += pb.area3d[f]; }
  }
  const double scale = std::sqrt(a2 / pb.total_area3d);
  stats.l2_stretch = std::sqrt(e / pb.total_weight) * scale;
  stats.l2_stretch_unweighted = std::sqrt(eu / pb.total_area3d) * scale;
  stats.linf_stretch = big_max * scale;
  if (!options.face_vertices.empty()) {
    stats.face_texture_share = face2 / a2;
    stats.face_area_share = face3 / pb.total_area3d;
  }
  return Status::success();
}

Status parameterize_tutte(const TriMesh& mesh, const UvOptions& options, std::vector<Vec2>& uv) {
  Problem pb;
  Status s = setup(mesh, options, pb);
  if (!s.ok()) return s;
  std::vector<std::vector<double>> w;
  s = tutte(pb, w, uv);
  if (!s.ok()) return s;
  normalize_to_unit_square(uv, options.margin);
  return Status::success();
}

Status parameterize_stretch(const TriMesh& mesh, const UvOptions& options, std::vector<Vec2>& uv,
                            UvStats& stats, const ProgressFn& progress) {
  stats = UvStats{};
  Problem pb;
  Status s = setup(mesh, options, pb);
  if (!s.ok()) return s;
  std::vector<std::vector<double>> w;
  s = tutte(pb, w, uv);
  if (!s.ok()) return s;
  const int nv = mesh.num_vertices(), nf = mesh.num_triangles();
  double current = total_l2(pb, uv);
  stats.evaluations += nf;
  const double initial = current;

  // Global phase (Yoshizawa, Belyaev & Seidel 2004): divide each weight
  // w_ij by the (view-weighted) stretch around neighbour j, so strongly
  // stretched regions push their neighbours away and get more texture
  // space; the boundary stays on the circle, so every solve is flip-free.
  double eta = 1.0;
  std::vector<double> vstretch(nv);
  for (int it = 0; it < options.global_iterations; ++it) {
    if (!report(progress, "uv: global", double(it) / std::max(1, options.global_iterations)))
      return Status::error(ErrorCode::Cancelled, "parameterization cancelled");
    for (int v = 0; v < nv; ++v) {
      double num = 0, den = 0;
      for (int f : pb.vertex_faces[v]) {
        num += face_energy(pb, uv, f);
        den += pb.weight[f];
      }
      vstretch[v] = std::sqrt(num / den);
    }
    stats.evaluations += 3 * nf;
    auto w_next = w;
    for (int v = 0; v < nv; ++v)
      for (size_t k = 0; k < w[v].size(); ++k) w_next[v][k] = w[v][k] / std::pow(vstretch[pb.topo.rings[v][k]], eta);
    std::vector<Vec2> trial = uv;
    const bool solved = solve_interior(pb, w_next, trial);
    const double value = solved && count_flipped(pb, trial) == 0 ? total_l2(pb, trial) : kInf;
    stats.evaluations += nf;
    ++stats.iterations;
    if (value < current * (1 - 1e-4)) {
      uv = trial;
      w = w_next;
      current = value;
    } else {
      eta *= 0.5;  // overshoot: smaller reweighting steps
      if (eta < 0.05) break;
    }
  }

  // Local phase (Sander et al. 2001, Sec. 4): vertex-wise line searches on
  // the scale-invariant objective, boundary vertices included, rejecting
  // any position that flips or collapses a triangle of the one-ring.
  double energy = 0, area = 0;
  for (int f = 0; f < nf; ++f) { energy += face_energy(pb, uv, f); area += face_uv_area(pb, uv, f); }
  for (int sweep = 0; sweep < options.local_sweeps; ++sweep) {
    if (!report(progress, "uv: local", double(sweep) / std::max(1, options.local_sweeps)))
      return Status::error(ErrorCode::Cancelled, "parameterization cancelled");
    const double before = objective(energy, area, pb);
    for (int v = 0; v < nv; ++v) {
      const auto& faces = pb.vertex_faces[v];
      auto local = [&](const Vec2& p, double& e, double& a) {
        const Vec2 keep = uv[v];
        uv[v] = p;
        e = 0;
        a = 0;
        for (int f : faces) { e += face_energy(pb, uv, f); a += face_uv_area(pb, uv, f); }
        uv[v] = keep;
        stats.evaluations += long(faces.size());
      };
      double e0, a0;
      local(uv[v], e0, a0);
      const double f0 = energy * area;
      auto total_at = [&](const Vec2& p) {
        double e, a;
        local(p, e, a);
        if (!std::isfinite(e)) return kInf;
        return (energy - e0 + e) * (area - a0 + a);
      };
      // Scale of moves: the shortest texture edge around v.
      double h = kInf;
      for (int j : pb.topo.rings[v]) h = std::min(h, (uv[j] - uv[v]).norm());
      if (!(h > 0)) continue;
      const double d = 1e-3 * h;
      const Vec2 grad((total_at(uv[v] + Vec2(d, 0)) - total_at(uv[v] - Vec2(d, 0))) / (2 * d),
                      (total_at(uv[v] + Vec2(0, d)) - total_at(uv[v] - Vec2(0, d))) / (2 * d));
      if (!grad.allFinite() || grad.norm() == 0) continue;
      const Vec2 dir = -grad.normalized();
      // Backtracking from half the shortest edge: keeps the vertex inside its ring.
      double step = 0.5 * h, best_f = f0;
      Vec2 best = uv[v];
      for (int tries = 0; tries < 12; ++tries, step *= 0.5) {
        const double fv = total_at(uv[v] + step * dir);
        if (fv < best_f) { best_f = fv; best = uv[v] + step * dir; break; }
      }
      if (best_f < f0) {
        double e1, a1;
        local(best, e1, a1);
        energy += e1 - e0;
        area += a1 - a0;
        uv[v] = best;
      }
    }
    ++stats.iterations;
    // Re-sum now and then so the running totals cannot drift.
    energy = 0;
    area = 0;
    for (int f = 0; f < nf; ++f) { energy += face_energy(pb, uv, f); area += face_uv_area(pb, uv, f); }
    const double after = objective(energy, area, pb);
    if (after > before * (1 - 1e-5)) break;
  }

  normalize_to_unit_square(uv, options.margin);
  const int iterations = stats.iterations;
  const long evaluations = stats.evaluations;
  s = measure_stretch(mesh, uv, options, stats);
  if (!s.ok()) return s;
  stats.iterations = iterations;
  stats.evaluations = evaluations;
  stats.initial_l2_stretch = initial;
  if (stats.flipped != 0)
    return Status::error(ErrorCode::Internal, "parameterization produced flipped triangles");
  report(progress, "uv", 1.0);
  return Status::success();
}

}  // namespace lk
