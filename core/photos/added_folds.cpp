#include "photos/added_folds.h"

#include "head/head_creases.h"
#include "mesh/topology.h"
#include "multires/multires.h"
#include "raycast/self_intersection.h"

#include <algorithm>
#include <cmath>

namespace lk {

namespace {

std::vector<double> edge_dihedrals_deg(const TriMesh& mesh, const MeshTopology& topo) {
  std::vector<Vec3> n(size_t(mesh.num_triangles()));
  for (int f = 0; f < mesh.num_triangles(); ++f) {
    const Tri& t = mesh.triangles[size_t(f)];
    const Vec3 &a = mesh.positions[size_t(t[0])], &b = mesh.positions[size_t(t[1])], &c = mesh.positions[size_t(t[2])];
    n[size_t(f)] = (b - a).cross(c - a).normalized();
  }
  std::vector<double> out(topo.edges.size(), 0.0);
  for (size_t e = 0; e < topo.edges.size(); ++e) {
    const Edge& ed = topo.edges[e];
    if (ed.f1 < 0) continue;
    out[e] = std::acos(std::clamp(n[size_t(ed.f0)].dot(n[size_t(ed.f1)]), -1.0, 1.0)) * 180 / 3.14159265358979323846;
  }
  return out;
}

}  // namespace

Status measure_added_folds(const GenericHead& generic, const std::vector<Vec3>& fitted, int level,
                           double crease_deg, std::vector<AddedFolds>& out) {
  out.clear();
  const TriMesh& m = generic.mesh;
  const HeadAnnotations& a = generic.annotations;
  if (int(fitted.size()) != m.num_vertices())
    return Status::error(ErrorCode::InvalidInput, "added folds: the fitted mesh is not the generic head's");
  if (level < 1 || level > 4) return Status::error(ErrorCode::InvalidInput, "added folds: level must be 1..4");
  const size_t nv = size_t(m.num_vertices());
  std::vector<std::pair<std::string, std::vector<char>>> sets;
  for (const char* name : {"face", "cheeks", "brow", "nose"}) {
    std::vector<char> in(nv, 0);
    auto it = a.regions.find(name);
    if (it != a.regions.end())
      for (int v : it->second)
        if (v >= 0 && size_t(v) < nv) in[size_t(v)] = 1;
    sets.emplace_back(name, in);
  }
  {
    std::vector<char> eyes(nv, 0);
    for (size_t v = 0; v < nv; ++v)
      for (const EyeSocket* s : {&a.eye_left, &a.eye_right}) {
        const double d = (m.positions[v] - s->center).norm();
        if (d > s->radius + 0.0012 && d < 0.022) eyes[v] = 1;
      }
    sets.emplace_back("eyes", eyes);
  }
  {
    std::vector<char> lips(nv, 0), pockets(nv, 0);
    auto it = a.regions.find("lips");
    if (it != a.regions.end())
      for (int v : it->second)
        if (v >= 0 && size_t(v) < nv) lips[size_t(v)] = 1;
    for (size_t v = 0; v < nv; ++v)
      for (const EyeSocket* s : {&a.eye_left, &a.eye_right})
        if ((m.positions[v] - s->center).norm() <= s->radius + 0.0012) pockets[v] = 1;
    sets.emplace_back("lips", lips);
    sets.emplace_back("eye pockets", pockets);
  }
  // Both refined with the generic head's creases (head/head_creases.h), as
  // the fit's exported levels are: the same corners and rings on both.
  const ButterflyCreases creases = head_creases(m, a);
  TriMesh fit_control = m;
  fit_control.positions = fitted;
  fit_control.normals.clear();
  MultiresMesh g, f;
  Status s = build_multires(m, creases, level, g);
  if (s) s = build_multires(fit_control, creases, level, f);
  if (!s) return with_context(s, "added folds");
  const TriMesh gl = level_mesh(g, level), fl = level_mesh(f, level);
  MeshTopology topo;
  s = build_topology(gl, topo);
  if (!s) return with_context(s, "added folds");
  const std::vector<double> dg = edge_dihedrals_deg(gl, topo), df = edge_dihedrals_deg(fl, topo);
  const int per_control = 1 << (2 * level);  // a level-L face's ancestor is its index over 4^L
  std::vector<std::array<int, 2>> crossing[2];
  s = find_self_intersections(gl, crossing[0]);
  if (s) s = find_self_intersections(fl, crossing[1]);
  if (!s) return with_context(s, "added folds");
  for (const auto& [name, vin] : sets) {
    AddedFolds r;
    r.region = name;
    std::vector<double> grow;
    for (size_t e = 0; e < topo.edges.size(); ++e) {
      const Edge& ed = topo.edges[e];
      if (ed.f1 < 0) continue;
      bool in = true;
      for (int face : {ed.f0, ed.f1}) {
        const Tri& t = m.triangles[size_t(face / per_control)];
        in = in && vin[size_t(t[0])] && vin[size_t(t[1])] && vin[size_t(t[2])];
      }
      if (!in) continue;
      grow.push_back(df[e] - dg[e]);
      r.creased += df[e] - dg[e] > crease_deg;
    }
    auto face_in = [&, &vin = vin](int face) {
      const Tri& t = m.triangles[size_t(face / per_control)];
      return vin[size_t(t[0])] && vin[size_t(t[1])] && vin[size_t(t[2])];
    };
    for (const auto& p : crossing[0]) r.generic_crossings += face_in(p[0]) || face_in(p[1]);
    for (const auto& p : crossing[1]) r.crossings += face_in(p[0]) || face_in(p[1]);
    r.edges = int(grow.size());
    if (!grow.empty()) {
      std::sort(grow.begin(), grow.end());
      r.p95_deg = grow[std::min(grow.size() - 1, size_t(0.95 * double(grow.size() - 1) + 0.5))];
      r.max_deg = grow.back();
    }
    out.push_back(r);
  }
  return Status::success();
}

}  // namespace lk
