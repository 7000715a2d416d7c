#include "fit/global_fit.h"

#include "common/cloud_tree.h"
#include "common/parallel.h"
#include "common/sampling.h"
#include "fit/block_ldlt.h"
#include "fit/closest_point.h"
#include "fit/data_surface.h"
#include "fit/factor_preconditioner.h"
#include "fit/point_patch.h"
#include "mesh/geometry.h"
#include "raycast/bvh.h"
#include "raycast/self_intersection.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Sparse>
#include <algorithm>
#include <cmath>
#include <memory>
#include <numeric>

namespace lk {
namespace {

using SpMat = Eigen::SparseMatrix<double>;
using Triplet = Eigen::Triplet<double>;
using VecX = Eigen::VectorXd;

// A linear residual block R x - b, with x the interleaved coordinates
// (x0 y0 z0 x1 ...) of all vertices.
struct LinearTerm {
  SpMat R;
  VecX b;
  double energy(const VecX& x) const { return R.rows() ? (R * x - b).squaredNorm() : 0.0; }
};

VecX to_vector(const std::vector<Vec3>& p) {
  VecX x(3 * p.size());
  for (size_t i = 0; i < p.size(); ++i) x.segment<3>(3 * i) = p[i];
  return x;
}

void from_vector(const VecX& x, std::vector<Vec3>& p) {
  for (size_t i = 0; i < p.size(); ++i) p[i] = x.segment<3>(3 * i);
}

// Umbrella operator rows: L(v) = x_v - mean(one-ring of v), minus rest.
LinearTerm smooth_term(const MeshTopology& topo, const VecX& rest, bool preserve_rest) {
  const int nv = topo.num_vertices;
  std::vector<Triplet> t;
  for (int v = 0; v < nv; ++v) {
    const auto& ring = topo.rings[v];
    if (ring.empty()) continue;
    const double w = 1.0 / ring.size();
    for (int c = 0; c < 3; ++c) {
      t.emplace_back(3 * v + c, 3 * v + c, 1.0);
      for (int u : ring) t.emplace_back(3 * v + c, 3 * u + c, -w);
    }
  }
  LinearTerm term;
  term.R.resize(3 * nv, 3 * nv);
  term.R.setFromTriplets(t.begin(), t.end());
  term.b = preserve_rest ? VecX(term.R * rest) : VecX::Zero(3 * nv);
  return term;
}

LinearTerm binding_term(const std::vector<std::array<int, 2>>& edges, int nv, const VecX& rest) {
  std::vector<Triplet> t;
  LinearTerm term;
  term.b.resize(3 * edges.size());
  for (size_t e = 0; e < edges.size(); ++e) {
    const int a = edges[e][0], b = edges[e][1];
    for (int c = 0; c < 3; ++c) {
      t.emplace_back(3 * e + c, 3 * a + c, 1.0);
      t.emplace_back(3 * e + c, 3 * b + c, -1.0);
      term.b[3 * e + c] = rest[3 * a + c] - rest[3 * b + c];
    }
  }
  term.R.resize(3 * edges.size(), 3 * nv);
  term.R.setFromTriplets(t.begin(), t.end());
  return term;
}

LinearTerm constraint_term(const std::vector<int>& vertices, int nv, const VecX& rest) {
  std::vector<Triplet> t;
  LinearTerm term;
  term.b.resize(3 * vertices.size());
  for (size_t i = 0; i < vertices.size(); ++i)
    for (int c = 0; c < 3; ++c) {
      t.emplace_back(3 * i + c, 3 * vertices[i] + c, 1.0);
      term.b[3 * i + c] = rest[3 * vertices[i] + c];
    }
  term.R.resize(3 * vertices.size(), 3 * nv);
  term.R.setFromTriplets(t.begin(), t.end());
  return term;
}

// Closest points of the point set on the mesh with positions x.
struct Projection {
  std::vector<SurfaceHit> hits;
  double dist_energy = 0;  // 1/#S sum min(d, tau)^2
};

// `points`: the round's points, in its order. `previous` (one per point, or
// empty) holds the last projection: the distance to the same triangle at
// the new positions bounds the search, which prunes most of the tree when
// the mesh moved little.
void project(const std::vector<Vec3>& points, DataSurface& data, const VecX& x, double tau,
             const std::vector<SurfaceHit>* previous, Projection& out) {
  data.set(x);
  const TriMesh& work = data.mesh;
  ClosestPointTree tree(work);
  out.hits.resize(points.size());
  const bool warm = previous && previous->size() == points.size();
  // Independent queries: in parallel, each writing its own hit.
  parallel_for(0, static_cast<int>(points.size()), 1024, [&](int i, int) {
    const Vec3& p = points[i];
    if (warm && (*previous)[i].face >= 0) {
      const int f = (*previous)[i].face;
      const Tri& t = work.triangles[f];
      SurfaceHit guess = closest_point_on_triangle(p, work.positions[t[0]], work.positions[t[1]], work.positions[t[2]]);
      guess.face = f;
      const SurfaceHit better = tree.closest(p, guess.squared_distance);
      out.hits[i] = better.face >= 0 ? better : guess;
    } else {
      out.hits[i] = tree.closest(p);
    }
  });
  double sum = 0;  // in point order: the same sum on any number of threads
  const double tau2 = tau * tau;
  for (const SurfaceHit& h : out.hits) sum += std::min(h.squared_distance, tau2);
  out.dist_energy = points.empty() ? 0.0 : sum / points.size();
}

// The normal equations are factorized by vertices (block_ldlt.h): AMD on
// the vertex graph, each vertex's x, y, z kept together (ordering the
// scalars gave James's guarded fit a factor with 9 % more entries), and
// 3x3 blocks for the scalars: the same factor as Eigen's SimplicialLDLT
// with that ordering, 2.4x faster to compute and about 3x faster to apply
// (docs/journal.md, "Speed of the global fit's solves").
using NormalSolver = BlockLdlt;

// 1/#S sum_p min(d_p, tau)^2 over the round's points (in its order), with
// d_p the distance from point p to the triangle it projected to before
// (hits; a point without one counts tau): an upper bound of E_dist at x.
double distance_energy_bound(const std::vector<Vec3>& points, const std::vector<Tri>& triangles, const VecX& x,
                             double tau, const std::vector<SurfaceHit>& hits) {
  const double tau2 = tau * tau;
  std::vector<double> d2(points.size(), tau2);
  parallel_for(0, static_cast<int>(points.size()), 4096, [&](int i, int) {
    const int f = hits[i].face;
    if (f < 0) return;
    const Tri& t = triangles[f];
    const Vec3 a = x.segment<3>(3 * t[0]), b = x.segment<3>(3 * t[1]), c = x.segment<3>(3 * t[2]);
    d2[i] = closest_point_on_triangle(points[i], a, b, c).squared_distance;
  });
  double sum = 0;  // in point order: the same sum on any number of threads
  for (double v : d2) sum += std::min(v, tau2);
  return points.empty() ? 0.0 : sum / points.size();
}

bool finite(const Vec3& p) { return std::isfinite(p.x()) && std::isfinite(p.y()) && std::isfinite(p.z()); }

Vec3 triangle_normal(const VecX& x, const Tri& t) {
  const Vec3 a = x.segment<3>(3 * t[0]), b = x.segment<3>(3 * t[1]), c = x.segment<3>(3 * t[2]);
  return (b - a).cross(c - a);
}

// The fold guard (header comment): per-vertex anchors a_v with weights g_v,
// E_guard = 1/#V sum_v g_v |x_v - a_v|^2, and the reference's triangle
// normals that say which way each triangle must face.
struct FoldGuard {
  std::vector<Vec3> reference_normals;  // #F, unnormalized
  VecX anchor;                          // 3#V: a_v (meaningful where g_v > 0)
  std::vector<double> weight;           // #V: g_v
  SpMat hessian;                        // diag(g) / #V, per coordinate
  VecX gradient;                        // diag(g) a / #V

  std::vector<int> turned(const std::vector<Tri>& triangles, const VecX& x) const {
    std::vector<int> out;
    for (size_t f = 0; f < triangles.size(); ++f)
      if (!(triangle_normal(x, triangles[f]).dot(reference_normals[f]) > 0)) out.push_back(static_cast<int>(f));
    return out;
  }

  double energy(const VecX& x, double inv_v) const {
    double e = 0;
    for (size_t v = 0; v < weight.size(); ++v)
      if (weight[v] > 0) e += weight[v] * (x.segment<3>(3 * v) - anchor.segment<3>(3 * v)).squaredNorm();
    return e * inv_v;
  }

  void reset(int nv, double inv_v) {
    weight.assign(nv, 0.0);
    anchor = VecX::Zero(3 * nv);
    rebuild(inv_v);
  }

  // The hessian keeps the full diagonal as its pattern (explicit zeros), so
  // the solver's symbolic analysis stays valid when weights change.
  void rebuild(double inv_v) {
    const int n = static_cast<int>(weight.size());
    std::vector<Triplet> t;
    t.reserve(3 * n);
    gradient = VecX::Zero(3 * n);
    for (int v = 0; v < n; ++v)
      for (int c = 0; c < 3; ++c) {
        t.emplace_back(3 * v + c, 3 * v + c, weight[v] * inv_v);
        gradient[3 * v + c] = weight[v] * inv_v * anchor[3 * v + c];
      }
    hessian.resize(3 * n, 3 * n);
    hessian.setFromTriplets(t.begin(), t.end());
  }

  // Raises g_v on the corners of the given triangles, anchoring a vertex
  // where it is now (x) when it is first guarded; returns how many rose.
  int stiffen(const std::vector<int>& faces, const std::vector<Tri>& triangles, const VecX& x,
              const GlobalFitOptions& o) {
    std::vector<char> corner(weight.size(), 0);
    for (int f : faces)
      for (int v : triangles[f]) corner[v] = 1;
    int raised = 0;
    for (size_t v = 0; v < weight.size(); ++v) {
      if (!corner[v]) continue;
      const double g = weight[v] > 0 ? std::min(weight[v] * o.fold_stiffen_factor, o.fold_max_stiffness)
                                     : o.fold_stiffness;
      if (!(g > weight[v])) continue;
      if (weight[v] == 0) anchor.segment<3>(3 * v) = x.segment<3>(3 * v);
      weight[v] = g;
      ++raised;
    }
    return raised;
  }
};

// The no-crossing guard's check (header comment): control triangle pairs
// that cross at positions x (self_intersection.h rules), sorted. `scratch`
// holds the mesh's triangles; its positions are overwritten.
std::vector<std::array<int, 2>> crossing_pairs(const VecX& x, TriMesh& scratch) {
  from_vector(x, scratch.positions);
  std::vector<std::array<int, 2>> pairs;
  find_self_intersections(scratch, pairs);  // x is finite (checked by the caller), indices valid
  return pairs;
}

// The pairs that may cross anywhere on the step from x0 to x1: a corner
// moves on a segment, so a triangle stays inside the box of its corners at
// both ends, and two triangles can meet only where those boxes overlap.
// Found once per solve by sweeping the boxes along their longest axis;
// each trial step then tests only these pairs (a full self-intersection
// search per trial cost about as much as the rest of the global fit).
// Pairs sharing an edge stay in: mesh_triangles_cross, which decides each
// pair, already says no to them (self_intersection.h rules).
std::vector<std::array<int, 2>> swept_candidates(const std::vector<Tri>& triangles, const VecX& x0,
                                                 const VecX& x1) {
  const int nf = static_cast<int>(triangles.size());
  std::vector<Vec3> lo(nf), hi(nf);
  Vec3 all_lo = Vec3::Constant(1e300), all_hi = Vec3::Constant(-1e300);
  for (int f = 0; f < nf; ++f) {
    lo[f] = Vec3::Constant(1e300);
    hi[f] = Vec3::Constant(-1e300);
    for (int v : triangles[f]) {
      lo[f] = lo[f].cwiseMin(x0.segment<3>(3 * v)).cwiseMin(x1.segment<3>(3 * v));
      hi[f] = hi[f].cwiseMax(x0.segment<3>(3 * v)).cwiseMax(x1.segment<3>(3 * v));
    }
    all_lo = all_lo.cwiseMin(lo[f]);
    all_hi = all_hi.cwiseMax(hi[f]);
  }
  int axis = 0;
  (all_hi - all_lo).maxCoeff(&axis);
  std::vector<int> order(nf);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return lo[a][axis] < lo[b][axis]; });
  std::vector<std::array<int, 2>> pairs;
  for (int i = 0; i < nf; ++i) {
    const int a = order[i];
    for (int j = i + 1; j < nf && lo[order[j]][axis] <= hi[a][axis]; ++j) {
      const int b = order[j];
      if (!((lo[a].array() <= hi[b].array()).all() && (lo[b].array() <= hi[a].array()).all())) continue;
      pairs.push_back({std::min(a, b), std::max(a, b)});
    }
  }
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

// A control face whose corners are all flagged in `ignored` (#V; empty:
// none is): the smooth-surface guard leaves its level triangles alone.
bool ignored_face(const Tri& control_face, const std::vector<char>& ignored) {
  if (ignored.empty()) return false;
  for (int v : control_face)
    if (!ignored[v]) return false;
  return true;
}

// The smooth-surface guard's check (header comment): the control mesh
// refined by Modified Butterfly, and the crossing pairs of that level which
// the reference's refinement does not have. Butterfly is linear in the
// control positions, so a pair found here is answered by the control
// vertices under it. The level's BVH is built at the first check and refit
// afterwards (the same triangles; the passes move vertices a little), and
// a pair is old when it crosses at the reference's level positions too
// (find_new_self_intersections).
struct SmoothSurfaceCheck {
  std::vector<ButterflyLevel> levels;
  std::vector<Vec3> reference_level;  // the reference refined
  int faces_per_control = 1;          // child c of triangle g is 4 g + c on every level
  TriMesh level;                      // scratch: the triangles of the level, positions of the last check
  MeshBvh bvh;

  std::vector<Vec3> refine(const VecX& x) const {
    std::vector<Vec3> control(x.size() / 3);
    from_vector(x, control);
    std::vector<std::vector<Vec3>> refined;
    apply_all(levels, control, refined);  // sizes match: the levels were built from this mesh
    return std::move(refined.back());
  }

  // The new pairs at x. The first call searches the whole level; later
  // calls (the guard's passes) search only from the level triangles in
  // `active` (#F of the level flags: under the control vertices the guard
  // weighs), where the passes change the shape, and keep the first search's
  // pairs elsewhere. `ignored` (#V flags or empty): pairs with a control
  // face that has only ignored corners do not count.
  std::vector<std::array<int, 2>> new_pairs_at(const VecX& x, const std::vector<char>& active,
                                               const std::vector<int>& active_list, const std::vector<Tri>& control,
                                               const std::vector<char>& ignored) {
    level.positions = refine(x);
    if (level.triangles.empty()) level.triangles = levels.back().fine_triangles;
    // x and the reference are finite and of the level's size (checked by
    // the caller), so the BVH and the search cannot fail.
    std::vector<std::array<int, 2>> pairs;
    if (bvh.empty() || !searched) {
      // A tree taken over (relief_start_tree) is refitted: the same pairs.
      if (bvh.empty()) build_bvh(level, bvh);
      else refit_bvh(level, bvh);
      find_new_self_intersections(bvh, reference_level, pairs);
    } else {
      refit_bvh(level, bvh);
      find_new_self_intersections(bvh, reference_level, pairs, &active_list);
      for (const auto& p : first_pairs)
        if (!active[p[0]] && !active[p[1]]) pairs.push_back(p);
      std::sort(pairs.begin(), pairs.end());
    }
    drop_ignored(pairs, control, ignored);
    if (first_pairs.empty() && !searched) first_pairs = pairs;
    searched = true;
    return pairs;
  }
  // Drops the pairs with a level triangle inside a control face whose
  // corners are all `ignored` (#V flags or empty: none).
  void drop_ignored(std::vector<std::array<int, 2>>& pairs, const std::vector<Tri>& control,
                    const std::vector<char>& ignored) const {
    if (ignored.empty()) return;
    auto ignored_level_face = [&](int f) { return ignored_face(control[f / faces_per_control], ignored); };
    size_t kept = 0;
    for (const auto& p : pairs)
      if (!ignored_level_face(p[0]) && !ignored_level_face(p[1])) pairs[kept++] = p;
    pairs.resize(kept);
  }
  std::vector<std::array<int, 2>> first_pairs;  // new pairs of the first (whole) search
  bool searched = false;
};

// E_back (header comment): the scan's local plane under each control vertex
// that lies over scanned skin, taken at the start of a round and fixed for
// it, so that the round minimizes one quadratic energy.
struct BackPlanes {
  std::vector<int> vertex;     // control vertices with a plane
  std::vector<Vec3> normal;    // unit normal of the scan there
  std::vector<double> offset;  // the plane: normal . x = offset
  SpMat hessian;               // of weight/#V sum (n . x_v - offset)^2
  VecX gradient;
  double weight = 0;           // back_weight / #V
  int rays = 0;                // of `vertex`, planes found by a normal ray

  double energy(const VecX& x) const {
    double e = 0;
    for (size_t i = 0; i < vertex.size(); ++i) {
      const double r = normal[i].dot(x.segment<3>(3 * vertex[i])) - offset[i];
      e += r * r;
    }
    return e * weight;
  }

  void find(const CloudTree& tree, const std::vector<Vec3>& points, const VecX& x, const TriMesh& mesh,
            const std::vector<char>& ignored, const GlobalFitOptions& o, double edge, int nv, double inv_v,
            bool cast_rays, const TriMesh* surface = nullptr, const MeshBvh* surface_bvh = nullptr) {
    vertex.clear();
    normal.clear();
    offset.clear();
    weight = o.back_weight * inv_v;
    TriMesh current;
    current.triangles = mesh.triangles;
    current.positions.resize(nv);
    from_vector(x, current.positions);
    const std::vector<Vec3>& pos = current.positions;
    const std::vector<Vec3> vn = vertex_normals(current);  // unit, or zero
    const double max_radius = o.back_patch_edges * edge;
    const double max_offset = o.back_max_edges * edge;
    std::vector<int> found(nv, 0);
    std::vector<Vec3> fn(nv);
    std::vector<double> fo(nv);
    parallel_for(0, nv, 64, [&](int v, int) {
      if (!ignored.empty() && ignored[v]) return;
      if (!(vn[v].squaredNorm() > 0)) return;
      PointPatch patch;
      if (!fit_patch_plane(tree, points, pos[v], o.back_neighbours, patch)) return;
      if (patch.radius > max_radius) return;           // the scan is too sparse or too far here
      if (!patch.flat(o.back_flatness)) return;         // not one sheet (a fold, a lip gap, a rim)
      if (std::abs(patch.height) > max_offset) return;
      if (!patch.over_patch()) return;                  // beyond the patch's rim (a hole's edge)
      if (std::abs(patch.plane_normal.dot(vn[v])) < o.back_min_cos) return;  // the mesh faces another way here
      if (!fit_patch_quadric(points, pos[v], patch)) return;
      found[v] = 1;
      fn[v] = patch.normal;
      fo[v] = patch.normal.dot(patch.foot);
    });
    rays = 0;
    if (cast_rays) {
      // Normal rays (header comment): vertices without a patch, off the
      // scan by more than back_ray_min_edges, take the scan's plane where
      // their normal line meets it first (either way, within reach).
      const double reach = o.back_ray_edges * edge, min_off = o.back_ray_min_edges * edge;
      const double step = o.back_ray_step_edges * edge;
      // The scan's distance from p: to its triangles, or its nearest point.
      auto off_scan = [&](const Vec3& p) {
        if (surface_bvh) {
          const ClosestPoint cp = closest_point(*surface_bvh, p);
          return cp.found() ? cp.distance : -1.0;
        }
        size_t nearest = 0;
        double d2 = 0;
        return tree.knnSearch(p.data(), 1, &nearest, &d2) < 1 ? -1.0 : std::sqrt(d2);
      };
      // Where the line from `from` along `dir` meets the scan before t_max,
      // with the scan's unit normal and a point of its plane there. A mesh:
      // the first triangle hit. A point cloud: the line is marched in steps
      // of back_ray_step_edges to the first with a point within one step;
      // the plane is that of the point's back_ray_neighbours nearest.
      auto meet = [&](const Vec3& from, const Vec3& dir, double t_max, double& t, Vec3& n, Vec3& at) {
        if (surface_bvh) {
          Ray ray;
          ray.origin = from;
          ray.direction = dir;
          ray.t_max = t_max;
          const RayHit h = intersect_first(*surface_bvh, ray);
          if (!h.hit()) return false;
          const Tri& tri = surface->triangles[h.triangle];
          const Vec3& a = surface->positions[tri[0]];
          n = (surface->positions[tri[1]] - a).cross(surface->positions[tri[2]] - a).normalized();
          t = h.t;
          at = from + h.t * dir;
          return true;
        }
        for (double s = step; s < t_max; s += step) {
          const Vec3 probe = from + s * dir;
          size_t nearest = 0;
          double d2 = 0;
          if (tree.knnSearch(probe.data(), 1, &nearest, &d2) < 1 || d2 > step * step) continue;
          PointPatch patch;
          if (!fit_patch_plane(tree, points, points[nearest], o.back_ray_neighbours, patch)) return false;
          n = patch.plane_normal;
          t = s;
          at = points[nearest];
          return true;
        }
        return false;
      };
      std::vector<char> by_ray(nv, 0);
      parallel_for(0, nv, 16, [&](int v, int) {
        if (found[v] || (!ignored.empty() && ignored[v]) || !(vn[v].squaredNorm() > 0)) return;
        if (!(off_scan(pos[v]) > min_off)) return;
        double best_t = reach;
        for (int sign : {1, -1}) {
          double t = 0;
          Vec3 n, at;
          if (!meet(pos[v], sign * vn[v], best_t, t, n, at)) continue;
          if (!(std::abs(n.dot(vn[v])) >= 0.5)) continue;  // sign-free: scans need not be oriented
          best_t = t;
          by_ray[v] = 1;
          fn[v] = n;
          fo[v] = n.dot(at);
        }
      });
      for (int v = 0; v < nv; ++v)
        if (by_ray[v]) found[v] = 1, ++rays;
    }
    for (int v = 0; v < nv; ++v)
      if (found[v]) vertex.push_back(v), normal.push_back(fn[v]), offset.push_back(fo[v]);
    std::vector<Triplet> trip;
    trip.reserve(vertex.size() * 9);
    gradient = VecX::Zero(3 * nv);
    for (size_t i = 0; i < vertex.size(); ++i) {
      const Mat3 nn = normal[i] * normal[i].transpose() * weight;
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) trip.emplace_back(3 * vertex[i] + a, 3 * vertex[i] + b, nn(a, b));
      gradient.segment<3>(3 * vertex[i]) += normal[i] * (offset[i] * weight);
    }
    hessian.resize(3 * nv, 3 * nv);
    hessian.setFromTriplets(trip.begin(), trip.end());
  }
};

}  // namespace

std::vector<int> turned_triangles(const std::vector<Vec3>& reference, const TriMesh& mesh) {
  std::vector<int> out;
  if (reference.size() != mesh.positions.size()) return out;
  for (int f = 0; f < mesh.num_triangles(); ++f) {
    const Tri& t = mesh.triangles[f];
    const Vec3 n0 = (reference[t[1]] - reference[t[0]]).cross(reference[t[2]] - reference[t[0]]);
    if (!(face_normal_area(mesh, f).dot(n0) > 0)) out.push_back(f);
  }
  return out;
}

Status fit_global(const std::vector<Vec3>& points, const TriMesh& mesh, const MeshTopology& topology,
                  const GlobalFitTerms& terms, const GlobalFitOptions& options, TriMesh& out,
                  GlobalFitResult& result, const ProgressFn& progress, MeshBvh* relief_tree) {
  if (relief_tree) *relief_tree = MeshBvh{};
  result = GlobalFitResult{};
  const int nv = mesh.num_vertices();
  if (points.empty()) return Status::error(ErrorCode::Empty, "global fit: no scan points to fit");
  if (mesh.triangles.empty() || nv == 0)
    return Status::error(ErrorCode::Empty, "global fit: the control mesh has no triangles");
  if (topology.num_vertices != nv || static_cast<int>(topology.rings.size()) != nv)
    return Status::error(ErrorCode::InvalidInput, "global fit: topology does not match the mesh");
  for (double share : options.smooth_guard_relief_shares)
    if (!(share > 0) || !std::isfinite(share))
      return Status::error(ErrorCode::InvalidInput, "global fit: smooth_guard_relief_shares must be positive and finite");
  if (!(options.smooth_guard_crease_min_angle_deg >= 0 && options.smooth_guard_crease_min_angle_deg < 180))
    return Status::error(ErrorCode::InvalidInput, "global fit: smooth_guard_crease_min_angle_deg must be in [0, 180)");
  if (options.smooth_guard_crease_trials < 0 || options.smooth_guard_crease_max_edges < 0)
    return Status::error(ErrorCode::InvalidInput, "global fit: smooth_guard_crease_trials and _max_edges must be >= 0");
  if (options.smooth_guard_pleat_steps < 0 || !(options.smooth_guard_pleat_max_move_edges >= 0) ||
      !std::isfinite(options.smooth_guard_pleat_max_move_edges))
    return Status::error(ErrorCode::InvalidInput,
                         "global fit: smooth_guard_pleat_steps must be >= 0 and smooth_guard_pleat_max_move_edges "
                         "finite and >= 0");
  if (options.smooth_guard_relief_level < 0 || options.smooth_guard_relief_level > 4)
    return Status::error(ErrorCode::InvalidInput, "global fit: smooth_guard_relief_level must be 0 (off) to 4");
  if (options.data_level < 0 || options.data_level > 3)
    return Status::error(ErrorCode::InvalidInput, "global fit: data_level must be 0 (the control mesh) to 3");
  if (!(options.back_weight >= 0) || !std::isfinite(options.back_weight) || options.back_neighbours < 6 ||
      !(options.back_patch_edges > 0) || !(options.back_max_edges > 0) || !(options.back_flatness > 0) ||
      !(options.back_min_cos >= 0 && options.back_min_cos <= 1))
    return Status::error(ErrorCode::InvalidInput,
                         "global fit: back_weight must be >= 0 and finite, back_neighbours >= 6, the back_ "
                         "distances and flatness positive, back_min_cos in [0, 1]");
  if (!(options.back_ray_edges >= 0) || !std::isfinite(options.back_ray_edges) ||
      !(options.back_ray_min_edges >= 0) || !std::isfinite(options.back_ray_min_edges) ||
      options.back_ray_first_round < 0 || !(options.back_ray_step_edges > 0) ||
      !std::isfinite(options.back_ray_step_edges) || options.back_ray_neighbours < 3)
    return Status::error(ErrorCode::InvalidInput,
                         "global fit: back_ray_edges and back_ray_min_edges must be finite and >= 0, "
                         "back_ray_first_round >= 0, back_ray_step_edges positive, back_ray_neighbours >= 3");
  for (const Tri& t : terms.back_surface.triangles)
    for (int i : t)
      if (i < 0 || i >= terms.back_surface.num_vertices())
        return Status::error(ErrorCode::InvalidInput, "global fit: a back_surface triangle indexes no vertex");
  if (!terms.back_ignored.empty() && static_cast<int>(terms.back_ignored.size()) != nv)
    return Status::error(ErrorCode::InvalidInput, "global fit: back_ignored has " +
                                                      std::to_string(terms.back_ignored.size()) +
                                                      " flags, the mesh " + std::to_string(nv) + " vertices");
  if (options.smooth_weights.empty())
    return Status::error(ErrorCode::InvalidInput, "global fit: no rounds (smooth_weights is empty)");
  for (const Vec3& p : points)
    if (!finite(p)) return Status::error(ErrorCode::InvalidInput, "global fit: non-finite scan point");
  for (const Vec3& p : mesh.positions)
    if (!finite(p)) return Status::error(ErrorCode::InvalidInput, "global fit: non-finite mesh vertex");
  for (const auto& e : terms.binding_edges)
    if (e[0] < 0 || e[1] < 0 || e[0] >= nv || e[1] >= nv || e[0] == e[1])
      return Status::error(ErrorCode::InvalidInput, "global fit: binding edge with a bad vertex index");
  for (int v : terms.constrained_vertices)
    if (v < 0 || v >= nv)
      return Status::error(ErrorCode::InvalidInput, "global fit: constrained vertex index out of range");
  if (!terms.fold_reference.empty() && static_cast<int>(terms.fold_reference.size()) != nv)
    return Status::error(ErrorCode::InvalidInput, "global fit: the fold reference has " +
                                                      std::to_string(terms.fold_reference.size()) +
                                                      " vertices, the mesh " + std::to_string(nv));
  for (const Vec3& p : terms.fold_reference)
    if (!finite(p)) return Status::error(ErrorCode::InvalidInput, "global fit: non-finite fold reference vertex");
  if (!terms.start.empty() && static_cast<int>(terms.start.size()) != nv)
    return Status::error(ErrorCode::InvalidInput, "global fit: the start has " + std::to_string(terms.start.size()) +
                                                      " vertices, the mesh " + std::to_string(nv));
  for (const Vec3& p : terms.start)
    if (!finite(p)) return Status::error(ErrorCode::InvalidInput, "global fit: non-finite start vertex");
  if (!terms.smooth_guard_ignored.empty() && static_cast<int>(terms.smooth_guard_ignored.size()) != nv)
    return Status::error(ErrorCode::InvalidInput, "global fit: smooth_guard_ignored has " +
                                                      std::to_string(terms.smooth_guard_ignored.size()) +
                                                      " flags, the mesh " + std::to_string(nv) + " vertices");

  const VecX rest = to_vector(mesh.positions);
  const VecX start = terms.start.empty() ? rest : to_vector(terms.start);
  const VecX reference = terms.fold_reference.empty() ? rest : to_vector(terms.fold_reference);
  std::vector<Vec3> reference_normals(mesh.triangles.size());
  for (size_t f = 0; f < mesh.triangles.size(); ++f)
    reference_normals[f] = triangle_normal(reference, mesh.triangles[f]);
  for (size_t f = 0; f < mesh.triangles.size(); ++f)
    result.turned_before += !(triangle_normal(start, mesh.triangles[f]).dot(reference_normals[f]) > 0);
  // The rest shape is the template as aligned (the reference), not the
  // local fit: see the header.
  const LinearTerm smooth = smooth_term(topology, reference, options.preserve_rest_shape);
  const LinearTerm binding = binding_term(terms.binding_edges, nv, rest);
  const LinearTerm constraint = constraint_term(terms.constrained_vertices, nv, rest);
  const double inv_v = 1.0 / nv;
  const SpMat h_smooth = SpMat(smooth.R.transpose() * smooth.R) * inv_v;
  const VecX g_smooth = smooth.R.transpose() * smooth.b * inv_v;
  SpMat h_fixed(3 * nv, 3 * nv);
  VecX g_fixed = VecX::Zero(3 * nv);
  if (binding.R.rows()) {
    h_fixed += SpMat(binding.R.transpose() * binding.R) * (options.binding_weight * inv_v);
    g_fixed += binding.R.transpose() * binding.b * (options.binding_weight * inv_v);
  }
  if (constraint.R.rows()) {
    h_fixed += SpMat(constraint.R.transpose() * constraint.R) * (options.constraint_weight * inv_v);
    g_fixed += constraint.R.transpose() * constraint.b * (options.constraint_weight * inv_v);
  }

  // Smooth-surface guard: per-vertex rest-shape weights r_v, the rows of
  // E_smooth weighted once more: E_rest = 1/#V sum_v r_v |L(v) - L0(v)|^2.
  SmoothSurfaceCheck smooth_check;
  bool smooth_guarded = options.smooth_guard_level > 0 && options.smooth_guard_passes > 0;
  if (smooth_guarded) {
    // A mesh Butterfly cannot refine (not a manifold) is fitted unguarded.
    smooth_guarded = build_butterfly_levels(mesh, terms.smooth_creases, options.smooth_guard_level,
                                            smooth_check.levels)
                         .ok();
    result.smooth_guard_skipped = !smooth_guarded;
  }
  if (smooth_guarded) {
    smooth_check.faces_per_control = 1 << (2 * options.smooth_guard_level);
    smooth_check.reference_level = smooth_check.refine(reference);
  }
  std::vector<double> rest_weight(nv, 0.0);
  std::vector<char> active_level;      // the smooth level's triangles under weighed vertices
  std::vector<int> active_level_list;  // ... as a list
  SpMat h_rest(3 * nv, 3 * nv);
  VecX g_rest = VecX::Zero(3 * nv);
  auto rebuild_rest = [&]() {
    VecX row_weight(3 * nv);
    for (int v = 0; v < nv; ++v) row_weight.segment<3>(3 * v).setConstant(rest_weight[v] * inv_v);
    const SpMat weighted = row_weight.asDiagonal() * smooth.R;
    h_rest = SpMat(smooth.R.transpose() * weighted);
    g_rest = weighted.transpose() * smooth.b;
  };
  auto rest_energy = [&](const VecX& xx) {
    if (result.smooth_guard_vertices == 0) return 0.0;
    const VecX residual = smooth.R * xx - smooth.b;
    double e = 0;
    for (int v = 0; v < nv; ++v)
      if (rest_weight[v] > 0) e += rest_weight[v] * residual.segment<3>(3 * v).squaredNorm();
    return e * inv_v;
  };

  FoldGuard guard;
  guard.reference_normals = std::move(reference_normals);
  guard.reset(nv, inv_v);
  const bool guarding = options.fold_guard_attempts > 0;
  const bool crossing_guarded = guarding && options.crossing_guard;
  TriMesh check_mesh = mesh;                         // scratch of the crossing check
  std::vector<std::array<int, 2>> crossing_at_x = crossing_pairs(start, check_mesh);  // at x, sorted
  result.crossing_before = static_cast<int>(crossing_at_x.size());

  const double edge = mean_edge_length(mesh);
  // A tiny pull towards the current positions keeps the system definite for
  // vertices that neither data nor regularizers reach (isolated vertices);
  // scaled far below every real term.
  const double tikhonov = 1e-9;

  // One random order of the points; round r uses a prefix of it.
  std::vector<int> order(points.size());
  std::iota(order.begin(), order.end(), 0);
  std::mt19937 rng(options.seed);
  mt19937_shuffle(order.begin(), order.end(), rng);

  // The data surface (header comment): the control mesh, or its Butterfly
  // level data_level (a mesh Butterfly cannot refine is fitted as level 0).
  DataSurface plain_data, refined_storage;
  plain_data.build(mesh, terms.smooth_creases, 0);
  DataSurface* refined_data = &plain_data;
  if (options.data_level > 0 && refined_storage.build(mesh, terms.smooth_creases, options.data_level))
    refined_data = &refined_storage;
  result.data_level = refined_data->level;
  int carried_level = -1;
  VecX x = start;
  const int sub_rounds = static_cast<int>(options.smooth_weights.size());
  // Level 0 on the subsample rounds unless data_level_on_subsamples.
  const int data_from = options.data_level_on_subsamples ? 0 : sub_rounds;
  const int base_rounds = sub_rounds + (options.final_iterations > 0 ? 1 : 0);
  int rounds = base_rounds;  // the smooth-surface guard adds passes
  VecX smooth_best;          // the guard's state with the fewest new smooth pairs
  int smooth_best_pairs = -1;
  const int total_iterations = sub_rounds * std::max(1, options.max_iterations_per_round) + options.final_iterations;
  NormalSolver solver;
  int factor_fresh_round = -1;  // the round whose matrix `solver` holds
  FactorPreconditionedCg<NormalSolver> cg;
  cg.preconditioner().factor = &solver;
  cg.setMaxIterations(12);
  cg.setTolerance(1e-5);
  int done_iterations = 0;

  // E_back's scan index (over the points fitted), when the term is on.
  std::unique_ptr<CloudAdaptor> back_adaptor;
  std::unique_ptr<CloudTree> back_tree;
  BackPlanes back;
  MeshBvh back_bvh;
  if (options.back_weight > 0) {
    back_adaptor = std::make_unique<CloudAdaptor>(CloudAdaptor{points});
    back_tree = std::make_unique<CloudTree>(3, *back_adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16));
    if (options.back_ray_edges > 0 && !terms.back_surface.triangles.empty()) {
      const Status bs = build_bvh(terms.back_surface, back_bvh);
      if (!bs) return bs;
    }
  }

  auto energy_parts = [&](const VecX& xx, double dist, double lambda, GlobalFitIteration& it) {
    it.e_dist = dist;
    it.e_smooth = smooth.energy(xx) * inv_v;
    it.e_binding = binding.energy(xx) * inv_v;
    it.e_constraint = constraint.energy(xx) * inv_v;
    it.e_guard = guard.energy(xx, inv_v) + rest_energy(xx);
    it.e_back = back.energy(xx);
    return it.e_dist + lambda * it.e_smooth + options.binding_weight * it.e_binding +
           options.constraint_weight * it.e_constraint + it.e_guard + it.e_back;
  };
  Projection carried;     // the last round's projection at x
  int carried_count = -1;  // ... of its first carried_count points of `order`
  for (int r = 0; r < rounds; ++r) {
    const bool final_pass = r >= sub_rounds;
    const double lambda = options.smooth_weights[std::min(r, sub_rounds - 1)];
    const bool guard_pass = r >= base_rounds;
    const int max_iterations = guard_pass   ? std::max(1, options.final_iterations)
                               : final_pass ? options.final_iterations
                                            : options.max_iterations_per_round;
    const bool last_round = r == rounds - 1;
    int count = final_pass ? 0 : options.subsample_points;
    if (count <= 0 || count > static_cast<int>(points.size())) count = static_cast<int>(points.size());
    // The round's points, in its order and side by side: every projection
    // and assembly walks them, and gathering them through the shuffled
    // order each time was most of the assembly's cost.
    std::vector<Vec3> set(count);
    for (int i = 0; i < count; ++i) set[i] = points[order[i]];

    // The trimming distance is fixed for the round so that the round
    // minimizes one well-defined energy.
    // The previous round ended with the projection of its points at x (the
    // accepted step's, or the round's first): the same points are not
    // projected again, and a larger set starts its prefix from those hits.
    Projection proj;
    DataSurface& data = r >= data_from ? *refined_data : plain_data;
    if (carried_level != data.level) carried_count = -1;
    carried_level = data.level;
    if (carried_count == count) {
      proj = std::move(carried);
    } else if (carried_count > 0 && carried_count < count) {
      std::vector<SurfaceHit> hint(count);  // face -1: searched from scratch
      std::copy(carried.hits.begin(), carried.hits.end(), hint.begin());
      project(set, data, x, 1e300, &hint, proj);
    } else {
      project(set, data, x, 1e300, nullptr, proj);
    }
    std::vector<double> d(proj.hits.size());
    for (size_t i = 0; i < d.size(); ++i) d[i] = std::sqrt(proj.hits[i].squared_distance);
    std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
    const double tau = std::max(options.trim_factor * d[d.size() / 2], options.trim_floor_edges * edge);
    {
      double sum = 0;
      for (const auto& h : proj.hits) sum += std::min(h.squared_distance, tau * tau);
      proj.dist_energy = sum / set.size();
    }
    // The guard starts afresh each round: anchors a stiff round needed
    // would hold vertices off the data in the relaxed rounds.
    if (guarding) guard.reset(nv, inv_v);
    if (back_tree)
      back.find(*back_tree, points, x, mesh, terms.back_ignored, options, edge, nv, inv_v,
                options.back_ray_edges > 0 && r >= options.back_ray_first_round,
                &terms.back_surface, back_bvh.empty() ? nullptr : &back_bvh);
    if (back_tree) result.back_ray_planes += back.rays;
    GlobalFitIteration scratch;
    double e_old = energy_parts(x, proj.dist_energy, lambda, scratch);

    SpMat h_reg = SpMat(h_smooth * lambda) + h_fixed + h_rest;
    VecX g_reg = g_smooth * lambda + g_fixed + g_rest;
    if (!back.vertex.empty()) {
      h_reg += back.hessian;
      g_reg += back.gradient;
    }
    if (r == 0) result.back_vertices_first = static_cast<int>(back.vertex.size());
    result.back_vertices = static_cast<int>(back.vertex.size());
    const double w = 1.0 / set.size();
    const double beta = options.point_to_point_weight;

    for (int it = 0; it < max_iterations; ++it) {
      if (!report(progress, "global_fitting", std::min(1.0, double(done_iterations) / total_iterations)))
        return Status::error(ErrorCode::Cancelled, "global fit cancelled");
      ++done_iterations;

      // Data term, accumulated per triangle as 9x9 blocks (the corners'
      // coordinates), so the assembly cost does not grow with the triplets.
      // On a refined data surface the blocks are over its vertices y = S x,
      // and the term is taken to the control vertices as S^T H_y S, S^T g_y.
      const int nf = data.mesh.num_triangles();
      const int ny = static_cast<int>(data.mesh.positions.size());
      std::vector<Eigen::Matrix<double, 9, 9>> blocks(nf, Eigen::Matrix<double, 9, 9>::Zero());
      // Level 0 adds the rows straight into g (g_y is g), level L into g_y.
      VecX g = g_reg;
      VecX g_refined;
      if (data.level > 0) g_refined = VecX::Zero(3 * ny);
      VecX& g_y = data.level > 0 ? g_refined : g;
      const double tau2 = tau * tau;
      for (size_t i = 0; i < set.size(); ++i) {
        const SurfaceHit& h = proj.hits[i];
        if (h.face < 0 || h.squared_distance > tau2) continue;
        const Vec3& p = set[i];
        const Tri& tri = data.mesh.triangles[h.face];
        Vec3 n = p - h.point;
        const double len = n.norm();
        if (len > 1e-12 * edge) {
          n /= len;
        } else {
          n = face_normal_area(data.mesh, h.face);
          const double nl = n.norm();
          if (nl <= 0) continue;
          n /= nl;
        }
        Eigen::Matrix<double, 9, 1> a;
        for (int k = 0; k < 3; ++k) a.segment<3>(3 * k) = h.barycentric[k] * n;
        auto& B = blocks[h.face];
        B.noalias() += w * a * a.transpose();
        const double np = n.dot(p);
        for (int k = 0; k < 3; ++k) {
          for (int l = 0; l < 3; ++l) {
            const double bb = w * beta * h.barycentric[k] * h.barycentric[l];
            for (int c = 0; c < 3; ++c) B(3 * k + c, 3 * l + c) += bb;
          }
          g_y.segment<3>(3 * tri[k]) += w * (a.segment<3>(3 * k) * np + beta * h.barycentric[k] * p);
        }
      }
      SpMat h_data(3 * nv, 3 * nv);
      if (data.level > 0) {
        h_data = data.to_control(blocks);
        g += data.S3.transpose() * g_y;
        for (int i = 0; i < 3 * nv; ++i) h_data.coeffRef(i, i) += tikhonov * w;  // in the pattern
      } else {
        std::vector<Triplet> trip;
        trip.reserve(size_t(nf) * 81 + 3 * nv);
        for (int f = 0; f < nf; ++f) {
          const Tri& tri = data.mesh.triangles[f];
          for (int k = 0; k < 3; ++k)
            for (int l = 0; l < 3; ++l)
              for (int c = 0; c < 3; ++c)
                for (int e = 0; e < 3; ++e)
                  trip.emplace_back(3 * tri[k] + c, 3 * tri[l] + e, blocks[f](3 * k + c, 3 * l + e));
        }
        for (int i = 0; i < 3 * nv; ++i) trip.emplace_back(i, i, tikhonov * w);
        h_data.setFromTriplets(trip.begin(), trip.end());
      }
      g += (tikhonov * w) * x;
      const SpMat h_data_reg = h_data + h_reg;

      const bool last_step_of_fit = last_round && it == max_iterations - 1;
      GlobalFitIteration rec;
      rec.round = r;
      rec.points = count;
      rec.smooth_weight = lambda;
      rec.trim_distance = tau;
      bool accepted = false;
      VecX x_new;
      Projection proj_new;
      // Triangles already turned at x may stay so (the guard works on
      // them); no other may turn in this step.
      std::vector<char> turned_at_x(mesh.triangles.size(), 0);
      if (guarding)
        for (int f : guard.turned(mesh.triangles, x)) turned_at_x[f] = 1;
      auto new_turns = [&](const VecX& xt) {
        std::vector<int> fresh;
        for (int f : guard.turned(mesh.triangles, xt))
          if (!turned_at_x[f]) fresh.push_back(f);
        return fresh;
      };
      // Likewise pairs already crossing at x may stay (the input's); no
      // other pair may come to cross. Returns the triangles of new pairs.
      // `candidates` are the swept_candidates of the current solve: every
      // pair that can cross at xt on the segment from x to x_star, so the
      // pairs found crossing are all that cross at xt.
      std::vector<std::array<int, 2>> candidates;
      auto new_crossings = [&](const VecX& xt, std::vector<std::array<int, 2>>* all) {
        std::vector<int> faces;
        if (!crossing_guarded) return faces;
        from_vector(xt, check_mesh.positions);
        std::vector<std::array<int, 2>> pairs;
        for (const auto& p : candidates)
          if (mesh_triangles_cross(check_mesh.positions, mesh.triangles[p[0]], mesh.triangles[p[1]])) {
            pairs.push_back(p);
            if (!std::binary_search(crossing_at_x.begin(), crossing_at_x.end(), p)) {
              faces.push_back(p[0]);
              faces.push_back(p[1]);
            }
          }
        if (all) *all = std::move(pairs);
        return faces;
      };
      std::vector<std::array<int, 2>> crossing_at_new, crossing_at_full_step;
      bool full_step_crosses = false;
      // Solve; backtrack to the longest step that lowers E_global and turns
      // no triangle; when the full step would have turned some, stiffen
      // around them (fold guard) and solve again from the same x, at most
      // fold_guard_attempts times.
      for (int attempt = 0;; ++attempt) {
        const SpMat H = h_data_reg + guard.hessian;
        const VecX rhs = g + guard.gradient;
        // The matrix changes little between iterations (the correspondences
        // move, lambda steps down), so it is factorized once and later
        // iterations run conjugate gradients preconditioned by that factor:
        // a few cheap triangular solves instead of a new factorization. When
        // CG does not converge quickly the matrix is factorized afresh.
        VecX x_star;
        bool solved = false;
        // CG stops at |r| <= 1e-5 |rhs| within 12 iterations, else it has not converged quickly.
        if (factor_fresh_round >= 0) {
          cg.compute(H);
          x_star = cg.solveWithGuess(rhs, x);
          solved = cg.info() == Eigen::Success && x_star.allFinite();
        }
        if (!solved) {
          // (a matrix whose pattern changed is analyzed afresh)
          bool factorized = solver.analyzed() && solver.factorize(H);
          if (!factorized) factorized = solver.analyze(H) && solver.factorize(H);
          if (!factorized)
            return Status::error(ErrorCode::NotConverged, "global fit: the normal equations are singular");
          factor_fresh_round = r;
          x_star = solver.solve(rhs);
        }
        if (!x_star.allFinite())
          return Status::error(ErrorCode::NotConverged, "global fit: the solve produced non-finite positions");

        // The fold check is cheap, the energy (a projection) is not: a full
        // step that would turn triangles is answered by stiffening at once.
        rec.energy_before = e_old;
        accepted = false;
        std::vector<int> folds_of_full_step;
        if (guarding) {
          folds_of_full_step = new_turns(x_star);
          if (crossing_guarded) candidates = swept_candidates(mesh.triangles, x, x_star);
          const std::vector<int> crossed = new_crossings(x_star, &crossing_at_full_step);
          full_step_crosses = !crossed.empty();
          folds_of_full_step.insert(folds_of_full_step.end(), crossed.begin(), crossed.end());
        }
        if (!folds_of_full_step.empty() && attempt < options.fold_guard_attempts) {
          const int raised = guard.stiffen(folds_of_full_step, mesh.triangles, x, options);
          if (raised > 0) {
            rec.stiffened += raised;
            guard.rebuild(inv_v);
            e_old = energy_parts(x, proj.dist_energy, lambda, scratch);
            continue;
          }
        }
        // Backtracking on the true energy: the linearization is exact only
        // at the current correspondences.
        double step = 1.0;
        for (int bt = 0; bt < 6; ++bt, step *= 0.5) {
          const VecX xt = x + step * (x_star - x);
          if (guarding && !new_turns(xt).empty()) continue;
          if (crossing_guarded) {
            // The full step was checked above.
            if (bt == 0) {
              if (full_step_crosses) continue;
              crossing_at_new = crossing_at_full_step;
            } else if (!new_crossings(xt, &crossing_at_new).empty()) {
              continue;
            }
          }
          Projection trial;
          GlobalFitIteration parts;
          // The fit's last step: nothing uses its projection afterwards, so
          // an upper bound of E_dist (each point's distance to the triangle
          // it projected to at x, which its true closest point can only
          // beat) accepts the step when it already lowers E_global, and the
          // points are projected only otherwise. Same steps as with exact
          // projections (a step the bound accepts, they accept too); only
          // this iteration's energy_after and e_dist are the bound.
          bool bounded = false;
          double e_new = 0;
          if (last_step_of_fit) {
            const double bound = distance_energy_bound(set, data.mesh.triangles, data.map(xt), tau, proj.hits);
            e_new = energy_parts(xt, bound, lambda, parts);
            bounded = e_new <= e_old;
          }
          if (!bounded) {
            project(set, data, xt, tau, &proj.hits, trial);
            e_new = energy_parts(xt, trial.dist_energy, lambda, parts);
          }
          if (e_new <= e_old) {
            rec.energy_after_is_bound = bounded;
            accepted = true;
            x_new = xt;
            proj_new = std::move(trial);
            rec.energy_after = e_new;
            rec.e_dist = parts.e_dist;
            rec.e_smooth = parts.e_smooth;
            rec.e_binding = parts.e_binding;
            rec.e_constraint = parts.e_constraint;
            rec.e_guard = parts.e_guard;
            rec.step = step;
            break;
          }
        }
        break;
      }
      if (!accepted) {
        data.set(x);  // project() left a trial in data.mesh
        rec.energy_before = e_old;
        rec.energy_after = e_old;
        energy_parts(x, proj.dist_energy, lambda, rec);
        rec.step = 0;
        rec.turned = static_cast<int>(guard.turned(mesh.triangles, x).size());
        result.iterations.push_back(rec);
        break;
      }
      data.set(x_new);
      x = std::move(x_new);
      if (crossing_guarded) crossing_at_x = std::move(crossing_at_new);
      proj = std::move(proj_new);
      rec.turned = static_cast<int>(guard.turned(mesh.triangles, x).size());
      result.iterations.push_back(rec);
      const double change = (e_old - rec.energy_after) / std::max(e_old, 1e-300);
      e_old = rec.energy_after;
      if (change < options.relative_tolerance) break;
    }
    carried = std::move(proj);
    carried_count = count;
    // The last step may have been accepted on a bound without projecting
    // (see above): a following pass projects afresh.
    if (!result.iterations.empty() && result.iterations.back().energy_after_is_bound) carried_count = -1;

    if (r == base_rounds - 1 && terms.after_rounds) {
      std::vector<Vec3> now(nv);
      from_vector(x, now);
      if (!terms.after_rounds(now)) {
        result.stopped_after_rounds = true;
        break;
      }
    }
    if (smooth_guarded && r == rounds - 1) {
      const std::vector<std::array<int, 2>> fresh =
          smooth_check.new_pairs_at(x, active_level, active_level_list, mesh.triangles, terms.smooth_guard_ignored);
      const int n = static_cast<int>(fresh.size());
      if (r == base_rounds - 1) result.smooth_crossing_before = n;
      // A pass that does not lower the count ends the guard: stiffer
      // weights then only moved the crossings to the rim of the weighed
      // patch (measured: Fran 53 -> 18 -> 4 -> 9 -> 18 pairs over four
      // passes, James 140 -> 72 -> 99).
      const bool improved = smooth_best_pairs < 0 || n < smooth_best_pairs;
      if (improved) smooth_best_pairs = n, smooth_best = x;
      if (n > 0 && improved && result.smooth_guard_passes < options.smooth_guard_passes) {
        // The corners of the control faces under each pair and their rings:
        // every control vertex whose umbrella row shapes those faces' level.
        std::vector<char> raise(nv, 0);
        for (const auto& p : fresh)
          for (int f : p)
            for (int v : mesh.triangles[f / smooth_check.faces_per_control]) {
              raise[v] = 1;
              for (int u : topology.rings[v]) raise[u] = 1;
            }
        for (int v = 0; v < nv; ++v) {
          if (!raise[v]) continue;
          if (rest_weight[v] == 0) ++result.smooth_guard_vertices;
          rest_weight[v] = rest_weight[v] > 0
                               ? std::min(rest_weight[v] * options.smooth_guard_factor, options.smooth_guard_max_stiffness)
: options.smooth_guard_stiffness;
        }
        rebuild_rest();
        // The level triangles whose control face has a weighed corner: where
        // the next pass changes the shape, searched again after it.
        const int per = smooth_check.faces_per_control;
        active_level.assign(size_t(mesh.num_triangles()) * per, 0);
        active_level_list.clear();
        std::vector<char> near(nv, 0);  // weighed vertices and their rings
        for (int v = 0; v < nv; ++v)
          if (rest_weight[v] > 0) {
            near[v] = 1;
            for (int u : topology.rings[v]) near[u] = 1;
          }
        for (int f = 0; f < mesh.num_triangles(); ++f) {
          const Tri& t = mesh.triangles[f];
          if (!(near[t[0]] || near[t[1]] || near[t[2]])) continue;
          for (int c = 0; c < per; ++c) active_level[f * per + c] = 1, active_level_list.push_back(f * per + c);
        }
        ++result.smooth_guard_passes;
        ++rounds;
      }
    }
  }
  if (result.stopped_after_rounds) smooth_guarded = false;
  if (smooth_guarded) {
    if (smooth_best_pairs >= 0 && smooth_best.size() == x.size()) x = smooth_best;
    result.smooth_crossing_after = std::max(0, smooth_best_pairs);
  }
  if (smooth_guarded && options.smooth_guard_relief_level > 0 && options.smooth_guard_relief_steps > 0) {
    // Fold relief (header comment): the smooth level smooth_guard_relief_level
    // may fold inside a control face or two that share a corner although
    // the guarded level does not cross there (James: 42 of his 48 smooth
    // level-3 pairs inside three sliver faces, none on level 2). Each fold
    // is a kink of a few control vertices: their umbrella vectors step
    // towards the template's, cluster by cluster, with the share (a line
    // search) that leaves the fewest folds anywhere.
    SmoothSurfaceCheck relief;
    const int per = 1 << (2 * options.smooth_guard_relief_level);
    bool relieving =
        build_butterfly_levels(mesh, terms.smooth_creases, options.smooth_guard_relief_level, relief.levels).ok();
    if (relieving) {
      relief.faces_per_control = per;
      relief.reference_level = relief.refine(reference);
      // The whole-level search (~100 ms on the generic head's level 3) only
      // where the level turns a triangle against the reference's: a fold
      // turns one (test_global_fold_relief.cpp).
      if (options.smooth_guard_relief_when_turned)
        relieving = count_turned_triangles(relief.levels.back().fine_triangles, relief.refine(x),
                                           relief.reference_level) > 0;
    }
    result.relief_searched = relieving;
    if (relieving) {
      std::vector<char> pinned(nv, 0);  // held by E_constraint or ignored by the guard: never moved
      for (int v : terms.constrained_vertices) pinned[v] = 1;
      for (size_t v = 0; v < terms.smooth_guard_ignored.size(); ++v)
        if (terms.smooth_guard_ignored[v]) pinned[v] = 1;
      // A fold: both control faces share a corner (two sheets meeting are
      // the guard's and the untangling's).
      auto keep_folds = [&](std::vector<std::array<int, 2>>& pairs) {
        size_t kept = 0;
        for (const auto& p : pairs) {
          bool shared = false;
          for (int a : mesh.triangles[p[0] / per])
            for (int b : mesh.triangles[p[1] / per]) shared |= a == b;
          if (shared) pairs[kept++] = p;
        }
        pairs.resize(kept);
      };
      // Pairs inside the control faces the guard ignores (the mouth bag)
      // are not the relief's.
      auto drop_ignored = [&](std::vector<std::array<int, 2>>& pairs) {
        relief.drop_ignored(pairs, mesh.triangles, terms.smooth_guard_ignored);
      };
      MeshBvh* start_tree = terms.relief_start_tree;
      if (start_tree && !start_tree->empty() && start_tree->triangles == relief.levels.back().fine_triangles &&
          start_tree->positions.size() == relief.reference_level.size()) {
        relief.bvh = std::move(*start_tree);
        *start_tree = MeshBvh{};
      }
      std::vector<char> no_active;
      std::vector<int> no_list;
      std::vector<std::array<int, 2>> current =
          relief.new_pairs_at(x, no_active, no_list, mesh.triangles, terms.smooth_guard_ignored);
      const std::vector<std::array<int, 2>> pairs_before_relief = current;
      const VecX x_before_relief = x;
      keep_folds(current);
      result.relief_folds_before = static_cast<int>(current.size());
      const int turned_start = static_cast<int>(guard.turned(mesh.triangles, x).size());
      const int crossing_start = static_cast<int>(crossing_pairs(x, check_mesh).size());
      std::vector<char> moved_ever(nv, 0), active(size_t(mesh.num_triangles()) * per, 0);
      // The folds at trial positions that differ from x at the control
      // vertices `moving`: Butterfly's stencils reach about two rings, so
      // the level changes only inside the control faces with a corner
      // within three rings of a moving vertex (`active` 2); a fold there has
      // both faces within four rings (they share a corner). Those faces'
      // level triangles are searched on their own tree, the pairs of
      // `current` outside `active` stay.
      // `outside`: the pairs kept for the level triangles outside `active`;
      // `folds_only`: the window's pairs are filtered to folds.
      // The last window's triangles and tree, and the control vertices it
      // was made for: the next call for the same vertices (the line
      // search's next share, a cluster tried again in the next sweep) refits
      // that tree to its positions instead of building one (a refitted tree
      // finds the same pairs: self_intersection.h).
      TriMesh window;
      std::vector<int> window_faces, window_moving;  // level triangle ids; the vertices `active` was set for
      MeshBvh window_bvh;
      bool window_built = false;
      auto pairs_in_window = [&](const std::vector<Vec3>& level_positions, const std::vector<Vec3>& reference_level,
                                 const std::vector<int>& moving, const std::vector<std::array<int, 2>>& outside,
                                 bool folds_only) {
        window.positions = level_positions;
        bool searchable = false;
        if (window_built && moving == window_moving) {
          searchable = refit_bvh(window, window_bvh).ok();
        } else {
          const std::vector<int> ring_of = ring_distances(topology, moving, 4);
          window.triangles.clear();
          window_faces.clear();
          std::fill(active.begin(), active.end(), 0);
          for (int f = 0; f < mesh.num_triangles(); ++f) {
            int nearest = 1 << 20;
            for (int v : mesh.triangles[f])
              if (ring_of[v] >= 0) nearest = std::min(nearest, ring_of[v]);
            if (nearest > 4) continue;
            for (int c = 0; c < per; ++c) {
              window_faces.push_back(f * per + c);
              window.triangles.push_back(relief.level.triangles[f * per + c]);
              active[f * per + c] = nearest <= 3 ? 2 : 1;  // 2: may change, 1: searched beside it
            }
          }
          window_moving = moving;
          searchable = window_built = build_bvh(window, window_bvh).ok();
        }
        std::vector<std::array<int, 2>> pairs;
        if (searchable) find_new_self_intersections(window_bvh, reference_level, pairs);
        for (auto& p : pairs) {
          p = {window_faces[p[0]], window_faces[p[1]]};
          if (p[0] > p[1]) std::swap(p[0], p[1]);
        }
        drop_ignored(pairs);
        if (folds_only) keep_folds(pairs);
        // A pair that may have changed was searched again, unless its other
        // triangle lies outside the window (two sheets far apart in the
        // mesh): that one is kept as it was, and the whole-level search
        // that decides in the end counts it.
        for (const auto& p : outside)
          if ((active[p[0]] != 2 && active[p[1]] != 2) || !active[p[0]] || !active[p[1]]) pairs.push_back(p);
        std::sort(pairs.begin(), pairs.end());
        pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
        return pairs;
      };
      auto folds_at = [&](const VecX& trial, const std::vector<int>& moving) {
        return pairs_in_window(relief.refine(trial), relief.reference_level, moving, current, true);
      };
      // The flagged vertices in groups connected over the mesh.
      auto connected_clusters = [&](const std::vector<char>& corner) {
        std::vector<int> cluster_of(nv, -1);
        std::vector<std::vector<int>> clusters;
        for (int v = 0; v < nv; ++v) {
          if (!corner[v] || cluster_of[v] >= 0) continue;
          clusters.emplace_back();
          std::vector<int> stack = {v};
          cluster_of[v] = static_cast<int>(clusters.size()) - 1;
          while (!stack.empty()) {
            const int u = stack.back();
            stack.pop_back();
            clusters.back().push_back(u);
            for (int w : topology.rings[u])
              if (corner[w] && cluster_of[w] < 0) cluster_of[w] = cluster_of[u], stack.push_back(w);
          }
        }
        return clusters;
      };
      // The unpinned corners of the control faces holding these level triangles.
      auto corners_of = [&](const std::vector<int>& level_faces) {
        std::vector<char> corner(nv, 0);
        for (int f : level_faces)
          for (int v : mesh.triangles[f / per])
            if (!pinned[v]) corner[v] = 1;
        return corner;
      };
      std::vector<char> failed(nv, 0);
      for (int step = 0; step < options.smooth_guard_relief_steps && !current.empty(); ++step) {
        // Clusters: corners of the folding faces, connected over the mesh.
        std::vector<int> folding;
        for (const auto& p : current) folding.insert(folding.end(), p.begin(), p.end());
        bool progress_made = false;
        for (const std::vector<int>& cluster : connected_clusters(corners_of(folding))) {
          // A cluster no share helped in the previous sweep is not tried
          // again unless a neighbour's step changed it.
          if (std::all_of(cluster.begin(), cluster.end(), [&](int v) { return failed[v]; })) continue;
          VecX best_x;
          std::vector<std::array<int, 2>> best_pairs;
          const VecX residual = smooth.R * x - smooth.b;  // L(v) - L0(v), the same for every share
          for (double share : options.smooth_guard_relief_shares) {
            VecX trial = x;
            for (int v : cluster) trial.segment<3>(3 * v) -= share * residual.segment<3>(3 * v);
            if (static_cast<int>(guard.turned(mesh.triangles, trial).size()) > turned_start ||
                static_cast<int>(crossing_pairs(trial, check_mesh).size()) > crossing_start)
              continue;
            std::vector<std::array<int, 2>> pairs = folds_at(trial, cluster);
            if (pairs.size() < (best_x.size() ? best_pairs.size() : current.size()))
              best_x = std::move(trial), best_pairs = std::move(pairs);
          }
          for (int v : cluster) failed[v] = best_x.size() == 0;
          if (best_x.size()) {
            x = std::move(best_x);
            current = std::move(best_pairs);
            for (int v : cluster) moved_ever[v] = 1;
            ++result.relief_steps;
            progress_made = true;
          }
        }
        if (!progress_made) break;
      }
      // The window searches steer the steps; whether the relief is kept is
      // decided on all new pairs of the whole level (folds or not), which
      // must be fewer than before it. all_new_pairs gives the set a
      // whole-level search at `at` would: the level differs from the first
      // search's (relief.level, at x_before_relief) only where the steps
      // moved it, so a pair of two unmoved triangles is the first search's,
      // and only the moved triangles are searched again, on the first
      // search's tree refit (a refit tree and a fresh one give the same
      // pairs since the pair test's orientations are filtered).
      // The level's new pairs after the triangles `moved` (listed, and
      // marked in moved_mark, #level F) changed, relief.bvh already fitted
      // to the new positions: those triangles searched again, and the pairs
      // of `base` (the new pairs before) between two unmoved ones kept.
      auto pairs_after_move = [&](const std::vector<int>& moved, const std::vector<char>& moved_mark,
                                  const std::vector<std::array<int, 2>>& base) {
        std::vector<std::array<int, 2>> found;
        find_new_self_intersections(relief.bvh, relief.reference_level, found, &moved);
        drop_ignored(found);
        return pairs_after_change(base, moved_mark, found);
      };
      auto all_new_pairs = [&](const VecX& at, std::vector<std::array<int, 2>>& pairs) {
        std::vector<Vec3> now = relief.refine(at);
        std::vector<char> moved;
        std::vector<int> moved_list;
        moved_triangles(relief.level.triangles, relief.level.positions, now, moved, moved_list);
        relief.level.positions = std::move(now);
        refit_bvh(relief.level, relief.bvh);
        pairs = pairs_after_move(moved_list, moved, pairs_before_relief);
      };
      std::vector<std::array<int, 2>> all_now = pairs_before_relief;  // the level's new pairs at x
      if (result.relief_steps > 0) {
        std::vector<std::array<int, 2>> after;
        all_new_pairs(x, after);
        if (after.size() < pairs_before_relief.size()) {
          all_now = after;
          keep_folds(after);
          result.relief_folds_after = static_cast<int>(after.size());
        } else {
          x = x_before_relief;
          relief.level.positions = relief.refine(x);  // where the first search's pairs are
          result.relief_folds_after = result.relief_folds_before;
          result.relief_steps = 0;
          std::fill(moved_ever.begin(), moved_ever.end(), 0);
        }
      } else {
        result.relief_folds_after = result.relief_folds_before;
      }
      if (options.smooth_guard_pleat_steps > 0) {
        // Pleats (header comment): level edges bent by more than 90 deg
        // where the reference's bend by less than 45, crossing nothing. The
        // same steps, scored by the pleat edges of the whole level; a step
        // may not add a new pair anywhere on the level. relief.level.positions
        // is the level at x and all_now its new pairs: a trial's pairs are
        // those of the triangles it moved, searched again on the tree refit,
        // and the rest of all_now (as all_new_pairs).
        const std::vector<Tri>& fine = relief.level.triangles;
        const int nf = static_cast<int>(fine.size());
        auto ignored_level_face = [&](int f) {
          return ignored_face(mesh.triangles[f / per], terms.smooth_guard_ignored);
        };
        // The tree at the level's positions (a reverted relief left it at
        // its steps'); each vertex's level triangles, for the edges below
        // and for refits of the moved vertices alone.
        refit_bvh(relief.level, relief.bvh);
        BvhRefitIndex refit_index;
        build_refit_index(relief.bvh, refit_index);
        const std::vector<int>& vt_offsets = refit_index.vertex_offsets;
        const std::vector<int>& vt = refit_index.vertex_triangles;
        // The level's interior edges as their two triangles, outside
        // ignored faces, those the reference bends by 45 deg or more left
        // out; each face's such edges (face_edges, at most 3).
        std::vector<std::array<int, 2>> edge_faces;
        std::vector<std::array<int, 3>> face_edges(nf, {-1, -1, -1});
        {
          std::vector<Vec3> ref_normal(nf);
          const std::vector<Vec3>& r = relief.reference_level;
          for (int f = 0; f < nf; ++f) {
            const Tri& t = fine[f];
            ref_normal[f] = (r[t[1]] - r[t[0]]).cross(r[t[2]] - r[t[0]]).normalized();
          }
          auto add_edge = [&](int f, int g) {
            const int e = static_cast<int>(edge_faces.size());
            edge_faces.push_back({f, g});
            for (int h : {f, g})
              for (int& slot : face_edges[h])
                if (slot < 0) {
                  slot = e;
                  break;
                }
          };
          const double cos45 = std::sqrt(0.5);
          for (int f = 0; f < nf; ++f) {
            if (ignored_level_face(f)) continue;
            for (int k = 0; k < 3; ++k) {
              const int a = fine[f][k], b = fine[f][(k + 1) % 3];
              for (int i = vt_offsets[a]; i < vt_offsets[a + 1]; ++i) {
                const int g = vt[i];
                if (g <= f || (fine[g][0] != b && fine[g][1] != b && fine[g][2] != b)) continue;
                if (ignored_level_face(g)) continue;
                if (ref_normal[f].dot(ref_normal[g]) > cos45) add_edge(f, g);
              }
            }
          }
        }
        // Whether edge e bends by more than 90 deg at `level`.
        auto pleated = [&](const std::vector<Vec3>& level, int e) -> char {
          const Tri& a = fine[edge_faces[e][0]];
          const Tri& b = fine[edge_faces[e][1]];
          const Vec3 na = (level[a[1]] - level[a[0]]).cross(level[a[2]] - level[a[0]]);
          const Vec3 nb = (level[b[1]] - level[b[0]]).cross(level[b[2]] - level[b[0]]);
          return na.dot(nb) < 0;
        };
        std::vector<char> is_pleat(edge_faces.size(), 0);
        int pleats_now = 0;
        for (size_t e = 0; e < edge_faces.size(); ++e)
          pleats_now += is_pleat[e] = pleated(relief.level.positions, static_cast<int>(e));
        result.pleats_before = result.pleats_after = pleats_now;
        // A step moves no vertex farther than this (the mean control edge
        // times smooth_guard_pleat_max_move_edges).
        double mean_edge = 0;
        for (const Edge& e : topology.edges) mean_edge += (x.segment<3>(3 * e.v0) - x.segment<3>(3 * e.v1)).norm();
        const double max_move =
            options.smooth_guard_pleat_max_move_edges * mean_edge / std::max<size_t>(1, topology.edges.size());
        const VecX x_before_pleats = x;
        std::vector<char> failed_pleat(nv, 0), face_mark(nf, 0), edge_mark(edge_faces.size(), 0);
        for (int step = 0; step < options.smooth_guard_pleat_steps && pleats_now > 0; ++step) {
          std::vector<int> pleated_faces;
          for (size_t e = 0; e < edge_faces.size(); ++e)
            if (is_pleat[e]) pleated_faces.insert(pleated_faces.end(), edge_faces[e].begin(), edge_faces[e].end());
          bool progress_made = false;
          for (const std::vector<int>& cluster : connected_clusters(corners_of(pleated_faces))) {
            if (std::all_of(cluster.begin(), cluster.end(), [&](int v) { return failed_pleat[v]; })) continue;
            VecX best_x;
            int best_count = pleats_now;
            std::vector<std::pair<int, char>> best_changes;  // edges whose pleat state flips
            std::vector<std::array<int, 2>> best_pairs;
            std::vector<Vec3> best_level;
            std::vector<int> best_moved;  // its moved level vertices
            const VecX residual = smooth.R * x - smooth.b;
            for (double share : options.smooth_guard_relief_shares) {
              if (std::any_of(cluster.begin(), cluster.end(),
                              [&](int v) { return share * residual.segment<3>(3 * v).norm() > max_move; }))
                continue;
              VecX trial = x;
              for (int v : cluster) trial.segment<3>(3 * v) -= share * residual.segment<3>(3 * v);
              if (static_cast<int>(guard.turned(mesh.triangles, trial).size()) > turned_start ||
                  static_cast<int>(crossing_pairs(trial, check_mesh).size()) > crossing_start)
                continue;
              std::vector<Vec3> level = relief.refine(trial);
              // What moved: its vertices, their triangles, those's edges.
              std::vector<int> moved_vertices, moved_faces, moved_edges;
              for (int v = 0; v < static_cast<int>(level.size()); ++v)
                if (level[v] != relief.level.positions[v]) {
                  moved_vertices.push_back(v);
                  for (int i = vt_offsets[v]; i < vt_offsets[v + 1]; ++i)
                    if (!face_mark[vt[i]]) face_mark[vt[i]] = 1, moved_faces.push_back(vt[i]);
                }
              for (int f : moved_faces)
                for (int e : face_edges[f])
                  if (e >= 0 && !edge_mark[e]) edge_mark[e] = 1, moved_edges.push_back(e);
              for (int f : moved_faces) face_mark[f] = 0;
              int count = pleats_now;
              std::vector<std::pair<int, char>> changes;
              for (int e : moved_edges) {
                edge_mark[e] = 0;
                const char now = pleated(level, e);
                if (now != is_pleat[e]) changes.push_back({e, now}), count += now ? 1 : -1;
              }
              if (count >= best_count) continue;
              // No new pair anywhere on the level: the moved triangles
              // searched again on the tree refit there (and back after).
              std::sort(moved_faces.begin(), moved_faces.end());
              const Status refit = refit_bvh_vertices(relief.bvh, refit_index, level, moved_vertices);
              std::vector<std::array<int, 2>> pairs;
              if (refit.ok()) {
                for (int f : moved_faces) face_mark[f] = 1;
                pairs = pairs_after_move(moved_faces, face_mark, all_now);
                for (int f : moved_faces) face_mark[f] = 0;
              }
              refit_bvh_vertices(relief.bvh, refit_index, relief.level.positions, moved_vertices);
              if (!refit.ok() || pairs.size() > all_now.size()) continue;
              best_x = std::move(trial), best_count = count, best_changes = std::move(changes);
              best_pairs = std::move(pairs), best_level = std::move(level), best_moved = std::move(moved_vertices);
            }
            for (int v : cluster) failed_pleat[v] = best_x.size() == 0;
            if (best_x.size()) {
              x = std::move(best_x);
              pleats_now = best_count;
              for (const auto& [e, now] : best_changes) is_pleat[e] = now;
              all_now = std::move(best_pairs);
              relief.level.positions = std::move(best_level);
              // The trials put the tree back where the level was: it follows
              // the step (later trials search against it).
              refit_bvh_vertices(relief.bvh, refit_index, relief.level.positions, best_moved);
              for (int v : cluster) moved_ever[v] = 1;
              ++result.pleat_steps;
              result.pleat_step_vertices.push_back(cluster);
              progress_made = true;
            }
          }
          if (!progress_made) break;
        }
        result.pleats_after = pleats_now;
        if (result.pleat_steps > 0) {
          result.pleat_shift.resize(nv);
          from_vector(VecX(x - x_before_pleats), result.pleat_shift);
          std::vector<std::array<int, 2>> folds = all_now;
          keep_folds(folds);
          result.relief_folds_after = static_cast<int>(folds.size());
        }
      }
      for (int v = 0; v < nv; ++v) result.relief_vertices += moved_ever[v];
      if (options.smooth_guard_crease_max_edges > 0 && result.relief_folds_after > 0) {
        // Fold creases (header comment): the folds the steps left, as the
        // whole level has them now. A crease is judged by all the new pairs
        // around it, folds or not: one that trades folds for two sheets
        // crossing does not pass (James turned 0.05 deg: 44 -> 23 folds,
        // but 102 -> 123 pairs when only folds were counted).
        std::vector<std::array<int, 2>> pairs = all_now, folds = all_now;
        keep_folds(folds);
        std::vector<Vec3> control(nv), reference_positions(nv);
        from_vector(x, control);
        from_vector(reference, reference_positions);
        auto unit_normal = [&](int f) {
          const Tri& t = mesh.triangles[f];
          return (control[t[1]] - control[t[0]]).cross(control[t[2]] - control[t[0]]).normalized();
        };
        const double cos_min = std::cos(options.smooth_guard_crease_min_angle_deg * std::acos(-1.0) / 180.0);
        ButterflyCreases creases = terms.smooth_creases;
        std::vector<char> creased(topology.edges.size(), 0), tried(topology.edges.size(), 0);
        for (const auto& e : creases.edges) {
          const int k = topology.find_edge(e[0], e[1]);
          if (k >= 0) creased[k] = 1;
        }
        // The relief level refined with `with` (the control at x and the
        // reference); false when the creases cannot be refined.
        std::vector<ButterflyLevel> trial_levels;
        std::vector<std::vector<Vec3>> refined;
        auto refine_with = [&](const ButterflyCreases& with, std::vector<Vec3>& level, std::vector<Vec3>& ref_level) {
          if (!build_butterfly_levels(mesh, with, options.smooth_guard_relief_level, trial_levels).ok()) return false;
          apply_all(trial_levels, reference_positions, refined);
          ref_level = std::move(refined.back());
          apply_all(trial_levels, control, refined);
          level = std::move(refined.back());
          return true;
        };
        std::vector<Vec3> trial_level, trial_reference, kept_level, kept_reference;  // kept: of `creases`
        std::vector<std::array<int, 2>> chosen;
        for (int trial = 0; trial < options.smooth_guard_crease_trials && !folds.empty() &&
                            static_cast<int>(chosen.size()) < options.smooth_guard_crease_max_edges;
             ++trial) {
          // The sharpest uncreased, untried edge of the folding faces.
          int pick = -1;
          double pick_cos = cos_min;
          for (const auto& p : folds)
            for (int f : {p[0] / per, p[1] / per})
              for (int k : topology.face_edges[f]) {
                const Edge& e = topology.edges[k];
                if (e.boundary() || creased[k] || tried[k]) continue;
                const double c = unit_normal(e.f0).dot(unit_normal(e.f1));
                if (c < pick_cos) pick_cos = c, pick = k;
              }
          if (pick < 0) break;
          tried[pick] = 1;
          ButterflyCreases with = creases;
          with.edges.push_back({topology.edges[pick].v0, topology.edges[pick].v1});
          close_crease_ends(with);
          if (!refine_with(with, trial_level, trial_reference)) continue;
          std::vector<std::array<int, 2>> now = pairs_in_window(
              trial_level, trial_reference, {topology.edges[pick].v0, topology.edges[pick].v1}, pairs, false);
          if (now.size() >= pairs.size()) continue;
          creases = std::move(with);
          kept_level.swap(trial_level);
          kept_reference.swap(trial_reference);
          creased[pick] = 1;
          pairs = std::move(now);
          folds = pairs;
          keep_folds(folds);
          chosen.push_back({topology.edges[pick].v0, topology.edges[pick].v1});
        }
        if (!chosen.empty()) {
          // Kept only when the whole level, with the creases (refined by
          // the last kept trial), has fewer new pairs (folds or not) than
          // without them.
          std::vector<std::array<int, 2>> all_creased;
          relief.level.positions = std::move(kept_level);
          refit_bvh(relief.level, relief.bvh);
          find_new_self_intersections(relief.bvh, kept_reference, all_creased);
          drop_ignored(all_creased);
          if (all_creased.size() < all_now.size()) {
            result.fold_crease_edges = chosen;
            keep_folds(all_creased);
            result.relief_folds_after = static_cast<int>(all_creased.size());
          }
        }
      }
    }
    if (relief_tree) *relief_tree = std::move(relief.bvh);
  }
  result.rounds = rounds;
  result.turned_after = static_cast<int>(guard.turned(mesh.triangles, x).size());
  result.crossing_after = static_cast<int>(crossing_pairs(x, check_mesh).size());
  for (const auto& it : result.iterations) result.guard_raises += it.stiffened;
  out = mesh;
  from_vector(x, out.positions);
  report(progress, "global_fitting", 1.0);
  return Status::success();
}

}  // namespace lk
