// Per-vertex ambient occlusion, baked on the CPU once per mesh, so cavities
// (eye sockets, nostrils, the mouth slit, behind the ears) read as such in
// the viewer without screen-space passes that WebGL2 on a CPU rasterizer
// could not afford. Not from the papers: a rendering aid.
//
// Each vertex casts `rays` cosine-weighted rays over the hemisphere around
// its normal (a fixed spiral set, turned per vertex to break banding) and
// counts those that hit the mesh within max_distance. The result is the
// unoccluded share. Deterministic: same mesh, same values, native or wasm.
//
// Shapes: mesh positions #V by 3, triangles #F by 3; out #V in [0,1]
// (1 = fully open, 0 = fully enclosed).
#pragma once
#include "common/progress.h"
#include "common/status.h"
#include "mesh/tri_mesh.h"

#include <vector>

namespace lk {

struct OcclusionOptions {
  int rays = 48;                   // per vertex; 16 is coarse, 128 smooth
  double max_distance_fraction = 0.12;  // ray length as a share of the bbox diagonal:
                                   // only nearby geometry shades (local cavities)
  int max_vertices = 400000;       // refuse bigger meshes (TooLarge): seconds per 100k vertices
};

Status vertex_ambient_occlusion(const TriMesh& mesh, const OcclusionOptions& options,
                                std::vector<float>& out, const ProgressFn& progress = {});

}  // namespace lk
