#include "head/skin_detail.h"

#include "common/parallel.h"
#include "head/head_creases.h"
#include "head/head_pockets.h"
#include "head/head_shape.h"
#include "mesh/topology.h"

#include <algorithm>
#include <cmath>

namespace lk {
namespace {

// Newton's method along n from p onto the shape's zero set: the signed
// step t with distance(p + t n) = 0, taken in full up to half of
// max_distance and tapered linearly to 0 at it (no step where a vertex
// crosses the limit); 0 when it does not converge (a normal grazing the
// shape, a vertex off it).
double distance_along(const HeadShape& shape, const Vec3& p, const Vec3& n, double max_distance) {
  const double h = 1e-6;
  double t = 0;
  for (int k = 0; k < 20; ++k) {
    const Vec3 q = p + t * n;
    const double f = shape.distance(q);
    if (std::abs(f) < 1e-9) return t * std::clamp(2 * (max_distance - std::abs(t)) / max_distance, 0.0, 1.0);
    const double slope = (shape.distance(q + h * n) - shape.distance(q - h * n)) / (2 * h);
    if (!(std::abs(slope) > 0.3)) return 0.0;
    t -= f / slope;
    if (!(std::abs(t) <= max_distance)) return 0.0;
  }
  return 0.0;
}

}  // namespace

Status generic_skin_detail(const GenericHead& head, int levels, const SkinDetailOptions& options,
                           std::vector<std::vector<double>>& detail) {
  detail.clear();
  if (levels < 0 || options.max_distance <= 0 || options.fade_rings < 0 || options.smooth_passes < 0)
    return Status::error(ErrorCode::InvalidInput,
                         "skin detail: levels >= 0, max_distance > 0, fade_rings and smooth_passes >= 0");
  MeshTopology topo;
  Status s = build_topology(head.mesh, topo);
  if (!s) return with_context(s, "skin detail");
  MultiresMesh mr;
  s = build_multires(head.mesh, head_creases(head.mesh, topo, head.annotations), levels, mr);
  if (!s) return with_context(s, "skin detail");

  std::vector<char> skin(topo.num_vertices, 1);
  const std::vector<char> pockets = pocket_vertices(topo, head.annotations);
  for (int v = 0; v < topo.num_vertices; ++v)
    if (pockets[v] || topo.is_boundary(v)) skin[v] = 0;
  // Of the nose only its lower half above its base (tip, wings, columella)
  // is left out. Its upper half, the bridge up to the glabella, is skin:
  // left out, it kept the levels' rolls across the bridge between the eyes.
  // So is its base (the lowest tenth of its height, where it meets the upper
  // lip): left out, it and its fade kept furrows over the philtrum.
  const Vec3 up = head.annotations.up.normalized();
  double nose_base = 0, nose_mid = 0;
  if (const auto nose = head.annotations.regions.find("nose"); nose != head.annotations.regions.end()) {
    double low = 1e300, high = -1e300;
    for (int v : nose->second)
      if (v >= 0 && v < topo.num_vertices) {
        const double height = up.dot(head.mesh.positions[v]);
        low = std::min(low, height);
        high = std::max(high, height);
      }
    nose_base = low + 0.1 * (high - low);
    nose_mid = 0.5 * (low + high);
  }
  const auto nose_left_out = [&](int v) {
    const double height = up.dot(head.mesh.positions[v]);
    return height > nose_base && height <= nose_mid;
  };
  // The lips are skin but for their lines (the slit's two edges, creases
  // below), the bag (a pocket) and the mouth corners (next). Left out
  // whole, the lower lip kept the levels' wavy ledge on every photos head.
  for (const auto& [name, vertices] : head.annotations.regions)
    if (name.rfind("ear", 0) == 0 || name == "nose")
      for (int v : vertices)
        if (v >= 0 && v < topo.num_vertices && (name != "nose" || nose_left_out(v)))
          skin[v] = 0;
  // Round the mouth's corners (the lip lines' ends) the lips stay out: with
  // the detail there, the refined corners crossed on photos heads.
  for (const CreaseCurve& c : head.annotations.creases)
    if (c.name.find("lip_line") != std::string::npos && !c.closed && !c.vertices.empty())
      for (int corner : {c.vertices.front(), c.vertices.back()})
        if (corner >= 0 && corner < topo.num_vertices) {
          skin[corner] = 0;
          for (int w : topo.rings[corner]) skin[w] = 0;
        }
  for (const auto& e : mr.creases.edges)
    for (int v : e)
      if (v >= 0 && v < topo.num_vertices) skin[v] = 0;
  const std::vector<std::vector<char>> skin_levels = propagate_vertex_mask(mr, skin);

  const HeadShape shape;
  for (int l = 1; l <= levels; ++l) {
    const std::vector<Vec3>& base = mr.state.base[l];
    const std::vector<Vec3>& normals = mr.state.normals[l];
    std::vector<double>& d = mr.displacements[l];
    // The level's one-rings (each vertex's normal reach is itself and its
    // one-ring: multires.h), and how far each vertex lies from the non-skin
    // ones in rings of this level (breadth first, up to the fade's width).
    const IndexRows& ring = mr.links[l].normal_reach;
    const int nl = static_cast<int>(base.size());
    std::vector<int> rings(nl, -1), front;
    for (int v = 0; v < nl; ++v)
      if (!skin_levels[l][v]) rings[v] = 0, front.push_back(v);
    for (int r = 1; r <= options.fade_rings && !front.empty(); ++r) {
      std::vector<int> next_front;
      for (int v : front)
        for (int k = ring.offsets[v]; k < ring.offsets[v + 1]; ++k)
          if (const int w = ring.items[k]; rings[w] < 0) rings[w] = r, next_front.push_back(w);
      front = std::move(next_front);
    }
    parallel_for(0, nl, 1024, [&](int v, int) {
      if (!skin_levels[l][v]) return;
      const double weight =
          rings[v] < 0 ? 1.0 : std::min(1.0, double(rings[v]) / double(options.fade_rings + 1));
      d[v] = weight * distance_along(shape, base[v], normals[v], options.max_distance);
    });
    // Where the shape creases (the lid's fold under the brow) the steps
    // along neighbouring normals differ vertex to vertex: averaged with the
    // one-ring, skin vertices only, the detail keeps its broad part.
    for (int pass = 0; pass < options.smooth_passes; ++pass) {
      std::vector<double> next = d;
      for (int v = 0; v < nl; ++v) {
        double sum = 0;
        int count = 0;
        for (int k = ring.offsets[v]; k < ring.offsets[v + 1]; ++k)
          if (const int w = ring.items[k]; w != v) sum += d[w], ++count;
        if (skin_levels[l][v] && count > 0) next[v] = 0.5 * d[v] + 0.5 * sum / count;
      }
      d = std::move(next);
    }
    s = evaluate(mr);
    if (!s) return with_context(s, "skin detail");
  }
  detail = mr.displacements;
  return Status::success();
}

Status apply_skin_detail(const std::vector<std::vector<double>>& detail, MultiresMesh& mesh) {
  const int levels = mesh.num_levels();
  for (int l = 0; l <= levels; ++l) {
    std::vector<double>& d = mesh.displacements[l];
    if (l == 0 || l >= static_cast<int>(detail.size())) {
      std::fill(d.begin(), d.end(), 0.0);
      continue;
    }
    if (detail[l].size() != d.size())
      return Status::error(ErrorCode::InvalidInput, "skin detail: level " + std::to_string(l) + " has " +
                                                        std::to_string(d.size()) + " vertices, the detail " +
                                                        std::to_string(detail[l].size()));
    d = detail[l];
  }
  return evaluate(mesh);
}

}  // namespace lk
