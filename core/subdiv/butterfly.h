// Modified Butterfly subdivision: Zorin, Schröder, Sweldens 1996,
// "Interpolating subdivision for meshes with arbitrary topology", used by
// jeong2002 Sec. 5 to build the multiresolution head.
//
// Refinement is split OpenSubdiv-style into a topology pass, run once
// (build_butterfly_levels: fine triangles + one stencil per new vertex), and a
// data pass (apply: any per-vertex data - positions, UVs, colours, scalars).
//
// One level, coarse mesh with #Vc vertices, #Ec edges, #Fc triangles:
//   fine vertices  #Vf = #Vc + #Ec; fine vertex i < #Vc IS coarse vertex i
//                  (interpolating scheme), fine vertex #Vc + k sits on coarse
//                  edge k (MeshTopology edge order);
//   fine triangles 4 #Fc, each coarse triangle split 1 -> 4.
//
// Rules (weights of the new vertex on edge a-b; c, d = the apexes of the two
// triangles on a-b; wings = the vertices across the four edges a-c, b-c, a-d,
// b-d):
//   regular (a and b interior, valence 6): 8-point butterfly
//       a, b: 1/2   c, d: 1/8   wings: -1/16
//     (Zorin's 10-point stencil with tension w = 0, the classic butterfly.)
//   one endpoint interior with valence K != 6 (the other regular or on the
//   boundary): the extraordinary rule around it, ring s_0 = the other endpoint,
//   centre 3/4:
//       K = 3:  s = 5/12, -1/12, -1/12
//       K = 4:  s = 3/8, 0, -1/8, 0
//       K >= 5: s_j = (1/4 + cos(2 pi j / K) + 1/2 cos(4 pi j / K)) / K
//   both endpoints interior and extraordinary: average of the two rules.
//   boundary edge: 4-point scheme along the boundary loop
//       -1/16, 9/16, 9/16, -1/16
//   interior edge with a boundary endpoint (and the other regular or also on
//   the boundary): the 8-point butterfly, where a wing that does not exist
//   (its edge lies on the boundary) is replaced by its reflection, e.g. the
//   wing across a-c becomes b + c - a.
// The boundary handling is OpenMesh's ModifiedButterflyT (Courbet), chosen so
// that the two implementations agree everywhere; it is simpler than the
// boundary stencils of Zorin's thesis (which distinguish boundary vertex
// valences), but every stencil is affine (weights sum to 1), so planes and
// straight boundaries are reproduced.
//
// Creases (feature curves; Hoppe et al. 1994, "Piecewise smooth surface
// reconstruction", Sec. 3; Zorin's thesis Ch. 5 for the butterfly): tagged
// control edges, whose children are tagged on every finer level. The mesh
// is treated as if it were cut along them:
//   a tagged edge's new vertex uses the 4-point rule along its crease
//     polyline, like a boundary edge;
//   every other stencil treats tagged edges as boundary: a wing across a
//     tagged edge is replaced by its reflection, and a vertex on a crease is
//     not interior (no extraordinary rule around it).
// So the two sides of a crease do not influence each other; only the crease
// curve, which depends on its own vertices alone, is shared. A curve
// (boundary or crease) continues through a vertex that has exactly two edges
// of its kind and is not a corner; elsewhere (a corner, a crease's open end,
// a junction of three or more crease edges) the missing curve neighbour is
// the reflection 2 v - w, i.e. weights 7/16 v, 10/16 w, -1/16 next.
// Without creases and corners the stencils are exactly the ones above.
#pragma once
#include "common/status.h"
#include "mesh/tri_mesh.h"

#include <algorithm>
#include <array>
#include <string>
#include <vector>

namespace lk {

// One refinement step: its topology and stencils. Built once, applied to any
// per-vertex data of the coarse mesh.
struct ButterflyLevel {
  int num_coarse_vertices = 0;            // #Vc
  int num_fine_vertices = 0;              // #Vf = #Vc + #Ec
  std::vector<Tri> coarse_triangles;      // #Fc
  std::vector<Tri> fine_triangles;        // 4 #Fc, child k of coarse triangle f is 4 f + k
  std::vector<std::array<int, 2>> edge_endpoints;  // #Ec: coarse vertices of the edge of new vertex #Vc + k
  // Stencils in compressed rows: new vertex #Vc + k is
  //   sum over i in [stencil_offsets[k], stencil_offsets[k+1]) of
  //   stencil_weights[i] * coarse[stencil_indices[i]].
  std::vector<int> stencil_offsets;       // #Ec + 1
  std::vector<int> stencil_indices;       // coarse vertex indices, distinct within a row
  std::vector<double> stencil_weights;    // same length, each row sums to 1
  std::vector<char> crease_edges;         // #Ec: 1 where coarse edge k is a crease (tagged or a tagged edge's child)

  int num_new_vertices() const { return num_fine_vertices - num_coarse_vertices; }
};

// Builds `levels` successive refinements of the control mesh's connectivity
// (positions are not used). out[0] refines the control mesh, out[l] refines
// out[l-1].fine_triangles. Fails with InvalidInput on a mesh that is not an
// oriented 2-manifold (see build_topology) or has an interior vertex of
// valence < 3, and with TooLarge if the finest level would exceed
// max_fine_triangles.
Status build_butterfly_levels(const TriMesh& control, int levels, std::vector<ButterflyLevel>& out,
                              int max_fine_triangles = 1 << 24);

// Crease curves of a control mesh (see the rules above).
struct ButterflyCreases {
  std::vector<std::array<int, 2>> edges;  // tagged control edges, vertex pairs in either order;
                                          // boundary edges are ignored (already a curve)
  std::vector<int> corners;               // vertices where a crease or boundary curve has a corner:
                                          // the 4-point rule does not reach past them
  bool empty() const { return edges.empty() && corners.empty(); }
};

// Adds a polyline of control vertices (consecutive ones must share a mesh
// edge) as tagged edges; closed joins the last vertex to the first, an open
// polyline's two ends become corners.
void add_crease_polyline(const std::vector<int>& vertices, bool closed, ButterflyCreases& creases);

// Makes every vertex with one or more than two tagged edges a corner (an
// open end, or where curves meet), as add_crease_polyline does for its
// ends; for creases assembled edge by edge.
void close_crease_ends(ButterflyCreases& creases);

// The same with creases. Fails (InvalidInput) also when a crease names a
// vertex out of range or two vertices that share no edge; with empty creases
// the result is identical to the overload above.
Status build_butterfly_levels(const TriMesh& control, const ButterflyCreases& creases, int levels,
                              std::vector<ButterflyLevel>& out, int max_fine_triangles = 1 << 24);

// The value of new vertex k (0 <= k < #Ec) from coarse data of any type T that
// supports T * double and +=  (double, Vec2, Vec3, Vec4, ...). Exposed so
// local updates evaluate exactly the same arithmetic as apply().
template <class T>
inline T butterfly_new_vertex(const ButterflyLevel& level, int k, const std::vector<T>& coarse) {
  const int begin = level.stencil_offsets[k], end = level.stencil_offsets[k + 1];
  T acc = coarse[level.stencil_indices[begin]] * level.stencil_weights[begin];
  for (int i = begin + 1; i < end; ++i) acc += coarse[level.stencil_indices[i]] * level.stencil_weights[i];
  return acc;
}

// Refines per-vertex data one level: fine (#Vf) from coarse (#Vc). The first
// #Vc entries of fine are copies of coarse. Fails (InvalidInput) when coarse
// does not have #Vc entries; fine is then left unchanged.
template <class T>
Status apply(const ButterflyLevel& level, const std::vector<T>& coarse, std::vector<T>& fine) {
  if (static_cast<int>(coarse.size()) != level.num_coarse_vertices)
    return Status::error(ErrorCode::InvalidInput,
                         "butterfly apply: data has " + std::to_string(coarse.size()) +
                             " entries, the level's coarse mesh has " +
                             std::to_string(level.num_coarse_vertices) + " vertices");
  fine.resize(level.num_fine_vertices);
  std::copy(coarse.begin(), coarse.end(), fine.begin());
  const int nc = level.num_coarse_vertices;
  const int nk = level.num_new_vertices();
  for (int k = 0; k < nk; ++k) fine[nc + k] = butterfly_new_vertex(level, k, coarse);
  return Status::success();
}

// Refines data through all levels: out[0] = control data, out[l] = data on
// the level-l mesh (#levels + 1 arrays).
template <class T>
Status apply_all(const std::vector<ButterflyLevel>& levels, const std::vector<T>& control,
                 std::vector<std::vector<T>>& out) {
  out.resize(levels.size() + 1);
  out[0] = control;
  for (size_t l = 0; l < levels.size(); ++l) {
    Status s = apply(levels[l], out[l], out[l + 1]);
    if (!s.ok()) return s;
  }
  return Status::success();
}

}  // namespace lk
