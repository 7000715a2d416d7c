#include "multires/multires.h"

#include "mesh/geometry.h"
#include "multires/multires_detail.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numeric>
#include <set>

namespace lk {
namespace {

// The per-vertex kernels below are the ONLY place where normals and
// displaced positions are computed, by evaluate() and by local updates alike:
// same operands in the same order give bit-identical results.

inline Vec3 vertex_normal(const IndexRows& vertex_faces, const std::vector<Vec3>& face_normals, int v) {
  Vec3 n = Vec3::Zero();
  for (int i = vertex_faces.offsets[v]; i < vertex_faces.offsets[v + 1]; ++i) n += face_normals[vertex_faces.items[i]];
  const double len = n.norm();
  if (len > 0) n /= len;
  return n;
}

inline bool same_bits(const Vec3& a, const Vec3& b) { return std::memcmp(a.data(), b.data(), sizeof(double) * 3) == 0; }

// Puts a work list of marked items (mark[i] == stamp exactly for the items
// listed) in ascending order. A large list is rebuilt by one sweep over the
// marks, linear and cache-friendly, instead of sorted: a full expression
// change reaches half of level 3, where sorting was 40 % of the update.
inline void sort_marked(std::vector<int>& list, const std::vector<std::uint32_t>& mark, std::uint32_t stamp) {
  if (list.size() * 16 < mark.size()) {
    std::sort(list.begin(), list.end());
    return;
  }
  list.clear();
  const int n = static_cast<int>(mark.size());
  for (int i = 0; i < n; ++i)
    if (mark[i] == stamp) list.push_back(i);
}

// Counting-sort construction of compressed rows, O(#items): count(emit)
// calls emit(row, item) for every pair, twice (count, then fill), in the
// same order, so rows keep the emission order.
template <class Emit>
IndexRows rows_by_counting(int rows, const Emit& emit_all) {
  IndexRows r;
  r.offsets.assign(rows + 1, 0);
  emit_all([&](int row, int) { ++r.offsets[row + 1]; });
  for (int i = 0; i < rows; ++i) r.offsets[i + 1] += r.offsets[i];
  r.items.resize(r.offsets[rows]);
  std::vector<int> fill(r.offsets.begin(), r.offsets.end() - 1);
  emit_all([&](int row, int item) { r.items[fill[row]++] = item; });
  return r;
}

MultiresLevelLinks build_links(int num_vertices, const std::vector<Tri>& tris, const ButterflyLevel* next) {
  MultiresLevelLinks L;
  const int nf = static_cast<int>(tris.size());
  // Faces in ascending order per vertex: the normal's summation order.
  L.vertex_faces = rows_by_counting(num_vertices, [&](auto&& emit) {
    for (int f = 0; f < nf; ++f)
      for (int v : tris[f]) emit(v, f);
  });

  // A vertex's normal reads every corner of its triangles, so moving u
  // changes the normals of u and of every vertex sharing a triangle with u.
  std::vector<int> seen(num_vertices, -1);
  L.normal_reach = rows_by_counting(num_vertices, [&](auto&& emit) {
    std::fill(seen.begin(), seen.end(), -1);
    for (int u = 0; u < num_vertices; ++u) {
      seen[u] = u;
      emit(u, u);
      for (int i = L.vertex_faces.offsets[u]; i < L.vertex_faces.offsets[u + 1]; ++i)
        for (int v : tris[L.vertex_faces.items[i]])
          if (seen[v] != u) {
            seen[v] = u;
            emit(u, v);
          }
    }
  });

  if (next) {
    // Coarse vertex u feeds fine vertex u (a copy) and every stencil naming it.
    L.refine_reach = rows_by_counting(num_vertices, [&](auto&& emit) {
      for (int v = 0; v < num_vertices; ++v) emit(v, v);
      for (int k = 0; k < next->num_new_vertices(); ++k)
        for (int i = next->stencil_offsets[k]; i < next->stencil_offsets[k + 1]; ++i)
          emit(next->stencil_indices[i], num_vertices + k);
    });
  }
  return L;
}

}  // namespace

namespace multires_detail {

// Normals and displaced positions of level l from its base positions.
void evaluate_level(MultiresMesh& m, int l) {
  MultiresState& s = m.state;
  const int nv = m.num_vertices(l);
  const auto& tris = m.triangles(l);
  s.normals[l].resize(nv);
  s.displaced[l].resize(nv);
  s.face_normals[l].resize(tris.size());
  for (int f = 0; f < static_cast<int>(tris.size()); ++f) s.face_normals[l][f] = face_normal(tris, s.base[l], f);
  for (int v = 0; v < nv; ++v) {
    s.normals[l][v] = vertex_normal(m.links[l].vertex_faces, s.face_normals[l], v);
    s.displaced[l][v] = displace(s.base[l][v], m.displacements[l][v], s.normals[l][v]);
  }
}

void update_level(MultiresMesh& m, int l, const std::vector<int>& moved_base) {
  MultiresState& s = m.state;
  const MultiresLevelLinks& links = m.links[l];
  const auto& tris = m.triangles(l);
  std::vector<int> faces, vertices;
  for (int u : moved_base) {
    for (int i = links.vertex_faces.offsets[u]; i < links.vertex_faces.offsets[u + 1]; ++i)
      faces.push_back(links.vertex_faces.items[i]);
    for (int i = links.normal_reach.offsets[u]; i < links.normal_reach.offsets[u + 1]; ++i)
      vertices.push_back(links.normal_reach.items[i]);
  }
  std::sort(faces.begin(), faces.end());
  faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
  for (int f : faces) s.face_normals[l][f] = face_normal(tris, s.base[l], f);
  std::sort(vertices.begin(), vertices.end());
  vertices.erase(std::unique(vertices.begin(), vertices.end()), vertices.end());
  for (int v : vertices) s.normals[l][v] = vertex_normal(links.vertex_faces, s.face_normals[l], v);
  const int nv = m.num_vertices(l);
  for (int v = 0; v < nv; ++v) s.displaced[l][v] = displace(s.base[l][v], m.displacements[l][v], s.normals[l][v]);
}

void update_refinement(MultiresMesh& m, int l, const std::vector<int>& moved) {
  const ButterflyLevel& next = m.levels[l];
  const IndexRows& reach = m.links[l].refine_reach;
  const int nc = next.num_coarse_vertices;
  std::vector<int> targets;
  for (int u : moved)
    for (int i = reach.offsets[u]; i < reach.offsets[u + 1]; ++i) targets.push_back(reach.items[i]);
  std::sort(targets.begin(), targets.end());
  targets.erase(std::unique(targets.begin(), targets.end()), targets.end());
  const std::vector<Vec3>& coarse = m.state.displaced[l];
  std::vector<Vec3>& fine = m.state.base[l + 1];
  for (int f : targets) fine[f] = f < nc ? coarse[f] : butterfly_new_vertex(next, f - nc, coarse);
}

void size_scratch(MultiresMesh& m) {
  const int L = m.num_levels();
  auto& sc = m.scratch;
  bool sized = static_cast<int>(sc.base_mark.size()) == L + 1;
  for (int l = 0; sized && l <= L; ++l)
    sized = static_cast<int>(sc.base_mark[l].size()) == m.num_vertices(l) &&
            sc.face_mark[l].size() == m.triangles(l).size();
  if (sized) return;
  sc.base_mark.assign(L + 1, {});
  sc.displaced_mark.assign(L + 1, {});
  sc.face_mark.assign(L + 1, {});
  for (int l = 0; l <= L; ++l) {
    sc.base_mark[l].assign(m.num_vertices(l), 0);
    sc.displaced_mark[l].assign(m.num_vertices(l), 0);
    sc.face_mark[l].assign(m.triangles(l).size(), 0);
  }
  sc.stamp = 0;
  sc.plans.clear();
  // Work lists as long as the finest level: no update grows them.
  const size_t most = static_cast<size_t>(m.num_vertices(L));
  for (auto* v : {&sc.changed, &sc.reached, &sc.spread, &sc.targets}) v->reserve(most);
}

void resize_state(MultiresMesh& m) {
  const int L = m.num_levels();
  m.state.base.resize(L + 1);
  m.state.normals.resize(L + 1);
  m.state.displaced.resize(L + 1);
  m.state.face_normals.resize(L + 1);
}

Status check_sizes(const MultiresMesh& m) {
  const int L = m.num_levels();
  if (static_cast<int>(m.displacements.size()) != L + 1 || static_cast<int>(m.links.size()) != L + 1)
    return Status::error(ErrorCode::InvalidInput, "multires: displacement or link arrays do not match the levels");
  for (int l = 0; l <= L; ++l)
    if (static_cast<int>(m.displacements[l].size()) != m.num_vertices(l))
      return Status::error(ErrorCode::InvalidInput, "multires: level " + std::to_string(l) + " has " +
                                                        std::to_string(m.displacements[l].size()) +
                                                        " displacements for " + std::to_string(m.num_vertices(l)) +
                                                        " vertices");
  return Status::success();
}

double mean_edge(const std::vector<Vec3>& P, const std::vector<Tri>& tris) {
  if (tris.empty()) return 0;
  double sum = 0;
  for (const Tri& t : tris)
    for (int k = 0; k < 3; ++k) sum += (P[t[k]] - P[t[(k + 1) % 3]]).norm();
  return sum / (3.0 * tris.size());
}

}  // namespace multires_detail

using namespace multires_detail;

Status build_multires(const TriMesh& control, int levels, MultiresMesh& out) {
  return build_multires(control, ButterflyCreases{}, levels, out);
}

Status build_multires(const TriMesh& control, const ButterflyCreases& creases, int levels, MultiresMesh& out) {
  out = MultiresMesh{};
  for (const Vec3& p : control.positions)
    if (!p.allFinite()) return Status::error(ErrorCode::InvalidInput, "multires: a control position is not finite");
  Status s = build_butterfly_levels(control, creases, levels, out.levels);
  if (!s.ok()) {
    out = MultiresMesh{};
    return s;
  }
  out.creases = creases;
  out.control = control.positions;
  out.control_triangles = control.triangles;
  const int L = out.num_levels();
  out.displacements.resize(L + 1);
  out.links.resize(L + 1);
  for (int l = 0; l <= L; ++l) {
    out.displacements[l].assign(out.num_vertices(l), 0.0);
    out.links[l] = build_links(out.num_vertices(l), out.triangles(l), l < L ? &out.levels[l] : nullptr);
  }
  return evaluate(out);
}

Status evaluate(MultiresMesh& mesh) {
  Status s = check_sizes(mesh);
  if (!s.ok()) return s;
  resize_state(mesh);
  size_scratch(mesh);
  mesh.stale_from = -1;
  mesh.state.base[0] = mesh.control;
  for (int l = 0; l <= mesh.num_levels(); ++l) {
    evaluate_level(mesh, l);
    if (l < mesh.num_levels()) {
      s = apply(mesh.levels[l], mesh.state.displaced[l], mesh.state.base[l + 1]);
      if (!s.ok()) return s;
    }
  }
  return Status::success();
}

TriMesh level_mesh(const MultiresMesh& mesh, int level) {
  TriMesh m;
  if (level < 0 || level > mesh.num_levels() || static_cast<int>(mesh.state.displaced.size()) <= level) return m;
  m.positions = mesh.state.displaced[level];
  m.triangles = mesh.triangles(level);
  m.normals = vertex_normals(m);  // of the displaced surface, for shading
  return m;
}
std::vector<std::vector<char>> propagate_vertex_mask(const MultiresMesh& mesh, const std::vector<char>& control_mask) {
  const int L = mesh.num_levels();
  std::vector<std::vector<char>> out(L + 1);
  out[0] = control_mask;
  out[0].resize(mesh.num_vertices(0), 0);
  for (int l = 0; l < L; ++l) {
    const ButterflyLevel& lv = mesh.levels[l];
    out[l + 1].assign(lv.num_fine_vertices, 0);
    std::copy(out[l].begin(), out[l].end(), out[l + 1].begin());
    for (int k = 0; k < lv.num_new_vertices(); ++k)
      out[l + 1][lv.num_coarse_vertices + k] = out[l][lv.edge_endpoints[k][0]] && out[l][lv.edge_endpoints[k][1]];
  }
  return out;
}

Status ensure_current(MultiresMesh& mesh) { return mesh.stale_from < 0 ? Status::success() : evaluate(mesh); }

namespace {

// The support of `moved` on every level up to top, without the bit-wise
// pruning of the marked path (every recomputed vertex counts as changed):
// the faces whose normals, the vertices whose normals and displaced
// positions, and the next level's vertices whose base positions an update
// of that list recomputes, each list ascending.
void build_plan(MultiresMesh& mesh, MultiresMesh::Scratch::Plan& plan) {
  const std::vector<int>& moved = plan.moved;
  const int top = plan.top;
  plan.faces.assign(top + 1, {});
  plan.reached.assign(top + 1, {});
  plan.targets.assign(top + 1, {});
  std::vector<int> changed(moved.begin(), moved.end());
  std::sort(changed.begin(), changed.end());
  changed.erase(std::unique(changed.begin(), changed.end()), changed.end());
  const auto closure = [](const std::vector<int>& from, const IndexRows& rows, int count) {
    std::vector<char> in(static_cast<size_t>(count), 0);
    for (int u : from)
      for (int i = rows.offsets[u]; i < rows.offsets[u + 1]; ++i) in[static_cast<size_t>(rows.items[i])] = 1;
    std::vector<int> out;
    for (int i = 0; i < count; ++i)
      if (in[static_cast<size_t>(i)]) out.push_back(i);
    return out;
  };
  for (int l = 0; l <= top; ++l) {
    const MultiresLevelLinks& links = mesh.links[l];
    plan.faces[l] = closure(changed, links.vertex_faces, static_cast<int>(mesh.triangles(l).size()));
    plan.reached[l] = closure(changed, links.normal_reach, mesh.num_vertices(l));
    if (l == top) break;
    plan.targets[l] = closure(plan.reached[l], links.refine_reach, mesh.num_vertices(l + 1));
    changed = plan.targets[l];
  }
  plan.built = true;
}

// The plan replayed: the same kernels on a superset of what the marked path
// recomputes, so the result is the same bit for bit.
void run_plan(MultiresMesh& mesh, const MultiresMesh::Scratch::Plan& plan, UpdateFootprint* footprint) {
  MultiresState& st = mesh.state;
  for (int l = 0; l <= plan.top; ++l) {
    const MultiresLevelLinks& links = mesh.links[l];
    const auto& tris = mesh.triangles(l);
    for (int f : plan.faces[l]) st.face_normals[l][f] = face_normal(tris, st.base[l], f);
    for (int v : plan.reached[l]) {
      st.normals[l][v] = vertex_normal(links.vertex_faces, st.face_normals[l], v);
      st.displaced[l][v] = displace(st.base[l][v], mesh.displacements[l][v], st.normals[l][v]);
    }
    if (footprint) {
      footprint->base_changed[l] = static_cast<int>(l == 0 ? plan.moved.size() : plan.targets[l - 1].size());
      footprint->displaced_changed[l] = static_cast<int>(plan.reached[l].size());
    }
    if (l == plan.top) break;
    const ButterflyLevel& next = mesh.levels[l];
    const int nc = next.num_coarse_vertices;
    auto& fine = st.base[l + 1];
    for (int f : plan.targets[l]) fine[f] = f < nc ? st.displaced[l][f] : butterfly_new_vertex(next, f - nc, st.displaced[l]);
  }
}

}  // namespace

Status update_control_vertices(MultiresMesh& mesh, const std::vector<int>& moved,
                               const std::vector<Vec3>& new_positions, UpdateFootprint* footprint, int max_level) {
  const int L = mesh.num_levels();
  const int top = max_level < 0 || max_level > L ? L : max_level;
  if (moved.size() != new_positions.size())
    return Status::error(ErrorCode::InvalidInput, "multires update: " + std::to_string(moved.size()) +
                                                      " indices but " + std::to_string(new_positions.size()) +
                                                      " positions");
  for (size_t i = 0; i < moved.size(); ++i) {
    if (moved[i] < 0 || moved[i] >= static_cast<int>(mesh.control.size()))
      return Status::error(ErrorCode::InvalidInput, "multires update: control vertex " + std::to_string(moved[i]) +
                                                        " does not exist");
    if (!new_positions[i].allFinite())
      return Status::error(ErrorCode::InvalidInput, "multires update: position of control vertex " +
                                                        std::to_string(moved[i]) + " is not finite");
  }
  MultiresState& st = mesh.state;
  if (static_cast<int>(st.displaced.size()) != L + 1 || static_cast<int>(mesh.links.size()) != L + 1 ||
      static_cast<int>(st.displaced[L].size()) != mesh.num_vertices(L) ||
      st.face_normals.size() != st.displaced.size())
    return Status::error(ErrorCode::InvalidInput, "multires update: the mesh has not been built and evaluated");
  if (mesh.stale_from >= 0 && top >= mesh.stale_from) {
    Status s = evaluate(mesh);  // the stale levels missed earlier moves: start from a full recompute
    if (!s.ok()) return s;
  }

  auto& sc = mesh.scratch;
  size_scratch(mesh);
  if (++sc.stamp == 0) {  // wrapped: clear the marks once every 2^32 updates
    for (int l = 0; l <= L; ++l) {
      std::fill(sc.base_mark[l].begin(), sc.base_mark[l].end(), 0);
      std::fill(sc.displaced_mark[l].begin(), sc.displaced_mark[l].end(), 0);
      std::fill(sc.face_mark[l].begin(), sc.face_mark[l].end(), 0);
    }
    sc.stamp = 1;
  }
  const std::uint32_t stamp = sc.stamp;
  if (footprint) {
    footprint->base_changed.assign(L + 1, 0);
    footprint->displaced_changed.assign(L + 1, 0);
  }

  // changed: P_l differs; reached: N_l and P'_l recomputed; spread: P'_l
  // differs bit-wise, so the next level must look at its dependents. A value
  // that comes out bit-identical (e.g. P' = P + 0 * N where d = 0 and P did
  // not move) stops the spread without changing the result.
  // A moved list given again: its plan (built on its second time), replayed.
  constexpr size_t kPlans = 4;
  auto& plans = sc.plans;
  const auto known = std::find_if(plans.begin(), plans.end(), [&](const MultiresMesh::Scratch::Plan& p) {
    return p.top == top && p.moved == moved;
  });
  if (known != plans.end()) {
    std::rotate(plans.begin(), known, known + 1);  // most recently used first
    for (size_t i = 0; i < moved.size(); ++i) {
      mesh.control[moved[i]] = new_positions[i];
      st.base[0][moved[i]] = new_positions[i];
    }
    if (!plans.front().built) build_plan(mesh, plans.front());
    run_plan(mesh, plans.front(), footprint);
    if (top < L) mesh.stale_from = mesh.stale_from < 0 ? top + 1 : std::min(mesh.stale_from, top + 1);
    return Status::success();
  }
  if (plans.size() == kPlans) plans.pop_back();
  MultiresMesh::Scratch::Plan fresh;
  fresh.moved = moved;
  fresh.top = top;
  plans.insert(plans.begin(), std::move(fresh));

  std::vector<int> &changed = sc.changed, &reached = sc.reached, &spread = sc.spread, &targets = sc.targets;
  changed.clear();
  for (size_t i = 0; i < moved.size(); ++i) {
    const int v = moved[i];
    mesh.control[v] = new_positions[i];
    st.base[0][v] = new_positions[i];
    if (sc.base_mark[0][v] != stamp) {
      sc.base_mark[0][v] = stamp;
      changed.push_back(v);
    }
  }
  for (int l = 0; l <= L; ++l) {
    const MultiresLevelLinks& links = mesh.links[l];
    auto& mark = sc.displaced_mark[l];
    reached.clear();
    for (int u : changed)
      for (int i = links.normal_reach.offsets[u]; i < links.normal_reach.offsets[u + 1]; ++i) {
        const int v = links.normal_reach.items[i];
        if (mark[v] != stamp) {
          mark[v] = stamp;
          reached.push_back(v);
        }
      }
    // Triangles with a moved corner get new face normals first.
    const auto& tris = mesh.triangles(l);
    auto& face_mark = sc.face_mark[l];
    for (int u : changed)
      for (int i = links.vertex_faces.offsets[u]; i < links.vertex_faces.offsets[u + 1]; ++i) {
        const int f = links.vertex_faces.items[i];
        if (face_mark[f] != stamp) {
          face_mark[f] = stamp;
          st.face_normals[l][f] = face_normal(tris, st.base[l], f);
        }
      }
    // Ascending order turns scattered reads into mostly forward sweeps.
    sort_marked(reached, mark, stamp);
    spread.clear();
    for (int v : reached) {
      st.normals[l][v] = vertex_normal(links.vertex_faces, st.face_normals[l], v);
      const Vec3 p = displace(st.base[l][v], mesh.displacements[l][v], st.normals[l][v]);
      if (!same_bits(p, st.displaced[l][v])) {
        st.displaced[l][v] = p;
        spread.push_back(v);
      }
    }
    if (footprint) {
      footprint->base_changed[l] = static_cast<int>(changed.size());
      footprint->displaced_changed[l] = static_cast<int>(reached.size());
    }
    if (l == top) break;

    const ButterflyLevel& next = mesh.levels[l];
    const int nc = next.num_coarse_vertices;
    auto& next_mark = sc.base_mark[l + 1];
    auto& fine = st.base[l + 1];
    targets.clear();
    for (int u : spread)
      for (int i = links.refine_reach.offsets[u]; i < links.refine_reach.offsets[u + 1]; ++i) {
        const int f = links.refine_reach.items[i];
        if (next_mark[f] != stamp) {
          next_mark[f] = stamp;
          targets.push_back(f);
        }
      }
    sort_marked(targets, next_mark, stamp);
    changed.clear();
    for (int f : targets) {
      const Vec3 p = f < nc ? st.displaced[l][f] : butterfly_new_vertex(next, f - nc, st.displaced[l]);
      if (!same_bits(p, fine[f])) {
        fine[f] = p;
        changed.push_back(f);
      }
    }
  }
  if (top < L) mesh.stale_from = mesh.stale_from < 0 ? top + 1 : std::min(mesh.stale_from, top + 1);
  return Status::success();
}

}  // namespace lk
