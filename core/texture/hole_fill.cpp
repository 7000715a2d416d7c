#include "texture/hole_fill.h"

#include <string>

namespace lk {

Status fill_vertex_colors(const MeshTopology& topology, std::vector<Vec3>& colors, std::vector<char>& colored,
                          const HoleFillOptions& options, HoleFillReport& report, std::vector<int>* fill_pass) {
  const int nv = topology.num_vertices;
  if (static_cast<int>(colors.size()) != nv || static_cast<int>(colored.size()) != nv ||
      static_cast<int>(topology.rings.size()) != nv)
    return Status::error(ErrorCode::InvalidInput, "hole filling: colours, flags and topology must have " +
                                                      std::to_string(nv) + " vertices");
  for (double p : options.thresholds)
    if (!(p > 0 && p <= 1))
      return Status::error(ErrorCode::InvalidInput, "hole filling: threshold " + std::to_string(p) +
                                                        " is outside (0, 1]");
  report = HoleFillReport();
  const int passes = static_cast<int>(options.thresholds.size());
  report.filled_per_pass.assign(passes + 1, 0);
  if (fill_pass) fill_pass->assign(nv, -1);

  std::vector<int> pending;  // uncoloured vertices, in index order (the paper's loop)
  for (int v = 0; v < nv; ++v)
    if (!colored[v]) pending.push_back(v);
  std::vector<char> initially_uncolored(nv, 0);
  for (int v : pending) initially_uncolored[v] = 1;

  for (int pass = 0; pass <= passes && !pending.empty(); ++pass) {
    // The last pass needs one coloured neighbour: any fraction above 0.
    const double need = pass < passes ? options.thresholds[pass] : 0.0;
    bool changed = true;
    while (changed && !pending.empty()) {
      changed = false;
      ++report.sweeps;
      size_t keep = 0;
      for (size_t j = 0; j < pending.size(); ++j) {
        const int v = pending[j];
        const std::vector<int>& ring = topology.rings[v];
        Vec3 sum = Vec3::Zero();
        int n = 0;
        for (int u : ring)
          if (colored[u]) {
            sum += colors[u];
            ++n;
          }
        const int total = static_cast<int>(ring.size());
        // n >= need * total, with a little slack for 0.6 * 5 = 2.9999...
        const bool enough = n > 0 && n + 1e-9 >= need * total;
        if (enough) {
          colors[v] = sum / n;
          colored[v] = 1;
          ++report.filled_per_pass[pass];
          if (fill_pass) (*fill_pass)[v] = pass;
          changed = true;
        } else {
          pending[keep++] = v;
        }
      }
      pending.resize(keep);
    }
  }
  std::vector<char> reached_by_passes(nv, 1);
  for (int v = 0; v < nv; ++v)
    if (!colored[v]) reached_by_passes[v] = 0;
  for (int v : pending) {
    colors[v] = options.fallback_color;
    colored[v] = 1;
    ++report.uncolorable;
    if (fill_pass) (*fill_pass)[v] = passes + 1;
  }
  // Relaxation of the filled vertices (the ones not coloured on input).
  std::vector<int> filled;
  for (int v = 0; v < nv; ++v)
    if (initially_uncolored[v] && reached_by_passes[v]) filled.push_back(v);
  for (int sweep = 0; sweep < options.smoothing_sweeps && !filled.empty(); ++sweep) {
    for (int v : filled) {
      const std::vector<int>& ring = topology.rings[v];
      if (ring.empty()) continue;
      Vec3 sum = Vec3::Zero();
      for (int u : ring) sum += colors[u];
      colors[v] = sum / static_cast<double>(ring.size());
    }
  }
  return Status::success();
}

}  // namespace lk
