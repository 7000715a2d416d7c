// Exact outlines for synthetic photo sessions (tests and `likeness bench
// --only photos`): the person's mesh rasterized by each known camera
// (texture/synthetic_photo.h, white on black) is the mask a perfect
// segmentation would give, neck included, background plain; outline.h
// extracts its outline as it would a real mask's.
//
// Shapes: cameras and outlines #C.
#pragma once
#include "calib/camera.h"
#include "photos/outline.h"
#include "mesh/tri_mesh.h"

#include <vector>

namespace lk {

Status synthetic_mask(const TriMesh& person, const Camera& camera, Image& mask);
// grow_px: the mask grown (> 0) or shrunk (< 0) by that many pixels (a
// disk), a segmentation's bias, before the outline is taken.
Status synthetic_outlines(const TriMesh& person, const std::vector<Camera>& cameras, const OutlineOptions& options,
                          std::vector<PhotoOutline>& out, int grow_px = 0);

}  // namespace lk
