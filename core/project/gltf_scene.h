// glTF 2.0 scenes built with tinygltf (Debian's libtinygltf-dev): the pieces
// the project file's scene (project_file.cpp) and the GLB export
// (glb_export.h) share: one binary buffer of bufferViews, float32 meshes
// with normals and uvs, PNG textures, materials, and the GLB bytes.
// Internal to core/project (its files see tinygltf's switches, CMakeLists).
#pragma once
#include "common/types.h"
#include "io/io.h"
#include "mesh/tri_mesh.h"

#include <tiny_gltf.h>

#include <string>
#include <vector>

namespace lk {

// A morph target: a name and each vertex's offset (#V).
struct MorphTarget {
  std::string name;
  std::vector<Vec3> delta;
};

class GltfBuilder {
 public:
  explicit GltfBuilder(tinygltf::Model& model);

  tinygltf::Model& model;

  // Appends bytes to the buffer as a bufferView (8-byte aligned).
  int view(const void* data, std::size_t bytes, int target = 0);
  // A float32/uint32 accessor over a new view.
  int accessor(const void* data, std::size_t bytes, int count, int component, int type, int target);
  // A texture of the PNG already in bufferView png_view (image, linear sampler).
  int png_texture(int png_view, const std::string& name);
  // A PBR material, non-metallic: textured by texture (>= 0) or of colour rgba.
  int material(const std::string& name, int texture, const std::vector<double>& rgba, double roughness = 0.8);
  // A mesh of one triangle primitive: positions and normals (#V), uvs (#V,
  // or empty; glTF's v runs down the image, so v is flipped), triangles, and
  // morph targets (position offsets; weights 0; names in extras.targetNames,
  // the convention three.js and avatar tools read). A target is written
  // sparse (only the vertices it moves, by 10 micrometres or more in some
  // axis) when that is smaller than dense.
  int mesh(const std::string& name, const std::vector<Vec3>& positions, const std::vector<Vec3>& normals,
           const std::vector<Vec2>& uvs, const std::vector<Tri>& triangles, int material,
           const std::vector<MorphTarget>& targets = {});
  // The POSITION accessor of one morph target over n vertices (see mesh).
  int morph_target(const std::vector<Vec3>& delta);
  // A node (name, mesh or -1, translation); returns its index.
  int node(const std::string& name, int mesh = -1, const Vec3& translation = Vec3::Zero());
};

// The GLB bytes of model (binary glTF).
Status write_glb(tinygltf::Model& model, Bytes& out);

}  // namespace lk
