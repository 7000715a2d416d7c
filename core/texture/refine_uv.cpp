#include "texture/refine_uv.h"

#include <string>

namespace lk {

Status refine_chart_uvs(const std::vector<ButterflyLevel>& levels, const std::vector<Vec2>& control_uv,
                        std::vector<Vec2>& fine_uv) {
  if (!levels.empty() && static_cast<int>(control_uv.size()) != levels[0].num_coarse_vertices)
    return Status::error(ErrorCode::InvalidInput, "refine uvs: " + std::to_string(control_uv.size()) +
                                                      " uvs for a control mesh of " +
                                                      std::to_string(levels[0].num_coarse_vertices) + " vertices");
  std::vector<Vec2> coarse = control_uv;
  for (const ButterflyLevel& level : levels) {
    if (static_cast<int>(coarse.size()) != level.num_coarse_vertices)
      return Status::error(ErrorCode::InvalidInput, "refine uvs: levels do not follow each other");
    std::vector<Vec2> fine(level.num_fine_vertices);
    std::copy(coarse.begin(), coarse.end(), fine.begin());
    for (int k = 0; k < level.num_new_vertices(); ++k) {
      const auto& e = level.edge_endpoints[k];
      fine[level.num_coarse_vertices + k] = 0.5 * (coarse[e[0]] + coarse[e[1]]);
    }
    coarse = std::move(fine);
  }
  fine_uv = std::move(coarse);
  return Status::success();
}

}  // namespace lk
