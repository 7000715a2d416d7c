// Shared scenes for the texturing tests: a plane grid with its own uvs and
// the generic head photographed by known cameras.
#pragma once
#include "head/generic_head.h"
#include "texture/synthetic_photo.h"
#include "texture/texture.h"

#include <cmath>

namespace lk::test {

// An n x n grid over [x0,x1] x [y0,y1] at height z, facing +z (or -z when
// flipped), uvs = the normalized grid coordinates.
inline TriMesh plane_grid(int n, double x0, double x1, double y0, double y1, double z, bool facing_plus_z = true) {
  TriMesh m;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const double u = double(i) / n, v = double(j) / n;
      m.positions.emplace_back(x0 + u * (x1 - x0), y0 + v * (y1 - y0), z);
      m.uvs.emplace_back(0.02 + 0.96 * u, 0.02 + 0.96 * v);
    }
  auto id = [n](int i, int j) { return j * (n + 1) + i; };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      if (facing_plus_z) {
        m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
        m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
      } else {
        m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i + 1, j)});
        m.triangles.push_back({id(i, j), id(i, j + 1), id(i + 1, j + 1)});
      }
    }
  return m;
}

// Appends b to a (indices shifted).
inline void append_mesh(TriMesh& a, const TriMesh& b) {
  const int off = a.num_vertices();
  a.positions.insert(a.positions.end(), b.positions.begin(), b.positions.end());
  a.uvs.insert(a.uvs.end(), b.uvs.begin(), b.uvs.end());
  for (Tri t : b.triangles) a.triangles.push_back({t[0] + off, t[1] + off, t[2] + off});
}

// Cameras around the generic head (it looks along +z, up +y, ~0.2 m wide):
// front, two three-quarter views, two profiles, at ~0.9 m.
inline std::vector<Camera> head_cameras(const BBox& box, int width, int height, int count = 5) {
  const Vec3 c = box.center();
  const double r = 0.9;
  const double angles[] = {0.0, 0.8, -0.8, 1.6, -1.6};
  std::vector<Camera> cams;
  for (int i = 0; i < count && i < 5; ++i) {
    const Vec3 eye = c + Vec3(r * std::sin(angles[i]), 0.05, r * std::cos(angles[i]));
    // Focal so the head (~0.3 m tall) fills about two thirds of the height.
    cams.push_back(look_at_camera(eye, c, Vec3::UnitY(), 0.66 * height * r / box.size().y(), width, height));
  }
  return cams;
}

// Linear-light PSNR (dB) between two linear colours sets, peak 1.
inline double psnr_from_mse(double mse) { return mse > 0 ? 10 * std::log10(1.0 / mse) : 200.0; }

}  // namespace lk::test
