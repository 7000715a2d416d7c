// Per-vertex ambient occlusion by ray casting (see ambient_occlusion.h).
#include "render/ambient_occlusion.h"

#include "mesh/geometry.h"
#include "raycast/bvh.h"

#include <cmath>
#include <string>

namespace lk {

Status vertex_ambient_occlusion(const TriMesh& mesh, const OcclusionOptions& options,
                                std::vector<float>& out, const ProgressFn& progress) {
  out.clear();
  if (mesh.positions.empty() || mesh.triangles.empty())
    return Status::error(ErrorCode::Empty, "ambient occlusion: mesh has no vertices or triangles");
  if (options.rays < 1 || options.rays > 4096)
    return Status::error(ErrorCode::InvalidInput, "ambient occlusion: rays must be 1..4096");
  if (!(options.max_distance_fraction > 0))
    return Status::error(ErrorCode::InvalidInput, "ambient occlusion: max_distance_fraction must be positive");
  if (mesh.num_vertices() > options.max_vertices)
    return Status::error(ErrorCode::TooLarge, "ambient occlusion: " + std::to_string(mesh.num_vertices()) +
                                                  " vertices, more than max_vertices " +
                                                  std::to_string(options.max_vertices));
  MeshBvh bvh;
  Status s = build_bvh(mesh, bvh);
  if (!s) return s;
  const std::vector<Vec3> normals =
      mesh.normals.size() == mesh.positions.size() ? mesh.normals : vertex_normals(mesh);
  const double reach = options.max_distance_fraction * bounding_box(mesh.positions).diagonal();
  // Rays start a hair off the surface so they do not hit the vertex's own fan.
  const double lift = 1e-4 * bounding_box(mesh.positions).diagonal();

  // Cosine-weighted directions in the unit hemisphere around +z: a spiral
  // (golden angle) over the disc, lifted onto the hemisphere (Malley).
  const int n = options.rays;
  const double golden = 3.14159265358979 * (3.0 - std::sqrt(5.0));
  std::vector<Vec3> local(n);
  for (int k = 0; k < n; ++k) {
    const double r = std::sqrt((k + 0.5) / n), a = k * golden;
    local[k] = Vec3(r * std::cos(a), r * std::sin(a), std::sqrt(std::max(0.0, 1.0 - r * r)));
  }

  out.assign(mesh.positions.size(), 1.0f);
  const int nv = mesh.num_vertices();
  for (int v = 0; v < nv; ++v) {
    if ((v & 1023) == 0 && !report(progress, "ambient occlusion", double(v) / nv))
      return Status::error(ErrorCode::Cancelled, "ambient occlusion cancelled");
    const Vec3& nrm = normals[v];
    if (nrm.squaredNorm() < 0.5) continue;  // isolated vertex: leave open
    // An orthonormal frame around the normal, turned by a per-vertex angle
    // (a hash of the index) so neighbours sample different directions.
    Vec3 t = std::abs(nrm.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
    t = (t - nrm * nrm.dot(t)).normalized();
    const Vec3 b = nrm.cross(t);
    const double turn = 2 * 3.14159265358979 * ((static_cast<unsigned>(v) * 2654435761u) >> 8) / double(1u << 24);
    const Vec3 tu = std::cos(turn) * t + std::sin(turn) * b, bu = nrm.cross(tu);
    int open = 0;
    for (const Vec3& d : local) {
      Ray ray;
      ray.direction = d.x() * tu + d.y() * bu + d.z() * nrm;
      ray.origin = mesh.positions[v] + lift * nrm;
      ray.t_min = 0.0;
      ray.t_max = reach;
      open += !intersect_any(bvh, ray);
    }
    out[v] = static_cast<float>(open) / n;
  }
  report(progress, "ambient occlusion", 1.0);
  return Status::success();
}

}  // namespace lk
