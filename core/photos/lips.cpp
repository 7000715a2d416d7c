#include "photos/lips.h"

#include "head/head_creases.h"
#include "mesh/topology.h"
#include "multires/multires.h"
#include "raycast/bvh.h"
#include "raycast/self_intersection.h"

#include <cmath>

namespace lk {

std::vector<std::array<int, 2>> lip_binding_edges(const GenericHead& generic) {
  std::vector<std::array<int, 2>> out;
  const int nv = generic.mesh.num_vertices();
  auto it = generic.annotations.regions.find("lips");
  if (it == generic.annotations.regions.end()) return out;
  std::vector<char> lips(size_t(nv), 0);
  for (int v : it->second)
    if (v >= 0 && v < nv) lips[size_t(v)] = 1;
  for (const auto& e : generic.annotations.binding_edges)
    if (e[0] >= 0 && e[1] >= 0 && e[0] < nv && e[1] < nv && lips[size_t(e[0])] && lips[size_t(e[1])]) out.push_back(e);
  return out;
}

Status keep_mouth_bag_inside(const GenericHead& generic, const MouthBagOptions& options, TriMesh& control,
                             MouthBagResult& result) {
  result = {};
  const int nv = generic.mesh.num_vertices();
  if (control.num_vertices() != nv || control.triangles != generic.mesh.triangles)
    return Status::error(ErrorCode::InvalidInput, "mouth bag: the fitted mesh is not the generic head's");
  if (options.level < 0 || options.level > 4 || !(options.step_share > 0) || !(options.step_share * options.max_steps <= 1) ||
      options.max_steps < 0)
    return Status::error(ErrorCode::InvalidInput, "mouth bag: level 0-4, step_share > 0, at most the whole way in");
  std::vector<char> in_bag(size_t(nv), 0);
  std::vector<int> bag;
  for (int v : generic.annotations.constrained_vertices)
    if (v >= 0 && v < nv && !in_bag[size_t(v)]) in_bag[size_t(v)] = 1, bag.push_back(v);
  if (bag.empty()) return Status::success();
  MeshTopology topo;
  Status s = build_topology(generic.mesh, topo);
  if (!s || options.level == 0) return with_context(s, "mouth bag");

  MultiresMesh mr;
  s = build_multires(control, head_creases(generic.mesh, topo, generic.annotations), options.level, mr);
  if (!s) return with_context(s, "mouth bag");
  // Every level 0..L is checked (a head exports each of them): per level
  // its mesh, tree and the triangles over a control face with a corner in
  // the bag (child c of triangle g is 4 g + c on every level).
  const int first = options.all_levels ? 0 : options.level;
  const int count = options.level - first + 1;
  std::vector<TriMesh> levels(static_cast<size_t>(count));
  std::vector<MeshBvh> trees(static_cast<size_t>(count));
  std::vector<std::vector<int>> over_bag(static_cast<size_t>(count));
  for (int i = 0; i < count; ++i) {
    const int k = first + i;
    levels[size_t(i)].triangles = mr.triangles(k);
    levels[size_t(i)].positions = mr.state.displaced[size_t(k)];
    s = build_bvh(levels[size_t(i)], trees[size_t(i)]);
    if (!s) return with_context(s, "mouth bag");
    const int per_control = 1 << (2 * k);
    for (int f = 0; f < generic.mesh.num_triangles(); ++f) {
      const Tri& t = generic.mesh.triangles[size_t(f)];
      if (in_bag[size_t(t[0])] || in_bag[size_t(t[1])] || in_bag[size_t(t[2])])
        for (int c = 0; c < per_control; ++c) over_bag[size_t(i)].push_back(f * per_control + c);
    }
  }
  // The pairs over the bag on every level checked, as control faces (the
  // pairs' ancestors), and their count.
  std::vector<std::array<int, 2>> pairs, control_pairs;
  auto search = [&]() -> Status {
    control_pairs.clear();
    for (int i = 0; i < count; ++i) {
      const int k = first + i;
      if (levels[size_t(i)].positions != mr.state.displaced[size_t(k)]) {
        levels[size_t(i)].positions = mr.state.displaced[size_t(k)];
        Status r = refit_bvh(levels[size_t(i)], trees[size_t(i)]);
        if (!r) return r;
      }
      find_intersections_with(trees[size_t(i)], over_bag[size_t(i)], pairs);
      const int per_control = 1 << (2 * k);
      for (const auto& p : pairs) control_pairs.push_back({p[0] / per_control, p[1] / per_control});
    }
    return Status::success();
  };
  s = search();
  if (!s) return with_context(s, "mouth bag");
  result.pairs_before = result.pairs_after = int(control_pairs.size());
  if (control_pairs.empty()) return Status::success();

  const std::vector<Vec3> carried = control.positions;
  Vec3 centre = Vec3::Zero();
  for (int v : bag) centre += carried[size_t(v)];
  centre /= double(bag.size());
  // The bag vertices drawn in: corners of the control faces under the
  // pairs, and their neighbours within the bag (the rest of the bag, which
  // a stereo patch may have placed, stays).
  std::vector<char> in_set(size_t(nv), 0);
  std::vector<int> set;
  for (const auto& p : control_pairs)
    for (int f : p)
      for (int v : generic.mesh.triangles[size_t(f)])
        if (in_bag[size_t(v)] && !in_set[size_t(v)]) in_set[size_t(v)] = 1, set.push_back(v);
  for (size_t i = 0, n = set.size(); i < n; ++i)
    for (int w : topo.rings[size_t(set[i])])
      if (in_bag[size_t(w)] && !in_set[size_t(w)]) in_set[size_t(w)] = 1, set.push_back(w);
  int best_step = 0;
  std::vector<Vec3> moved(set.size());
  for (int step = 1; step <= options.max_steps && result.pairs_after > 0 && !set.empty(); ++step) {
    const double share = step * options.step_share;
    for (size_t i = 0; i < set.size(); ++i) moved[i] = carried[size_t(set[i])] + share * (centre - carried[size_t(set[i])]);
    s = update_control_vertices(mr, set, moved);
    if (s) s = search();
    if (!s) return with_context(s, "mouth bag");
    if (int(control_pairs.size()) < result.pairs_after) {
      result.pairs_after = int(control_pairs.size());
      best_step = step;
    }
  }
  result.share = best_step * options.step_share;
  for (int v : set) control.positions[size_t(v)] = carried[size_t(v)] + result.share * (centre - carried[size_t(v)]);
  return Status::success();
}

}  // namespace lk
