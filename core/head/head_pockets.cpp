#include "head/head_pockets.h"

#include <algorithm>

namespace lk {

std::vector<char> vertices_cut_off(const MeshTopology& topo, const std::vector<int>& loop) {
  const int nv = topo.num_vertices;
  std::vector<char> inside(nv, 0);
  if (loop.empty()) return inside;
  // Components of the mesh without the loop: all but the largest are inside.
  std::vector<int> component(nv, -1);
  for (int v : loop)
    if (v >= 0 && v < nv) component[v] = -2;
  std::vector<int> sizes;
  for (int seed = 0; seed < nv; ++seed) {
    if (component[seed] != -1) continue;
    const int id = static_cast<int>(sizes.size());
    sizes.push_back(0);
    std::vector<int> stack = {seed};
    component[seed] = id;
    while (!stack.empty()) {
      const int v = stack.back();
      stack.pop_back();
      ++sizes[id];
      for (int w : topo.rings[v])
        if (component[w] == -1) {
          component[w] = id;
          stack.push_back(w);
        }
    }
  }
  if (sizes.size() < 2) return inside;  // the loop cuts nothing off
  const int largest = static_cast<int>(std::max_element(sizes.begin(), sizes.end()) - sizes.begin());
  for (int v = 0; v < nv; ++v)
    if (component[v] >= 0 && component[v] != largest) inside[v] = 1;
  return inside;
}

std::vector<char> eye_socket_vertices(const MeshTopology& topo, const HeadAnnotations& ann) {
  std::vector<char> pocket(topo.num_vertices, 0);
  for (const EyeSocket* eye : {&ann.eye_left, &ann.eye_right}) {
    const std::vector<char> inside = vertices_cut_off(topo, eye->rim);
    for (size_t v = 0; v < pocket.size(); ++v) pocket[v] = pocket[v] || inside[v];
  }
  return pocket;
}

std::vector<char> pocket_vertices(const MeshTopology& topo, const HeadAnnotations& ann) {
  std::vector<char> pocket = eye_socket_vertices(topo, ann);
  for (int v : ann.constrained_vertices)
    if (v >= 0 && v < topo.num_vertices) pocket[v] = 1;
  for (const char* name : {"nostril_left", "nostril_right"})
    if (const auto it = ann.regions.find(name); it != ann.regions.end())
      for (int v : it->second)
        if (v >= 0 && v < topo.num_vertices) pocket[v] = 1;
  return pocket;
}

}  // namespace lk
