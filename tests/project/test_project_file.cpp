// The project file (core/project/project_file.h): a fitted and textured
// project comes back bit for bit and poses and exports as the original;
// the GLB's scene is the head for any glTF reader; cut, damaged, foreign
// and future files are refused with a reason and never crash.
#include "anim/bake.h"
#include "anim/clips.h"
#include "anim/face_pose.h"
#include "anim/face_shapes.h"
#include "head/generic_head.h"
#include "io/io.h"
#include "mesh/topology.h"
#include "project/export.h"
#include "project/glb_export.h"
#include "project/parts.h"
#include "project/pose.h"
#include "photos/landmarks.h"
#include "project/project_file.h"
#include "project/quality_job.h"
#include "project/texture_job.h"
#include "project_photos.h"
#include "project_scene.h"

// The same switches as core/project's own tinygltf (its implementation
// lives there): the test reads and rewrites GLBs directly.
#define TINYGLTF_NO_FS
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#include <fstream>
#include <nlohmann/json.hpp>
#include <tiny_gltf.h>
// Declarations only (the implementation is in lk_io): JPEGs made here.
#include <stb/stb_image_write.h>

#include <catch2/catch.hpp>

#include <cstring>
#include <functional>
#include <map>
#include <random>
#include <set>
#include <sstream>

using namespace lk;

namespace {

// The scene's project, re-evaluated at rest (the fit's own state differs
// from an evaluation by rounding: a loaded project is an evaluation) and
// textured from three synthetic photos at 256 x 256.
const HeadProject& textured_project() {
  static const HeadProject p = [] {
    HeadProject q = test::fitted_project();
    REQUIRE(pose_project(q, 0.0).ok());
    TriMesh level;
    REQUIRE(project_level_mesh(q, q.fit.multires.num_levels(), ExportFrame::Scan, level).ok());
    TextureJobInput input = test::job_input(test::photograph(level), 256);
    TextureJobResult out;
    const Status st = texture_project(q, input, out);
    INFO(st.message);
    REQUIRE(st.ok());
    return q;
  }();
  return p;
}

Bytes saved(const HeadProject& p) {
  Bytes b;
  const Status st = save_project(p, b);
  INFO(st.message);
  REQUIRE(st.ok());
  return b;
}

HeadProject loaded(const Bytes& b) {
  HeadProject p;
  const Status st = load_project(b.data(), b.size(), p);
  INFO(st.message);
  REQUIRE(st.ok());
  return p;
}

Status try_load(const Bytes& b, bool verify_checksum = true) {
  HeadProject p;
  return load_project(b.data(), b.size(), p, verify_checksum);
}

bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

// The GLB as tinygltf reads it (images left undecoded).
tinygltf::Model parsed_glb(const Bytes& bytes) {
  tinygltf::TinyGLTF gltf;
  gltf.SetImageLoader([](tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int,
                         void*) { return true; },
                      nullptr);
  tinygltf::Model m;
  std::string err, warn;
  INFO(err);
  REQUIRE(gltf.LoadBinaryFromMemory(&m, &err, &warn, bytes.data(), static_cast<unsigned>(bytes.size())));
  return m;
}

void check_same_head(const HeadProject& a, const HeadProject& b) {
  const MultiresMesh &ma = a.fit.multires, &mb = b.fit.multires;
  REQUIRE(ma.num_levels() == mb.num_levels());
  CHECK(ma.control == mb.control);
  CHECK(ma.displacements == mb.displacements);
  CHECK(ma.creases.edges == mb.creases.edges);
  CHECK(ma.creases.corners == mb.creases.corners);
  for (int l = 0; l <= ma.num_levels(); ++l) {
    CHECK(ma.triangles(l) == mb.triangles(l));
    CHECK(ma.state.base[l] == mb.state.base[l]);
    CHECK(ma.state.normals[l] == mb.state.normals[l]);
    CHECK(ma.state.displaced[l] == mb.state.displaced[l]);
  }
  CHECK(a.pose == b.pose);
}

}  // namespace

TEST_CASE("project file: a fitted, textured project comes back bit for bit") {
  const HeadProject& a = textured_project();
  const Bytes bytes = saved(a);
  const HeadProject b = loaded(bytes);
  const int L = a.fit.multires.num_levels();

  check_same_head(a, b);
  CHECK(b.scan.positions == a.scan.positions);
  CHECK(b.scan.faces == a.scan.faces);
  CHECK(b.fit.control.positions == a.fit.control.positions);
  CHECK(b.fit.control.triangles == a.fit.control.triangles);
  CHECK(b.fit.aligned.positions == a.fit.aligned.positions);
  CHECK(b.fit.local.positions == a.fit.local.positions);
  // The level meshes are the rest pose's: the fitted control mesh's (the
  // project's own control positions went through pose 0, whose jaw
  // rotation by 0 moves them by rounding).
  MultiresMesh rest = a.fit.multires;
  rest.control = a.fit.control.positions;
  REQUIRE(evaluate(rest).ok());
  REQUIRE(b.fit.level_meshes.size() == static_cast<size_t>(L));
  for (int l = 1; l <= L; ++l) {
    CHECK(b.fit.level_meshes[l - 1].positions == rest.state.displaced[l]);
    CHECK(b.fit.level_meshes[l - 1].triangles == a.fit.level_meshes[l - 1].triangles);
  }
  CHECK(b.fit.scan_to_head.A == a.fit.scan_to_head.A);
  CHECK(b.fit.scan_to_head.t == a.fit.scan_to_head.t);
  CHECK(b.frame.head_to_scan == a.frame.head_to_scan);
  CHECK(b.frame.head_offset == a.frame.head_offset);
  CHECK(b.fit.notes == a.fit.notes);
  REQUIRE(b.fit.stages.size() == a.fit.stages.size());
  for (size_t i = 0; i < a.fit.stages.size(); ++i) {
    CHECK(b.fit.stages[i].name == a.fit.stages[i].name);
    CHECK(b.fit.stages[i].distance.mean_pct == a.fit.stages[i].distance.mean_pct);
    CHECK(b.fit.stages[i].distance.max == a.fit.stages[i].distance.max);
  }
  CHECK(b.fit.points == a.fit.points);
  CHECK(b.fit.unit_to_metres == a.fit.unit_to_metres);
  CHECK(b.fit.untangle.pairs_after == a.fit.untangle.pairs_after);
  CHECK(b.options.levels == a.options.levels);
  CHECK(b.options.up == a.options.up);
  CHECK(b.rig.moved == a.rig.moved);
  CHECK(b.rig.rest == a.rig.rest);
  CHECK(b.rig.kind == a.rig.kind);
  CHECK(b.rig.weight == a.rig.weight);
  CHECK(b.rig.jaw_pivot == a.rig.jaw_pivot);
  CHECK(b.rig.head_size == a.rig.head_size);
  REQUIRE(!b.texture.empty());
  CHECK(b.texture.uvs == a.texture.uvs);
  CHECK(b.texture.skin.width == a.texture.skin.width);
  CHECK(b.texture.skin.channels == a.texture.skin.channels);
  CHECK(b.texture.skin.pixels == a.texture.skin.pixels);
  CHECK(!b.quality.measured);  // measured again on demand

  // The control mesh as the fit left it (normals too), and the parts placed
  // from it.
  CHECK(b.fit.control.normals == a.fit.control.normals);
  CHECK(b.fit.aligned.triangles == a.fit.aligned.triangles);
  CHECK(b.fit.local.triangles == a.fit.local.triangles);
  HeadParts pa, pb;
  REQUIRE(place_head_parts(a.fit.control, test::project_scene().generic, pa).ok());
  REQUIRE(place_head_parts(b.fit.control, test::project_scene().generic, pb).ok());
  for (int i = 0; i < 2; ++i) CHECK(pa.placed.eye[i].positions == pb.placed.eye[i].positions);
  CHECK(pa.upper_teeth.positions == pb.upper_teeth.positions);
  CHECK(pa.lower_teeth.positions == pb.lower_teeth.positions);
  CHECK(pa.placed.tongue.positions == pb.placed.tongue.positions);

  // Saving the loaded project gives the same bytes.
  CHECK(saved(b) == bytes);
}

TEST_CASE("project file: a loaded project poses and exports exactly as the original") {
  HeadProject a = textured_project();
  HeadProject b = loaded(saved(a));
  const int L = a.fit.multires.num_levels();
  for (double amount : {0.0, 0.7, 1.0, 0.3}) {
    REQUIRE(pose_project(a, amount).ok());
    REQUIRE(pose_project(b, amount).ok());
    check_same_head(a, b);
    CHECK(jaw_motion(a, amount) == jaw_motion(b, amount));
    for (int l = 0; l <= L; ++l)
      for (LevelFormat f : {LevelFormat::Obj, LevelFormat::Ply}) {
        Bytes ea, eb;
        REQUIRE(export_level(a, l, f, ExportFrame::Scan, ea).ok());
        REQUIRE(export_level(b, l, f, ExportFrame::Scan, eb).ok());
        CHECK(ea == eb);
      }
    TexturedFiles ta, tb;
    REQUIRE(export_textured(a, L, "head", ExportFrame::Scan, ta).ok());
    REQUIRE(export_textured(b, L, "head", ExportFrame::Scan, tb).ok());
    CHECK(ta.obj == tb.obj);
    CHECK(ta.png == tb.png);
  }

  // A posed project keeps its pose; its scene and level meshes are at rest.
  const Bytes posed = saved(a);
  HeadProject c = loaded(posed);
  CHECK(c.pose == a.pose);
  check_same_head(a, c);
  REQUIRE(pose_project(c, 0.0).ok());
  REQUIRE(pose_project(b, 0.0).ok());
  check_same_head(b, c);

  // The checks measured on the loaded project are the original's.
  HeadProject q = loaded(saved(textured_project()));
  HeadProject r = textured_project();
  REQUIRE(measure_project_quality(q, test::project_scene().generic).ok());
  REQUIRE(measure_project_quality(r, test::project_scene().generic).ok());
  CHECK(q.quality.status.ok() == r.quality.status.ok());
  CHECK(q.quality.fit.flipped == r.quality.fit.flipped);
  CHECK(q.quality.fit.degenerate == r.quality.fit.degenerate);
  CHECK(q.quality.fit.crossings.total == r.quality.fit.crossings.total);
  CHECK(q.quality.fit.smooth_crossings.total == r.quality.fit.smooth_crossings.total);
  CHECK(q.quality.to_scan.mean == Approx(r.quality.to_scan.mean).epsilon(1e-12));
  CHECK(q.quality.to_scan.max == Approx(r.quality.to_scan.max).epsilon(1e-12));
}

TEST_CASE("project file: the GLB's scene is the textured finest level for any glTF reader") {
  const HeadProject& a = textured_project();
  const Bytes bytes = saved(a);
  tinygltf::Model m = parsed_glb(bytes);
  REQUIRE(m.scenes.size() == 1);
  REQUIRE(m.meshes.size() == 1);
  const tinygltf::Primitive& prim = m.meshes[0].primitives.at(0);
  const int L = a.fit.multires.num_levels();
  MultiresMesh rest_mesh = a.fit.multires;  // the fitted control mesh's levels
  rest_mesh.control = a.fit.control.positions;
  REQUIRE(evaluate(rest_mesh).ok());
  const std::vector<Vec3>& rest = rest_mesh.state.displaced[L];
  const std::vector<Tri>& tris = a.fit.multires.triangles(L);
  auto data = [&](int accessor) {
    const tinygltf::Accessor& acc = m.accessors.at(accessor);
    const tinygltf::BufferView& v = m.bufferViews.at(acc.bufferView);
    return m.buffers.at(v.buffer).data.data() + v.byteOffset + acc.byteOffset;
  };
  const tinygltf::Accessor& pos = m.accessors.at(prim.attributes.at("POSITION"));
  REQUIRE(pos.count == rest.size());
  REQUIRE(pos.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT);
  const float* P = reinterpret_cast<const float*>(data(prim.attributes.at("POSITION")));
  for (size_t i = 0; i < rest.size(); i += 97)
    for (int k = 0; k < 3; ++k) CHECK(P[3 * i + k] == static_cast<float>(rest[i][k]));
  const tinygltf::Accessor& idx = m.accessors.at(prim.indices);
  REQUIRE(idx.count == 3 * tris.size());
  const std::uint32_t* I = reinterpret_cast<const std::uint32_t*>(data(prim.indices));
  for (size_t t = 0; t < tris.size(); t += 31)
    for (int k = 0; k < 3; ++k) CHECK(I[3 * t + k] == static_cast<std::uint32_t>(tris[t][k]));
  const float* UV = reinterpret_cast<const float*>(data(prim.attributes.at("TEXCOORD_0")));
  for (size_t i = 0; i < rest.size(); i += 97) {
    CHECK(UV[2 * i] == static_cast<float>(a.texture.uvs[i].x()));
    CHECK(UV[2 * i + 1] == static_cast<float>(1.0 - a.texture.uvs[i].y()));  // glTF's v runs down
  }
  // The material's texture is the skin.
  const int tex = m.materials.at(prim.material).pbrMetallicRoughness.baseColorTexture.index;
  const tinygltf::Image& im = m.images.at(m.textures.at(tex).source);
  CHECK(im.mimeType == "image/png");
  const tinygltf::BufferView& iv = m.bufferViews.at(im.bufferView);
  Image skin;
  REQUIRE(read_image(m.buffers[0].data.data() + iv.byteOffset, iv.byteLength, skin).ok());
  CHECK(skin.pixels == a.texture.skin.pixels);
}

namespace {

// A GLB rewritten with its project's extras changed by edit (the checksum
// is left as it was: loads that skip it reach the checks behind it).
Bytes rewritten(const Bytes& bytes, const std::function<void(tinygltf::Value::Object&)>& edit) {
  tinygltf::Model m = parsed_glb(bytes);
  tinygltf::Value::Object root = m.extras.Get<tinygltf::Value::Object>();
  tinygltf::Value::Object doc = root["likeness"].Get<tinygltf::Value::Object>();
  edit(doc);
  root["likeness"] = tinygltf::Value(doc);
  m.extras = tinygltf::Value(root);
  std::ostringstream out;
  REQUIRE(tinygltf::TinyGLTF().WriteGltfSceneToStream(&m, out, false, true));
  const std::string s = out.str();
  return Bytes(s.begin(), s.end());
}

// A small project for the exhaustive tests: the scene's head at one level,
// 300 scan points, a 16 x 16 skin.
const Bytes& small_project() {
  static const Bytes b = [] {
    HeadProject p = textured_project();
    MultiresMesh& mr = p.fit.multires;
    MultiresMesh one;
    REQUIRE(build_multires(p.fit.control, mr.creases, 1, one).ok());
    one.displacements[0] = mr.displacements[0];
    one.displacements[1] = mr.displacements[1];
    REQUIRE(evaluate(one).ok());
    mr = std::move(one);
    p.fit.level_meshes.resize(1);
    p.options.levels = 1;
    p.scan.positions.resize(300);
    p.scan.faces.clear();
    p.texture.uvs.resize(static_cast<size_t>(mr.num_vertices(1)));
    p.texture.skin = Image::make(16, 16, 3, 128);
    p.texture.skin.pixels[5] = 7;
    return saved(p);
  }();
  return b;
}

}  // namespace

TEST_CASE("project file: foreign, future and edited files are refused with a reason") {
  const Bytes bytes = saved(textured_project());
  Status st = try_load(Bytes{});
  CHECK(st.code == ErrorCode::Empty);

  // A PLY, an OBJ.
  TriMesh tri;
  tri.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  tri.triangles = {{0, 1, 2}};
  st = try_load(write_ply(tri));
  CHECK(contains(st.message, "not a Likeness project"));
  const std::string obj = write_obj(tri);
  st = try_load(Bytes(obj.begin(), obj.end()));
  CHECK(contains(st.message, "not a Likeness project"));

  // A plain GLB from elsewhere: one triangle, no project.
  {
    tinygltf::Model m;
    m.asset.version = "2.0";
    m.asset.generator = "some modeller";
    m.buffers.resize(1);
    const float P[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    m.buffers[0].data.assign(reinterpret_cast<const unsigned char*>(P), reinterpret_cast<const unsigned char*>(P) + 36);
    tinygltf::BufferView v;
    v.buffer = 0;
    v.byteLength = 36;
    m.bufferViews.push_back(v);
    tinygltf::Accessor a;
    a.bufferView = 0;
    a.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
    a.count = 3;
    a.type = TINYGLTF_TYPE_VEC3;
    a.minValues = {0, 0, 0};
    a.maxValues = {1, 1, 0};
    m.accessors.push_back(a);
    tinygltf::Primitive prim;
    prim.attributes["POSITION"] = 0;
    tinygltf::Mesh mesh;
    mesh.primitives.push_back(prim);
    m.meshes.push_back(mesh);
    tinygltf::TinyGLTF gltf;
    std::ostringstream out;
    REQUIRE(gltf.WriteGltfSceneToStream(&m, out, false, true));
    const std::string s = out.str();
    st = try_load(Bytes(s.begin(), s.end()));
    CHECK(st.code == ErrorCode::InvalidInput);
    CHECK(contains(st.message, "not a Likeness project: a glTF file with no Likeness project in it (made by some modeller)"));
  }

  // A newer version, another format's extras, an edited pose.
  st = try_load(rewritten(bytes, [](tinygltf::Value::Object& d) { d["version"] = tinygltf::Value(4); }));
  CHECK(st.code == ErrorCode::Unsupported);
  CHECK(st.message == "made by a newer Likeness (project version 4); this one reads version 3");
  st = try_load(rewritten(bytes, [](tinygltf::Value::Object& d) { d["format"] = tinygltf::Value(std::string("x")); }));
  CHECK(contains(st.message, "not a Likeness project"));
  const Bytes edited = rewritten(bytes, [](tinygltf::Value::Object& d) { d["pose"] = tinygltf::Value(0.5); });
  st = try_load(edited);
  CHECK(contains(st.message, "checksum does not match"));
  // Without the checksum, the edit loads (the checks behind it pass).
  HeadProject p;
  REQUIRE(load_project(edited.data(), edited.size(), p, false).ok());
  CHECK(p.pose == 0.5);
  // Inconsistent contents behind the checksum are refused one by one.
  const auto refused = [&](const std::function<void(tinygltf::Value::Object&)>& edit, const std::string& why) {
    const Status s = try_load(rewritten(bytes, edit), false);
    INFO(why << ": " << s.message);
    CHECK(s.code != ErrorCode::Ok);
    CHECK(contains(s.message, why));
  };
  using Obj = tinygltf::Value::Object;
  const auto at = [](Obj& d, std::initializer_list<const char*> path) -> Obj {
    Obj o = d;
    for (const char* k : path) {
      Obj next = o[k].Get<Obj>();
      o = std::move(next);
    }
    return o;
  };
  refused([](Obj& d) { d["pose"] = tinygltf::Value(2.0); }, "the pose");
  refused([](Obj& d) { d.erase("rig"); }, "rig");
  refused([&](Obj& d) {
    Obj fit = at(d, {"fit"}), mr = at(d, {"fit", "multires"});
    mr["levels"] = tinygltf::Value(3);
    fit["multires"] = tinygltf::Value(mr);
    d["fit"] = tinygltf::Value(fit);
  }, "displacements");
  refused([&](Obj& d) {
    Obj scan = at(d, {"scan"}), pos = at(d, {"scan", "positions"});
    pos["count"] = tinygltf::Value(pos["count"].Get<int>() + 1);
    scan["positions"] = tinygltf::Value(pos);
    d["scan"] = tinygltf::Value(scan);
  }, "scan positions");
  refused([&](Obj& d) {
    Obj rig = at(d, {"rig"}), moved = at(d, {"rig", "moved"});
    moved["view"] = tinygltf::Value(100000);
    rig["moved"] = tinygltf::Value(moved);
    d["rig"] = tinygltf::Value(rig);
  }, "no such bufferView");
  refused([&](Obj& d) {  // the control triangles read as the scan's positions: out of range or wrong type
    Obj fit = at(d, {"fit"}), control = at(d, {"fit", "control"});
    control["triangles"] = tinygltf::Value(at(d, {"scan", "positions"}));
    fit["control"] = tinygltf::Value(control);
    d["fit"] = tinygltf::Value(fit);
  }, "control mesh triangles");
  refused([&](Obj& d) {  // invertible on paper, its inverse 1e100 (found by tests/fuzz/fuzz_project)
    Obj fit = at(d, {"fit"}), map = at(d, {"fit", "scan_to_head"});
    tinygltf::Value::Array a = map["A"].Get<tinygltf::Value::Array>();
    for (int k = 0; k < 3; ++k) a[k] = tinygltf::Value(1e-100);  // a row (or column) 1e-100 long, turned or not
    map["A"] = tinygltf::Value(a);
    fit["scan_to_head"] = tinygltf::Value(map);
    d["fit"] = tinygltf::Value(fit);
  }, "cannot be inverted");
}

namespace {

// The file's checksum made again after an edit, as the writer computes it
// (FNV-1a 64 over the extras without the checksum, each bufferView's
// place, the buffers), spelled out here so an edited file is a file the
// reader accepts with its check on: a version 1 file, as the earlier
// writer made it.
Bytes resealed(const Bytes& bytes) {
  tinygltf::TinyGLTF gltf;
  gltf.SetStoreOriginalJSONForExtrasAndExtensions(true);
  gltf.SetImageLoader([](tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int,
                         void*) { return true; },
                      nullptr);
  tinygltf::Model m;
  std::string err, warn;
  REQUIRE(gltf.LoadBinaryFromMemory(&m, &err, &warn, bytes.data(), static_cast<unsigned>(bytes.size())));
  nlohmann::json doc = nlohmann::json::parse(m.extras_json_string)["likeness"];
  doc.erase("checksum");
  std::uint64_t h = 14695981039346656037ull;
  const auto add = [&](const void* data, size_t n) {
    const auto* q = static_cast<const std::uint8_t*>(data);
    for (size_t i = 0; i < n; ++i) h = (h ^ q[i]) * 1099511628211ull;
  };
  const auto add_u64 = [&](std::uint64_t v) { add(&v, sizeof v); };
  const std::string text = doc.dump();
  add(text.data(), text.size());
  add_u64(m.bufferViews.size());
  for (const tinygltf::BufferView& v : m.bufferViews) {
    add_u64(static_cast<std::uint64_t>(v.buffer));
    add_u64(v.byteOffset);
    add_u64(v.byteLength);
  }
  add_u64(m.buffers.size());
  for (const tinygltf::Buffer& b : m.buffers) {
    add_u64(b.data.size());
    add(b.data.data(), b.data.size());
  }
  std::string hex(16, '0');
  for (int i = 0; i < 16; ++i) hex[15 - i] = "0123456789abcdef"[(h >> (4 * i)) & 15];
  return rewritten(bytes, [&](tinygltf::Value::Object& d) { d["checksum"] = tinygltf::Value(hex); });
}

// A deterministic image whose every pixel differs from its neighbours.
Image pattern(int w, int h, int channels, std::uint32_t seed) {
  Image im = Image::make(w, h, channels, 0);
  std::mt19937 rng(seed);
  for (std::uint8_t& v : im.pixels) v = static_cast<std::uint8_t>(rng() & 255u);
  return im;
}

}  // namespace

TEST_CASE("project file: the eyes' and teeth's textures from photos come back byte for byte") {
  HeadProject a = textured_project();
  a.parts.eye_texture = pattern(96, 64, 3, 1);
  a.parts.eye_source = "eye close-up.jpg";
  a.parts.teeth_texture = pattern(64, 32, 4, 2);  // RGBA: the voids' alpha too
  a.parts.teeth_source = "smile.png";
  const Bytes bytes = saved(a);
  const HeadProject b = loaded(bytes);
  CHECK(b.parts.eye_texture.width == 96);
  CHECK(b.parts.eye_texture.height == 64);
  CHECK(b.parts.eye_texture.channels == 3);
  CHECK(b.parts.eye_texture.pixels == a.parts.eye_texture.pixels);
  CHECK(b.parts.eye_source == "eye close-up.jpg");
  CHECK(b.parts.teeth_texture.channels == 4);
  CHECK(b.parts.teeth_texture.pixels == a.parts.teeth_texture.pixels);
  CHECK(b.parts.teeth_source == "smile.png");
  check_same_head(a, b);
  CHECK(saved(b) == bytes);

  // One part alone: the other stays generic (empty).
  HeadProject c = textured_project();
  c.parts.teeth_texture = a.parts.teeth_texture;
  c.parts.teeth_source = "smile.png";
  const HeadProject d = loaded(saved(c));
  CHECK(d.parts.eye_texture.empty());
  CHECK(d.parts.eye_source.empty());
  CHECK(d.parts.teeth_texture.pixels == c.parts.teeth_texture.pixels);

  // Without parts the file holds none, and none come back.
  const Bytes plain = saved(textured_project());
  CHECK(!contains(std::string(plain.begin(), plain.end()), "\"parts\""));
  CHECK(loaded(plain).parts.eye_texture.empty());

  // Edited parts behind the checksum are refused with a reason.
  using Obj = tinygltf::Value::Object;
  const auto refused = [&](const std::function<void(Obj&)>& edit, const std::string& why) {
    const Status s = try_load(rewritten(bytes, edit), false);
    INFO(why << ": " << s.message);
    CHECK(s.code != ErrorCode::Ok);
    CHECK(contains(s.message, why));
  };
  const auto edit_eye = [](Obj& d, const std::function<void(Obj&)>& f) {
    Obj parts = d["parts"].Get<Obj>(), eye = parts["eye"].Get<Obj>();
    f(eye);
    parts["eye"] = tinygltf::Value(eye);
    d["parts"] = tinygltf::Value(parts);
  };
  refused([&](Obj& d) { edit_eye(d, [](Obj& e) { e["source"] = tinygltf::Value(3); }); }, "the eye texture");
  refused([&](Obj& d) {
    edit_eye(d, [](Obj& e) {
      Obj t = e["texture"].Get<Obj>();
      t["type"] = tinygltf::Value(std::string("f64"));
      e["texture"] = tinygltf::Value(t);
    });
  }, "the eye texture");
  refused([&](Obj& d) {  // the rig's integers read as the eye's PNG
    Obj rig = d["rig"].Get<Obj>();
    Obj moved = rig["moved"].Get<Obj>();
    edit_eye(d, [&](Obj& e) {
      Obj t = e["texture"].Get<Obj>();
      t["view"] = moved["view"];
      t["count"] = tinygltf::Value(moved["count"].Get<int>() * 4);
      e["texture"] = tinygltf::Value(t);
    });
  }, "the eye texture");
  refused([](Obj& d) { d["parts"] = tinygltf::Value(std::string("eyes")); }, "the eyes' and teeth's textures");
}

namespace {

Bytes jpeg_of(const Image& im) {
  Bytes out;
  stbi_write_jpg_to_func([](void* c, void* data, int n) {
    auto* o = static_cast<Bytes*>(c);
    o->insert(o->end(), static_cast<std::uint8_t*>(data), static_cast<std::uint8_t*>(data) + n);
  }, &out, im.width, im.height, im.channels, im.pixels.data(), 90);
  REQUIRE(out.size() > 100);
  return out;
}

// A photo's face points as the page writes them: 468 points (a few the
// detector missed), the dragged ones listed in "corrected".
std::string page_points(const std::string& name, int w, int h, std::uint32_t seed, const std::vector<int>& corrected) {
  LandmarkPhoto lm;
  lm.name = name;
  lm.width = w;
  lm.height = h;
  lm.detector = "mediapipe-face-mesh";
  std::mt19937 rng(seed);
  for (int i = 0; i < 468; ++i) {
    lm.points.push_back(Vec2(std::uniform_real_distribution<double>(0, w)(rng), std::uniform_real_distribution<double>(0, h)(rng)));
    lm.present.push_back(i % 97 == 5 ? 0 : 1);
  }
  nlohmann::json doc = nlohmann::json::parse(landmarks_to_json(lm));
  doc["corrected"] = corrected;
  return doc.dump();
}

// A textured project with a face photo (JPEG) and an eye photo (PNG), the
// face's points with two drags, and the page's options.
HeadProject project_with_photos() {
  HeadProject a = textured_project();
  ProjectPhoto face{"front photo.jpg", "face", jpeg_of(pattern(120, 90, 3, 7)), page_points("front photo.jpg", 120, 90, 3, {1, 200})};
  ProjectPhoto eye{"eye close-up.png", "eye", write_png(pattern(40, 30, 3, 8)), ""};
  a.inputs.photos = {face, eye};
  a.inputs.page_options = R"({"level":"3","autoFit":true,"thin":4,"textureSize":1024,"fullDetail":false})";
  return a;
}

}  // namespace

TEST_CASE("project file: the photos, their face points and the page's options come back byte for byte") {
  const HeadProject a = project_with_photos();
  const Bytes bytes = saved(a);
  const HeadProject b = loaded(bytes);
  REQUIRE(b.inputs.photos.size() == 2);
  for (std::size_t i = 0; i < 2; ++i) {
    INFO("photo " << i);
    CHECK(b.inputs.photos[i].name == a.inputs.photos[i].name);
    CHECK(b.inputs.photos[i].role == a.inputs.photos[i].role);
    CHECK(b.inputs.photos[i].bytes == a.inputs.photos[i].bytes);  // the file itself, not re-encoded
    CHECK(b.inputs.photos[i].points == a.inputs.photos[i].points);
  }
  CHECK(b.inputs.photos[0].bytes[0] == 0xff);  // still the JPEG
  // The points are the CLI's points file, corrections marked.
  LandmarkPhoto lm;
  REQUIRE(parse_landmarks_json(b.inputs.photos[0].points, lm).ok());
  CHECK(lm.points.size() == 468);
  CHECK(nlohmann::json::parse(b.inputs.photos[0].points)["corrected"] == nlohmann::json::array({1, 200}));
  CHECK(b.inputs.page_options == a.inputs.page_options);
  CHECK(b.file_version == 3);
  check_same_head(a, b);
  CHECK(b.texture.skin.pixels == a.texture.skin.pixels);
  CHECK(saved(b) == bytes);  // the loaded project saves the same file
  // Without photos or options the file holds none.
  const Bytes plain = saved(textured_project());
  CHECK(!contains(std::string(plain.begin(), plain.end()), "\"photos\""));
  CHECK(loaded(plain).inputs.empty());
}

TEST_CASE("project file: version 1 and 2 files open without photos, a newer one is refused by its number") {
  const HeadProject a = project_with_photos();
  const Bytes bytes = saved(a);
  for (int v : {1, 2}) {
    INFO("version " << v);
    const Bytes old = resealed(rewritten(bytes, [v](tinygltf::Value::Object& d) {
      d["version"] = tinygltf::Value(v);
      d.erase("photos");
      d.erase("page_options");
    }));
    HeadProject b;
    const Status st = load_project(old.data(), old.size(), b);
    INFO(st.message);
    REQUIRE(st.ok());
    CHECK(b.file_version == v);
    CHECK(b.inputs.empty());
    check_same_head(a, b);
  }
  const Bytes newer = resealed(rewritten(bytes, [](tinygltf::Value::Object& d) { d["version"] = tinygltf::Value(4); }));
  const Status st = try_load(newer);
  CHECK(st.code == ErrorCode::Unsupported);
  CHECK(st.message == "made by a newer Likeness (project version 4); this one reads version 3");
}

TEST_CASE("project file: a damaged photo entry is refused with a reason, never loaded half") {
  const HeadProject good = project_with_photos();
  // Saved with a bad entry (the writer keeps what it is given), so the
  // checksum is right and the reader's own checks must refuse it.
  const auto refused_saved = [&](const std::function<void(ProjectInputs&)>& edit, const std::string& why) {
    HeadProject p = good;
    edit(p.inputs);
    Bytes b;
    REQUIRE(save_project(p, b).ok());
    HeadProject out;
    out.pose = 0.25;  // a failed load leaves it untouched
    const Status s = load_project(b.data(), b.size(), out);
    INFO(why << ": " << s.message);
    CHECK(!s.ok());
    CHECK(contains(s.message, why));
    CHECK(out.pose == 0.25);
    CHECK(out.inputs.empty());
  };
  refused_saved([](ProjectInputs& in) { in.photos[0].bytes = Bytes{'h', 'e', 'l', 'l', 'o'}; }, "photo 1 (front photo.jpg)");
  refused_saved([](ProjectInputs& in) { in.photos[0].bytes.resize(10); }, "photo 1 (front photo.jpg)");
  refused_saved([](ProjectInputs& in) { in.photos[1].name = "../eye.png"; }, "photo 2: no plain file name");
  refused_saved([](ProjectInputs& in) { in.photos[1].name = ""; }, "photo 2: no plain file name");
  refused_saved([](ProjectInputs& in) { in.photos[1].role = "hat"; }, "its role is not face, eye or smile");
  refused_saved([](ProjectInputs& in) { in.photos[0].points = "{\"format\":\"likeness-landmarks\""; }, "face points");
  refused_saved([](ProjectInputs& in) {
    nlohmann::json d = nlohmann::json::parse(in.photos[0].points);
    d["corrected"] = {1, 468};  // past its 468 points
    in.photos[0].points = d.dump();
  }, "a corrected point that is not one of its points");
  refused_saved([](ProjectInputs& in) { in.page_options = "[1, 2]"; }, "the page's options are not a JSON object");
  refused_saved([](ProjectInputs& in) { in.page_options = "{\"level\":"; }, "the page's options are not a JSON object");
  refused_saved([](ProjectInputs& in) { in.page_options = "{\"a\":" + std::string(5000, '[') + std::string(5000, ']') + "}"; },
                "the page's options are not a JSON object");

  // Edited entries behind the checksum.
  const Bytes bytes = saved(good);
  using Obj = tinygltf::Value::Object;
  using Arr = tinygltf::Value::Array;
  const auto refused = [&](const std::function<void(Obj&)>& edit, const std::string& why) {
    const Status s = try_load(rewritten(bytes, edit), false);
    INFO(why << ": " << s.message);
    CHECK(s.code != ErrorCode::Ok);
    CHECK(contains(s.message, why));
  };
  const auto edit_photo = [](Obj& d, const std::function<void(Obj&)>& f) {
    Arr photos = d["photos"].Get<Arr>();
    Obj e = photos[0].Get<Obj>();
    f(e);
    photos[0] = tinygltf::Value(e);
    d["photos"] = tinygltf::Value(photos);
  };
  refused([](Obj& d) { d["photos"] = tinygltf::Value(std::string("photos")); }, "the photos are not a list");
  refused([&](Obj& d) { edit_photo(d, [](Obj& e) { e["name"] = tinygltf::Value(3); }); }, "photo 1: no plain file name");
  refused([&](Obj& d) {
    edit_photo(d, [](Obj& e) {
      Obj f = e["file"].Get<Obj>();
      f["count"] = tinygltf::Value(f["count"].Get<int>() + 1);  // one byte more than its view
      e["file"] = tinygltf::Value(f);
    });
  }, "photo 1 (front photo.jpg)");
  refused([&](Obj& d) {
    edit_photo(d, [](Obj& e) {
      Obj f = e["file"].Get<Obj>();
      f["view"] = tinygltf::Value(100000);
      e["file"] = tinygltf::Value(f);
    });
  }, "no such bufferView");
  refused([&](Obj& d) {  // the rig's integers read as the photo's file
    const Obj moved = d["rig"].Get<Obj>()["moved"].Get<Obj>();
    edit_photo(d, [&](Obj& e) {
      Obj f = e["file"].Get<Obj>();
      f["view"] = moved.at("view");
      f["count"] = tinygltf::Value(moved.at("count").Get<int>() * 4);
      e["file"] = tinygltf::Value(f);
    });
  }, "photo 1 (front photo.jpg)");
  refused([&](Obj& d) {  // the photo's bytes read as its points
    edit_photo(d, [](Obj& e) {
      Obj f = e["file"].Get<Obj>();
      f["type"] = tinygltf::Value(std::string("json"));
      e["points"] = tinygltf::Value(f);
    });
  }, "face points");
}

TEST_CASE("project file: a version 1 file (before the parts) still opens, with the generic eyes and teeth") {
  const HeadProject& a = textured_project();
  const Bytes v1 = resealed(rewritten(saved(a), [](tinygltf::Value::Object& d) { d["version"] = tinygltf::Value(1); }));
  HeadProject b;
  const Status st = load_project(v1.data(), v1.size(), b);  // the checksum checked
  INFO(st.message);
  REQUIRE(st.ok());
  check_same_head(a, b);
  CHECK(b.texture.skin.pixels == a.texture.skin.pixels);
  CHECK(b.parts.eye_texture.empty());
  CHECK(b.parts.teeth_texture.empty());
  CHECK(b.file_version == 1);  // what `likeness project info` prints
  HeadProject c;
  const Bytes now = saved(a);
  REQUIRE(load_project(now.data(), now.size(), c).ok());
  CHECK(c.file_version == kProjectFileVersion);
  // The reseal is a real checksum: the same file with the old one is refused.
  const Bytes stale = rewritten(saved(a), [](tinygltf::Value::Object& d) { d["version"] = tinygltf::Value(1); });
  CHECK(contains(try_load(stale).message, "checksum does not match"));
}

TEST_CASE("project file: the fit's thinning option comes back, and a file without it fits every point") {
  HeadProject a = textured_project();
  a.options.thin_cells_per_edge = 4;  // a refit of the opened project thins as the first fit did
  const Bytes bytes = saved(a);
  HeadProject b;
  REQUIRE(load_project(bytes.data(), bytes.size(), b).ok());
  CHECK(b.options.thin_cells_per_edge == 4);
  const Bytes older = resealed(rewritten(bytes, [](tinygltf::Value::Object& d) {
    tinygltf::Value::Object o = d["options"].Get<tinygltf::Value::Object>();
    o.erase("thin_cells_per_edge");
    d["options"] = tinygltf::Value(o);
  }));
  HeadProject c;
  REQUIRE(load_project(older.data(), older.size(), c).ok());
  CHECK(c.options.thin_cells_per_edge == 0);
  const Bytes bad = resealed(rewritten(bytes, [](tinygltf::Value::Object& d) {
    tinygltf::Value::Object o = d["options"].Get<tinygltf::Value::Object>();
    o["thin_cells_per_edge"] = tinygltf::Value(-1.0);
    d["options"] = tinygltf::Value(o);
  }));
  CHECK(contains(try_load(bad).message, "options"));
}

TEST_CASE("project file: every cut of a small project is refused, and says it is cut") {
  const Bytes& full = small_project();
  INFO("small project: " << full.size() << " bytes");
  REQUIRE(try_load(full).ok());
  REQUIRE(full.size() < 2000000);
  int wrong = 0;
  for (size_t n = 0; n < full.size(); ++n) {
    HeadProject p;
    const Status st = load_project(n ? full.data() : nullptr, n, p);
    const bool expected = n == 0 ? st.code == ErrorCode::Empty
                          : n < 4 ? contains(st.message, "not a Likeness project")
                                  : st.code == ErrorCode::Truncated && contains(st.message, "truncated Likeness project");
    if (!expected && ++wrong < 5) FAIL_CHECK("cut at " << n << ": " << st.message);
  }
  CHECK(wrong == 0);
}

TEST_CASE("project file: random byte flips are refused or change nothing, and never crash") {
  const Bytes& full = small_project();
  HeadProject original = loaded(full);
  std::mt19937 rng(36);
  std::uniform_int_distribution<size_t> where(0, full.size() - 1);
  std::uniform_int_distribution<int> mask(1, 255);
  int refused = 0, same = 0, unchecked_loaded = 0;
  Bytes b = full;
  for (int i = 0; i < 3000; ++i) {
    const size_t at = where(rng);
    b[at] = static_cast<std::uint8_t>(b[at] ^ mask(rng));
    HeadProject p;
    const Status st = load_project(b.data(), b.size(), p);
    if (!st.ok()) {
      CHECK(!st.message.empty());
      ++refused;
    } else {
      // Accepted only where the flip is outside the project (the scene's
      // JSON, say): the project is the original, byte for byte.
      CHECK(saved(p) == full);
      ++same;
    }
    // Without the checksum the checks behind it meet the damage: no crash.
    HeadProject q;
    if (load_project(b.data(), b.size(), q, false).ok()) ++unchecked_loaded;
    b[at] = full[at];
  }
  INFO("refused " << refused << ", unchanged " << same << ", loaded without the checksum " << unchecked_loaded);
  CHECK(refused > 2500);
  CHECK(refused + same == 3000);
  WARN("byte flips: refused " << refused << ", accepted unchanged " << same << ", loaded without the checksum "
                              << unchecked_loaded << " of 3000");
}

// ---------------------------------------------------------------- GLB export

TEST_CASE("GLB export: the head at its level with uvs and skin, the parts under their nodes") {
  HeadProject p = textured_project();
  REQUIRE(pose_project(p, 0.6).ok());  // exported at rest whatever the pose
  GenericHead generic;
  REQUIRE(load_generic_head(generic).ok());
  GlbExportOptions o;
  o.level = 2;
  o.eye_texture = Image::make(8, 8, 3, 200);
  o.teeth_texture = Image::make(8, 4, 4, 255);
  Bytes bytes;
  GlbExportReport r;
  const Status st = export_glb(p, generic, o, bytes, &r);
  INFO(st.message);
  REQUIRE(st.ok());
  CHECK(p.pose == 0);
  tinygltf::Model m = parsed_glb(bytes);
  auto node = [&](const std::string& name) -> const tinygltf::Node& {
    for (const tinygltf::Node& n : m.nodes)
      if (n.name == name) return n;
    FAIL("no node " << name);
    return m.nodes[0];
  };
  auto index = [&](const std::string& name) {
    for (size_t i = 0; i < m.nodes.size(); ++i)
      if (m.nodes[i].name == name) return static_cast<int>(i);
    return -1;
  };
  REQUIRE(m.scenes.size() == 1);
  REQUIRE(m.scenes[0].nodes.size() == 2);  // the skeleton, and the skinned head at the root
  CHECK(m.nodes[m.scenes[0].nodes[0]].name == "Neck");
  CHECK(m.nodes[m.scenes[0].nodes[1]].name == "HeadMesh");
  auto children = [&](const std::string& name) {
    std::vector<std::string> out;
    for (int c : node(name).children) out.push_back(m.nodes[c].name);
    std::sort(out.begin(), out.end());
    return out;
  };
  CHECK(children("Neck") == std::vector<std::string>{"Head"});
  CHECK(children("Head") == std::vector<std::string>{"Jaw", "LeftEye", "RightEye", "UpperTeeth"});
  CHECK(children("Jaw") == std::vector<std::string>{"LowerTeeth", "Tongue"});

  auto data = [&](int accessor) {
    const tinygltf::Accessor& acc = m.accessors.at(accessor);
    const tinygltf::BufferView& v = m.bufferViews.at(acc.bufferView);
    return reinterpret_cast<const float*>(m.buffers.at(v.buffer).data.data() + v.byteOffset + acc.byteOffset);
  };
  // The head: level 2 at rest, head frame, with the skin's uvs.
  REQUIRE(pose_project(p, 0.0).ok());
  TriMesh level2;
  REQUIRE(project_level_mesh(p, 2, ExportFrame::Head, level2).ok());
  const tinygltf::Primitive& head = m.meshes.at(node("HeadMesh").mesh).primitives.at(0);
  REQUIRE(m.accessors.at(head.attributes.at("POSITION")).count == level2.positions.size());
  CHECK(r.head_vertices == level2.num_vertices());
  const float* P = data(head.attributes.at("POSITION"));
  const float* UV = data(head.attributes.at("TEXCOORD_0"));
  for (size_t i = 0; i < level2.positions.size(); i += 53) {
    for (int k = 0; k < 3; ++k) CHECK(P[3 * i + k] == static_cast<float>(level2.positions[i][k]));
    CHECK(UV[2 * i + 1] == static_cast<float>(1.0 - p.texture.uvs[i].y()));
  }
  CHECK(m.materials.at(head.material).pbrMetallicRoughness.baseColorTexture.index >= 0);

  // The parts: each where place_head_parts puts it, in its node's frame.
  HeadParts parts;
  REQUIRE(place_head_parts(p.fit.control, generic, parts).ok());
  auto world_at = [&](const std::string& name) {  // a node's place: its translations summed up to the root
    Vec3 at = Vec3::Zero();
    for (int i = index(name); i >= 0;) {
      const tinygltf::Node& a = m.nodes[i];
      if (a.translation.size() == 3) at += Vec3(a.translation[0], a.translation[1], a.translation[2]);
      int parent = -1;
      for (size_t k = 0; k < m.nodes.size(); ++k)
        for (int c : m.nodes[k].children)
          if (c == i) parent = static_cast<int>(k);
      i = parent;
    }
    return at;
  };
  auto world_of = [&](const std::string& name, const TriMesh& expect) {
    const tinygltf::Node& n = node(name);
    const Vec3 offset = world_at(name);
    const tinygltf::Primitive& prim = m.meshes.at(n.mesh).primitives.at(0);
    REQUIRE(m.accessors.at(prim.attributes.at("POSITION")).count == expect.positions.size());
    const float* Q = data(prim.attributes.at("POSITION"));
    double worst = 0;
    for (size_t i = 0; i < expect.positions.size(); ++i)
      worst = std::max(worst, (Vec3(Q[3 * i], Q[3 * i + 1], Q[3 * i + 2]) + offset - expect.positions[i]).norm());
    CHECK(worst < 1e-6);
    return offset;
  };
  const Vec3 left = world_of("LeftEye", parts.placed.eye[0]);
  world_of("RightEye", parts.placed.eye[1]);
  CHECK((left - parts.placement.eye_center[0]).norm() < 1e-9);
  CHECK(left.x() > 0);  // the head's left is +x
  world_of("UpperTeeth", parts.upper_teeth);
  world_of("LowerTeeth", parts.lower_teeth);
  world_of("Tongue", parts.placed.tongue);
  CHECK((world_at("Jaw") - p.rig.jaw_pivot).norm() < 1e-9);
  // The teeth's voids are transparent: alpha-masked.
  CHECK(m.materials.at(m.meshes.at(node("UpperTeeth").mesh).primitives[0].material).alphaMode == "MASK");

  // Morph targets: the muscle layer's 77 shapes on the head, named in
  // extras.targetNames, each what bake_face_shapes makes on level 2 (sparse
  // accessors read back), with their meaning: jawOpen lowers the chin by
  // over a centimetre and leaves the brows; browInnerUp lifts the brows and
  // leaves the chin. The parts carry the shapes that move them.
  const tinygltf::Mesh& hm = m.meshes.at(node("HeadMesh").mesh);
  const std::vector<std::string>& names = face_shape_names();
  REQUIRE(hm.primitives[0].targets.size() == names.size());
  REQUIRE(hm.extras.Get("targetNames").ArrayLen() == names.size());
  CHECK(r.head_targets == static_cast<int>(names.size()));
  for (size_t t = 0; t < names.size(); ++t) CHECK(hm.extras.Get("targetNames").Get(int(t)).Get<std::string>() == names[t]);
  CHECK(hm.weights == std::vector<double>(names.size(), 0.0));
  // A target's offsets, dense or sparse (zeros where sparse leaves them).
  auto offsets = [&](int accessor) {
    const tinygltf::Accessor& acc = m.accessors.at(accessor);
    std::vector<Vec3> out(acc.count, Vec3::Zero());
    if (acc.bufferView >= 0) {
      const float* D = data(accessor);
      for (size_t i = 0; i < acc.count; ++i) out[i] = Vec3(D[3 * i], D[3 * i + 1], D[3 * i + 2]);
    }
    if (acc.sparse.isSparse) {
      const tinygltf::BufferView& iv = m.bufferViews.at(acc.sparse.indices.bufferView);
      const tinygltf::BufferView& vv = m.bufferViews.at(acc.sparse.values.bufferView);
      const unsigned char* I = m.buffers.at(iv.buffer).data.data() + iv.byteOffset;
      const float* V = reinterpret_cast<const float*>(m.buffers.at(vv.buffer).data.data() + vv.byteOffset);
      for (int k = 0; k < acc.sparse.count; ++k) {
        const size_t i = acc.sparse.indices.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT
                             ? reinterpret_cast<const std::uint16_t*>(I)[k]
                             : reinterpret_cast<const std::uint32_t*>(I)[k];
        out.at(i) = Vec3(V[3 * k], V[3 * k + 1], V[3 * k + 2]);
      }
    }
    return out;
  };
  FaceRig face;
  REQUIRE(make_face_rig(p.fit.control, generic, face).ok());
  MultiresMesh work = p.fit.multires;
  std::vector<BakedShape> baked;
  REQUIRE(bake_face_shapes(face, &work, 2, {}, baked).ok());
  int sparse = 0;
  std::map<std::string, std::vector<Vec3>> head_delta;
  for (size_t t = 0; t < names.size(); ++t) {
    INFO(names[t]);
    const int acc = hm.primitives[0].targets[t].at("POSITION");
    sparse += m.accessors.at(acc).sparse.isSparse;
    head_delta[names[t]] = offsets(acc);
    const std::vector<Vec3>& d = head_delta[names[t]];
    REQUIRE(d.size() == baked[t].level.size());
    double worst = 0;
    for (size_t i = 0; i < d.size(); ++i) worst = std::max(worst, (d[i] - baked[t].level[i]).cwiseAbs().maxCoeff());
    CHECK(worst < 1.1e-5);  // float32, and offsets under 10 micrometres dropped
  }
  CHECK(sparse > 40);  // most shapes move a part of the face only
  const std::vector<int>& chin = generic.annotations.regions.at("chin");
  const std::vector<int>& brow = generic.annotations.regions.at("brow");
  double chin_drop = 0, chin_brow = 0, brow_lift = 0, brow_jaw = 0;
  for (int v : chin) {
    chin_drop = std::max(chin_drop, -head_delta["jawOpen"][v].y());
    chin_brow = std::max(chin_brow, head_delta["browInnerUp"][v].norm());
  }
  for (int v : brow) {
    brow_lift = std::max(brow_lift, head_delta["browInnerUp"][v].y());
    brow_jaw = std::max(brow_jaw, head_delta["jawOpen"][v].norm());
  }
  INFO("chin drop " << chin_drop << " m, brow lift " << brow_lift << " m");
  CHECK(chin_drop > 0.01);
  CHECK(chin_brow < 1e-9);
  CHECK(brow_lift > 0.002);
  CHECK(brow_jaw < 1e-9);
  auto target_names = [&](const std::string& n) {
    std::vector<std::string> out;
    const tinygltf::Mesh& mesh = m.meshes.at(node(n).mesh);
    for (size_t t = 0; t < mesh.extras.Get("targetNames").ArrayLen(); ++t)
      out.push_back(mesh.extras.Get("targetNames").Get(int(t)).Get<std::string>());
    REQUIRE(out.size() == mesh.primitives[0].targets.size());
    return out;
  };
  auto has = [](const std::vector<std::string>& v, const std::string& n) { return std::find(v.begin(), v.end(), n) != v.end(); };
  const std::vector<std::string> left_eye = target_names("LeftEye"), lower = target_names("LowerTeeth"),
                                 tongue = target_names("Tongue");
  CHECK(has(left_eye, "eyeLookUpLeft"));
  CHECK_FALSE(has(left_eye, "eyeLookUpRight"));
  CHECK_FALSE(has(left_eye, "smile"));
  CHECK(has(lower, "jawOpen"));
  CHECK(has(lower, "viseme_aa"));
  CHECK_FALSE(has(lower, "browInnerUp"));
  CHECK(has(tongue, "tongueOut"));
  const tinygltf::Primitive& lower_prim = m.meshes.at(node("LowerTeeth").mesh).primitives[0];
  const auto jaw_at = std::find(lower.begin(), lower.end(), "jawOpen") - lower.begin();
  const std::vector<Vec3> LD = offsets(lower_prim.targets[static_cast<size_t>(jaw_at)].at("POSITION"));
  double teeth_drop = 0;
  for (const Vec3& d : LD) teeth_drop = std::max(teeth_drop, -d.y());
  CHECK(teeth_drop > 0.002);

  // The skin: the head mesh's vertices share Neck, Head and Jaw; the inverse
  // bind matrices undo each joint's place. Turning the Jaw joint by 15
  // degrees about x (linear blend skinning, as glTF defines it) drops the
  // chin and leaves the brows; turning the Head joint about y moves the
  // brows and leaves the neck's bottom ring.
  REQUIRE(m.skins.size() == 1);
  const tinygltf::Skin& skin = m.skins[0];
  CHECK(node("HeadMesh").skin == 0);
  std::vector<std::string> joint_names;
  for (int j : skin.joints) joint_names.push_back(m.nodes.at(j).name);
  CHECK(joint_names == std::vector<std::string>{"Neck", "Head", "LeftEye", "RightEye", "Jaw"});
  const float* IBM = data(skin.inverseBindMatrices);
  for (size_t j = 0; j < joint_names.size(); ++j) {
    const Vec3 at = world_at(joint_names[j]);
    for (int k = 0; k < 3; ++k) CHECK(IBM[16 * j + 12 + k] == Approx(-at[k]).margin(1e-6));
    CHECK(IBM[16 * j] == 1.0f);
  }
  const tinygltf::Accessor& JA = m.accessors.at(head.attributes.at("JOINTS_0"));
  REQUIRE(JA.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE);
  REQUIRE(JA.count == level2.positions.size());
  const tinygltf::BufferView& JV = m.bufferViews.at(JA.bufferView);
  const unsigned char* J = m.buffers.at(JV.buffer).data.data() + JV.byteOffset + JA.byteOffset;
  const float* W = data(head.attributes.at("WEIGHTS_0"));
  auto skinned = [&](size_t v, int turned_joint, const Eigen::Matrix3d& R) {
    Vec3 out = Vec3::Zero();
    for (int k = 0; k < 4; ++k) {
      const int j = J[4 * v + k];
      const Vec3 at = world_at(joint_names.at(j));
      const bool turned = j == turned_joint || (turned_joint == 1 && j == 4);  // the jaw turns with the head
      out += W[4 * v + k] * (turned ? Vec3(R * (level2.positions[v] - at) + at) : level2.positions[v]);
    }
    return out;
  };
  double worst_sum = 0;
  for (size_t v = 0; v < level2.positions.size(); ++v) {
    double sum = 0;
    for (int k = 0; k < 4; ++k) {
      CHECK(W[4 * v + k] >= 0.0f);
      sum += W[4 * v + k];
    }
    worst_sum = std::max(worst_sum, std::abs(sum - 1));
  }
  CHECK(worst_sum < 1e-6);
  const Eigen::Matrix3d open = Eigen::AngleAxisd(15 * M_PI / 180, Vec3::UnitX()).matrix();
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(20 * M_PI / 180, Vec3::UnitY()).matrix();
  double chin_opened = 0, brow_opened = 0, brow_turned = 0;
  for (int v : chin) chin_opened = std::max(chin_opened, level2.positions[v].y() - skinned(v, 4, open).y());
  for (int v : brow) {
    brow_opened = std::max(brow_opened, (skinned(v, 4, open) - level2.positions[v]).norm());
    brow_turned = std::max(brow_turned, (skinned(v, 1, turn) - level2.positions[v]).norm());
  }
  MeshTopology topo;
  REQUIRE(build_topology(p.fit.control, topo).ok());
  double bottom_turned = 0;
  for (const auto& loop : topo.boundary_loops)
    for (int v : loop) bottom_turned = std::max(bottom_turned, (skinned(v, 1, turn) - level2.positions[v]).norm());
  INFO("Jaw 15 deg: chin " << chin_opened << " m down, brows " << brow_opened << " m; Head 20 deg: brows "
                           << brow_turned << " m, the neck's bottom " << bottom_turned << " m");
  CHECK(chin_opened > 0.005);
  CHECK(brow_opened < 1e-9);
  CHECK(brow_turned > 0.01);
  CHECK(bottom_turned < 1e-9);
}

namespace {

// An accessor's floats (dense), or its values with the sparse ones put in.
std::vector<float> floats_of(const tinygltf::Model& m, int accessor, int per_element) {
  const tinygltf::Accessor& acc = m.accessors.at(accessor);
  REQUIRE(acc.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT);
  std::vector<float> out(acc.count * static_cast<size_t>(per_element), 0.0f);
  if (acc.bufferView >= 0) {
    const tinygltf::BufferView& v = m.bufferViews.at(acc.bufferView);
    std::memcpy(out.data(), m.buffers.at(v.buffer).data.data() + v.byteOffset + acc.byteOffset, out.size() * 4);
  }
  if (acc.sparse.isSparse) {
    const tinygltf::BufferView& iv = m.bufferViews.at(acc.sparse.indices.bufferView);
    const tinygltf::BufferView& vv = m.bufferViews.at(acc.sparse.values.bufferView);
    const unsigned char* I = m.buffers.at(iv.buffer).data.data() + iv.byteOffset;
    const float* V = reinterpret_cast<const float*>(m.buffers.at(vv.buffer).data.data() + vv.byteOffset);
    for (int k = 0; k < acc.sparse.count; ++k) {
      const size_t i = acc.sparse.indices.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT
                           ? reinterpret_cast<const std::uint16_t*>(I)[k]
                           : reinterpret_cast<const std::uint32_t*>(I)[k];
      for (int j = 0; j < per_element; ++j) out.at(per_element * i + j) = V[per_element * k + j];
    }
  }
  return out;
}

std::vector<std::string> target_names_of(const tinygltf::Mesh& mesh) {
  std::vector<std::string> out;
  for (size_t t = 0; t < mesh.extras.Get("targetNames").ArrayLen(); ++t)
    out.push_back(mesh.extras.Get("targetNames").Get(int(t)).Get<std::string>());
  return out;
}

// glTF's CUBICSPLINE at time t over keys (times) and output (per key: m in
// tangents, m values, m out tangents): the m weights.
std::vector<double> cubic_spline_at(const std::vector<float>& times, const std::vector<float>& out, size_t m, double t) {
  std::vector<double> w(m);
  size_t k = 0;
  while (k + 2 < times.size() && times[k + 1] <= t) ++k;
  const double h = times[k + 1] - times[k], u = std::clamp((t - times[k]) / h, 0.0, 1.0);
  for (size_t j = 0; j < m; ++j) {
    const double v0 = out[(3 * k + 1) * m + j], b0 = out[(3 * k + 2) * m + j];
    const double v1 = out[(3 * (k + 1) + 1) * m + j], a1 = out[(3 * (k + 1)) * m + j];
    w[j] = (2 * u * u * u - 3 * u * u + 1) * v0 + (u * u * u - 2 * u * u + u) * h * b0 + (-2 * u * u * u + 3 * u * u) * v1 +
           (u * u * u - u * u) * h * a1;
  }
  return w;
}

// The largest difference, every 5 ms over the clip, between the weights
// glTF's interpolation gives a weights channel's targets (names) and the
// clip's for the shapes it drives (0 for the others); largest: the
// largest weight the channel reaches.
double worst_weight_error(const tinygltf::Model& m, const tinygltf::AnimationSampler& s, const std::vector<std::string>& names,
                          const WeightClip& clip, double* largest = nullptr) {
  const std::vector<float> times = floats_of(m, s.input, 1), out = floats_of(m, s.output, 1);
  REQUIRE(times.size() == clip.times.size());
  REQUIRE(out.size() == 3 * times.size() * names.size());
  double worst = 0, high = 0;
  for (int ms = 0; ms <= static_cast<int>(1000 * clip.duration()); ms += 5) {
    const std::vector<double> got = cubic_spline_at(times, out, names.size(), ms / 1000.0);
    const std::vector<double> want = clip_weights(clip, ms / 1000.0);
    for (size_t t = 0; t < names.size(); ++t) {
      const auto at = std::find(clip.shapes.begin(), clip.shapes.end(), names[t]);
      const double w = at == clip.shapes.end() ? 0.0 : want[static_cast<size_t>(at - clip.shapes.begin())];
      worst = std::max(worst, std::abs(got[t] - w));
      high = std::max(high, got[t]);
    }
  }
  if (largest) *largest = high;
  return worst;
}

}  // namespace

TEST_CASE("GLB export: Talk, Blink and Gaze as glTF animations of the morph weights, playing the clips' weights") {
  HeadProject p = textured_project();
  GenericHead generic;
  REQUIRE(load_generic_head(generic).ok());
  GlbExportOptions o;
  o.level = 1;
  Bytes bytes;
  GlbExportReport r;
  REQUIRE(export_glb(p, generic, o, bytes, &r).ok());
  CHECK(r.animations == std::vector<std::string>{"Talk", "Blink", "Gaze"});
  const tinygltf::Model m = parsed_glb(bytes);
  REQUIRE(m.animations.size() == 3);
  const std::vector<WeightClip> clips = weight_clips();
  std::map<std::string, int> channels_on;  // node name -> weights channels (over the clips)
  std::map<std::string, int> turns_on;     // "node in clip" -> rotation channels
  for (size_t a = 0; a < 3; ++a) {
    const tinygltf::Animation& anim = m.animations[a];
    const WeightClip& clip = clips[a];
    INFO(anim.name);
    CHECK(anim.name == clip.name);
    for (const tinygltf::AnimationChannel& ch : anim.channels) {
      const tinygltf::Node& node = m.nodes.at(ch.target_node);
      INFO(node.name);
      if (ch.target_path == "rotation") {
        turns_on[node.name + " in " + anim.name]++;
        continue;  // checked below, against pose_eye
      }
      channels_on[node.name]++;
      CHECK(ch.target_path == "weights");
      const tinygltf::AnimationSampler& s = anim.samplers.at(ch.sampler);
      CHECK(s.interpolation == "CUBICSPLINE");
      // At every 5 ms, each target's weight by glTF's interpolation is the
      // clip's for the shapes it drives and 0 for the others.
      double largest = 0;
      const double worst = worst_weight_error(m, s, target_names_of(m.meshes.at(node.mesh)), clip, &largest);
      INFO("largest weight " << largest);
      CHECK(worst < 1e-5);  // float32 keys
      CHECK(largest > 0.99);
    }
  }
  // Talk drives the head and, through the visemes that open the jaw, the
  // lower teeth and tongue; Blink only the head (the lids are skin); Gaze
  // the head where the eyeLook shapes move its lids, and turns the eyes'
  // joints (not their eyeLook targets as well: they would turn twice).
  CHECK(channels_on["HeadMesh"] == 3);
  CHECK(channels_on["LowerTeeth"] == 1);
  CHECK(channels_on["Tongue"] == 1);
  CHECK(channels_on.count("LeftEye") == 0);
  CHECK(channels_on.count("RightEye") == 0);
  CHECK(turns_on == std::map<std::string, int>{{"LeftEye in Gaze", 1}, {"RightEye in Gaze", 1}});

  // Gaze's joints turn each eyeball where pose_eye turns it: its vertices
  // (in the node's frame, the node at the eye's centre) turned by the
  // slerped key quaternion, every 5 ms, against the clip's weights posed
  // by the muscle layer; and they look to the head's left at 0.6 s.
  HeadParts parts;
  REQUIRE(place_head_parts(p.fit.control, generic, parts).ok());
  FaceRig face;
  REQUIRE(make_face_rig(p.fit.control, generic, face).ok());
  const WeightClip& gaze = gaze_clip();
  const tinygltf::Animation& anim = m.animations[2];
  for (const tinygltf::AnimationChannel& ch : anim.channels) {
    if (ch.target_path != "rotation") continue;
    const tinygltf::Node& node = m.nodes.at(ch.target_node);
    const int e = node.name == "LeftEye" ? 0 : 1;
    INFO(node.name);
    const tinygltf::AnimationSampler& s = anim.samplers.at(ch.sampler);
    CHECK(s.interpolation == "LINEAR");
    const std::vector<float> times = floats_of(m, s.input, 1), q = floats_of(m, s.output, 4);
    REQUIRE(q.size() == 4 * times.size());
    CHECK(times.front() == 0.0f);
    CHECK(std::abs(times.back() - gaze.duration()) < 1e-6);
    const std::vector<Vec3>& rest = parts.placed.eye[static_cast<size_t>(e)].positions;
    const Vec3 centre = parts.placement.eye_center[e];
    double worst = 0, widest = 0;
    for (int ms = 0; ms <= static_cast<int>(1000 * gaze.duration()); ms += 5) {
      const double t = ms / 1000.0;
      size_t k = static_cast<size_t>(std::upper_bound(times.begin(), times.end(), float(t)) - times.begin());
      k = std::clamp<size_t>(k, 1, times.size() - 1) - 1;
      const double u = std::clamp((t - times[k]) / (times[k + 1] - times[k]), 0.0, 1.0);
      const Eigen::Quaterniond a(q[4 * k + 3], q[4 * k], q[4 * k + 1], q[4 * k + 2]);
      const Eigen::Quaterniond b(q[4 * k + 7], q[4 * k + 4], q[4 * k + 5], q[4 * k + 6]);
      const Mat3 R = a.slerp(u, b).normalized().toRotationMatrix();
      const std::vector<double> w = clip_weights(gaze, t);
      std::map<std::string, double> named;
      for (size_t i = 0; i < gaze.shapes.size(); ++i) named[gaze.shapes[i]] += w[i];
      FaceControls c;
      REQUIRE(face_controls_from_weights(named, c).ok());
      const std::vector<Vec3> want = pose_eye(face, rest, c, e);
      for (size_t i = 0; i < rest.size(); ++i) {
        worst = std::max(worst, (centre + R * (rest[i] - centre) - want[i]).norm());
        widest = std::max(widest, (want[i] - rest[i]).norm());
      }
      if (ms == 600) CHECK((R * Vec3(0, 0, 1)).x() > std::sin(0.9 * kGazeAngle));  // towards +x, the head's left
    }
    INFO("worst " << worst * 1000 << " mm; the eye moves up to " << widest * 1000 << " mm");
    CHECK(worst < 2.5e-5);
    CHECK(widest > 0.004);
  }

  o.animations = false;
  Bytes plain;
  REQUIRE(export_glb(p, generic, o, plain, &r).ok());
  CHECK(parsed_glb(plain).animations.empty());
  CHECK(r.animations.empty());
  CHECK(plain.size() < bytes.size());
  INFO("animations cost " << (bytes.size() - plain.size()) << " bytes");
  CHECK(bytes.size() - plain.size() < 64 * 1024);
}

TEST_CASE("GLB export: words to say as a Say animation, playing speech_clip's weights, and nothing to say refused") {
  HeadProject p = textured_project();
  GenericHead generic;
  REQUIRE(load_generic_head(generic).ok());
  GlbExportOptions o;
  o.level = 0;
  o.animations = false;
  // "papa" as the page's lip-sync reader writes it (web/js/speech.js).
  o.say.visemes = {"PP", "aa", "PP", "aa"};
  o.say.times = {0, 1.08, 2.03, 3.11};
  o.say.durations = {1.08, 0.95, 1.08, 0.95};
  Bytes bytes;
  GlbExportReport r;
  REQUIRE(export_glb(p, generic, o, bytes, &r).ok());
  CHECK(r.animations == std::vector<std::string>{"Say"});
  const tinygltf::Model m = parsed_glb(bytes);
  REQUIRE(m.animations.size() == 1);
  WeightClip clip;
  REQUIRE(speech_clip(o.say, clip).ok());
  std::set<std::string> on;
  for (const tinygltf::AnimationChannel& ch : m.animations[0].channels) {
    const tinygltf::Node& node = m.nodes.at(ch.target_node);
    INFO(node.name);
    on.insert(node.name);
    REQUIRE(ch.target_path == "weights");  // no gaze: no joint turns
    CHECK(worst_weight_error(m, m.animations[0].samplers.at(ch.sampler), target_names_of(m.meshes.at(node.mesh)), clip) < 1e-5);
  }
  // The head says it; viseme_aa opens the jaw, so the lower teeth and tongue go along.
  CHECK(on == std::set<std::string>{"HeadMesh", "LowerTeeth", "Tongue"});

  o.say.visemes = {"sil"};  // a pause alone
  o.say.times = {0};
  o.say.durations = {2.5};
  const Status refused = export_glb(p, generic, o, bytes, &r);
  CHECK_FALSE(refused.ok());
  CHECK(refused.message.find("nothing to say") != std::string::npos);
}

TEST_CASE("GLB export: tongueOut pushes the tongue's tip out of the mouth, the other shapes only carry it on the jaw") {
  HeadProject p = textured_project();
  GenericHead generic;
  REQUIRE(load_generic_head(generic).ok());
  GlbExportOptions o;
  o.level = 0;
  o.animations = false;
  Bytes bytes;
  REQUIRE(export_glb(p, generic, o, bytes).ok());
  const tinygltf::Model m = parsed_glb(bytes);
  const tinygltf::Mesh* tongue = nullptr;
  for (const tinygltf::Node& n : m.nodes)
    if (n.name == "Tongue") tongue = &m.meshes.at(n.mesh);
  REQUIRE(tongue);
  const std::vector<std::string> names = target_names_of(*tongue);
  const tinygltf::Primitive& prim = tongue->primitives[0];
  const std::vector<float> rest = floats_of(m, prim.attributes.at("POSITION"), 3);
  const size_t n = rest.size() / 3;
  size_t tip = 0;
  for (size_t i = 1; i < n; ++i)
    if (rest[3 * i + 2] > rest[3 * tip + 2]) tip = i;
  FaceRig face;
  REQUIRE(make_face_rig(p.fit.control, generic, face).ok());
  const double lip_z = face.rest[static_cast<size_t>(face.landmarks.lower_lip_mid)].z();
  HeadParts parts;
  REQUIRE(place_head_parts(p.fit.control, generic, parts).ok());
  const Vec3 hinge = p.rig.jaw_pivot;  // the Jaw node's place: the tongue's mesh is about it
  size_t root = 0;
  for (size_t i = 1; i < n; ++i)
    if (rest[3 * i + 2] < rest[3 * root + 2]) root = i;
  bool saw_out = false;
  for (size_t t = 0; t < names.size(); ++t) {
    INFO(names[t]);
    const std::vector<float> d = floats_of(m, prim.targets[t].at("POSITION"), 3);
    FaceControls c;
    REQUIRE(face_shape(names[t], c).ok());
    // Where the jaw alone would carry each vertex.
    Mat3 R;
    Vec3 tr;
    jaw_motion(face, c, R, tr);
    auto on_jaw = [&](size_t i) {
      const Vec3 q = hinge + Vec3(rest[3 * i], rest[3 * i + 1], rest[3 * i + 2]);
      return Vec3(R * (q - face.jaw.hinge) + face.jaw.hinge + tr - q);
    };
    const Vec3 moved_root(d[3 * root], d[3 * root + 1], d[3 * root + 2]);
    CHECK((moved_root - on_jaw(root)).cwiseAbs().maxCoeff() < 1.1e-5);  // the root stays on the jaw
    CHECK(std::abs(c[kJawOpen]) + std::abs(c[kJawSide]) + std::abs(c[kJawForward]) + c[kTongueOut] > 0);
    if (c[kTongueOut] > 0) {
      // The tip forward (+z) beyond where the jaw carries it, in proportion
      // to the shape's tongue-out; tongueOut's past the lower lip's front.
      const double forward = d[3 * tip + 2] - on_jaw(tip).z();
      const double tip_z = hinge.z() + rest[3 * tip + 2] + d[3 * tip + 2];
      INFO("tip forward " << 1000 * forward << " mm beyond the jaw's motion, " << 1000 * (tip_z - lip_z)
                          << " mm past the lower lip");
      CHECK(forward > 0.9 * c[kTongueOut] * 0.02 * face.scale);
      if (names[t] == "tongueOut") {
        saw_out = true;
        CHECK(tip_z > lip_z + 0.008 * face.scale);
        WARN("tongueOut: the tongue's tip " << 1000 * d[3 * tip + 2] << " mm forward (" << 1000 * forward
                                            << " beyond the jaw's motion), " << 1000 * (tip_z - lip_z)
                                            << " mm past the lower lip's rest front");
      }
      continue;
    }
    // Any other shape: the tongue rides the jaw rigidly, nothing else.
    double worst = 0;
    for (size_t i = 0; i < n; ++i)
      worst = std::max(worst, (on_jaw(i) - Vec3(d[3 * i], d[3 * i + 1], d[3 * i + 2])).cwiseAbs().maxCoeff());
    CHECK(worst < 1.1e-5);
  }
  CHECK(saw_out);
}
