#include "project/project_file.h"

#include "multires/multires.h"
#include "photos/landmarks.h"
#include "project/gltf_scene.h"

#include <nlohmann/json.hpp>
#include <tiny_gltf.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <sstream>

namespace lk {

const char* const kProjectFormat = "likeness-project";

namespace {

using json = nlohmann::json;

// Largest project the reader accepts: the finest level's triangles (the
// worker allows 4 levels of the generic head, ~1.3 M triangles; the CLI
// more) and the skin's pixels (texture sizes go up to 4096^2).
constexpr std::uint64_t kMaxFinestTriangles = 1u << 23;
constexpr int kMaxLevels = 6;
constexpr std::size_t kMaxSkinPixels = 4096u * 4096u;
// The kept photos (version 3): a photo is at most the page's cap on any
// file (256 MB, files.js), and a project holds at most 256 of them; the
// page's options (with clicks and points files) stay far below 1 MB.
constexpr std::size_t kMaxPhotos = 256;
constexpr std::size_t kMaxPhotoBytes = std::size_t(256) << 20;
constexpr std::size_t kMaxPageOptionsBytes = std::size_t(1) << 20;

// FNV-1a, 64 bits: a damaged file's fingerprint, not a security measure.
struct Fnv1a {
  std::uint64_t h = 14695981039346656037ull;
  void add(const void* data, std::size_t n) {
    const auto* p = static_cast<const std::uint8_t*>(data);
    for (std::size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 1099511628211ull;
  }
  void add_u64(std::uint64_t v) { add(&v, sizeof v); }
  std::string hex() const {
    static const char* digits = "0123456789abcdef";
    std::string s(16, '0');
    for (int i = 0; i < 16; ++i) s[15 - i] = digits[(h >> (4 * i)) & 15];
    return s;
  }
};

// The checksum covers the project's extras (without the checksum itself),
// every bufferView's place and the binary buffer.
std::string project_checksum(const json& extras_without_checksum, const tinygltf::Model& model) {
  Fnv1a f;
  const std::string text = extras_without_checksum.dump();
  f.add(text.data(), text.size());
  f.add_u64(model.bufferViews.size());
  for (const tinygltf::BufferView& v : model.bufferViews) {
    f.add_u64(static_cast<std::uint64_t>(v.buffer));
    f.add_u64(v.byteOffset);
    f.add_u64(v.byteLength);
  }
  f.add_u64(model.buffers.size());
  for (const tinygltf::Buffer& b : model.buffers) {
    f.add_u64(b.data.size());
    f.add(b.data.data(), b.data.size());
  }
  return f.hex();
}

tinygltf::Value to_value(const json& j) {
  switch (j.type()) {
    case json::value_t::object: {
      tinygltf::Value::Object o;
      for (auto it = j.begin(); it != j.end(); ++it) o[it.key()] = to_value(it.value());
      return tinygltf::Value(std::move(o));
    }
    case json::value_t::array: {
      tinygltf::Value::Array a;
      for (const json& e : j) a.push_back(to_value(e));
      return tinygltf::Value(std::move(a));
    }
    case json::value_t::string: return tinygltf::Value(j.get<std::string>());
    case json::value_t::boolean: return tinygltf::Value(j.get<bool>());
    case json::value_t::number_integer:
    case json::value_t::number_unsigned: return tinygltf::Value(j.get<int>());
    case json::value_t::number_float: return tinygltf::Value(j.get<double>());
    default: return tinygltf::Value();
  }
}

// tinygltf 2.7 writes an empty array or object in extras as null: such
// members are left out (the reader takes a missing list as empty), so the
// extras read back are the ones written and hashed.
void drop_empty(json& j) {
  if (j.is_object()) {
    for (auto it = j.begin(); it != j.end();) {
      drop_empty(*it);
      if ((it->is_array() || it->is_object()) && it->empty()) it = j.erase(it);
      else ++it;
    }
  } else if (j.is_array()) {
    for (json& e : j) drop_empty(e);
  }
}

// ---------------------------------------------------------------- writing

// The extras' arrays go into the scene's binary buffer as bufferViews
// (8-byte aligned: the doubles are read in place by anyone who maps it).
struct BinWriter : GltfBuilder {
  using GltfBuilder::GltfBuilder;

  // {"view", "type", "count", "width"}: count tuples of width values; an
  // empty array has no view (glTF views are at least one byte).
  template <class T>
  json array(const std::vector<T>& flat, const char* type, int width) {
    json ref = {{"type", type}, {"width", width}, {"count", static_cast<int>(flat.size() / width)}};
    if (!flat.empty()) ref["view"] = view(flat.data(), flat.size() * sizeof(T));
    return ref;
  }
  json vec3s(const std::vector<Vec3>& v) {
    std::vector<double> flat(3 * v.size());
    for (std::size_t i = 0; i < v.size(); ++i)
      for (int k = 0; k < 3; ++k) flat[3 * i + k] = v[i][k];
    return array(flat, "f64", 3);
  }
  json vec2s(const std::vector<Vec2>& v) {
    std::vector<double> flat(2 * v.size());
    for (std::size_t i = 0; i < v.size(); ++i)
      for (int k = 0; k < 2; ++k) flat[2 * i + k] = v[i][k];
    return array(flat, "f64", 2);
  }
  json tris(const std::vector<Tri>& t) {
    std::vector<std::int32_t> flat(3 * t.size());
    for (std::size_t i = 0; i < t.size(); ++i)
      for (int k = 0; k < 3; ++k) flat[3 * i + k] = t[i][k];
    return array(flat, "i32", 3);
  }
  json ints(const std::vector<int>& v) {
    return array(std::vector<std::int32_t>(v.begin(), v.end()), "i32", 1);
  }
  json doubles(const std::vector<double>& v) { return array(v, "f64", 1); }
};

json mat3_json(const Mat3& m) {
  json a = json::array();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) a.push_back(m(r, c));
  return a;
}
json vec3_json(const Vec3& v) { return json::array({v.x(), v.y(), v.z()}); }
json affine_json(const AffineMap& m) { return {{"A", mat3_json(m.A)}, {"t", vec3_json(m.t)}}; }

json stats_json(const DistanceStats& d) {
  return {{"count", d.count}, {"mean", d.mean}, {"max", d.max}, {"rms", d.rms},
          {"p95", d.p95}, {"mean_pct", d.mean_pct}, {"max_pct", d.max_pct}};
}

// The options the CLI and the page set; the others are this version's
// defaults when the project is fitted again.
json options_json(const FitHeadOptions& o) {
  return {{"levels", o.levels},
          {"up", vec3_json(o.up)},
          {"facing", vec3_json(o.facing)},
          {"scan_kind", static_cast<int>(o.scan_kind)},
          {"orientation_check", static_cast<int>(o.orientation_check)},
          {"fit_eye_region", o.fit_eye_region},
          {"smooth_finest_levels", o.displacement.smooth_finest_levels},
          {"max_footprint_points", o.displacement.max_footprint_points},
          {"data_level", o.global.data_level},
          {"whole_head_data_level", o.whole_head_data_level},
          {"thin_cells_per_edge", o.thin_cells_per_edge}};
}

// The scene: the finest level at rest, head frame, float32, with normals
// and, when textured, uvs and the skin (the PNG in bufferView skin_view).
void add_scene(const HeadProject& p, const std::vector<Vec3>& rest, const std::vector<Vec3>& normals,
               int skin_view, BinWriter& w) {
  const MultiresMesh& mr = p.fit.multires;
  const bool textured = skin_view >= 0 && p.texture.uvs.size() >= rest.size();
  std::vector<Vec2> uvs;
  if (textured) uvs.assign(p.texture.uvs.begin(), p.texture.uvs.begin() + static_cast<std::ptrdiff_t>(rest.size()));
  const int material = w.material("skin", textured ? w.png_texture(skin_view, "skin") : -1, {0.8, 0.62, 0.52, 1.0});
  const int mesh = w.mesh("head", rest, normals, uvs, mr.triangles(mr.num_levels()), material);
  tinygltf::Scene scene;
  scene.name = "head";
  scene.nodes.push_back(w.node("head", mesh));
  w.model.scenes.push_back(scene);
  w.model.defaultScene = 0;
}

// ---------------------------------------------------------------- reading

Status damaged(const std::string& what) {
  return Status::error(ErrorCode::InvalidInput, "damaged Likeness project: " + what);
}
Status foreign(const std::string& what) {
  return Status::error(ErrorCode::InvalidInput, "not a Likeness project: " + what);
}

// Every stored number lies within this magnitude (metres, scan units, pixels
// are far below it), so nothing evaluated from a file overflows to infinity.
constexpr double kMaxMagnitude = 1e9;
bool sane(double x) { return std::isfinite(x) && std::abs(x) <= kMaxMagnitude; }

bool get_number(const json& o, const char* key, double& v) {
  const auto it = o.find(key);
  if (it == o.end() || !it->is_number()) return false;
  v = it->get<double>();
  return sane(v);
}
bool get_int(const json& o, const char* key, int& v, int lo = std::numeric_limits<int>::min(),
             int hi = std::numeric_limits<int>::max()) {
  const auto it = o.find(key);
  if (it == o.end() || !it->is_number_integer()) return false;
  const std::int64_t x = it->get<std::int64_t>();
  if (x < lo || x > hi) return false;
  v = static_cast<int>(x);
  return true;
}
bool get_bool(const json& o, const char* key, bool& v) {
  const auto it = o.find(key);
  if (it == o.end() || !it->is_boolean()) return false;
  v = it->get<bool>();
  return true;
}
bool get_vec3(const json& o, const char* key, Vec3& v) {
  const auto it = o.find(key);
  if (it == o.end() || !it->is_array() || it->size() != 3) return false;
  for (int k = 0; k < 3; ++k) {
    if (!(*it)[k].is_number()) return false;
    v[k] = (*it)[k].get<double>();
    if (!sane(v[k])) return false;
  }
  return true;
}
bool get_affine(const json& o, const char* key, AffineMap& m) {
  const auto it = o.find(key);
  if (it == o.end() || !it->is_object()) return false;
  const auto a = it->find("A");
  if (a == it->end() || !a->is_array() || a->size() != 9) return false;
  for (int i = 0; i < 9; ++i) {
    if (!(*a)[i].is_number()) return false;
    m.A(i / 3, i % 3) = (*a)[i].get<double>();
    if (!sane(m.A(i / 3, i % 3))) return false;
  }
  return get_vec3(*it, "t", m.t);
}
const json& member(const json& o, const char* key) {
  static const json null_json;
  const auto it = o.find(key);
  return it == o.end() ? null_json : *it;
}

// Reads arrays out of the buffer after checking the reference, the view
// and the buffer's bounds; nothing is allocated before the checks.
struct BinReader {
  const tinygltf::Model& model;

  template <class T>
  Status array(const json& ref, const std::string& what, const char* type, int width, std::vector<T>& out) {
    int count = 0, w = 0;
    const auto t = ref.find("type");
    if (!ref.is_object() || t == ref.end() || !t->is_string() || t->get<std::string>() != type ||
        !get_int(ref, "width", w) || w != width || !get_int(ref, "count", count, 0))
      return damaged(what + ": not a " + type + " array of width " + std::to_string(width));
    out.clear();
    if (count == 0) return Status::success();
    int v = 0;
    if (!get_int(ref, "view", v, 0, static_cast<int>(model.bufferViews.size()) - 1))
      return damaged(what + ": no such bufferView");
    const tinygltf::BufferView& view = model.bufferViews[static_cast<std::size_t>(v)];
    if (view.buffer < 0 || static_cast<std::size_t>(view.buffer) >= model.buffers.size())
      return damaged(what + ": its bufferView names no buffer");
    const std::vector<unsigned char>& buf = model.buffers[static_cast<std::size_t>(view.buffer)].data;
    const std::uint64_t bytes = std::uint64_t(count) * std::uint64_t(width) * sizeof(T);
    if (view.byteLength != bytes)
      return damaged(what + ": " + std::to_string(count) + " values of " + std::to_string(sizeof(T)) +
                     " bytes in a bufferView of " + std::to_string(view.byteLength));
    if (view.byteOffset > buf.size() || buf.size() - view.byteOffset < bytes)
      return damaged(what + ": its bufferView runs past the end of the buffer");
    out.resize(static_cast<std::size_t>(bytes / sizeof(T)));
    std::memcpy(out.data(), buf.data() + view.byteOffset, static_cast<std::size_t>(bytes));
    return Status::success();
  }

  Status doubles(const json& ref, const std::string& what, int width, std::vector<double>& out) {
    if (Status st = array(ref, what, "f64", width, out); !st.ok()) return st;
    for (double x : out)
      if (!sane(x)) return damaged(what + ": a number that is not finite or out of range");
    return Status::success();
  }
  Status vec3s(const json& ref, const std::string& what, std::vector<Vec3>& out) {
    std::vector<double> flat;
    if (Status st = doubles(ref, what, 3, flat); !st.ok()) return st;
    out.resize(flat.size() / 3);
    for (std::size_t i = 0; i < out.size(); ++i) out[i] = Vec3(flat[3 * i], flat[3 * i + 1], flat[3 * i + 2]);
    return Status::success();
  }
  Status vec2s(const json& ref, const std::string& what, std::vector<Vec2>& out) {
    std::vector<double> flat;
    if (Status st = doubles(ref, what, 2, flat); !st.ok()) return st;
    out.resize(flat.size() / 2);
    for (std::size_t i = 0; i < out.size(); ++i) out[i] = Vec2(flat[2 * i], flat[2 * i + 1]);
    return Status::success();
  }
  // Indices in [0, bound).
  Status ints(const json& ref, const std::string& what, int width, std::size_t bound, std::vector<std::int32_t>& out) {
    if (Status st = array(ref, what, "i32", width, out); !st.ok()) return st;
    for (std::int32_t i : out)
      if (i < 0 || static_cast<std::size_t>(i) >= bound)
        return damaged(what + ": index " + std::to_string(i) + " out of range (" + std::to_string(bound) + ")");
    return Status::success();
  }
  Status tris(const json& ref, const std::string& what, std::size_t vertices, std::vector<Tri>& out) {
    std::vector<std::int32_t> flat;
    if (Status st = ints(ref, what, 3, vertices, flat); !st.ok()) return st;
    out.resize(flat.size() / 3);
    for (std::size_t i = 0; i < out.size(); ++i) out[i] = {flat[3 * i], flat[3 * i + 1], flat[3 * i + 2]};
    return Status::success();
  }
  Status mesh(const json& ref, const std::string& what, TriMesh& out) {
    out = TriMesh{};
    if (Status st = vec3s(member(ref, "positions"), what + " positions", out.positions); !st.ok()) return st;
    return tris(member(ref, "triangles"), what + " triangles", out.positions.size(), out.triangles);
  }
};

// The GLB header, checked before tinygltf sees the bytes, so a cut file
// says so rather than "invalid glTF".
Status check_glb_header(const std::uint8_t* data, std::size_t size) {
  if (size < 4 || std::memcmp(data, "glTF", 4) != 0) return foreign("the file is not a glTF binary (.glb)");
  if (size < 20) return Status::error(ErrorCode::Truncated, "truncated Likeness project: " + std::to_string(size) + " bytes");
  std::uint32_t version = 0, length = 0;
  std::memcpy(&version, data + 4, 4);
  std::memcpy(&length, data + 8, 4);
  if (version != 2) return foreign("glTF binary version " + std::to_string(version) + " (a project is glTF 2)");
  if (length > size)
    return Status::error(ErrorCode::Truncated, "truncated Likeness project: the file says " + std::to_string(length) +
                                                   " bytes, " + std::to_string(size) + " are there");
  // tinygltf 2.7 copies each buffer from the binary chunk with
  // data.at(0), which throws on an empty buffer; a project's buffers are
  // never empty nor external, so such a file is refused here.
  std::uint32_t json_length = 0;
  std::memcpy(&json_length, data + 12, 4);
  if (std::uint64_t(json_length) + 20 > length) return Status::error(ErrorCode::Truncated, "truncated Likeness project: its JSON chunk is cut");
  // tinygltf converts extras recursively: deep nesting would overflow the
  // stack, so it is refused here (a project nests 5 deep).
  bool too_deep = false;
  const json::parser_callback_t depth = [&too_deep](int d, json::parse_event_t, json&) {
    if (d > 32) too_deep = true;
    return true;
  };
  const json doc = json::parse(data + 20, data + 20 + json_length, depth, /*allow_exceptions=*/false);
  if (!doc.is_object()) return foreign("its JSON chunk does not parse");
  if (too_deep) return foreign("its JSON nests deeper than a project's");
  const json& buffers = member(doc, "buffers");
  if (!buffers.is_null()) {
    if (!buffers.is_array()) return foreign("its buffers are not a list");
    for (const json& b : buffers) {
      int length_field = 0;
      if (!get_int(b, "byteLength", length_field, 1) || b.find("uri") != b.end())
        return foreign("a buffer that is empty or refers to another file");
    }
  }
  return Status::success();
}

bool ignore_image(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int,
                  void*) {
  return true;  // the skin is read from its bufferView by load_project
}

// A name that is safe as a file name in another folder (project --extract-photos).
bool plain_file_name(const std::string& n) {
  if (n.empty() || n.size() > 255 || n == "." || n == "..") return false;
  for (char c : n)
    if (c == '/' || c == '\\' || static_cast<unsigned char>(c) < 0x20) return false;
  return true;
}

// A photo's face points: a likeness-landmarks document that parses (the
// CLI's own reader), whose "corrected" indices, if any, name its points.
Status check_photo_points(const std::string& text, const std::string& what) {
  LandmarkPhoto lm;
  if (Status s = parse_landmarks_json(text, lm); !s.ok()) return with_context(s, "damaged Likeness project: " + what);
  const json doc = json::parse(text, nullptr, /*allow_exceptions=*/false);
  const json& corrected = member(doc, "corrected");
  if (corrected.is_null()) return Status::success();
  if (!corrected.is_array()) return damaged(what + ": \"corrected\" is not a list");
  for (const json& i : corrected)
    if (!i.is_number_integer() || i.get<std::int64_t>() < 0 || i.get<std::int64_t>() >= static_cast<std::int64_t>(lm.points.size()))
      return damaged(what + ": a corrected point that is not one of its points");
  return Status::success();
}

// entry's bytes: its "count" 1..max (else damaged(empty_or_large)), then its view.
Status read_counted(BinReader& r, const json& entry, const std::string& what, const char* type, std::size_t max,
                    const std::string& empty_or_large, std::vector<std::uint8_t>& out) {
  int count = 0;
  if (!get_int(entry, "count", count, 1) || static_cast<std::size_t>(count) > max) return damaged(empty_or_large);
  return r.array(entry, what, type, 1, out);
}

// The photos and the page's options (version 3; older files have none).
Status read_inputs(BinReader& r, const json& doc, ProjectInputs& in) {
  in = {};
  const json& pj = member(doc, "photos");
  if (!pj.is_null() && !pj.is_array()) return damaged("the photos are not a list");
  if (pj.size() > kMaxPhotos) return damaged(std::to_string(pj.size()) + " photos (at most " + std::to_string(kMaxPhotos) + ")");
  for (std::size_t i = 0; i < pj.size(); ++i) {
    const json& e = pj[i];
    std::string what = "photo " + std::to_string(i + 1);
    const auto name = e.is_object() ? e.find("name") : e.end();
    const auto role = e.is_object() ? e.find("role") : e.end();
    if (!e.is_object() || name == e.end() || !name->is_string() || !plain_file_name(name->get<std::string>()))
      return damaged(what + ": no plain file name");
    ProjectPhoto ph;
    ph.name = name->get<std::string>();
    what += " (" + ph.name + ")";
    if (role == e.end() || !role->is_string() ||
        (*role != "face" && *role != "eye" && *role != "smile"))
      return damaged(what + ": its role is not face, eye or smile");
    ph.role = role->get<std::string>();
    if (Status s = read_counted(r, member(e, "file"), what, "image", kMaxPhotoBytes,
                                what + ": its file is empty or larger than " + std::to_string(kMaxPhotoBytes >> 20) + " MB",
                                ph.bytes);
        !s.ok())
      return s;
    // Its header only (JPEG or PNG, its size): whoever shows it decodes it.
    ImageInfo info;
    if (Status s = inspect_image(ph.bytes.data(), ph.bytes.size(), info); !s.ok())
      return with_context(s, "damaged Likeness project: " + what);
    const json& points = member(e, "points");
    if (!points.is_null()) {
      std::vector<std::uint8_t> text;
      if (Status s = read_counted(r, points, what + " face points", "json", kMaxLandmarkFileBytes,
                                  what + ": its face points are empty or too large", text);
          !s.ok())
        return s;
      ph.points.assign(text.begin(), text.end());
      if (Status s = check_photo_points(ph.points, what + " face points"); !s.ok()) return s;
    }
    in.photos.push_back(std::move(ph));
  }
  const json& page = member(doc, "page_options");
  if (!page.is_null()) {
    std::vector<std::uint8_t> text;
    if (Status s = read_counted(r, page, "the page's options", "json", kMaxPageOptionsBytes,
                                "the page's options are empty or too large", text);
        !s.ok())
      return s;
    in.page_options.assign(text.begin(), text.end());
    bool too_deep = false;  // the page nests 6 deep (a click: photos, photo, clicks, pair, point)
    const json::parser_callback_t depth = [&too_deep](int d, json::parse_event_t, json&) {
      if (d > 16) too_deep = true;
      return !too_deep;
    };
    if (!json::parse(in.page_options, depth, /*allow_exceptions=*/false).is_object() || too_deep)
      return damaged("the page's options are not a JSON object of a few levels");
  }
  return Status::success();
}

Status read_project(const tinygltf::Model& model, const json& doc, HeadProject& p) {
  BinReader r{model};

  // Options.
  const json& o = member(doc, "options");
  FitHeadOptions& opt = p.options;
  int scan_kind = 0, orientation = 0;
  if (!get_int(o, "levels", opt.levels, 1, kMaxLevels) || !get_vec3(o, "up", opt.up) ||
      !get_vec3(o, "facing", opt.facing) || !get_int(o, "scan_kind", scan_kind, 0, 2) ||
      !get_int(o, "orientation_check", orientation, 0, 2) || !get_bool(o, "fit_eye_region", opt.fit_eye_region) ||
      !get_int(o, "smooth_finest_levels", opt.displacement.smooth_finest_levels) ||
      !get_int(o, "max_footprint_points", opt.displacement.max_footprint_points) ||
      !get_int(o, "data_level", opt.global.data_level) || !get_int(o, "whole_head_data_level", opt.whole_head_data_level))
    return damaged("the fit's options");
  // Dense clouds fitted on cell averages (absent before 29 Nov: every point).
  const auto thin = o.find("thin_cells_per_edge");
  if (thin != o.end()) {
    if (!thin->is_number() || !(thin->get<double>() >= 0) || thin->get<double>() > 1000)
      return damaged("the fit's options");
    opt.thin_cells_per_edge = thin->get<double>();
  }
  opt.scan_kind = static_cast<FitHeadOptions::ScanKind>(scan_kind);
  opt.orientation_check = static_cast<FitHeadOptions::OrientationCheck>(orientation);

  // The scan.
  const json& scan = member(doc, "scan");
  if (Status s = r.vec3s(member(scan, "positions"), "scan positions", p.scan.positions); !s.ok()) return s;
  if (Status s = r.tris(member(scan, "faces"), "scan faces", p.scan.positions.size(), p.scan.faces); !s.ok()) return s;

  // The fit: its figures, meshes and the multiresolution head.
  const json& f = member(doc, "fit");
  FitHeadResult& fit = p.fit;
  if (!get_int(f, "points", fit.points, 0) || !get_int(f, "fitted_points", fit.fitted_points, 0) ||
      !get_number(f, "bbox_diagonal", fit.bbox_diagonal) || !get_number(f, "unit_to_metres", fit.unit_to_metres) ||
      !(fit.unit_to_metres > 0) || !get_affine(f, "scan_to_head", fit.scan_to_head) ||
      !get_affine(f, "generic_to_head", fit.generic_to_head) || !get_bool(f, "face_only", fit.face_only) ||
      !get_int(f, "ears_held", fit.ears_held) || !get_int(f, "zeroed_displacements", fit.zeroed_displacements) ||
      !get_int(f, "pocket_points", fit.pocket_points) || !get_int(f, "isolated_points", fit.isolated_points) ||
      !get_number(f, "near_fraction", fit.near_fraction))
    return damaged("the fit's figures");
  // HeadFrame inverts the map: a singular one, or one whose inverse leaves
  // kMaxMagnitude, would put every exported vertex at infinity.
  {
    const Mat3 inverse = fit.scan_to_head.A.inverse();
    if (std::abs(fit.scan_to_head.A.determinant()) < 1e-300 || !inverse.allFinite() ||
        inverse.cwiseAbs().maxCoeff() > kMaxMagnitude)
      return damaged("a scan to head map that cannot be inverted");
  }
  const json& notes = member(f, "notes");
  if (!notes.is_array() && !notes.is_null()) return damaged("the fit's notes");
  for (const json& n : notes) {
    if (!n.is_string()) return damaged("the fit's notes");
    fit.notes.push_back(n.get<std::string>());
  }
  const json& stages = member(f, "stages");
  if (!stages.is_array() && !stages.is_null()) return damaged("the fit's stages");
  for (const json& s : stages) {
    FitStageReport rep;
    const auto name = s.find("name");
    const json& d = member(s, "distance");
    DistanceStats& ds = rep.distance;
    if (name == s.end() || !name->is_string() || !get_int(d, "count", ds.count, 0) || !get_number(d, "mean", ds.mean) ||
        !get_number(d, "max", ds.max) || !get_number(d, "rms", ds.rms) || !get_number(d, "p95", ds.p95) ||
        !get_number(d, "mean_pct", ds.mean_pct) || !get_number(d, "max_pct", ds.max_pct))
      return damaged("the fit's stages");
    rep.name = name->get<std::string>();
    fit.stages.push_back(rep);
  }
  const json& u = member(f, "untangle");
  if (!get_int(u, "pairs_before", fit.untangle.pairs_before) || !get_int(u, "pairs_eroded", fit.untangle.pairs_eroded) ||
      !get_int(u, "pairs_after", fit.untangle.pairs_after) || !get_int(u, "restore_steps", fit.untangle.restore_steps) ||
      !get_int(u, "restored_vertices", fit.untangle.restored_vertices))
    return damaged("the fit's untangling figures");
  if (Status s = r.mesh(member(f, "control"), "control mesh", fit.control); !s.ok()) return s;
  if (Status s = r.mesh(member(f, "aligned"), "aligned mesh", fit.aligned); !s.ok()) return s;
  if (Status s = r.mesh(member(f, "local"), "locally fitted mesh", fit.local); !s.ok()) return s;
  const std::size_t nc = fit.control.positions.size();
  if (nc < 4 || fit.control.triangles.empty()) return damaged("the control mesh is empty");

  const json& mj = member(f, "multires");
  int levels = 0;
  if (!get_int(mj, "levels", levels, 1, kMaxLevels)) return damaged("the number of levels");
  if (fit.control.triangles.size() > (kMaxFinestTriangles >> (2 * levels)))
    return Status::error(ErrorCode::TooLarge, "Likeness project too large: " +
                                                  std::to_string(fit.control.triangles.size()) + " control triangles at " +
                                                  std::to_string(levels) + " levels");
  ButterflyCreases creases;
  std::vector<std::int32_t> flat;
  if (Status s = r.ints(member(mj, "crease_edges"), "crease edges", 2, nc, flat); !s.ok()) return s;
  for (std::size_t i = 0; i + 1 < flat.size(); i += 2) creases.edges.push_back({flat[i], flat[i + 1]});
  if (Status s = r.ints(member(mj, "crease_corners"), "crease corners", 1, nc, flat); !s.ok()) return s;
  creases.corners.assign(flat.begin(), flat.end());
  std::vector<Vec3> current;
  if (Status s = r.vec3s(member(mj, "control"), "current control positions", current); !s.ok()) return s;
  if (current.size() != nc) return damaged("the current control positions are not the control mesh's");

  MultiresMesh& mr = fit.multires;
  if (Status s = build_multires(fit.control, creases, levels, mr); !s.ok())
    return with_context(s, "damaged Likeness project: the levels");
  const json& disp = member(mj, "displacements");
  if (!disp.is_array() || static_cast<int>(disp.size()) != levels + 1) return damaged("the displacements");
  for (int l = 0; l <= levels; ++l) {
    std::vector<double> d;
    const std::string what = "level " + std::to_string(l) + " displacements";
    if (Status s = r.doubles(disp[static_cast<std::size_t>(l)], what, 1, d); !s.ok()) return s;
    if (static_cast<int>(d.size()) != mr.num_vertices(l))
      return damaged("level " + std::to_string(l) + " has " + std::to_string(mr.num_vertices(l)) + " vertices and " +
                     std::to_string(d.size()) + " displacements");
    mr.displacements[static_cast<std::size_t>(l)] = std::move(d);
  }
  // The fit's level meshes are the rest pose's.
  if (Status s = evaluate(mr); !s.ok()) return s;
  for (int l = 1; l <= levels; ++l) fit.level_meshes.push_back(level_mesh(mr, l));
  if (current != mr.control) {
    mr.control = current;
    if (Status s = evaluate(mr); !s.ok()) return s;
  }
  p.frame = HeadFrame::from(fit.scan_to_head);

  // The rig and the pose.
  const json& rj = member(doc, "rig");
  AnimationRig& rig = p.rig;
  if (Status s = r.ints(member(rj, "moved"), "rig vertices", 1, nc, flat); !s.ok()) return s;
  rig.moved.assign(flat.begin(), flat.end());
  if (Status s = r.vec3s(member(rj, "rest"), "rig rest positions", rig.rest); !s.ok()) return s;
  if (Status s = r.ints(member(rj, "kind"), "rig kinds", 1, 2, flat); !s.ok()) return s;
  rig.kind.clear();
  for (std::int32_t k : flat) rig.kind.push_back(k == 0 ? AnimationRig::Kind::Brow : AnimationRig::Kind::Jaw);
  if (Status s = r.doubles(member(rj, "weight"), "rig weights", 1, rig.weight); !s.ok()) return s;
  if (rig.rest.size() != rig.moved.size() || rig.kind.size() != rig.moved.size() ||
      rig.weight.size() != rig.moved.size() || !get_vec3(rj, "jaw_pivot", rig.jaw_pivot) ||
      !get_number(rj, "head_size", rig.head_size))
    return damaged("the animation rig");
  if (!get_number(doc, "pose", p.pose) || p.pose < 0 || p.pose > 1) return damaged("the pose");

  // The texture.
  const json& tj = member(doc, "texture");
  if (!tj.is_null()) {
    if (Status s = r.vec2s(member(tj, "uvs"), "texture chart", p.texture.uvs); !s.ok()) return s;
    if (static_cast<int>(p.texture.uvs.size()) != mr.num_vertices(levels))
      return damaged("the texture chart does not cover the finest level");
    std::vector<std::uint8_t> png;
    if (Status s = r.array(member(tj, "skin"), "skin", "png", 1, png); !s.ok()) return s;
    if (Status s = read_image(png.data(), png.size(), p.texture.skin, 0, kMaxSkinPixels); !s.ok())
      return with_context(s, "damaged Likeness project: the skin");
    if (p.texture.empty()) return damaged("an empty texture");
  }

  // The eyes' and teeth's textures from the user's photos (version 2; a
  // version 1 file has none: the generic ones).
  const json& pj = member(doc, "parts");
  if (!pj.is_null() && !pj.is_object()) return damaged("the eyes' and teeth's textures");
  const std::pair<const char*, std::pair<Image*, std::string*>> parts[2] = {
      {"eye", {&p.parts.eye_texture, &p.parts.eye_source}}, {"teeth", {&p.parts.teeth_texture, &p.parts.teeth_source}}};
  for (const auto& [name, into] : parts) {
    const json& part = member(pj, name);
    if (part.is_null()) continue;
    const std::string what = std::string("the ") + name + " texture";
    const auto source = part.find("source");
    if (!part.is_object() || source == part.end() || !source->is_string()) return damaged(what);
    std::vector<std::uint8_t> png;
    if (Status s = r.array(member(part, "texture"), what, "png", 1, png); !s.ok()) return s;
    if (Status s = read_image(png.data(), png.size(), *into.first, 0, kMaxSkinPixels); !s.ok())
      return with_context(s, "damaged Likeness project: " + what);
    if (into.first->empty()) return damaged(what + " is empty");
    *into.second = source->get<std::string>();
  }
  return read_inputs(r, doc, p.inputs);
}

}  // namespace

Status save_project(const HeadProject& p, Bytes& out) {
  const MultiresMesh& mr = p.fit.multires;
  const int L = mr.num_levels();
  if (L == 0) return Status::error(ErrorCode::InvalidInput, "no fitted head to save");
  if (p.fit.control.positions.size() != mr.control.size())
    return Status::error(ErrorCode::Internal, "the control mesh and the levels disagree");

  tinygltf::Model model;
  model.asset.version = "2.0";
  model.asset.generator = "Likeness";
  model.buffers.resize(1);
  BinWriter w(model);

  // The finest level at rest for the scene: the fit's own (a posed
  // project's state is the pose's).
  MultiresMesh rest_eval;
  const std::vector<Vec3>* rest = &mr.state.displaced[static_cast<std::size_t>(L)];
  const std::vector<Vec3>* normals = &mr.state.normals[static_cast<std::size_t>(L)];
  if (mr.control != p.fit.control.positions || mr.stale_from >= 0) {
    rest_eval = mr;
    rest_eval.control = p.fit.control.positions;
    if (Status st = evaluate(rest_eval); !st.ok()) return st;
    rest = &rest_eval.state.displaced[static_cast<std::size_t>(L)];
    normals = &rest_eval.state.normals[static_cast<std::size_t>(L)];
  }
  Bytes png;
  int skin_view = -1;
  const bool textured = !p.texture.empty();
  if (textured) {
    png = write_png(p.texture.skin);
    if (png.empty()) return Status::error(ErrorCode::Internal, "could not encode the skin as PNG");
    skin_view = w.view(png.data(), png.size());
  }
  add_scene(p, *rest, *normals, skin_view, w);

  const FitHeadResult& f = p.fit;
  json doc;
  doc["format"] = kProjectFormat;
  doc["version"] = kProjectFileVersion;
  doc["options"] = options_json(p.options);
  doc["scan"] = {{"positions", w.vec3s(p.scan.positions)}, {"faces", w.tris(p.scan.faces)}};
  json stages = json::array();
  for (const FitStageReport& s : f.stages) stages.push_back({{"name", s.name}, {"distance", stats_json(s.distance)}});
  json displacements = json::array();
  for (const std::vector<double>& d : mr.displacements) displacements.push_back(w.doubles(d));
  std::vector<int> crease_edges;
  for (const auto& e : mr.creases.edges) crease_edges.insert(crease_edges.end(), e.begin(), e.end());
  json crease_ref = w.ints(crease_edges);
  crease_ref["width"] = 2;
  crease_ref["count"] = static_cast<int>(mr.creases.edges.size());
  doc["fit"] = {
      {"points", f.points},
      {"fitted_points", f.fitted_points},
      {"bbox_diagonal", f.bbox_diagonal},
      {"unit_to_metres", f.unit_to_metres},
      {"scan_to_head", affine_json(f.scan_to_head)},
      {"generic_to_head", affine_json(f.generic_to_head)},
      {"face_only", f.face_only},
      {"notes", f.notes},
      {"stages", stages},
      {"untangle",
       {{"pairs_before", f.untangle.pairs_before},
        {"pairs_eroded", f.untangle.pairs_eroded},
        {"pairs_after", f.untangle.pairs_after},
        {"restore_steps", f.untangle.restore_steps},
        {"restored_vertices", f.untangle.restored_vertices}}},
      {"ears_held", f.ears_held},
      {"zeroed_displacements", f.zeroed_displacements},
      {"pocket_points", f.pocket_points},
      {"isolated_points", f.isolated_points},
      {"near_fraction", f.near_fraction},
      {"control", {{"positions", w.vec3s(f.control.positions)}, {"triangles", w.tris(f.control.triangles)}}},
      {"aligned", {{"positions", w.vec3s(f.aligned.positions)}, {"triangles", w.tris(f.aligned.triangles)}}},
      {"local", {{"positions", w.vec3s(f.local.positions)}, {"triangles", w.tris(f.local.triangles)}}},
      {"multires",
       {{"levels", L},
        {"control", w.vec3s(mr.control)},
        {"crease_edges", crease_ref},
        {"crease_corners", w.ints(mr.creases.corners)},
        {"displacements", displacements}}}};
  std::vector<int> kinds;
  for (AnimationRig::Kind k : p.rig.kind) kinds.push_back(k == AnimationRig::Kind::Brow ? 0 : 1);
  doc["rig"] = {{"moved", w.ints(p.rig.moved)},
                {"rest", w.vec3s(p.rig.rest)},
                {"kind", w.ints(kinds)},
                {"weight", w.doubles(p.rig.weight)},
                {"jaw_pivot", vec3_json(p.rig.jaw_pivot)},
                {"head_size", p.rig.head_size}};
  doc["pose"] = p.pose;
  if (textured) {
    json skin = {{"type", "png"}, {"width", 1}, {"count", static_cast<int>(png.size())}, {"view", skin_view}};
    doc["texture"] = {{"uvs", w.vec2s(p.texture.uvs)}, {"skin", skin}};
  }
  // The eyes' and teeth's textures, each a PNG with the photo's name.
  json parts = json::object();
  const std::pair<const char*, std::pair<const Image*, const std::string*>> part_list[2] = {
      {"eye", {&p.parts.eye_texture, &p.parts.eye_source}}, {"teeth", {&p.parts.teeth_texture, &p.parts.teeth_source}}};
  for (const auto& [name, from] : part_list) {
    if (from.first->empty()) continue;
    const Bytes part_png = write_png(*from.first);
    if (part_png.empty()) return Status::error(ErrorCode::Internal, std::string("could not encode the ") + name + " texture as PNG");
    const int view = w.view(part_png.data(), part_png.size());
    parts[name] = {{"source", *from.second},
                   {"texture", {{"type", "png"}, {"width", 1}, {"count", static_cast<int>(part_png.size())}, {"view", view}}}};
  }
  if (!parts.empty()) doc["parts"] = parts;
  // The photos as their files' bytes, their points and the page's options
  // as JSON text (kept verbatim: the reader checks them, the page reads them).
  const auto text_ref = [&w](const std::string& text) {
    return w.array(std::vector<std::uint8_t>(text.begin(), text.end()), "json", 1);
  };
  json photos = json::array();
  for (const ProjectPhoto& ph : p.inputs.photos) {
    if (ph.bytes.empty()) return Status::error(ErrorCode::InvalidInput, "the photo " + ph.name + " has no bytes");
    json e = {{"name", ph.name}, {"role", ph.role}, {"file", w.array(ph.bytes, "image", 1)}};
    if (!ph.points.empty()) e["points"] = text_ref(ph.points);
    photos.push_back(e);
  }
  if (!photos.empty()) doc["photos"] = photos;
  if (!p.inputs.page_options.empty()) doc["page_options"] = text_ref(p.inputs.page_options);
  // The buffer ends on an 8-byte boundary: no padding after it in the
  // binary chunk, so every byte of the chunk is under the checksum.
  while (model.buffers[0].data.size() % 8) model.buffers[0].data.push_back(0);
  drop_empty(doc);
  doc["checksum"] = project_checksum(doc, model);
  model.extras = tinygltf::Value(tinygltf::Value::Object{{"likeness", to_value(doc)}});

  return with_context(write_glb(model, out), "the project file");
}

Status load_project(const std::uint8_t* data, std::size_t size, HeadProject& out, bool verify_checksum) {
  if (!data || size == 0) return Status::error(ErrorCode::Empty, "an empty file is not a Likeness project");
  if (size > std::numeric_limits<unsigned int>::max())
    return Status::error(ErrorCode::TooLarge, "a project file of 4 GB or more");
  if (Status st = check_glb_header(data, size); !st.ok()) return st;
  tinygltf::TinyGLTF gltf;
  gltf.SetStoreOriginalJSONForExtrasAndExtensions(true);
  gltf.SetImageLoader(&ignore_image, nullptr);
  tinygltf::Model model;
  std::string err, warn;
  if (!gltf.LoadBinaryFromMemory(&model, &err, &warn, data, static_cast<unsigned int>(size)))
    return foreign("the glTF does not parse (" + err.substr(0, err.find('\n')) + ")");
  const json extras = json::parse(model.extras_json_string, nullptr, /*allow_exceptions=*/false);
  const json& doc = member(extras, "likeness");
  if (!doc.is_object()) {
    const std::string by = model.asset.generator.empty() ? "" : " (made by " + model.asset.generator.substr(0, 80) + ")";
    return foreign("a glTF file with no Likeness project in it" + by);
  }
  const auto format = doc.find("format");
  if (format == doc.end() || !format->is_string() || format->get<std::string>() != kProjectFormat)
    return foreign("its extras name another format");
  int version = 0;
  if (!get_int(doc, "version", version)) return damaged("no version");
  if (version > kProjectFileVersion)
    return Status::error(ErrorCode::Unsupported, "made by a newer Likeness (project version " +
                                                     std::to_string(version) + "); this one reads version " +
                                                     std::to_string(kProjectFileVersion));
  if (version < 1) return foreign("project version " + std::to_string(version));
  if (verify_checksum) {
    const auto sum = doc.find("checksum");
    json rest = doc;
    rest.erase("checksum");
    if (sum == doc.end() || !sum->is_string() || sum->get<std::string>() != project_checksum(rest, model))
      return damaged("its checksum does not match (the file was changed or cut after it was saved)");
  }
  HeadProject p;
  if (Status st = read_project(model, doc, p); !st.ok()) return st;
  p.file_version = version;
  out = std::move(p);
  return Status::success();
}

}  // namespace lk
