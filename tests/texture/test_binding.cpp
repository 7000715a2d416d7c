// Vertex-to-photo binding (tarini2002 Sec. 3.2): visibility = inside the
// photo, facing the camera, not occluded, not on a silhouette.
#include "fixtures.h"
#include "mesh/geometry.h"
#include "raycast/bvh.h"
#include "texture/binding.h"

#include <catch2/catch.hpp>

using namespace lk;
using namespace lk::test;

namespace {

struct Scene {
  TriMesh mesh;
  int back_begin = 0, back_end = 0;     // the back plane (z = 0, faces +z)
  int front_begin = 0, front_end = 0;   // the occluder (z = 0.5, faces +z)
  int away_begin = 0, away_end = 0;     // a plane facing -z (away from the camera)
};

Scene make_scene() {
  Scene s;
  s.back_begin = 0;
  // Shifted off the occluder's grid lines: core/raycast's Moller-Trumbore
  // test is not watertight, and a shadow ray through exactly a shared edge
  // of the occluder can slip between its two triangles.
  s.mesh = plane_grid(20, -1.0123, 0.9877, -0.9931, 1.0069, 0.0);
  s.back_end = s.front_begin = s.mesh.num_vertices();
  append_mesh(s.mesh, plane_grid(4, -0.3, 0.3, -0.3, 0.3, 0.5));
  s.front_end = s.away_begin = s.mesh.num_vertices();
  append_mesh(s.mesh, plane_grid(4, 1.2, 1.6, -0.2, 0.2, 0.2, /*facing_plus_z=*/false));
  s.away_end = s.mesh.num_vertices();
  return s;
}

}  // namespace

TEST_CASE("binding: occluded, back-facing and out-of-photo vertices are not bound") {
  const Scene s = make_scene();
  const Camera cam = look_at_camera(Vec3(0, 0, 4), Vec3::Zero(), Vec3::UnitY(), 700, 640, 480);
  MeshBvh bvh;
  REQUIRE(build_bvh(s.mesh, bvh).ok());
  VertexBinding b;
  REQUIRE(bind_vertices(s.mesh, vertex_normals(s.mesh), bvh, {cam}, BindingOptions(), b).ok());
  REQUIRE(b.valid.size() == size_t(s.mesh.num_vertices()));

  int occluded = 0, open = 0;
  for (int v = s.back_begin; v < s.back_end; ++v) {
    const Vec3& p = s.mesh.positions[v];
    Vec2 px(0, 0);
    REQUIRE(cam.project(p, px));
    // Behind the occluder as seen from the camera: the ray to (0,0,4) crosses
    // z = 0.5 at 7/8 of p's x, y.
    const bool behind = std::abs(p.x() * 7 / 8) < 0.3 - 1e-6 && std::abs(p.y() * 7 / 8) < 0.3 - 1e-6;
    const bool clear = std::abs(p.x() * 7 / 8) > 0.3 + 0.02 || std::abs(p.y() * 7 / 8) > 0.3 + 0.02;
    const bool inside = px.x() > 3 && px.x() < 637 && px.y() > 3 && px.y() < 477;
    if (behind) {
      INFO("vertex " << p.transpose());
      CHECK_FALSE(b.bound(v));
      ++occluded;
    } else if (clear && inside) {
      CHECK(b.bound(v));
      CHECK(b.main_photo[v] == 0);
      CHECK(b.facing[v] > 0.8f);
      ++open;
    } else if (!inside && (px.x() < 1 || px.x() > 639 || px.y() < 1 || px.y() > 479)) {
      CHECK_FALSE(b.bound(v));
    }
  }
  CHECK(occluded > 20);
  CHECK(open > 100);
  for (int v = s.front_begin; v < s.front_end; ++v) CHECK(b.bound(v));     // the occluder itself is seen
  for (int v = s.away_begin; v < s.away_end; ++v) CHECK_FALSE(b.bound(v));  // faces away
}

TEST_CASE("binding: silhouette vertices (a fan triangle faces away) are not bound") {
  // A roof ridge along y: two planes meeting at x = 0, seen from the side so
  // one slope faces the camera and the other faces away. The ridge vertices
  // face the camera (their normal points up) but their fan includes a
  // triangle of the far slope: silhouette.
  TriMesh m;
  const int n = 6;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= 2 * n; ++i) {
      const double x = -1 + double(i) / n, y = -1 + 2.0 * j / n;
      m.positions.emplace_back(x, y, 1.0 - std::abs(x));
    }
  auto id = [n](int i, int j) { return j * (2 * n + 1) + i; };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < 2 * n; ++i) {
      m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  // Camera low on the +x side, looking at the ridge nearly along the -x slope's plane... 
  // from direction (1, 0, 0.2): sees the +x slope (normal (1,0,1)/sqrt2) and
  // not the -x slope (normal (-1,0,1)/sqrt2, dot < 0).
  const Camera cam = look_at_camera(Vec3(4, 0, 0.8 + 0.2 * 4), Vec3(0, 0, 0.8), Vec3::UnitZ(), 300, 640, 480);
  MeshBvh bvh;
  REQUIRE(build_bvh(m, bvh).ok());
  VertexBinding b;
  BindingOptions opt;
  opt.min_facing = 0.05;
  REQUIRE(bind_vertices(m, vertex_normals(m), bvh, {cam}, opt, b).ok());
  int ridge_checked = 0, slope_bound = 0;
  for (int j = 1; j < n; ++j) {
    const int ridge = id(n, j);
    const Vec3 dir = (cam.center() - m.positions[ridge]).normalized();
    REQUIRE(vertex_normals(m)[ridge].dot(dir) > 0.1);  // faces the camera...
    CHECK_FALSE(b.bound(ridge));                      // ...but sits on the silhouette
    ++ridge_checked;
    slope_bound += b.bound(id(n + 3, j));
    CHECK_FALSE(b.bound(id(n - 3, j)));  // the far slope faces away
  }
  CHECK(ridge_checked == n - 1);
  CHECK(slope_bound == n - 1);
}

TEST_CASE("binding: the main photo is the most frontal valid one") {
  const TriMesh plane = plane_grid(10, -0.5, 0.5, -0.5, 0.5, 0.0);
  const Camera frontal = look_at_camera(Vec3(0, 0, 3), Vec3::Zero(), Vec3::UnitY(), 600, 640, 480);
  const Camera slanted = look_at_camera(Vec3(2, 0, 2), Vec3::Zero(), Vec3::UnitY(), 600, 640, 480);
  MeshBvh bvh;
  REQUIRE(build_bvh(plane, bvh).ok());
  VertexBinding b;
  REQUIRE(bind_vertices(plane, vertex_normals(plane), bvh, {slanted, frontal}, BindingOptions(), b).ok());
  for (int v = 0; v < plane.num_vertices(); ++v) {
    REQUIRE(b.valid[v] == 3u);
    CHECK(b.main_photo[v] == 1);
  }
}

TEST_CASE("binding: bad inputs are errors") {
  const TriMesh plane = plane_grid(4, -0.5, 0.5, -0.5, 0.5, 0.0);
  MeshBvh bvh;
  REQUIRE(build_bvh(plane, bvh).ok());
  VertexBinding b;
  Camera no_size;
  CHECK(bind_vertices(plane, vertex_normals(plane), bvh, {no_size}, BindingOptions(), b).code ==
        ErrorCode::InvalidInput);
  const Camera cam = look_at_camera(Vec3(0, 0, 3), Vec3::Zero(), Vec3::UnitY(), 600, 640, 480);
  CHECK(bind_vertices(plane, {}, bvh, {cam}, BindingOptions(), b).code == ErrorCode::InvalidInput);
  CHECK(bind_vertices(plane, vertex_normals(plane), MeshBvh(), {cam}, BindingOptions(), b).code ==
        ErrorCode::InvalidInput);
  std::vector<Camera> many(kMaxTexturePhotos + 1, cam);
  CHECK(bind_vertices(plane, vertex_normals(plane), bvh, many, BindingOptions(), b).code == ErrorCode::InvalidInput);
}
