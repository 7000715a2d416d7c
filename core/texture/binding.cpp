#include "texture/binding.h"

#include "mesh/geometry.h"

#include <cmath>
#include <string>

namespace lk {

Status bind_vertices(const TriMesh& mesh, const std::vector<Vec3>& normals, const MeshBvh& bvh,
                     const std::vector<Camera>& cameras, const BindingOptions& options,
                     VertexBinding& binding) {
  const int nv = mesh.num_vertices(), nf = mesh.num_triangles();
  const int np = static_cast<int>(cameras.size());
  if (static_cast<int>(normals.size()) != nv)
    return Status::error(ErrorCode::InvalidInput, "binding: " + std::to_string(normals.size()) +
                                                      " normals for " + std::to_string(nv) + " vertices");
  if (np > kMaxTexturePhotos)
    return Status::error(ErrorCode::InvalidInput, "binding: " + std::to_string(np) + " photos, at most " +
                                                      std::to_string(kMaxTexturePhotos) + " are supported");
  if (bvh.num_triangles() != nf || bvh.positions.size() != mesh.positions.size())
    return Status::error(ErrorCode::InvalidInput, "binding: the BVH was not built from this mesh");
  std::string why;
  if (!is_valid(mesh, &why)) return Status::error(ErrorCode::InvalidInput, "binding: " + why);
  for (int i = 0; i < np; ++i)
    if (cameras[i].width <= 0 || cameras[i].height <= 0)
      return Status::error(ErrorCode::InvalidInput, "binding: camera of photo " + std::to_string(i) +
                                                        " has no image size");

  binding.num_photos = np;
  binding.valid.assign(nv, 0);
  binding.facing.assign(static_cast<size_t>(nv) * np, 0.f);
  binding.main_photo.assign(nv, -1);
  if (np == 0 || nv == 0) return Status::success();

  // Fans as compressed rows: the silhouette test visits each vertex's triangles.
  std::vector<int> fan_start(nv + 1, 0), fan;
  for (const Tri& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) ++fan_start[t[k] + 1];
  for (int v = 0; v < nv; ++v) fan_start[v + 1] += fan_start[v];
  fan.resize(fan_start[nv]);
  {
    std::vector<int> fill(fan_start.begin(), fan_start.end() - 1);
    for (int f = 0; f < nf; ++f)
      for (int k = 0; k < 3; ++k) fan[fill[mesh.triangles[f][k]]++] = f;
  }
  const std::vector<Vec3> face_n = face_normals(mesh);
  const double offset = options.occlusion_offset * bounding_box(mesh.positions).diagonal();

  for (int i = 0; i < np; ++i) {
    const Camera& cam = cameras[i];
    const Vec3 eye = cam.center();
    const double lo_u = options.image_margin_px, hi_u = cam.width - options.image_margin_px;
    const double lo_v = options.image_margin_px, hi_v = cam.height - options.image_margin_px;
    for (int v = 0; v < nv; ++v) {
      const Vec3& p = mesh.positions[v];
      Vec2 px;
      if (!cam.project(p, px)) continue;
      if (!(px.x() >= lo_u && px.x() <= hi_u && px.y() >= lo_v && px.y() <= hi_v)) continue;
      const Vec3 to_eye = eye - p;
      const double dist = to_eye.norm();
      if (!(dist > 0)) continue;
      const Vec3 dir = to_eye / dist;
      const double facing = normals[v].dot(dir);
      if (!(facing > options.min_facing)) continue;
      bool silhouette = false;
      for (int j = fan_start[v]; j < fan_start[v + 1] && !silhouette; ++j)
        silhouette = face_n[fan[j]].dot(dir) < -options.silhouette_tolerance;
      if (silhouette) continue;
      // Shadow ray from just off the surface to the camera centre. Leaving
      // along the normal (which faces the camera) clears the vertex's own fan.
      Ray ray;
      ray.origin = p + offset * normals[v];
      ray.direction = eye - ray.origin;
      ray.t_min = 0.0;
      ray.t_max = 1.0;
      if (intersect_any(bvh, ray)) continue;
      binding.valid[v] |= std::uint64_t{1} << i;
      binding.facing[static_cast<size_t>(v) * np + i] = static_cast<float>(facing);
    }
  }
  for (int v = 0; v < nv; ++v) {
    float best = 0.f;
    for (int i = 0; i < np; ++i) {
      const float f = binding.facing[static_cast<size_t>(v) * np + i];
      if (binding.is_valid(v, i) && f > best) {
        best = f;
        binding.main_photo[v] = i;
      }
    }
  }
  return Status::success();
}

}  // namespace lk
