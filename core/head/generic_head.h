// Loading the generic head of jeong2002 (Sec. 4, Fig. 4) and reading/writing
// its annotations (feature boxes with landmarks, binding edges, constrained
// lip vertices, clipping planes, named regions, eye sockets, mouth, crease
// curves along the eye rims and lip lines).
//
// The asset is core/head/data/generic_head.obj (#V vertices, #F triangles,
// metres) and core/head/data/generic_head.json (annotations, indices into the
// OBJ's vertices, 0-based), made by `likeness make-generic-head` from
// generic_head_builder.h and embedded into the library at build time, so the
// web app needs no file system.
#pragma once
#include "common/status.h"
#include "head/head_model.h"

#include <string>

namespace lk {

// Names of the regions every annotation file must carry.
const std::vector<std::string>& required_head_regions();

// The embedded generic head: mesh from the OBJ, annotations from the JSON,
// both validated (indices in range, disk topology is the builder's promise
// and is checked by the tests, not here).
Status load_generic_head(GenericHead& out);

// The embedded asset's bytes, for tools that want to write them out as-is.
std::string generic_head_obj_text();
std::string generic_head_json_text();
// The embedded map of MediaPipe Face Mesh's 468 landmarks onto the generic
// head's surface (core/head/data/mediapipe_landmark_map.json, format
// likeness-landmark-map: photos/landmarks.h reads it).
std::string mediapipe_landmark_map_text();

// Parses annotation JSON for a mesh with num_vertices vertices. Every field is
// checked: vectors are 3 finite numbers, indices are integers in
// [0, num_vertices), boxes are exactly ear_left, ear_right, nose, mouth with
// 3/3/4/4 landmarks inside them, planes have non-zero normals, all required
// regions are present; "creases" (optional) are named curves of >= 2 (open)
// or >= 3 (closed) vertices. Fails with InvalidInput and a message naming the field.
Status parse_head_annotations(const std::string& json, int num_vertices, HeadAnnotations& out);

// #V flags, 1 for the listed vertices (a region, the constrained vertices);
// indices outside [0, num_vertices) are ignored.
std::vector<char> vertex_mask(const std::vector<int>& vertices, int num_vertices);

// The JSON text parse_head_annotations reads (round trip is exact up to
// printing doubles with 17 significant digits).
std::string head_annotations_to_json(const HeadAnnotations& annotations, int num_vertices = -1);

}  // namespace lk
