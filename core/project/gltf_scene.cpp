#include "project/gltf_scene.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace lk {

GltfBuilder::GltfBuilder(tinygltf::Model& m) : model(m) {
  if (model.buffers.empty()) model.buffers.resize(1);
}

int GltfBuilder::view(const void* data, std::size_t bytes, int target) {
  std::vector<unsigned char>& buf = model.buffers[0].data;
  while (buf.size() % 8) buf.push_back(0);
  tinygltf::BufferView v;
  v.buffer = 0;
  v.byteOffset = buf.size();
  v.byteLength = bytes;
  v.target = target;
  const auto* p = static_cast<const unsigned char*>(data);
  buf.insert(buf.end(), p, p + bytes);
  model.bufferViews.push_back(v);
  return static_cast<int>(model.bufferViews.size()) - 1;
}

int GltfBuilder::accessor(const void* data, std::size_t bytes, int count, int component, int type, int target) {
  tinygltf::Accessor a;
  a.bufferView = view(data, bytes, target);
  a.componentType = component;
  a.count = count;
  a.type = type;
  model.accessors.push_back(a);
  return static_cast<int>(model.accessors.size()) - 1;
}

int GltfBuilder::png_texture(int png_view, const std::string& name) {
  tinygltf::Image image;
  image.name = name;
  image.mimeType = "image/png";
  image.bufferView = png_view;
  model.images.push_back(image);
  tinygltf::Sampler sampler;
  sampler.magFilter = TINYGLTF_TEXTURE_FILTER_LINEAR;
  sampler.minFilter = TINYGLTF_TEXTURE_FILTER_LINEAR_MIPMAP_LINEAR;
  sampler.wrapS = sampler.wrapT = TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE;
  model.samplers.push_back(sampler);
  tinygltf::Texture tex;
  tex.source = static_cast<int>(model.images.size()) - 1;
  tex.sampler = static_cast<int>(model.samplers.size()) - 1;
  model.textures.push_back(tex);
  return static_cast<int>(model.textures.size()) - 1;
}

int GltfBuilder::material(const std::string& name, int texture, const std::vector<double>& rgba, double roughness) {
  tinygltf::Material mat;
  mat.name = name;
  mat.pbrMetallicRoughness.metallicFactor = 0;
  mat.pbrMetallicRoughness.roughnessFactor = roughness;
  if (texture >= 0) mat.pbrMetallicRoughness.baseColorTexture.index = texture;
  else mat.pbrMetallicRoughness.baseColorFactor = rgba;
  model.materials.push_back(mat);
  return static_cast<int>(model.materials.size()) - 1;
}

namespace {

// float32 copies of points, with their per-axis bounds (glTF wants min and
// max on every POSITION accessor, morph targets' too).
std::vector<float> floats(const std::vector<Vec3>& v, std::vector<double>& lo, std::vector<double>& hi) {
  std::vector<float> out(3 * v.size());
  lo.assign(3, v.empty() ? 0.0 : 1e300);
  hi.assign(3, v.empty() ? 0.0 : -1e300);
  for (std::size_t i = 0; i < v.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      out[3 * i + k] = static_cast<float>(v[i][k]);
      lo[k] = std::min(lo[k], double(out[3 * i + k]));
      hi[k] = std::max(hi[k], double(out[3 * i + k]));
    }
  return out;
}

}  // namespace

int GltfBuilder::mesh(const std::string& name, const std::vector<Vec3>& positions, const std::vector<Vec3>& normals,
                      const std::vector<Vec2>& uvs, const std::vector<Tri>& triangles, int material,
                      const std::vector<MorphTarget>& targets) {
  const int n = static_cast<int>(positions.size());
  std::vector<double> lo, hi;
  const std::vector<float> pos = floats(positions, lo, hi);
  std::vector<float> nrm(3 * positions.size());
  // glTF wants unit normals: each is normalized in float (the validator's
  // check), and a vertex without one (degenerate) gets +z.
  for (std::size_t i = 0; i < normals.size() && i < positions.size(); ++i) {
    const double len = normals[i].norm();
    const Vec3 u = len > 1e-12 && std::isfinite(len) ? Vec3(normals[i] / len) : Vec3(0, 0, 1);
    for (int k = 0; k < 3; ++k) nrm[3 * i + k] = static_cast<float>(u[k]);
  }
  std::vector<std::uint32_t> idx(3 * triangles.size());
  for (std::size_t i = 0; i < triangles.size(); ++i)
    for (int k = 0; k < 3; ++k) idx[3 * i + k] = static_cast<std::uint32_t>(triangles[i][k]);

  tinygltf::Primitive prim;
  prim.mode = TINYGLTF_MODE_TRIANGLES;
  prim.attributes["POSITION"] = accessor(pos.data(), pos.size() * 4, n, TINYGLTF_COMPONENT_TYPE_FLOAT,
                                         TINYGLTF_TYPE_VEC3, TINYGLTF_TARGET_ARRAY_BUFFER);
  model.accessors.back().minValues = lo;
  model.accessors.back().maxValues = hi;
  prim.attributes["NORMAL"] = accessor(nrm.data(), nrm.size() * 4, n, TINYGLTF_COMPONENT_TYPE_FLOAT,
                                       TINYGLTF_TYPE_VEC3, TINYGLTF_TARGET_ARRAY_BUFFER);
  if (!uvs.empty()) {
    std::vector<float> uv(2 * positions.size());
    for (std::size_t i = 0; i < positions.size(); ++i) {
      uv[2 * i] = static_cast<float>(uvs[i].x());
      uv[2 * i + 1] = static_cast<float>(1.0 - uvs[i].y());
    }
    prim.attributes["TEXCOORD_0"] = accessor(uv.data(), uv.size() * 4, n, TINYGLTF_COMPONENT_TYPE_FLOAT,
                                             TINYGLTF_TYPE_VEC2, TINYGLTF_TARGET_ARRAY_BUFFER);
  }
  std::vector<double> weights;
  tinygltf::Value::Array names;
  for (const MorphTarget& t : targets) {
    if (t.delta.size() != positions.size()) continue;
    prim.targets.push_back({{"POSITION", morph_target(t.delta)}});
    weights.push_back(0);
    names.emplace_back(t.name);
  }
  prim.material = material;
  prim.indices = accessor(idx.data(), idx.size() * 4, static_cast<int>(idx.size()), TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT,
                          TINYGLTF_TYPE_SCALAR, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
  tinygltf::Mesh m;
  m.name = name;
  m.primitives.push_back(prim);
  if (!weights.empty()) {
    m.weights = weights;
    m.extras = tinygltf::Value(tinygltf::Value::Object{{"targetNames", tinygltf::Value(names)}});
  }
  model.meshes.push_back(m);
  return static_cast<int>(model.meshes.size()) - 1;
}

int GltfBuilder::morph_target(const std::vector<Vec3>& delta) {
  const int n = static_cast<int>(delta.size());
  std::vector<double> lo, hi;
  std::vector<float> d = floats(delta, lo, hi);  // lo, hi: recomputed below
  // Offsets under 10 micrometres in every axis are dropped (zero): a tenth
  // of a scan's noise, and a tail of every falloff that would cost bytes.
  std::vector<std::uint32_t> moved;
  for (int i = 0; i < n; ++i) {
    bool keep = false;
    for (int k = 0; k < 3; ++k) keep = keep || std::abs(d[3 * i + k]) >= 1e-5f;
    if (keep) moved.push_back(static_cast<std::uint32_t>(i));
    else d[3 * i] = d[3 * i + 1] = d[3 * i + 2] = 0.0f;
  }
  // glTF's min and max are of the values the accessor yields (the dropped
  // offsets' zeros included).
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(i == 0 ? 1e300 : lo[k], double(d[3 * i + k]));
      hi[k] = std::max(i == 0 ? -1e300 : hi[k], double(d[3 * i + k]));
    }
  const bool short_index = n <= 65536;
  const std::size_t index_bytes = short_index ? 2 : 4;
  // A sparse accessor needs one entry at least: a target that moves
  // nothing keeps vertex 0 with a zero offset.
  if (moved.empty() && n > 0) moved.push_back(0);
  int acc = -1;
  if (moved.size() * (index_bytes + 12) < static_cast<std::size_t>(n) * 12) {
    std::vector<float> values;
    for (std::uint32_t i : moved) values.insert(values.end(), {d[3 * i], d[3 * i + 1], d[3 * i + 2]});
    tinygltf::Accessor a;
    a.bufferView = -1;  // no base: zeros, replaced where sparse says
    a.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
    a.count = static_cast<std::size_t>(n);
    a.type = TINYGLTF_TYPE_VEC3;
    a.sparse.isSparse = true;
    a.sparse.count = static_cast<int>(moved.size());
    if (short_index) {
      std::vector<std::uint16_t> idx(moved.begin(), moved.end());
      a.sparse.indices.bufferView = view(idx.data(), idx.size() * 2);
      a.sparse.indices.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT;
    } else {
      a.sparse.indices.bufferView = view(moved.data(), moved.size() * 4);
      a.sparse.indices.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
    }
    a.sparse.indices.byteOffset = 0;
    a.sparse.values.bufferView = view(values.data(), values.size() * 4);
    a.sparse.values.byteOffset = 0;
    model.accessors.push_back(a);
    acc = static_cast<int>(model.accessors.size()) - 1;
  } else {
    acc = accessor(d.data(), d.size() * 4, n, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, TINYGLTF_TARGET_ARRAY_BUFFER);
  }
  model.accessors[static_cast<std::size_t>(acc)].minValues = lo;
  model.accessors[static_cast<std::size_t>(acc)].maxValues = hi;
  return acc;
}

int GltfBuilder::node(const std::string& name, int mesh, const Vec3& translation) {
  tinygltf::Node n;
  n.name = name;
  n.mesh = mesh;
  if (translation != Vec3::Zero()) n.translation = {translation.x(), translation.y(), translation.z()};
  model.nodes.push_back(n);
  return static_cast<int>(model.nodes.size()) - 1;
}

Status write_glb(tinygltf::Model& model, Bytes& out) {
  tinygltf::TinyGLTF gltf;
  std::ostringstream stream;
  if (!gltf.WriteGltfSceneToStream(&model, stream, /*prettyPrint=*/false, /*writeBinary=*/true))
    return Status::error(ErrorCode::Internal, "could not write the GLB");
  const std::string bytes = stream.str();
  out.assign(bytes.begin(), bytes.end());
  return Status::success();
}

}  // namespace lk
