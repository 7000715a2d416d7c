#include "raycast/bvh.h"

#include "common/parallel.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace lk {

namespace {

// Deeper trees than this are forced into median splits, so the fixed-size
// traversal stacks below can never overflow (one entry per level).
constexpr int kMaxDepth = 48;
constexpr int kStackSize = 2 * kMaxDepth + 8;
// Meshes with at least this many triangles build their two top subtrees on
// two threads (natively; a thread start costs more than small builds).
constexpr int kMinParallelBuild = 20000;

struct BuildTri {
  Vec3 box_min, box_max, centroid;
};

double half_area(const Vec3& lo, const Vec3& hi) {
  const Vec3 d = (hi - lo).cwiseMax(Vec3::Zero());
  return d.x() * d.y() + d.y() * d.z() + d.z() * d.x();
}

struct Builder {
  const BvhOptions& opt;
  const std::vector<BuildTri>& tris;
  std::vector<int>& order;
  std::vector<BvhNode>& nodes;

  void make_leaf(int node, int begin, int end) {
    BvhNode& n = nodes[node];
    n.first = begin;
    n.count = end - begin;
  }

  // Builds the subtree over order[begin, end) into nodes[node].
  void build(int node, int begin, int end, int depth) {
    Vec3 lo = Vec3::Constant(1e300), hi = Vec3::Constant(-1e300);
    Vec3 clo = lo, chi = hi;
    for (int i = begin; i < end; ++i) {
      const BuildTri& t = tris[order[i]];
      lo = lo.cwiseMin(t.box_min);
      hi = hi.cwiseMax(t.box_max);
      clo = clo.cwiseMin(t.centroid);
      chi = chi.cwiseMax(t.centroid);
    }
    nodes[node].box_min = lo;
    nodes[node].box_max = hi;
    const int count = end - begin;
    if (count <= opt.max_leaf_triangles) return make_leaf(node, begin, end);

    int mid = -1;
    const Vec3 cext = chi - clo;
    if (depth < kMaxDepth - 8) mid = sah_split(begin, end, clo, cext, lo, hi);
    if (mid < 0) {
      // SAH found nothing better than a leaf, or the tree is getting deep:
      // a leaf when small enough, otherwise a median split on the widest axis.
      if (count <= 4 * opt.max_leaf_triangles && depth < kMaxDepth - 8)
        return make_leaf(node, begin, end);
      int axis = 0;
      cext.maxCoeff(&axis);
      mid = begin + count / 2;
      std::nth_element(order.begin() + begin, order.begin() + mid, order.begin() + end,
                       [&](int a, int b) {
                         if (tris[a].centroid[axis] != tris[b].centroid[axis])
                           return tris[a].centroid[axis] < tris[b].centroid[axis];
                         return a < b;  // ties broken by id: the build stays deterministic
                       });
    }
    if (depth == 0 && opt.threads && count >= kMinParallelBuild && parallel_workers() > 1) {
      // The two halves are independent (disjoint runs of `order`): built on
      // two threads into their own arrays, then spliced in the serial
      // depth-first layout (node, left subtree, right subtree), so the tree
      // is the same as a serial build's.
      std::vector<BvhNode> halves[2];
      parallel_for(0, 2, 1, [&](int side, int) {
        halves[side].emplace_back();
        Builder half{opt, tris, order, halves[side]};
        if (side == 0) half.build(0, begin, mid, depth + 1);
        else half.build(0, mid, end, depth + 1);
      });
      const int left = static_cast<int>(nodes.size());
      splice(halves[0], left);
      const int right = static_cast<int>(nodes.size());
      splice(halves[1], right);
      nodes[node].first = right;
      nodes[node].count = 0;
      return;
    }
    const int left = static_cast<int>(nodes.size());
    nodes.emplace_back();
    build(left, begin, mid, depth + 1);
    const int right = static_cast<int>(nodes.size());
    nodes.emplace_back();
    build(right, mid, end, depth + 1);
    nodes[node].first = right;
    nodes[node].count = 0;
  }

  // Appends a subtree built with its root at index 0, its inner nodes'
  // right-child indices moved by the offset it lands at (leaves index
  // `order`, which the halves share).
  void splice(const std::vector<BvhNode>& sub, int offset) {
    for (BvhNode n : sub) {
      if (!n.leaf()) n.first += offset;
      nodes.push_back(n);
    }
  }

  // Scratch of sah_split, kept across nodes (a build visits ~F/2 nodes; new
  // arrays per node and stable_partition's buffer were a fifth of its time).
  std::vector<int> bin_count;      // 3 * bins: per axis, per bin
  std::vector<Vec3> bin_lo, bin_hi;
  std::vector<double> right_cost;  // bins
  std::vector<int> spill;          // the right side while partitioning

  // Binned SAH; returns the partition point or -1 when splitting does not pay.
  int sah_split(int begin, int end, const Vec3& clo, const Vec3& cext, const Vec3& lo,
                const Vec3& hi) {
    const int nb = std::max(2, opt.sah_bins);
    const int count = end - begin;
    double best_cost = half_area(lo, hi) * count;  // cost of a leaf (traversal cost ~ 1 triangle)
    int best_axis = -1, best_bin = -1;
    bin_count.assign(3 * nb, 0);
    bin_lo.assign(3 * nb, Vec3::Constant(1e300));
    bin_hi.assign(3 * nb, Vec3::Constant(-1e300));
    right_cost.resize(nb);
    // All axes binned in one pass over the triangles (min / max are exact,
    // so the bins are those of one pass per axis).
    bool binned[3];
    double scale[3];
    for (int axis = 0; axis < 3; ++axis) {
      binned[axis] = cext[axis] > 0;
      scale[axis] = binned[axis] ? nb / cext[axis] : 0.0;
    }
    for (int i = begin; i < end; ++i) {
      const BuildTri& t = tris[order[i]];
      for (int axis = 0; axis < 3; ++axis) {
        if (!binned[axis]) continue;
        const int b =
            axis * nb + std::min(nb - 1, static_cast<int>((t.centroid[axis] - clo[axis]) * scale[axis]));
        ++bin_count[b];
        bin_lo[b] = bin_lo[b].cwiseMin(t.box_min);
        bin_hi[b] = bin_hi[b].cwiseMax(t.box_max);
      }
    }
    for (int axis = 0; axis < 3; ++axis) {
      if (!binned[axis]) continue;
      const int* counts = &bin_count[axis * nb];
      const Vec3* blo = &bin_lo[axis * nb];
      const Vec3* bhi = &bin_hi[axis * nb];
      // Sweep from the right, then from the left, evaluating the split after bin b.
      Vec3 rlo = Vec3::Constant(1e300), rhi = Vec3::Constant(-1e300);
      int rc = 0;
      for (int b = nb - 1; b > 0; --b) {
        rlo = rlo.cwiseMin(blo[b]);
        rhi = rhi.cwiseMax(bhi[b]);
        rc += counts[b];
        right_cost[b] = rc ? half_area(rlo, rhi) * rc : 0.0;
      }
      Vec3 llo = Vec3::Constant(1e300), lhi = Vec3::Constant(-1e300);
      int lc = 0;
      for (int b = 0; b < nb - 1; ++b) {
        llo = llo.cwiseMin(blo[b]);
        lhi = lhi.cwiseMax(bhi[b]);
        lc += counts[b];
        if (lc == 0 || lc == count) continue;
        // One node visit costs about half a triangle test.
        const double cost =
            0.5 * half_area(lo, hi) + half_area(llo, lhi) * lc + right_cost[b + 1];
        if (cost < best_cost) {
          best_cost = cost;
          best_axis = axis;
          best_bin = b;
        }
      }
    }
    if (best_axis < 0) return -1;
    // A stable partition (the order of each side kept, as std::stable_partition).
    spill.clear();
    int mid = begin;
    for (int i = begin; i < end; ++i) {
      const int id = order[i];
      const int b =
          std::min(nb - 1, static_cast<int>((tris[id].centroid[best_axis] - clo[best_axis]) * scale[best_axis]));
      if (b <= best_bin) order[mid++] = id;
      else spill.push_back(id);
    }
    std::copy(spill.begin(), spill.end(), order.begin() + mid);
    return (mid == begin || mid == end) ? -1 : mid;
  }
};

void triangle_box(const MeshBvh& bvh, int f, Vec3& lo, Vec3& hi) {
  const Tri& t = bvh.triangles[f];
  const Vec3& a = bvh.positions[t[0]];
  const Vec3& b = bvh.positions[t[1]];
  const Vec3& c = bvh.positions[t[2]];
  lo = a.cwiseMin(b).cwiseMin(c);
  hi = a.cwiseMax(b).cwiseMax(c);
}

Status check_mesh(const TriMesh& mesh) {
  for (size_t i = 0; i < mesh.positions.size(); ++i)
    if (!mesh.positions[i].allFinite())
      return Status::error(ErrorCode::InvalidInput,
                           "vertex " + std::to_string(i) + " has a non-finite coordinate");
  const int nv = mesh.num_vertices();
  for (size_t f = 0; f < mesh.triangles.size(); ++f)
    for (int v : mesh.triangles[f])
      if (v < 0 || v >= nv)
        return Status::error(ErrorCode::InvalidInput,
                             "triangle " + std::to_string(f) + " references vertex " +
                                 std::to_string(v) + " of " + std::to_string(nv));
  return Status::success();
}

// Slab test; returns the entry distance or +inf when the box is missed.
inline double ray_box(const Vec3& lo, const Vec3& hi, const Vec3& origin, const Vec3& inv_dir,
                      double t_min, double t_max) {
  double t0 = t_min, t1 = t_max;
  for (int k = 0; k < 3; ++k) {
    double a = (lo[k] - origin[k]) * inv_dir[k];
    double b = (hi[k] - origin[k]) * inv_dir[k];
    if (a > b) std::swap(a, b);
    // NaN (origin on a slab plane of a zero-direction axis) fails both
    // comparisons and so leaves the interval unchanged: the box is kept.
    if (a > t0) t0 = a;
    if (b < t1) t1 = b;
    if (t0 > t1) return std::numeric_limits<double>::infinity();
  }
  return t0;
}

// Möller-Trumbore; both faces count. Returns true with t, u, v on a hit.
inline bool ray_triangle(const Vec3& o, const Vec3& d, const Vec3& a, const Vec3& b,
                         const Vec3& c, double& t, double& u, double& v) {
  const Vec3 e1 = b - a, e2 = c - a;
  const Vec3 pv = d.cross(e2);
  const double det = e1.dot(pv);
  if (det == 0.0 || !std::isfinite(det)) return false;
  const double inv = 1.0 / det;
  const Vec3 tv = o - a;
  u = tv.dot(pv) * inv;
  if (u < 0.0 || u > 1.0) return false;
  const Vec3 qv = tv.cross(e1);
  v = d.dot(qv) * inv;
  if (v < 0.0 || u + v > 1.0) return false;
  t = e2.dot(qv) * inv;
  return true;
}

inline double box_distance2(const Vec3& lo, const Vec3& hi, const Vec3& p) {
  const Vec3 d = (lo - p).cwiseMax(p - hi).cwiseMax(Vec3::Zero());
  return d.squaredNorm();
}

template <bool kAnyHit>
RayHit traverse(const MeshBvh& bvh, const Ray& ray, int skip_triangle) {
  RayHit best;
  if (bvh.nodes.empty()) return best;
  const Vec3 inv(1.0 / ray.direction.x(), 1.0 / ray.direction.y(), 1.0 / ray.direction.z());
  double t_max = ray.t_max;
  int stack[kStackSize];
  int top = 0;
  if (ray_box(bvh.nodes[0].box_min, bvh.nodes[0].box_max, ray.origin, inv, ray.t_min, t_max) ==
      std::numeric_limits<double>::infinity())
    return best;
  stack[top++] = 0;
  while (top > 0) {
    const BvhNode& n = bvh.nodes[stack[--top]];
    if (n.leaf()) {
      for (int i = n.first; i < n.first + n.count; ++i) {
        const int f = bvh.triangle_order[i];
        if (f == skip_triangle) continue;
        const Tri& tri = bvh.triangles[f];
        double t, u, v;
        if (!ray_triangle(ray.origin, ray.direction, bvh.positions[tri[0]], bvh.positions[tri[1]],
                          bvh.positions[tri[2]], t, u, v))
          continue;
        if (t < ray.t_min || t > t_max) continue;
        best.triangle = f;
        best.t = t;
        best.barycentric = Vec3(1.0 - u - v, u, v);
        if (kAnyHit) return best;
        t_max = t;
      }
      continue;
    }
    const int left = static_cast<int>(&n - bvh.nodes.data()) + 1, right = n.first;
    const double tl = ray_box(bvh.nodes[left].box_min, bvh.nodes[left].box_max, ray.origin, inv,
                              ray.t_min, t_max);
    const double tr = ray_box(bvh.nodes[right].box_min, bvh.nodes[right].box_max, ray.origin, inv,
                              ray.t_min, t_max);
    const double inf = std::numeric_limits<double>::infinity();
    // Push the farther child first so the nearer one is searched first and
    // shrinks t_max for the other.
    if (tl < tr) {
      if (tr != inf) stack[top++] = right;
      stack[top++] = left;
    } else {
      if (tl != inf) stack[top++] = left;
      if (tr != inf) stack[top++] = right;
    }
  }
  return best;
}

}  // namespace

Status build_bvh(const TriMesh& mesh, MeshBvh& out, const BvhOptions& options) {
  out = MeshBvh{};
  Status s = check_mesh(mesh);
  if (!s.ok()) return s;
  if (options.max_leaf_triangles < 1)
    return Status::error(ErrorCode::InvalidInput, "max_leaf_triangles must be at least 1");
  out.triangles = mesh.triangles;
  out.positions = mesh.positions;
  const int nf = mesh.num_triangles();
  if (nf == 0) return Status::success();
  std::vector<BuildTri> tris(nf);
  for (int f = 0; f < nf; ++f) {
    triangle_box(out, f, tris[f].box_min, tris[f].box_max);
    tris[f].centroid = 0.5 * (tris[f].box_min + tris[f].box_max);
  }
  out.triangle_order.resize(nf);
  for (int f = 0; f < nf; ++f) out.triangle_order[f] = f;
  out.nodes.reserve(2 * nf / std::max(1, options.max_leaf_triangles) + 1);
  out.nodes.emplace_back();
  Builder b{options, tris, out.triangle_order, out.nodes};
  b.build(0, 0, nf, 0);
  return Status::success();
}

namespace {

// A leaf's box from its triangles, in leaf order; an inner node's from its
// children. The only box kernels of refit_bvh and refit_bvh_vertices, so the
// two agree bit for bit.
inline void refit_leaf(MeshBvh& bvh, BvhNode& n) {
  Vec3 lo = Vec3::Constant(1e300), hi = Vec3::Constant(-1e300), tlo, thi;
  for (int k = n.first; k < n.first + n.count; ++k) {
    triangle_box(bvh, bvh.triangle_order[k], tlo, thi);
    lo = lo.cwiseMin(tlo);
    hi = hi.cwiseMax(thi);
  }
  n.box_min = lo;
  n.box_max = hi;
}

inline void refit_inner(MeshBvh& bvh, int i) {
  BvhNode& n = bvh.nodes[i];
  const BvhNode& l = bvh.nodes[i + 1];
  const BvhNode& r = bvh.nodes[n.first];
  n.box_min = l.box_min.cwiseMin(r.box_min);
  n.box_max = l.box_max.cwiseMax(r.box_max);
}

}  // namespace

Status refit_bvh(const TriMesh& mesh, MeshBvh& bvh) {
  if (mesh.num_vertices() != static_cast<int>(bvh.positions.size()) ||
      mesh.num_triangles() != bvh.num_triangles())
    return Status::error(ErrorCode::InvalidInput,
                         "refit_bvh: the mesh's vertex or triangle count differs from the build");
  for (size_t i = 0; i < mesh.positions.size(); ++i)
    if (!mesh.positions[i].allFinite())
      return Status::error(ErrorCode::InvalidInput,
                           "vertex " + std::to_string(i) + " has a non-finite coordinate");
  bvh.positions = mesh.positions;
  // Children always follow their parent in the array, so a reverse sweep
  // sees both children before the parent.
  for (int i = static_cast<int>(bvh.nodes.size()) - 1; i >= 0; --i) {
    if (bvh.nodes[i].leaf()) refit_leaf(bvh, bvh.nodes[i]);
    else refit_inner(bvh, i);
  }
  return Status::success();
}

void build_refit_index(const MeshBvh& bvh, BvhRefitIndex& out) {
  const int nn = static_cast<int>(bvh.nodes.size());
  const int nf = bvh.num_triangles();
  const int nv = static_cast<int>(bvh.positions.size());
  out.parent.assign(nn, -1);
  out.leaf_of_triangle.assign(nf, -1);
  for (int i = 0; i < nn; ++i) {
    const BvhNode& n = bvh.nodes[i];
    if (n.leaf()) {
      for (int k = n.first; k < n.first + n.count; ++k) out.leaf_of_triangle[bvh.triangle_order[k]] = i;
    } else {
      out.parent[i + 1] = i;
      out.parent[n.first] = i;
    }
  }
  out.vertex_offsets.assign(nv + 1, 0);
  for (const Tri& t : bvh.triangles)
    for (int v : t) ++out.vertex_offsets[v + 1];
  for (int v = 0; v < nv; ++v) out.vertex_offsets[v + 1] += out.vertex_offsets[v];
  out.vertex_triangles.resize(out.vertex_offsets[nv]);
  std::vector<int> fill(out.vertex_offsets.begin(), out.vertex_offsets.end() - 1);
  for (int f = 0; f < nf; ++f)
    for (int v : bvh.triangles[f]) out.vertex_triangles[fill[v]++] = f;
}

Status refit_bvh_vertices(MeshBvh& bvh, const BvhRefitIndex& index, const std::vector<Vec3>& positions,
                          const std::vector<int>& moved) {
  const int nv = static_cast<int>(bvh.positions.size());
  if (static_cast<int>(positions.size()) != nv || static_cast<int>(index.vertex_offsets.size()) != nv + 1 ||
      index.parent.size() != bvh.nodes.size() || static_cast<int>(index.leaf_of_triangle.size()) != bvh.num_triangles())
    return Status::error(ErrorCode::InvalidInput,
                         "refit_bvh_vertices: the positions or the refit index do not match the BVH");
  for (int v : moved) {
    if (v < 0 || v >= nv)
      return Status::error(ErrorCode::InvalidInput, "refit_bvh_vertices: vertex " + std::to_string(v) +
                                                        " of " + std::to_string(nv));
    if (!positions[v].allFinite())
      return Status::error(ErrorCode::InvalidInput,
                           "vertex " + std::to_string(v) + " has a non-finite coordinate");
  }
  // The leaves holding the moved vertices' triangles and their ancestors,
  // recomputed in descending node order: children follow their parent in
  // the array, so every node comes after both of its children.
  std::vector<char> marked(bvh.nodes.size(), 0);
  std::vector<int> dirty;
  for (int v : moved) {
    bvh.positions[v] = positions[v];
    for (int i = index.vertex_offsets[v]; i < index.vertex_offsets[v + 1]; ++i)
      for (int node = index.leaf_of_triangle[index.vertex_triangles[i]]; node >= 0 && !marked[node];
           node = index.parent[node]) {
        marked[node] = 1;
        dirty.push_back(node);
      }
  }
  std::sort(dirty.begin(), dirty.end(), [](int a, int b) { return a > b; });
  for (int i : dirty) {
    if (bvh.nodes[i].leaf()) refit_leaf(bvh, bvh.nodes[i]);
    else refit_inner(bvh, i);
  }
  return Status::success();
}

RayHit intersect_first(const MeshBvh& bvh, const Ray& ray) {
  return traverse<false>(bvh, ray, -1);
}

bool intersect_any(const MeshBvh& bvh, const Ray& ray, int skip_triangle) {
  return traverse<true>(bvh, ray, skip_triangle).hit();
}

Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c,
                               Vec3& bary) {
  // Ericson, Real-Time Collision Detection, Sec. 5.1.5: Voronoi regions.
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) { bary = Vec3(1, 0, 0); return a; }
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) { bary = Vec3(0, 1, 0); return b; }
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    bary = Vec3(1 - v, v, 0);
    return a + v * ab;
  }
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) { bary = Vec3(0, 0, 1); return c; }
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double w = d2 / (d2 - d6);
    bary = Vec3(1 - w, 0, w);
    return a + w * ac;
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    bary = Vec3(0, 1 - w, w);
    return b + w * (c - b);
  }
  const double sum = va + vb + vc;
  if (!(sum > 0)) {  // degenerate (zero-area) triangle: fall back to its longest edge
    Vec3 best = a;
    double best_d = (p - a).squaredNorm();
    bary = Vec3(1, 0, 0);
    const Vec3* corners[3] = {&a, &b, &c};
    for (int k = 0; k < 3; ++k) {
      const Vec3& s = *corners[k];
      const Vec3& e = *corners[(k + 1) % 3];
      const Vec3 se = e - s;
      const double len2 = se.squaredNorm();
      const double t = len2 > 0 ? std::clamp((p - s).dot(se) / len2, 0.0, 1.0) : 0.0;
      const Vec3 q = s + t * se;
      const double dq = (p - q).squaredNorm();
      if (dq < best_d) {
        best_d = dq;
        best = q;
        bary = Vec3::Zero();
        bary[k] = 1 - t;
        bary[(k + 1) % 3] = t;
      }
    }
    return best;
  }
  const double v = vb / sum, w = vc / sum;
  bary = Vec3(1 - v - w, v, w);
  return a + v * ab + w * ac;
}

ClosestPoint closest_point(const MeshBvh& bvh, const Vec3& p, double max_distance) {
  ClosestPoint best;
  if (bvh.nodes.empty() || !p.allFinite()) return best;
  double best_d2 = max_distance * max_distance;
  if (!(max_distance >= 0)) return best;
  // Each node is pushed with its box distance, so the check when it is
  // popped (the bound may have shrunk since) needs no second computation.
  int stack[kStackSize];
  double stack_d2[kStackSize];
  int top = 0;
  const double root_d2 = box_distance2(bvh.nodes[0].box_min, bvh.nodes[0].box_max, p);
  if (root_d2 > best_d2) return best;
  stack[top] = 0;
  stack_d2[top++] = root_d2;
  while (top > 0) {
    --top;
    const int ni = stack[top];
    if (stack_d2[top] > best_d2) continue;  // shrunk since pushed
    const BvhNode& n = bvh.nodes[ni];
    if (n.leaf()) {
      for (int i = n.first; i < n.first + n.count; ++i) {
        const int f = bvh.triangle_order[i];
        const Tri& t = bvh.triangles[f];
        Vec3 bary;
        const Vec3 q = closest_point_on_triangle(p, bvh.positions[t[0]], bvh.positions[t[1]],
                                                 bvh.positions[t[2]], bary);
        const double d2 = (q - p).squaredNorm();
        if (d2 < best_d2 || (d2 == best_d2 && !best.found())) {
          best_d2 = d2;
          best.triangle = f;
          best.point = q;
          best.barycentric = bary;
        }
      }
      continue;
    }
    const int left = ni + 1, right = n.first;
    const double dl = box_distance2(bvh.nodes[left].box_min, bvh.nodes[left].box_max, p);
    const double dr = box_distance2(bvh.nodes[right].box_min, bvh.nodes[right].box_max, p);
    auto push = [&](int child, double d2) {
      stack[top] = child;
      stack_d2[top++] = d2;
    };
    if (dl < dr) {
      if (dr <= best_d2) push(right, dr);
      if (dl <= best_d2) push(left, dl);
    } else {
      if (dl <= best_d2) push(left, dl);
      if (dr <= best_d2) push(right, dr);
    }
  }
  if (best.found()) best.distance = std::sqrt(best_d2);
  return best;
}

ClosestPoint closest_point_near(const MeshBvh& bvh, const Vec3& p, int guess) {
  if (guess >= 0 && guess < bvh.num_triangles()) {
    const Tri& t = bvh.triangles[guess];
    Vec3 bary;
    const Vec3 on = closest_point_on_triangle(p, bvh.positions[t[0]], bvh.positions[t[1]], bvh.positions[t[2]], bary);
    const ClosestPoint c = closest_point(bvh, p, (on - p).norm() * (1 + 1e-9) + 1e-300);
    if (c.found()) return c;  // (not found is not expected: the guess lies within the bound)
  }
  return closest_point(bvh, p);
}

}  // namespace lk
