// Hole filling for vertices no photo sees (tarini2002 Sec. 3.2): iterative
// passes over the uncoloured vertices; in the pass with threshold p a vertex
// takes the average colour of its coloured one-ring neighbours if at least
// p of them are coloured (80 %, then 60 %, 40 %, 20 %), each pass repeated
// until it changes nothing; a last pass accepts any coloured neighbour.
// Colours assigned in a sweep count for the following vertices of the same
// sweep, as in the paper's loop.
//
// Shapes: topology of #V vertices; colors #V by 3; colored #V (1 = has colour).
#pragma once
#include "common/status.h"
#include "common/types.h"
#include "mesh/topology.h"

#include <vector>

namespace lk {

struct HoleFillOptions {
  // Fractions of coloured one-ring neighbours required, pass by pass (paper).
  std::vector<double> thresholds = {0.8, 0.6, 0.4, 0.2};
  // Colour given to vertices of components with no coloured vertex at all
  // (linear RGB); they are counted in HoleFillReport::uncolorable.
  Vec3 fallback_color = Vec3(0.5, 0.5, 0.5);
  // Ours, after the paper's passes: Gauss-Seidel sweeps that replace each
  // filled vertex's colour by the mean of its neighbours (vertices coloured
  // on input stay fixed), i.e. relaxation towards the membrane (harmonic)
  // fill. The paper's passes fill a hole from its rim inwards, so the fronts
  // coming from two photos of different brightness meet in a hard line in
  // the middle of the hole (seen across the back of the head); relaxing
  // spreads that step over the whole hole. 0 = the paper's fill exactly.
  int smoothing_sweeps = 300;
};

struct HoleFillReport {
  // Vertices filled in each pass: thresholds.size() entries, then the final
  // "any coloured neighbour" pass.
  std::vector<int> filled_per_pass;
  int sweeps = 0;        // sweeps over the uncoloured vertices, all passes
  int uncolorable = 0;   // vertices given fallback_color
};

// Colours every uncoloured vertex. fill_pass (optional, #V) gets the pass
// index that coloured each vertex: -1 for vertices coloured on input,
// thresholds.size() for the final pass, thresholds.size() + 1 for fallback.
// Fails with InvalidInput on size mismatches or thresholds outside (0, 1].
Status fill_vertex_colors(const MeshTopology& topology, std::vector<Vec3>& colors,
                          std::vector<char>& colored, const HoleFillOptions& options,
                          HoleFillReport& report, std::vector<int>* fill_pass = nullptr);

}  // namespace lk
