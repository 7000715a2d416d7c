// Small analytic shapes for the fitting tests: an icosphere deformed into
// ellipsoids and bumps, and points sampled uniformly on a mesh's surface.
// The ground truth is known exactly, so the tests can tell a wrong fit.
#pragma once
#include "mesh/geometry.h"
#include "mesh/tri_mesh.h"

#include <cmath>
#include <map>
#include <random>

namespace lk::test {

// Unit icosphere with `levels` 1:4 splits (levels 3: 642 vertices).
inline TriMesh icosphere(int levels) {
  TriMesh m;
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  m.positions = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                 {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (Vec3& p : m.positions) p.normalize();
  m.triangles = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                 {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
                 {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      auto key = std::make_pair(std::min(a, b), std::max(a, b));
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      m.positions.push_back((m.positions[a] + m.positions[b]).normalized());
      const int id = m.num_vertices() - 1;
      mid[key] = id;
      return id;
    };
    std::vector<Tri> next;
    for (const Tri& f : m.triangles) {
      const int a = midpoint(f[0], f[1]), b = midpoint(f[1], f[2]), c = midpoint(f[2], f[0]);
      next.push_back({f[0], a, c});
      next.push_back({f[1], b, a});
      next.push_back({f[2], c, b});
      next.push_back({a, b, c});
    }
    m.triangles = next;
  }
  return m;
}

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
