// Synthetic photos of a fitted head for the project tests that texture it:
// three photos (480 x 360, one camera) of the level in the scan frame, and
// 15 visible vertices per photo with their exact pixels.
#pragma once
#include "mesh/geometry.h"
#include "raycast/bvh.h"
#include "texture/binding.h"
#include "texture/synthetic_photo.h"
#include "project/texture_job.h"
#include "texture/texture.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <string>
#include <vector>

namespace lk::test {

struct Photos {
  std::vector<TexturePhoto> photos;
  std::vector<std::vector<Correspondence>> points;
  std::vector<std::string> names = {"front.png", "left.png", "right.png"};
};

inline Photos photograph(const TriMesh& mesh) {
  Photos out;
  const BBox box = bounding_box(mesh.positions);
  const double scale = 0.1 * box.size().y();
  const Vec3 c = box.center();
  const double r = 4.5 * box.size().y();
  MeshBvh bvh;
  REQUIRE(build_bvh(mesh, bvh).ok());
  const std::vector<Vec3> normals = vertex_normals(mesh);
  for (double angle : {0.0, 0.6, -0.6}) {
    const Vec3 eye = c + Vec3(r * std::sin(angle), 0.05 * r, r * std::cos(angle));
    const Camera cam = look_at_camera(eye, c, Vec3::UnitY(), 0.7 * 360 * r / box.size().y(), 480, 360);
    TexturePhoto photo;
    photo.camera = cam;  // the true camera (the texture job overwrites it unless cameras_given)
    const SurfaceColorFn field = [scale](const Vec3& p, const Vec3&) { return procedural_color_field(p, scale); };
    REQUIRE(render_synthetic_photo(mesh, cam, field, Vec3(0.1, 0.12, 0.15), photo.image).ok());
    VertexBinding b;
    BindingOptions bo;
    bo.min_facing = 0.4;
    REQUIRE(bind_vertices(mesh, normals, bvh, {cam}, bo, b).ok());
    std::vector<int> visible;
    for (int v = 0; v < mesh.num_vertices(); ++v)
      if (b.bound(v)) visible.push_back(v);
    REQUIRE(visible.size() >= 15);
    std::vector<Correspondence> points;
    for (int k = 0; k < 15; ++k) {  // spread over the visible vertices
      const int v = visible[visible.size() * k / 15];
      Vec2 px;
      REQUIRE(cam.project(mesh.positions[v], px));
      points.push_back({px, mesh.positions[v]});
    }
    out.photos.push_back(photo);
    out.points.push_back(points);
  }
  return out;
}

// The texture job's input of those photos, at size x size texels.
inline TextureJobInput job_input(const Photos& shots, int size) {
  TextureJobInput input;
  input.photos = shots.photos;
  input.points = shots.points;
  input.names = shots.names;
  input.options.size = size;
  return input;
}

}  // namespace lk::test
