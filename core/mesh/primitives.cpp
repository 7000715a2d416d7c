#include "mesh/primitives.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

namespace lk {

TriMesh make_icosahedron() {
  TriMesh m;
  const double g = (1.0 + std::sqrt(5.0)) / 2.0;
  m.positions = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0}, {0, -1, g}, {0, 1, g},
                 {0, -1, -g}, {0, 1, -g}, {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
  for (Vec3& p : m.positions) p.normalize();
  m.triangles = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                 {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                 {3, 8, 9},  {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  return m;
}

TriMesh make_icosphere(int splits) {
  TriMesh m = make_icosahedron();
  for (int s = 0; s < splits; ++s) {
    std::map<std::pair<int, int>, int> midpoint_of;
    auto midpoint = [&](int a, int b) {
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      const auto it = midpoint_of.find(key);
      if (it != midpoint_of.end()) return it->second;
      m.positions.push_back((m.positions[a] + m.positions[b]).normalized());
      return midpoint_of[key] = m.num_vertices() - 1;
    };
    std::vector<Tri> finer;
    finer.reserve(4 * m.triangles.size());
    for (const Tri& t : m.triangles) {
      const int a = midpoint(t[0], t[1]), b = midpoint(t[1], t[2]), c = midpoint(t[2], t[0]);
      finer.push_back({t[0], a, c});
      finer.push_back({t[1], b, a});
      finer.push_back({t[2], c, b});
      finer.push_back({a, b, c});
    }
    m.triangles = std::move(finer);
  }
  return m;
}

TriMesh make_regular_grid(int n, int m) {
  TriMesh g;
  for (int j = 0; j <= m; ++j)
    for (int i = 0; i <= n; ++i) g.positions.push_back(Vec3(i, j, 0));
  auto id = [n](int i, int j) { return j * (n + 1) + i; };
  for (int j = 0; j < m; ++j)
    for (int i = 0; i < n; ++i) {
      g.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      g.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return g;
}

}  // namespace lk
