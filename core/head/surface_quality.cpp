#include "head/surface_quality.h"

#include "head/generic_head.h"
#include "head/head_creases.h"
#include "head/skin_detail.h"
#include "mesh/topology.h"
#include "multires/multires.h"
#include "raycast/self_intersection.h"

#include <algorithm>
#include <cmath>

namespace lk {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Control faces with all three corners flagged.
std::vector<char> faces_within(const TriMesh& m, const std::vector<char>& vertex_in) {
  std::vector<char> in(m.num_triangles(), 0);
  for (int f = 0; f < m.num_triangles(); ++f) {
    const Tri& t = m.triangles[f];
    in[f] = vertex_in[t[0]] && vertex_in[t[1]] && vertex_in[t[2]];
  }
  return in;
}

double percentile(const std::vector<double>& sorted, double q) {
  if (sorted.empty()) return 0;
  const size_t k = std::min(sorted.size() - 1, static_cast<size_t>(q * (sorted.size() - 1) + 0.5));
  return sorted[k];
}

}  // namespace

std::vector<double> dihedral_angles(const TriMesh& mesh, const std::vector<char>& face_in) {
  std::vector<double> angles;
  MeshTopology topo;
  if (!build_topology(mesh, topo).ok() || face_in.size() != mesh.triangles.size()) return angles;
  std::vector<Vec3> normal(mesh.num_triangles());
  for (int f = 0; f < mesh.num_triangles(); ++f) {
    const Tri& t = mesh.triangles[f];
    const Vec3 &a = mesh.positions[t[0]], &b = mesh.positions[t[1]], &c = mesh.positions[t[2]];
    normal[f] = (b - a).cross(c - a).normalized();
  }
  for (const Edge& e : topo.edges)
    if (e.f1 >= 0 && face_in[e.f0] && face_in[e.f1])
      angles.push_back(std::acos(std::clamp(normal[e.f0].dot(normal[e.f1]), -1.0, 1.0)) * 180 / kPi);
  std::sort(angles.begin(), angles.end());
  return angles;
}

Status measure_head_surface(const GenericHead& head, int level, HeadSurfaceQuality& out) {
  return measure_head_surface(head, head_creases(head.mesh, head.annotations), level, out);
}

Status measure_head_surface(const GenericHead& head, const ButterflyCreases& creases, int level,
                            HeadSurfaceQuality& out, const std::vector<std::vector<double>>* detail) {
  if (level < 1 || level > 4) return Status::error(ErrorCode::InvalidInput, "surface level must be 1..4");
  const TriMesh& m = head.mesh;
  const HeadAnnotations& a = head.annotations;
  const int nv = m.num_vertices();
  out = HeadSurfaceQuality{};
  out.level = level;

  // Control vertex sets of the regions.
  std::vector<std::pair<std::string, std::vector<char>>> sets;
  for (const char* name : {"cheeks", "brow", "nose"}) {
    const auto it = a.regions.find(name);
    if (it == a.regions.end())
      return Status::error(ErrorCode::InvalidInput, std::string("head annotations have no region ") + name);
    sets.emplace_back(name, vertex_mask(it->second, nv));
  }
  // The nose's skin without the nostrils' pockets (as the mouth's without
  // the mouth bag): their rims are creases, meant to be sharp.
  for (const char* pocket : {"nostril_left", "nostril_right"})
    if (const auto it = a.regions.find(pocket); it != a.regions.end())
      for (int v : it->second)
        if (v >= 0 && v < nv) sets[2].second[v] = 0;
  {
    // Lid and eye-corner skin: near an eyeball, outside its socket pocket
    // (the pocket sits at the eyeball's radius plus a clearance under 1 mm,
    // the lid rim at the lid sphere's ~2 mm more).
    std::vector<char> eyes(nv, 0);
    for (int v = 0; v < nv; ++v)
      for (const EyeSocket* s : {&a.eye_left, &a.eye_right}) {
        const double d = (m.positions[v] - s->center).norm();
        if (d > s->radius + 0.0012 && d < 0.022) eyes[v] = 1;
      }
    sets.emplace_back("eyes", eyes);
  }
  {
    const auto lips = a.regions.find("lips");
    const auto ears = a.regions.find("ears");
    if (lips == a.regions.end() || ears == a.regions.end())
      return Status::error(ErrorCode::InvalidInput, "head annotations have no region lips or ears");
    std::vector<char> mouth = vertex_mask(lips->second, nv);
    for (int v : a.constrained_vertices)
      if (v >= 0 && v < nv) mouth[v] = 0;
    sets.emplace_back("mouth", mouth);
    sets.emplace_back("ears", vertex_mask(ears->second, nv));
  }

  MultiresMesh smooth;
  Status s = build_multires(m, creases, level, smooth);
  if (s.ok() && detail) s = apply_skin_detail(*detail, smooth);
  if (!s.ok()) return with_context(s, "smooth levels of the head");

  for (int l = 0; l <= level; ++l) {
    std::vector<std::array<int, 2>> pairs;
    s = find_self_intersections(level_mesh(smooth, l), pairs);
    if (!s.ok()) return with_context(s, "crossings of level " + std::to_string(l));
    out.crossing_pairs.push_back(static_cast<int>(pairs.size()));
  }

  // A level-L face's ancestor is its index over 4^L (subdiv/butterfly.h).
  const TriMesh fine = level_mesh(smooth, level);
  const int per_control = 1 << (2 * level);
  for (const auto& [name, vertex_in] : sets) {
    const std::vector<char> control_in = faces_within(m, vertex_in);
    std::vector<char> fine_in(fine.num_triangles(), 0);
    for (int f = 0; f < fine.num_triangles(); ++f) fine_in[f] = control_in[f / per_control];
    const std::vector<double> angles = dihedral_angles(fine, fine_in);
    RegionRoughness r;
    r.region = name;
    r.edges = static_cast<int>(angles.size());
    if (!angles.empty()) {
      double sum = 0;
      for (double x : angles) sum += x;
      r.mean_deg = sum / angles.size();
      r.p95_deg = percentile(angles, 0.95);
      r.p99_deg = percentile(angles, 0.99);
      r.max_deg = angles.back();
    }
    out.regions.push_back(r);
  }
  return Status::success();
}

}  // namespace lk
