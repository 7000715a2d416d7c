// Vertex-to-photo binding (tarini2002 Sec. 3.2, after Rocchini et al. [28]):
// a vertex v is valid for photo i when
//   - its projection lies inside the photo (with a margin),
//   - its normal faces the camera: <N(v), V_i> > min_facing, V_i the unit
//     direction from v to the camera centre,
//   - the segment from v to the camera centre meets no other part of the mesh
//     (a shadow ray through the BVH, started a small offset off the surface),
//   - it is not a silhouette vertex: no triangle of its fan faces away from
//     the camera.
// The paper does not require every vertex to be bound; unbound vertices are
// coloured later by hole filling (hole_fill.h).
//
// Shapes: mesh positions #V by 3, triangles #F by 3, normals #V by 3 (unit),
// cameras #P (at most kMaxTexturePhotos). Outputs are #V, facing #V by #P.
#pragma once
#include "calib/camera.h"
#include "common/status.h"
#include "mesh/tri_mesh.h"
#include "raycast/bvh.h"

#include <cstdint>
#include <vector>

namespace lk {

// Valid-photo sets are bit masks, so "a photo common to all three corners"
// is one AND. Five photos is the paper's case; 64 is far beyond it.
constexpr int kMaxTexturePhotos = 64;

struct BindingOptions {
  // Smallest <N, V> (cosine between the vertex normal and the direction to
  // the camera) that counts as facing. 0.1 (84 deg) drops grazing samples,
  // whose colour is smeared over many texels and usually darkened.
  double min_facing = 0.1;
  // A projection closer than this to the photo border is outside (pixels):
  // bilinear lookup needs the neighbouring pixel, and the border of real
  // photos is often vignetted.
  double image_margin_px = 2.0;
  // The shadow ray starts this far off the vertex (fraction of the mesh's
  // bounding-box diagonal), so it does not hit the vertex's own fan.
  double occlusion_offset = 1e-4;
  // A fan triangle counts as facing away when <N(T), V> < -silhouette_tolerance;
  // a small tolerance keeps nearly edge-on fan triangles from unbinding
  // vertices on flat regions seen at a slant.
  double silhouette_tolerance = 0.0;
};

struct VertexBinding {
  int num_photos = 0;
  std::vector<std::uint64_t> valid;   // #V: bit i set = photo i is valid for the vertex
  std::vector<float> facing;          // #V * #P, row per vertex: <N(v), V_i>, 0 where not valid
  std::vector<int> main_photo;        // #V: valid photo with the largest <N, V>, -1 = unbound

  bool is_valid(int vertex, int photo) const { return (valid[vertex] >> photo) & 1u; }
  bool bound(int vertex) const { return valid[vertex] != 0; }
};

// Binds every vertex. `bvh` must be built from `mesh` (occlusion test).
// Fails with InvalidInput on inconsistent sizes (normals, bvh), more than
// kMaxTexturePhotos cameras, a camera with no image size, or NaN positions.
Status bind_vertices(const TriMesh& mesh, const std::vector<Vec3>& normals, const MeshBvh& bvh,
                     const std::vector<Camera>& cameras, const BindingOptions& options,
                     VertexBinding& binding);

}  // namespace lk
