// Carrying a chart from the control mesh to its subdivision levels: the
// stretch-minimizing parameterization (tarini2002 Sec. 3.1) is computed on
// the ~1.4k-vertex control mesh (the paper's ~1.6k triangles) and every
// new vertex of a refinement step gets the midpoint of its edge's uvs.
// Each coarse uv triangle is thus split 1-to-4 inside itself: the refined
// chart has no flips and the same border, and the fine mesh (jeong2002's
// displaced Butterfly levels) is textured with the same layout as the
// control mesh. Linear, not Butterfly, on purpose: Butterfly stencils would
// move uvs off their triangles and could fold the chart.
//
// Shapes: control_uv #Vc by 2; levels from build_butterfly_levels;
// fine_uv #Vf of the last level.
#pragma once
#include "common/status.h"
#include "common/types.h"
#include "subdiv/butterfly.h"

#include <vector>

namespace lk {

// Fails with InvalidInput when control_uv does not have the first level's
// #Vc entries.
Status refine_chart_uvs(const std::vector<ButterflyLevel>& levels, const std::vector<Vec2>& control_uv,
                        std::vector<Vec2>& fine_uv);

}  // namespace lk
