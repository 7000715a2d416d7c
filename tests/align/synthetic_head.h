// A procedural head-like test shape for the alignment tests: cranium, jaw,
// nose and ears as ellipsoids and a capped neck cylinder (all closed and
// outward-oriented, overlapping), with annotations
// in the generic head's conventions (looks along +z, up +y, metres, about
// 0.26 m from neck cut to crown). Front/back, up/down and left/right are
// told apart by the nose, the neck and a slightly offset left ear, so every
// one of the 9 affine parameters is visible in some silhouette.
#pragma once
#include "head/head_model.h"
#include "mesh/tri_mesh.h"

#include <algorithm>
#include <cmath>
#include <random>

namespace lk::test {

inline void add_ellipsoid(TriMesh& m, const Vec3& c, const Vec3& r, int stacks = 20, int slices = 40) {
  const double pi = 3.14159265358979323846;
  const int base = m.num_vertices();
  m.positions.push_back(c + Vec3(0, r.y(), 0));
  for (int i = 1; i < stacks; ++i) {
    const double phi = pi * i / stacks;
    for (int j = 0; j < slices; ++j) {
      const double th = 2 * pi * j / slices;
      m.positions.push_back(c + Vec3(r.x() * std::sin(phi) * std::sin(th), r.y() * std::cos(phi),
                                     r.z() * std::sin(phi) * std::cos(th)));
    }
  }
  m.positions.push_back(c - Vec3(0, r.y(), 0));
  const int south = m.num_vertices() - 1;
  auto ring = [&](int i, int j) { return base + 1 + (i - 1) * slices + (j % slices); };
  for (int j = 0; j < slices; ++j) m.triangles.push_back({base, ring(1, j), ring(1, j + 1)});
  for (int i = 1; i + 1 < stacks; ++i)
    for (int j = 0; j < slices; ++j) {
      m.triangles.push_back({ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)});
      m.triangles.push_back({ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)});
    }
  for (int j = 0; j < slices; ++j) m.triangles.push_back({ring(stacks - 1, j), south, ring(stacks - 1, j + 1)});
}

// Closed cylinder along y from y0 to y1 (capped, outward-oriented).
inline void add_cylinder(TriMesh& m, const Vec3& c, double radius_x, double radius_z, double y0, double y1,
                         int rings = 12, int slices = 40) {
  const double pi = 3.14159265358979323846;
  const int base = m.num_vertices();
  for (int i = 0; i <= rings; ++i)
    for (int j = 0; j < slices; ++j) {
      const double th = 2 * pi * j / slices;
      m.positions.push_back(Vec3(c.x() + radius_x * std::sin(th), y0 + (y1 - y0) * i / rings,
                                 c.z() + radius_z * std::cos(th)));
    }
  auto at = [&](int i, int j) { return base + i * slices + (j % slices); };
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < slices; ++j) {
      m.triangles.push_back({at(i, j), at(i, j + 1), at(i + 1, j + 1)});
      m.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i + 1, j)});
    }
  const int bottom = m.num_vertices();
  m.positions.push_back(Vec3(c.x(), y0, c.z()));
  const int top = m.num_vertices();
  m.positions.push_back(Vec3(c.x(), y1, c.z()));
  for (int j = 0; j < slices; ++j) {
    m.triangles.push_back({bottom, at(0, j + 1), at(0, j)});
    m.triangles.push_back({top, at(rings, j), at(rings, j + 1)});
  }
}

// neck_bottom: where the neck cylinder ends (the generic: -0.19; a scan
// with a longer neck: lower).
inline GenericHead synthetic_head(double neck_bottom = -0.19) {
  GenericHead h;
  TriMesh& m = h.mesh;
  add_ellipsoid(m, Vec3(0, 0.03, -0.01), Vec3(0.078, 0.105, 0.1));     // cranium
  add_ellipsoid(m, Vec3(0, -0.045, 0.03), Vec3(0.058, 0.06, 0.066));   // jaw and cheeks
  add_ellipsoid(m, Vec3(0, -0.005, 0.098), Vec3(0.014, 0.026, 0.022), 10, 20);  // nose
  add_ellipsoid(m, Vec3(0.079, 0.012, -0.012), Vec3(0.012, 0.032, 0.02), 10, 20);   // left ear
  add_ellipsoid(m, Vec3(-0.079, 0.006, -0.018), Vec3(0.012, 0.03, 0.02), 10, 20);   // right ear
  add_cylinder(m, Vec3(0, 0, -0.02), 0.05, 0.055, neck_bottom, -0.06);  // neck, capped
  HeadAnnotations& a = h.annotations;
  a.neck_clip.point = Vec3(0, -0.115, 0);
  a.neck_clip.normal = Vec3(0, 1, 0);
  a.back_clip.point = Vec3(0, 0, -0.2);  // behind everything: keeps the whole head
  a.back_clip.normal = Vec3(0, 0, 1);
  return h;
}

// Area-weighted uniform samples on the mesh surface.
inline PointCloud sample_surface(const TriMesh& m, int count, unsigned seed) {
  std::vector<double> cumulative(m.triangles.size());
  double total = 0;
  for (size_t f = 0; f < m.triangles.size(); ++f) {
    const Tri& t = m.triangles[f];
    total += 0.5 * (m.positions[t[1]] - m.positions[t[0]]).cross(m.positions[t[2]] - m.positions[t[0]]).norm();
    cumulative[f] = total;
  }
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  PointCloud cloud;
  cloud.positions.reserve(count);
  for (int i = 0; i < count; ++i) {
    const size_t f = std::lower_bound(cumulative.begin(), cumulative.end(), u(rng) * total) - cumulative.begin();
    const Tri& t = m.triangles[std::min(f, m.triangles.size() - 1)];
    double a = u(rng), b = u(rng);
    if (a + b > 1) { a = 1 - a; b = 1 - b; }
    cloud.positions.push_back(m.positions[t[0]] + a * (m.positions[t[1]] - m.positions[t[0]]) +
                              b * (m.positions[t[2]] - m.positions[t[0]]));
  }
  return cloud;
}

}  // namespace lk::test
