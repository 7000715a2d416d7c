#include "synth/synth_head.h"

#include "head/generic_head.h"
#include "mesh/geometry.h"
#include "mesh/topology.h"
#include "common/prng.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <queue>

namespace lk {

namespace {

double smoothstep01(double t) {
  t = std::clamp(t, 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}
double pos(double x) { return x > 0 ? x : 0.0; }

using Adjacency = std::vector<std::vector<std::pair<int, double>>>;

Adjacency edge_graph(const TriMesh& m) {
  Adjacency adj(m.positions.size());
  for (const Tri& t : m.triangles)
    for (int k = 0; k < 3; ++k) {
      const int a = t[k], b = t[(k + 1) % 3];
      const double len = (m.positions[a] - m.positions[b]).norm();
      adj[a].push_back({b, len});
      adj[b].push_back({a, len});
    }
  return adj;
}

// 1 on the seed vertices, fading to 0 at geodesic (edge-path) distance
// `falloff`; the smoothstep keeps the blend free of creases at both ends.
std::vector<double> region_weight(const Adjacency& adj, const std::vector<int>& seeds,
                                  double falloff) {
  const size_t n = adj.size();
  std::vector<double> dist(n, std::numeric_limits<double>::infinity());
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> queue;
  for (int s : seeds) {
    if (s < 0 || static_cast<size_t>(s) >= n) continue;
    dist[s] = 0;
    queue.push({0.0, s});
  }
  while (!queue.empty()) {
    const auto [d, v] = queue.top();
    queue.pop();
    if (d > dist[v] || d > falloff) continue;
    for (const auto& [u, len] : adj[v])
      if (d + len < dist[u]) {
        dist[u] = d + len;
        queue.push({dist[u], u});
      }
  }
  std::vector<double> w(n, 0.0);
  for (size_t v = 0; v < n; ++v)
    if (dist[v] <= falloff) w[v] = 1.0 - smoothstep01(falloff > 0 ? dist[v] / falloff : 1.0);
  return w;
}

const FeatureBox* find_box(const HeadAnnotations& a, const std::string& name) {
  for (const FeatureBox& b : a.boxes)
    if (b.name == name) return &b;
  return nullptr;
}

// The vertices of a named region, or those inside the named box when the
// region is missing (older annotation files), or none.
std::vector<int> region_vertices(const GenericHead& h, const std::string& region,
                                 const std::string& box) {
  auto it = h.annotations.regions.find(region);
  if (it != h.annotations.regions.end() && !it->second.empty()) return it->second;
  std::vector<int> out;
  if (const FeatureBox* b = find_box(h.annotations, box))
    for (int v = 0; v < h.mesh.num_vertices(); ++v)
      if (b->contains(h.mesh.positions[v])) out.push_back(v);
  return out;
}

// Mean displacement of the vertices within `radius` of p (linearly
// weighted), or of the nearest vertex when none is that close.
Vec3 carried_displacement(const std::vector<Vec3>& before, const std::vector<Vec3>& after,
                          const Vec3& p, double radius) {
  Vec3 sum = Vec3::Zero();
  double wsum = 0;
  int nearest = -1;
  double nearest_d = std::numeric_limits<double>::infinity();
  for (size_t v = 0; v < before.size(); ++v) {
    const double d = (before[v] - p).norm();
    if (d < nearest_d) {
      nearest_d = d;
      nearest = static_cast<int>(v);
    }
    if (d < radius) {
      const double w = 1.0 - d / radius;
      sum += w * (after[v] - before[v]);
      wsum += w;
    }
  }
  if (wsum > 0) return sum / wsum;
  return nearest >= 0 ? Vec3(after[nearest] - before[nearest]) : Vec3::Zero();
}

// Smooth value noise in [-1, 1] on a unit lattice, quintic fade (C2).
double value_noise(const Vec3& p, std::uint64_t seed) {
  const double fx = std::floor(p.x()), fy = std::floor(p.y()), fz = std::floor(p.z());
  const auto ix = static_cast<std::int64_t>(fx), iy = static_cast<std::int64_t>(fy),
             iz = static_cast<std::int64_t>(fz);
  auto fade = [](double t) { return t * t * t * (t * (t * 6 - 15) + 10); };
  const double tx = fade(p.x() - fx), ty = fade(p.y() - fy), tz = fade(p.z() - fz);
  auto corner = [&](int dx, int dy, int dz) {
    const std::uint64_t h = hash_mix(seed, static_cast<std::uint64_t>(ix + dx),
                                     static_cast<std::uint64_t>(iy + dy),
                                     static_cast<std::uint64_t>(iz + dz));
    return static_cast<double>(h >> 11) * (2.0 / 9007199254740992.0) - 1.0;
  };
  auto lerp = [](double a, double b, double t) { return a + (b - a) * t; };
  const double x00 = lerp(corner(0, 0, 0), corner(1, 0, 0), tx);
  const double x10 = lerp(corner(0, 1, 0), corner(1, 1, 0), tx);
  const double x01 = lerp(corner(0, 0, 1), corner(1, 0, 1), tx);
  const double x11 = lerp(corner(0, 1, 1), corner(1, 1, 1), tx);
  return lerp(lerp(x00, x10, ty), lerp(x01, x11, ty), tz);
}

}  // namespace

double SynthHeadParams::get(const std::string& name) const {
  for (const auto& [n, v] : values)
    if (n == name) return v;
  return 0.0;
}

SynthHeadParams draw_synth_params(std::uint32_t seed, const SynthHeadOptions& o) {
  SynthHeadParams p;
  p.seed = seed;
  // Mix the seed so that seeds 0, 1, 2 ... start far apart in the stream.
  SplitMix64 rng(hash_mix(seed, 0x5EEDull));
  const double s = o.variation;
  auto draw = [&](const char* name, double range) { p.values.push_back({name, s * range * rng.bell()}); };
  // The order below fixes the meaning of a seed: append, never reorder.
  draw("width", o.proportion_range);
  draw("height", o.proportion_range);
  draw("depth", o.proportion_range);
  draw("taper", o.shape_range);
  draw("crown", o.shape_range);
  draw("occiput", o.shape_range);
  draw("forehead", o.shape_range);
  draw("jaw_width", o.jaw_width_range);
  draw("chin_forward_m", o.chin_range_m);
  draw("chin_down_m", o.chin_range_m);
  draw("nose_length", o.nose_length_range);
  draw("nose_width", o.nose_width_range);
  draw("nose_projection", o.nose_projection_range);
  draw("ear_up_m", o.ear_shift_m);
  draw("ear_back_m", o.ear_shift_m);
  draw("ear_size", o.ear_size_range);
  draw("ear_asymmetry", o.asymmetry);
  draw("upper_lip_m", o.lip_fullness_m);
  draw("lower_lip_m", o.lip_fullness_m);
  draw("mouth_width", o.mouth_width_range);
  draw("brow_ridge_m", o.brow_ridge_m);
  draw("cheeks_m", o.cheek_m);
  return p;
}

Status synthesize_head(const GenericHead& generic, std::uint32_t seed, const SynthHeadOptions& o,
                       GenericHead& out, SynthHeadParams* params_out) {
  const TriMesh& gm = generic.mesh;
  if (gm.positions.empty() || gm.triangles.empty())
    return Status::error(ErrorCode::Empty, "synthesize_head: the generic head has no mesh");
  std::string why;
  if (!is_valid(gm, &why)) return Status::error(ErrorCode::InvalidInput, "synthesize_head: " + why);
  const double opts[] = {o.variation, o.proportion_range, o.shape_range, o.jaw_width_range,
                         o.chin_range_m, o.nose_length_range, o.nose_width_range,
                         o.nose_projection_range, o.ear_shift_m, o.ear_size_range,
                         o.lip_fullness_m, o.mouth_width_range, o.brow_ridge_m, o.cheek_m,
                         o.falloff_m, o.asymmetry};
  for (double v : opts)
    if (!std::isfinite(v))
      return Status::error(ErrorCode::InvalidInput, "synthesize_head: an option is not finite");
  if (!(o.falloff_m > 0))
    return Status::error(ErrorCode::InvalidInput, "synthesize_head: falloff_m must be positive");

  const SynthHeadParams P = draw_synth_params(seed, o);
  const HeadAnnotations& ga = generic.annotations;

  // The head frame: x = head's left, y = up, z = look; origin = box centre.
  Vec3 look = ga.look.norm() > 0 ? Vec3(ga.look.normalized()) : Vec3(Vec3::UnitZ());
  Vec3 up = ga.up - ga.up.dot(look) * look;
  up = up.norm() > 1e-9 ? Vec3(up.normalized()) : Vec3(Vec3::UnitY());
  Mat3 R;
  R.col(0) = up.cross(look).normalized();
  R.col(1) = up;
  R.col(2) = look;
  const BBox box = bounding_box(gm.positions);
  const Vec3 centre = box.center();
  const int nv = gm.num_vertices();
  std::vector<Vec3> q0(nv), n0(nv);
  const std::vector<Vec3> normals = vertex_normals(gm);
  Vec3 half = Vec3::Zero();
  for (int v = 0; v < nv; ++v) {
    q0[v] = R.transpose() * (gm.positions[v] - centre);
    n0[v] = R.transpose() * normals[v];
    half = half.cwiseMax(q0[v].cwiseAbs());
  }
  half = half.cwiseMax(Vec3::Constant(1e-9));

  const Adjacency adj = edge_graph(gm);
  std::vector<Vec3> dq(nv, Vec3::Zero());
  auto weights = [&](const std::string& region, const std::string& box_name) {
    return region_weight(adj, region_vertices(generic, region, box_name), o.falloff_m);
  };
  auto centroid = [&](const std::vector<int>& vs) {
    Vec3 c = Vec3::Zero();
    for (int v : vs) c += q0[v];
    return vs.empty() ? c : Vec3(c / static_cast<double>(vs.size()));
  };

  {  // jaw: wider or narrower about the midline
    const auto w = weights("jaw", "");
    for (int v = 0; v < nv; ++v) dq[v].x() += w[v] * P.get("jaw_width") * q0[v].x();
  }
  {  // chin: forward/back and down/up
    const auto w = weights("chin", "");
    const Vec3 shift(0, -P.get("chin_down_m"), P.get("chin_forward_m"));
    for (int v = 0; v < nv; ++v) dq[v] += w[v] * shift;
  }
  {  // nose: length from its root, width about its centre, projection from its base
    const auto verts = region_vertices(generic, "nose", "nose");
    if (!verts.empty()) {
      const auto w = region_weight(adj, verts, o.falloff_m);
      const Vec3 c = centroid(verts);
      double root_y = -1e300, base_z = 1e300;
      for (int v : verts) {
        root_y = std::max(root_y, q0[v].y());
        base_z = std::min(base_z, q0[v].z());
      }
      for (int v = 0; v < nv; ++v)
        dq[v] += w[v] * Vec3(P.get("nose_width") * (q0[v].x() - c.x()),
                             P.get("nose_length") * (q0[v].y() - root_y),
                             P.get("nose_projection") * (q0[v].z() - base_z));
    }
  }
  for (int side = 0; side < 2; ++side) {  // ears: shift and scale about their centre
    const std::string name = side == 0 ? "ear_left" : "ear_right";
    const auto verts = region_vertices(generic, name, name);
    if (verts.empty()) continue;
    const auto w = region_weight(adj, verts, o.falloff_m);
    const Vec3 c = centroid(verts);
    // People are not symmetric: one ear gets a bit more than the other.
    const double k = 1.0 + (side == 0 ? 1.0 : -1.0) * P.get("ear_asymmetry");
    const Vec3 shift(0, k * P.get("ear_up_m"), -k * P.get("ear_back_m"));
    const double scale = k * P.get("ear_size");
    for (int v = 0; v < nv; ++v) dq[v] += w[v] * (shift + scale * (q0[v] - c));
  }
  {  // lips: fullness (forward) per lip, mouth width about the mouth centre
    auto upper = region_vertices(generic, "upper_lip", "");
    auto lower = region_vertices(generic, "lower_lip", "");
    const auto lips = region_vertices(generic, "lips", "mouth");
    if (upper.empty() && lower.empty()) upper = lips;
    const auto wu = region_weight(adj, upper, o.falloff_m);
    const auto wl = region_weight(adj, lower, o.falloff_m);
    const auto w = region_weight(adj, lips, o.falloff_m);
    const double cx = centroid(lips).x();
    for (int v = 0; v < nv; ++v) {
      dq[v].z() += wu[v] * P.get("upper_lip_m") + wl[v] * P.get("lower_lip_m");
      dq[v].x() += w[v] * P.get("mouth_width") * (q0[v].x() - cx);
    }
  }
  {  // brow ridge: forward/back
    const auto w = weights("brow", "");
    for (int v = 0; v < nv; ++v) dq[v].z() += w[v] * P.get("brow_ridge_m");
  }
  {  // cheeks: fuller/hollower along the surface normal
    const auto w = weights("cheeks", "");
    for (int v = 0; v < nv; ++v) dq[v] += w[v] * P.get("cheeks_m") * n0[v];
  }

  // Low-frequency head shape, then overall proportions.
  const Vec3 scale(1 + P.get("width"), 1 + P.get("height"), 1 + P.get("depth"));
  out = generic;
  for (int v = 0; v < nv; ++v) {
    Vec3 q = q0[v] + dq[v];
    const Vec3 u = q.cwiseQuotient(half);
    q.x() *= 1.0 + P.get("taper") * std::clamp(u.y(), -1.0, 1.0);
    q.y() += P.get("crown") * half.y() * pos(u.y()) * pos(u.y());
    q.z() -= P.get("occiput") * half.z() * pos(-u.z()) * pos(-u.z());
    q.z() += P.get("forehead") * half.z() * pos(u.y()) * pos(u.y()) * pos(u.z());
    q = q.cwiseProduct(scale);
    out.mesh.positions[v] = centre + R * q;
  }
  out.mesh.normals.clear();
  if (!gm.normals.empty()) out.mesh.normals = vertex_normals(out.mesh);

  // Annotations follow the mesh.
  HeadAnnotations& a = out.annotations;
  const std::vector<Vec3>& before = gm.positions;
  const std::vector<Vec3>& after = out.mesh.positions;
  for (size_t bi = 0; bi < a.boxes.size(); ++bi) {
    const FeatureBox& gb = ga.boxes[bi];
    BBox held_before, held_after;
    for (int v = 0; v < nv; ++v)
      if (gb.contains(before[v])) {
        held_before.extend(before[v]);
        held_after.extend(after[v]);
      }
    if (!held_before.valid()) continue;  // an empty box stays where it was
    // Keep the generic box's margins around the vertices it held.
    a.boxes[bi].min = held_after.min - (held_before.min - gb.min);
    a.boxes[bi].max = held_after.max + (gb.max - held_before.max);
  }
  const double carry_radius = 0.03;
  for (EyeSocket* e : {&a.eye_left, &a.eye_right}) {
    Vec3 d = Vec3::Zero();
    if (!e->rim.empty()) {
      for (int v : e->rim)
        if (v >= 0 && v < nv) d += (after[v] - before[v]) / static_cast<double>(e->rim.size());
    } else {
      d = carried_displacement(before, after, e->center, carry_radius);
    }
    e->center += d;
  }
  a.mouth_center += carried_displacement(before, after, ga.mouth_center, carry_radius);
  {
    const auto lips = region_vertices(generic, "lips", "mouth");
    double w0 = 0, w1 = 0;
    if (!lips.empty()) {
      double lo0 = 1e300, hi0 = -1e300, lo1 = 1e300, hi1 = -1e300;
      for (int v : lips) {
        const double x0 = R.col(0).dot(before[v]), x1 = R.col(0).dot(after[v]);
        lo0 = std::min(lo0, x0), hi0 = std::max(hi0, x0);
        lo1 = std::min(lo1, x1), hi1 = std::max(hi1, x1);
      }
      w0 = hi0 - lo0, w1 = hi1 - lo1;
    }
    if (w0 > 0) a.mouth_width = ga.mouth_width * w1 / w0;
  }
  a.neck_clip.point += carried_displacement(before, after, ga.neck_clip.point, 0.0);
  a.back_clip.point += carried_displacement(before, after, ga.back_clip.point, 0.0);

  if (params_out) *params_out = P;
  return Status::success();
}

GenericHead synthesize_head(const GenericHead& generic, std::uint32_t seed,
                            const SynthHeadOptions& options) {
  GenericHead out;
  if (!synthesize_head(generic, seed, options, out).ok()) return GenericHead{};
  return out;
}

Status loop_subdivide(const TriMesh& coarse, TriMesh& fine) {
  MeshTopology topo;
  Status s = build_topology(coarse, topo);
  if (!s.ok()) return with_context(s, "loop_subdivide");
  const int nv = coarse.num_vertices();
  const std::vector<Vec3>& P = coarse.positions;
  TriMesh out;
  out.positions.resize(nv + topo.edges.size());
  for (int v = 0; v < nv; ++v) {
    const auto& ring = topo.rings[v];
    const int n = static_cast<int>(ring.size());
    if (n == 0) {
      out.positions[v] = P[v];
    } else if (topo.is_boundary(v)) {
      // Cubic B-spline along the boundary: the ring starts and ends at the
      // two boundary neighbours.
      out.positions[v] = 0.75 * P[v] + 0.125 * (P[ring.front()] + P[ring.back()]);
    } else {
      const double beta = n == 3 ? 3.0 / 16.0 : 3.0 / (8.0 * n);
      Vec3 sum = Vec3::Zero();
      for (int u : ring) sum += P[u];
      out.positions[v] = (1.0 - n * beta) * P[v] + beta * sum;
    }
  }
  for (size_t e = 0; e < topo.edges.size(); ++e) {
    const Edge& ed = topo.edges[e];
    Vec3& q = out.positions[nv + e];
    if (ed.boundary()) {
      q = 0.5 * (P[ed.v0] + P[ed.v1]);
    } else {
      const int c = topo.opposite_vertex(coarse, ed.f0, static_cast<int>(e));
      const int d = topo.opposite_vertex(coarse, ed.f1, static_cast<int>(e));
      q = 0.375 * (P[ed.v0] + P[ed.v1]) + 0.125 * (P[c] + P[d]);
    }
  }
  out.triangles.reserve(4 * coarse.triangles.size());
  for (int f = 0; f < coarse.num_triangles(); ++f) {
    const Tri& t = coarse.triangles[f];
    const auto& fe = topo.face_edges[f];
    const int m01 = nv + fe[0], m12 = nv + fe[1], m20 = nv + fe[2];
    out.triangles.push_back({t[0], m01, m20});
    out.triangles.push_back({m01, t[1], m12});
    out.triangles.push_back({m20, m12, t[2]});
    out.triangles.push_back({m01, m12, m20});
  }
  fine = std::move(out);
  return Status::success();
}

Status make_truth_surface(const GenericHead& head, std::uint32_t seed, const TruthOptions& o,
                          TruthSurface& out) {
  out = TruthSurface{};
  if (o.subdivision_levels < 0 || o.subdivision_levels > 5)
    return Status::error(ErrorCode::InvalidInput,
                         "make_truth_surface: subdivision_levels must be in 0..5");
  if (!std::isfinite(o.detail_amplitude_m) || !(o.detail_wavelength_m > 0))
    return Status::error(ErrorCode::InvalidInput,
                         "make_truth_surface: detail amplitude/wavelength invalid");
  if (head.mesh.triangles.empty())
    return Status::error(ErrorCode::Empty, "make_truth_surface: the head has no mesh");
  TriMesh mesh = head.mesh;
  mesh.normals.clear();
  mesh.colors.clear();
  mesh.uvs.clear();
  std::vector<int> parent(mesh.triangles.size());
  for (size_t f = 0; f < parent.size(); ++f) parent[f] = static_cast<int>(f);
  for (int level = 0; level < o.subdivision_levels; ++level) {
    TriMesh fine;
    Status s = loop_subdivide(mesh, fine);
    if (!s.ok()) return with_context(s, "make_truth_surface");
    std::vector<int> fine_parent(fine.triangles.size());
    for (size_t f = 0; f < fine_parent.size(); ++f) fine_parent[f] = parent[f / 4];
    mesh = std::move(fine);
    parent = std::move(fine_parent);
  }
  if (o.detail_amplitude_m != 0) {
    // Skin detail: two octaves of value noise along the normal.
    const std::vector<Vec3> n = vertex_normals(mesh);
    const std::uint64_t s1 = hash_mix(seed, 0xDE7A11ull), s2 = hash_mix(seed, 0xDE7A12ull);
    const double f = 1.0 / o.detail_wavelength_m;
    for (int v = 0; v < mesh.num_vertices(); ++v) {
      const Vec3& p = mesh.positions[v];
      const double h = (value_noise(p * f, s1) + 0.5 * value_noise(p * (2 * f), s2)) / 1.5;
      mesh.positions[v] += o.detail_amplitude_m * h * n[v];
    }
  }
  const auto it = head.annotations.regions.find("scalp");
  const std::vector<char> scalp = vertex_mask(it != head.annotations.regions.end() ? it->second : std::vector<int>{},
                                              head.mesh.num_vertices());
  out.hair.resize(mesh.triangles.size());
  for (size_t f = 0; f < parent.size(); ++f) {
    const Tri& t = head.mesh.triangles[parent[f]];
    out.hair[f] = (scalp[t[0]] + scalp[t[1]] + scalp[t[2]]) >= 2;
  }
  out.mesh = std::move(mesh);
  out.parent_triangle = std::move(parent);
  return Status::success();
}

}  // namespace lk
