// One 1-to-4 split of a triangle list: a new vertex at each edge's
// midpoint, shared by the edge's two triangles. The callers place the new
// vertices (and whatever else a vertex carries) from the edges returned:
// the same surface sampled more densely (the dense copies of bench
// fit-real, the draw bench's level-3-sized head, the tests).
#pragma once
#include "common/types.h"
#include "mesh/tri_mesh.h"

#include <algorithm>
#include <array>
#include <map>
#include <utility>
#include <vector>

namespace lk {

// The four triangles of each of `triangles` (vertices 0..vertex_count-1),
// in order; new vertex vertex_count + k is the midpoint of edges[k].
inline std::vector<Tri> split_at_midpoints(const std::vector<Tri>& triangles, int vertex_count,
                                           std::vector<std::array<int, 2>>& edges) {
  edges.clear();
  std::map<std::pair<int, int>, int> made;
  auto midpoint = [&](int a, int b) {
    const std::pair<int, int> key(std::min(a, b), std::max(a, b));
    const auto found = made.find(key);
    if (found != made.end()) return found->second;
    edges.push_back({a, b});
    return made[key] = vertex_count + static_cast<int>(edges.size()) - 1;
  };
  std::vector<Tri> out;
  out.reserve(4 * triangles.size());
  for (const Tri& t : triangles) {
    const int ab = midpoint(t[0], t[1]), bc = midpoint(t[1], t[2]), ca = midpoint(t[2], t[0]);
    out.push_back({t[0], ab, ca});
    out.push_back({ab, t[1], bc});
    out.push_back({ca, bc, t[2]});
    out.push_back({ab, bc, ca});
  }
  return out;
}

// A scan given as a mesh, split so: the new points at the midpoints, their
// normals (normalized) and colours the averages of the edge's ends.
inline PointCloud split_at_midpoints(const PointCloud& scan) {
  std::vector<std::array<int, 2>> edges;
  PointCloud out = scan;
  out.faces = split_at_midpoints(scan.faces, scan.size(), edges);
  for (const auto& [a, b] : edges) {
    out.positions.push_back(0.5 * (scan.positions[a] + scan.positions[b]));
    if (!scan.normals.empty()) {
      const Vec3 n = scan.normals[a] + scan.normals[b];
      out.normals.push_back(n.norm() > 0 ? Vec3(n.normalized()) : scan.normals[a]);
    }
    if (!scan.colors.empty()) out.colors.push_back(0.5 * (scan.colors[a] + scan.colors[b]));
  }
  return out;
}

}  // namespace lk
