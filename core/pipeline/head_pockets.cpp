#include "pipeline/head_pockets.h"

#include <algorithm>

namespace lk {

std::vector<char> eye_socket_vertices(const MeshTopology& topo, const HeadAnnotations& ann) {
  const int nv = topo.num_vertices;
  std::vector<char> pocket(nv, 0);
  for (const EyeSocket* eye : {&ann.eye_left, &ann.eye_right}) {
    if (eye->rim.empty()) continue;
    // Components of the mesh without the rim: all but the largest are inside.
    std::vector<int> component(nv, -1);
    for (int v : eye->rim)
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
    if (sizes.size() < 2) continue;  // the rim cuts nothing off: no pocket
    const int largest = static_cast<int>(std::max_element(sizes.begin(), sizes.end()) - sizes.begin());
    for (int v = 0; v < nv; ++v)
      if (component[v] >= 0 && component[v] != largest) pocket[v] = 1;
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
