// Small analytic shapes for the fitting tests: an icosphere deformed into
// ellipsoids and bumps, and points sampled uniformly on a mesh's surface.
// The ground truth is known exactly, so the tests can tell a wrong fit.
#pragma once
#include "mesh/geometry.h"
#include "mesh/primitives.h"
#include "mesh/tri_mesh.h"

#include <cmath>
#include <map>
#include <random>

namespace lk::test {

// Unit icosphere with `levels` 1:4 splits (levels 3: 642 vertices).
inline TriMesh icosphere(int levels) { return make_icosphere(levels); }

// Ellipsoid with semi-axes r plus a Gaussian bump of height h (along the
// outward direction) centred on direction `at`, of angular width sigma.
inline TriMesh bumpy_ellipsoid(const TriMesh& sphere, const Vec3& r, const Vec3& at, double h, double sigma) {
  TriMesh m = sphere;
  const Vec3 a = at.normalized();
  for (Vec3& p : m.positions) {
    const Vec3 u = p.normalized();
    const double ang = std::acos(std::clamp(u.dot(a), -1.0, 1.0));
    const double bump = h * std::exp(-0.5 * ang * ang / (sigma * sigma));
    p = Vec3(u.x() * r.x(), u.y() * r.y(), u.z() * r.z()) + bump * u;
  }
  return m;
}

// n points uniformly on the surface (area-weighted), plus Gaussian noise.
inline std::vector<Vec3> sample_surface(const TriMesh& m, int n, double noise, unsigned seed) {
  std::mt19937 rng(seed);
  std::vector<double> cdf(m.num_triangles());
  double acc = 0;
  for (int f = 0; f < m.num_triangles(); ++f) {
    acc += face_normal_area(m, f).norm();
    cdf[f] = acc;
  }
  std::uniform_real_distribution<double> U(0, 1);
  std::normal_distribution<double> N(0, 1);
  std::vector<Vec3> pts(n);
  for (int i = 0; i < n; ++i) {
    const int f = int(std::lower_bound(cdf.begin(), cdf.end(), U(rng) * acc) - cdf.begin());
    double a = U(rng), b = U(rng);
    if (a + b > 1) { a = 1 - a; b = 1 - b; }
    const Tri& t = m.triangles[std::min(f, m.num_triangles() - 1)];
    pts[i] = (1 - a - b) * m.positions[t[0]] + a * m.positions[t[1]] + b * m.positions[t[2]] +
             noise * Vec3(N(rng), N(rng), N(rng));
  }
  return pts;
}

}  // namespace lk::test
