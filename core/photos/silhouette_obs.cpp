#include "photos/silhouette_obs.h"

#include "fit/closest_point.h"
#include "photos/self_calibration.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <utility>

namespace lk {
namespace {
double cross2(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }
}  // namespace

double line_distance(const Vec2& pa, const Vec2& pb, const Vec2& s, Vec2* ga, Vec2* gb) {
  const Vec2 e = pb - pa, w = s - pa;
  const double L = e.norm();
  if (L < 1e-9) {
    if (ga) *ga = Vec2::Zero();
    if (gb) *gb = Vec2::Zero();
    return 0;
  }
  const double f = cross2(e, w);
  const Vec2 dd_de = Vec2(w.y(), -w.x()) / L - f * e / (L * L * L);
  const Vec2 dd_dw = Vec2(-e.y(), e.x()) / L;
  if (gb) *gb = dd_de;
  if (ga) *ga = -dd_de - dd_dw;
  return f / L;
}

namespace {

// Whether the pixel (qx, qy)'s centre is covered by a projected triangle
// (any facing): only the pixels just beyond each rim edge are asked, so they
// are tested against the triangles directly (the triangles' pixel boxes as a
// raster of the whole photo would take them) rather than by rasterizing the
// head, which costs the photo's pixel count: millions at 12 megapixels.
bool pixel_covered(const std::vector<Vec2>& p, const std::vector<char>& ok, const std::vector<Tri>& tris, int w, int h,
                   int qx, int qy) {
  if (qx < 0 || qy < 0 || qx >= w || qy >= h) return false;
  const Vec2 q(qx + 0.5, qy + 0.5);
  for (const Tri& t : tris) {
    if (!ok[size_t(t[0])] || !ok[size_t(t[1])] || !ok[size_t(t[2])]) continue;
    const Vec2 &a = p[size_t(t[0])], &b = p[size_t(t[1])], &c = p[size_t(t[2])];
    if (qx < int(std::floor(std::min({a.x(), b.x(), c.x()}))) || qx > int(std::ceil(std::max({a.x(), b.x(), c.x()}))) ||
        qy < int(std::floor(std::min({a.y(), b.y(), c.y()}))) || qy > int(std::ceil(std::max({a.y(), b.y(), c.y()}))))
      continue;
    const double area = cross2(b - a, c - a);
    if (std::abs(area) < 1e-12) continue;
    const double sgn = area > 0 ? 1 : -1;
    if (sgn * cross2(b - a, q - a) >= 0 && sgn * cross2(c - b, q - b) >= 0 && sgn * cross2(a - c, q - c) >= 0) return true;
  }
  return false;
}

}  // namespace

std::vector<std::array<int, 4>> mesh_edge_list(const std::vector<Tri>& triangles) {
  std::vector<std::array<int, 4>> edges;
  std::map<std::pair<int, int>, size_t> index;
  for (size_t f = 0; f < triangles.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int u = triangles[f][size_t(k)], v = triangles[f][size_t((k + 1) % 3)];
      const auto key = std::make_pair(std::min(u, v), std::max(u, v));
      auto it = index.find(key);
      if (it == index.end()) {
        index.emplace(key, edges.size());
        edges.push_back({u, v, int(f), -1});
      } else if (edges[it->second][3] < 0) {
        edges[it->second][3] = int(f);
      }
    }
  return edges;
}

std::vector<RimEdge> find_rim_edges(const std::vector<Vec3>& P, const std::vector<Tri>& triangles,
                                    const std::vector<std::array<int, 4>>& edges, const Camera& cam,
                                    bool silhouette_only) {
  std::vector<Vec2> proj(P.size());
  std::vector<char> ok(P.size());
  for (size_t v = 0; v < P.size(); ++v) ok[v] = cam.project(P[v], proj[v]);
  const Vec3 C = cam.center();
  std::vector<char> front(triangles.size());
  for (size_t f = 0; f < triangles.size(); ++f) {
    const Tri& t = triangles[f];
    const Vec3 n = (P[size_t(t[1])] - P[size_t(t[0])]).cross(P[size_t(t[2])] - P[size_t(t[0])]);
    front[f] = n.dot(C - P[size_t(t[0])]) > 0;
  }
  std::vector<RimEdge> rims;
  for (const auto& e : edges) {
    const int tl = e[2], tr = e[3];
    const bool border = tr < 0;
    if (!border && front[size_t(tl)] == front[size_t(tr)]) continue;
    const int ft = border ? tl : (front[size_t(tl)] ? tl : tr);
    const Tri& t = triangles[size_t(ft)];
    int third = t[0];
    for (int v : t)
      if (v != e[0] && v != e[1]) third = v;
    if (!ok[size_t(e[0])] || !ok[size_t(e[1])] || !ok[size_t(third)]) continue;
    RimEdge r{e[0], e[1], third, proj[size_t(e[0])], proj[size_t(e[1])], Vec2::Zero(), border};
    const Vec2 d = r.pb - r.pa;
    if (d.norm() < 1e-9) continue;
    r.outward = Vec2(-d.y(), d.x()) / d.norm();
    if ((proj[size_t(third)] - r.pa).dot(r.outward) > 0) r.outward = -r.outward;
    if (silhouette_only) {
      const Vec2 q = 0.5 * (r.pa + r.pb) + 2.0 * r.outward;
      if (pixel_covered(proj, ok, triangles, cam.width, cam.height, int(std::floor(q.x())), int(std::floor(q.y()))))
        continue;  // surface beyond it: an inner occluding contour, not the silhouette
    }
    rims.push_back(r);
  }
  return rims;
}

SilhouetteSet::SilhouetteSet(const TriMesh& mesh, std::vector<Camera> cameras, std::vector<PhotoOutline> outlines,
                             std::vector<char> excluded, ChinLine chin, const SilhouetteOptions& options)
    : triangles_(mesh.triangles),
      cameras_(std::move(cameras)),
      outlines_(std::move(outlines)),
      excluded_(std::move(excluded)),
      chin_(std::move(chin)),
      options_(options) {
  excluded_.resize(mesh.positions.size(), 0);
  outlines_.resize(cameras_.size());
  edges_ = mesh_edge_list(triangles_);
  reweight(mesh.positions);
}

std::vector<SilhouetteSet::Match> SilhouetteSet::find_matches(const std::vector<Vec3>& P) const {
  std::vector<Match> out;
  for (size_t c = 0; c < cameras_.size(); ++c) {
    const Camera& cam = cameras_[c];
    const PhotoOutline& outline = outlines_[c];
    if (outline.points.empty() || cam.width <= 0 || cam.height <= 0) continue;
    // The rim edges on the footprint's border.
    std::vector<RimEdge> rims = find_rim_edges(P, triangles_, edges_, cam, true);
    for (RimEdge& r : rims) r.excluded = r.excluded || excluded_[size_t(r.a)] || excluded_[size_t(r.b)];
    // The chin's line: outline points below it are neck and shoulders.
    bool have_chin = false;
    Vec2 chin_px = Vec2::Zero(), down = Vec2::Zero();
    {
      int lowest = -1;
      for (int v : chin_.vertices)
        if (v >= 0 && size_t(v) < P.size() && (lowest < 0 || P[size_t(v)].dot(chin_.up) < P[size_t(lowest)].dot(chin_.up)))
          lowest = v;
      Vec2 below;
      if (lowest >= 0 && cam.project(P[size_t(lowest)], chin_px) &&
          cam.project(P[size_t(lowest)] - 0.05 * chin_.up.normalized(), below) && (below - chin_px).norm() > 1e-9) {
        down = (below - chin_px).normalized();
        have_chin = true;
      }
    }
    // search_m in pixels at the depth of the mesh's centre.
    Vec3 centre = Vec3::Zero();
    for (const Vec3& p : P) centre += p;
    centre /= double(std::max<size_t>(1, P.size()));
    const double depth = cam.to_camera(centre).z();
    const double reach_px = depth > 1e-9 ? options_.search_m * 0.5 * (cam.fx + cam.fy) / depth : 0.0;
    for (size_t k = 0; k < outline.points.size(); ++k) {
      const Vec2& s = outline.points[k].pixel;
      const Vec2& n = outline.points[k].normal;
      if (have_chin && (s - chin_px).dot(down) > 0) continue;
      const RimEdge* best = nullptr;
      double best_t = std::numeric_limits<double>::infinity();
      for (const RimEdge& r : rims) {
        if (r.outward.dot(n) < options_.min_normal_cos) continue;
        const Vec2 e = r.pb - r.pa;
        const double den = cross2(n, e);
        if (std::abs(den) < 1e-3 * e.norm()) continue;
        const double t = cross2(r.pa - s, e) / den, u = cross2(r.pa - s, n) / den;
        if (u < -0.05 || u > 1.05 || std::abs(t) > reach_px || std::abs(t) >= std::abs(best_t)) continue;
        best_t = t;
        best = &r;
      }
      if (!best || best->excluded) continue;
      Match m;
      m.camera = int(c);
      m.point = int(k);
      m.a = best->a;
      m.b = best->b;
      m.c = best->c;
      out.push_back(m);
    }
  }
  return out;
}

double SilhouetteSet::distance(const std::vector<Vec3>& P, const Match& m) const {
  const Camera& cam = cameras_[size_t(m.camera)];
  Vec2 pa, pb;
  if (!cam.project(P[size_t(m.a)], pa) || !cam.project(P[size_t(m.b)], pb))
    return std::numeric_limits<double>::infinity();
  return line_distance(pa, pb, outlines_[size_t(m.camera)].points[size_t(m.point)].pixel, nullptr, nullptr);
}

bool SilhouetteSet::evaluate(const std::vector<Vec3>& P, Eigen::VectorXd& r, int row,
                             std::vector<Eigen::Triplet<double>>* jacobian) const {
  for (const Match& m : matches_) {
    const Camera& cam = cameras_[size_t(m.camera)];
    const Vec2& s = outlines_[size_t(m.camera)].points[size_t(m.point)].pixel;
    const double sw = std::sqrt(m.weight);
    const int nv = options_.facet_equations ? 3 : 2;
    const int verts[3] = {m.a, m.b, m.c};
    ProjectionJacobian pj[3];
    for (int i = 0; i < nv; ++i)
      if (!projection_jacobian(cam, P[size_t(verts[i])], Vec2::Zero(), pj[i])) return false;
    // The rim edge's pair; the facet's other two pairs with facet_equations.
    static const int kPairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
    for (int q = 0; q < rows_per_match(); ++q) {
      const int i = kPairs[q][0], j = kPairs[q][1];
      Vec2 gi, gj;
      r[row] = sw * line_distance(pj[i].residual, pj[j].residual, s, &gi, &gj);
      if (jacobian)
        for (int k = 0; k < 3; ++k) {
          jacobian->emplace_back(row, 3 * verts[i] + k, sw * gi.dot(pj[i].d_point.col(k)));
          jacobian->emplace_back(row, 3 * verts[j] + k, sw * gj.dot(pj[j].d_point.col(k)));
        }
      ++row;
    }
  }
  return true;
}

void SilhouetteSet::reweight(const std::vector<Vec3>& positions) {
  matches_ = find_matches(positions);
  for (Match& m : matches_) m.weight = huber_weight(std::abs(distance(positions, m)), options_.huber_px);
}

SilhouetteStats SilhouetteSet::stats(const std::vector<Vec3>& positions) const {
  SilhouetteStats st;
  for (const PhotoOutline& o : outlines_) st.points += int(o.points.size());
  std::vector<double> d;
  for (const Match& m : find_matches(positions)) {
    const double x = std::abs(distance(positions, m));
    if (std::isfinite(x)) d.push_back(x);
  }
  st.matched = int(d.size());
  const DistanceStats s = summarize_distances(d, 0);
  st.mean_px = s.mean;
  st.p95_px = s.p95;
  return st;
}

}  // namespace lk
