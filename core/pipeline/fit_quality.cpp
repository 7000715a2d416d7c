#include "pipeline/fit_quality.h"

#include "head/generic_head.h"
#include "mesh/geometry.h"
#include "mesh/topology.h"
#include "multires/displacement.h"
#include "pipeline/fit_head.h"
#include "head/head_pockets.h"
#include "raycast/self_intersection.h"

#include <algorithm>

namespace lk {
namespace {

// Level-`level` vertices of a region given by its control vertices.
std::vector<char> level_mask(const MultiresMesh& mesh, int level, const std::vector<int>& control_vertices) {
  return propagate_vertex_mask(mesh, vertex_mask(control_vertices, mesh.num_vertices(0)))[level];
}

bool pair_touches(const std::vector<Tri>& tris, const std::vector<char>& mask, const std::array<int, 2>& p) {
  for (int f : p)
    for (int v : tris[f])
      if (mask[v]) return true;
  return false;
}

}  // namespace

int count_pairs_touching(const MultiresMesh& mesh, int level, const std::vector<std::array<int, 2>>& pairs,
                         const std::vector<int>& control_vertices) {
  const std::vector<char> mask = level_mask(mesh, level, control_vertices);
  int n = 0;
  for (const auto& p : pairs) n += pair_touches(mesh.triangles(level), mask, p);
  return n;
}

CrossingCounts count_crossings_by_region(const MultiresMesh& mesh, int level,
                                         const std::vector<std::array<int, 2>>& pairs,
                                         const HeadAnnotations& annotations) {
  const std::vector<Tri>& tris = mesh.triangles(level);
  std::map<std::string, std::vector<char>> masks;
  for (const auto& kv : annotations.regions) masks[kv.first] = level_mask(mesh, level, kv.second);
  const std::vector<char> none(mesh.num_vertices(level), 0);
  auto region = [&](const char* name) -> const std::vector<char>& {
    auto it = masks.find(name);
    return it == masks.end() ? none : it->second;
  };
  const std::vector<char>&lips = region("lips"), &ears = region("ears");
  std::vector<char> sockets = none;
  {
    TriMesh control;  // connectivity only
    control.positions.assign(mesh.num_vertices(0), Vec3::Zero());
    control.triangles = mesh.triangles(0);
    MeshTopology topo;
    if (build_topology(control, topo).ok()) {
      std::vector<int> socket_vertices;
      const std::vector<char> flags = eye_socket_vertices(topo, annotations);
      for (int v = 0; v < static_cast<int>(flags.size()); ++v)
        if (flags[v]) socket_vertices.push_back(v);
      sockets = level_mask(mesh, level, socket_vertices);
    }
  }
  auto touches = [&](const std::vector<char>& m, const std::array<int, 2>& p) { return pair_touches(tris, m, p); };
  CrossingCounts c;
  c.total = static_cast<int>(pairs.size());
  for (const auto& p : pairs) {
    if (touches(lips, p)) {
      ++c.lips;
    } else if (touches(ears, p)) {
      ++c.ears;
    } else if (touches(sockets, p)) {
      ++c.eye_sockets;
    } else {
      ++c.rest;
      for (const auto& kv : masks)
        if (touches(kv.second, p)) ++c.rest_by_region[kv.first];
    }
  }
  return c;
}

void count_turned_and_degenerate(const TriMesh& m, const TriMesh& reference, int& flipped, int& degenerate) {
  // Same connectivity (the header): reference's positions under m's triangles.
  flipped = reference.positions.size() == m.positions.size()
                ? count_turned_triangles(m.triangles, m.positions, reference.positions)
                : 0;
  degenerate = 0;
  const double area_eps = 1e-6 * surface_area(m) / std::max(1, m.num_triangles());
  for (int f = 0; f < m.num_triangles(); ++f)
    if (0.5 * face_normal_area(m, f).norm() < area_eps) ++degenerate;
}

Status finest_region_skip(const FitHeadResult& fit, const GenericHead& generic, const std::string& region,
                          std::vector<char>& skip) {
  skip.clear();
  if (fit.multires.num_levels() < 1 || fit.level_meshes.empty())
    return Status::error(ErrorCode::InvalidInput, "fit to scan: the fit holds no subdivision levels");
  const auto named = generic.annotations.regions.find(region);
  if (!region.empty() && named == generic.annotations.regions.end())
    return Status::error(ErrorCode::InvalidInput, "fit to scan: the head has no region '" + region + "'");
  MeshTopology topo;
  Status st = build_topology(generic.mesh, topo);
  if (!st) return st;
  // Skipped: the pockets and every vertex outside the region (a new vertex
  // is skipped when both its parents are, so the region's rim is kept).
  std::vector<char> control = pocket_vertices(topo, generic.annotations);
  if (!region.empty()) {
    const std::vector<char> in_region = vertex_mask(named->second, static_cast<int>(control.size()));
    for (size_t v = 0; v < control.size(); ++v) control[v] = control[v] || !in_region[v];
  }
  skip = propagate_vertex_mask(fit.multires, control).back();
  return Status::success();
}

Status measure_fit_to_scan(const FitHeadResult& fit, const PointCloud& scan, const GenericHead& generic,
                           CoveredDistances& out, const std::string& region, std::vector<double>* per_vertex) {
  out = CoveredDistances();
  std::vector<char> skip;
  Status st = finest_region_skip(fit, generic, region, skip);
  if (!st) return st;
  TriMesh scan_mesh;
  scan_mesh.triangles = scan.faces;
  scan_mesh.positions.reserve(scan.positions.size());
  for (const Vec3& p : scan.positions) scan_mesh.positions.push_back(fit.scan_to_head.apply(p));
  if (!std::all_of(scan_mesh.positions.begin(), scan_mesh.positions.end(), [](const Vec3& p) { return p.allFinite(); }))
    return Status::error(ErrorCode::InvalidInput, "fit to scan: the scan holds non-finite positions");
  if (scan.faces.empty()) {
    // Stray returns far sparser than the scan's sampling are left out, as
    // the fit leaves them out (DisplacementOptions::isolated_density_ratio):
    // a lip vertex with no skin points near had its patch on junk 20 mm
    // in front of the mouth.
    const std::vector<char> isolated =
        isolated_scan_points(scan_mesh.positions, DisplacementOptions{}.isolated_density_ratio);
    std::vector<Vec3> kept;
    kept.reserve(scan_mesh.positions.size());
    for (size_t i = 0; i < isolated.size(); ++i)
      if (!isolated[i]) kept.push_back(scan_mesh.positions[i]);
    out = surface_to_cloud(fit.level_meshes.back(), skip, kept, 16, per_vertex);
  } else {
    out = surface_to_reference(fit.level_meshes.back(), skip, scan_mesh, inside_scan_mesh(scan_mesh), per_vertex);
  }
  return Status::success();
}

std::vector<Vec3> distance_colors(const std::vector<double>& metres) {
  // Stops of the ramp (mm -> linear RGB).
  struct Stop {
    double mm;
    Vec3 rgb;
  };
  static const Stop stops[] = {{0.0, Vec3(0.85, 0.85, 0.85)}, {0.25, Vec3(0.85, 0.85, 0.85)},
                               {1.0, Vec3(0.95, 0.75, 0.05)}, {3.0, Vec3(0.75, 0.02, 0.02)}};
  const Vec3 unmeasured(0.22, 0.28, 0.5);
  std::vector<Vec3> out(metres.size(), unmeasured);
  for (size_t i = 0; i < metres.size(); ++i) {
    if (!(metres[i] >= 0)) continue;
    const double mm = 1e3 * metres[i];
    out[i] = stops[3].rgb;
    for (int s = 1; s < 4; ++s)
      if (mm < stops[s].mm) {
        const double t = (mm - stops[s - 1].mm) / (stops[s].mm - stops[s - 1].mm);
        out[i] = (1 - t) * stops[s - 1].rgb + t * stops[s].rgb;
        break;
      }
  }
  return out;
}

Status measure_fit_quality(const FitHeadResult& fit, const HeadAnnotations& annotations, FitQuality& out) {
  out = FitQuality();
  const int L = fit.multires.num_levels();
  if (L < 1) return Status::error(ErrorCode::InvalidInput, "fit quality: the fit holds no subdivision levels");
  out.level = L;
  const TriMesh finest = level_mesh(fit.multires, L);
  out.triangles = finest.num_triangles();

  // The fold limiter already searched the finest level whole as it left it
  // (its second pass or last resort: the same sorted pairs as a search
  // here), unless it moved since (an edit).
  std::vector<std::array<int, 2>> pairs;
  Status st = finest_crossing_pairs(fit.fold_limit, finest, pairs);
  if (!st) return st;
  out.crossings = count_crossings_by_region(fit.multires, L, pairs, annotations);

  MultiresMesh smooth;
  st = build_multires(fit.control, fit.multires.creases, L, smooth);
  if (!st) return st;
  const TriMesh smooth_finest = level_mesh(smooth, L);
  count_turned_and_degenerate(finest, smooth_finest, out.flipped, out.degenerate);
  pairs.clear();
  st = find_self_intersections(smooth_finest, pairs);
  if (!st) return st;
  out.smooth_crossings = count_crossings_by_region(smooth, L, pairs, annotations);

  pairs.clear();
  st = find_self_intersections(fit.control, pairs);
  if (!st) return st;
  out.control_crossings = static_cast<int>(pairs.size());
  return Status::success();
}

}  // namespace lk
