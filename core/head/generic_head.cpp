#include "head/generic_head.h"

#include <algorithm>

#include "io/io.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <set>

namespace likeness_embedded {
extern const unsigned char head_generic_head_obj[];
extern const std::size_t head_generic_head_obj_size;
extern const unsigned char head_generic_head_json[];
extern const std::size_t head_generic_head_json_size;
extern const unsigned char head_mediapipe_landmark_map_json[];
extern const std::size_t head_mediapipe_landmark_map_json_size;
}  // namespace likeness_embedded

namespace lk {

using Json = nlohmann::json;

const std::vector<std::string>& required_head_regions() {
  static const std::vector<std::string> names = {
      "face",      "scalp",     "ears",         "ear_left",      "ear_right", "neck",
      "lips",      "upper_lip", "lower_lip",    "eye_rim_left",  "eye_rim_right",
      "nose",      "brow",      "jaw",          "chin",          "cheeks"};
  return names;
}

namespace {

const char* const kFormat = "likeness-generic-head-annotations";
constexpr int kVersion = 1;

Status invalid(const std::string& field, const std::string& problem) {
  return Status::error(ErrorCode::InvalidInput, "head annotations: " + field + ": " + problem);
}

Json vec_json(const Vec3& v) { return Json::array({v.x(), v.y(), v.z()}); }

// Field readers: each checks presence and type and names the field on failure.
const Json* member(const Json& obj, const std::string& key) {
  auto it = obj.find(key);
  return it == obj.end() ? nullptr : &*it;
}

Status read_vec3(const Json& obj, const std::string& key, const std::string& where, Vec3& out) {
  const Json* j = member(obj, key);
  const std::string field = where + key;
  if (!j) return invalid(field, "missing");
  if (!j->is_array() || j->size() != 3) return invalid(field, "must be an array of 3 numbers");
  for (int k = 0; k < 3; ++k) {
    if (!(*j)[k].is_number()) return invalid(field, "must be an array of 3 numbers");
    out[k] = (*j)[k].get<double>();
    if (!std::isfinite(out[k])) return invalid(field, "is not finite");
  }
  return Status::success();
}

Status read_number(const Json& obj, const std::string& key, const std::string& where, double& out) {
  const Json* j = member(obj, key);
  if (!j) return invalid(where + key, "missing");
  if (!j->is_number()) return invalid(where + key, "must be a number");
  out = j->get<double>();
  if (!std::isfinite(out)) return invalid(where + key, "is not finite");
  return Status::success();
}

Status read_index(const Json& j, const std::string& field, int num_vertices, int& out) {
  if (!j.is_number_integer()) return invalid(field, "vertex index must be an integer");
  const long long v = j.get<long long>();
  if (v < 0 || v >= num_vertices)
    return invalid(field, "vertex index " + std::to_string(v) + " out of range [0, " +
                              std::to_string(num_vertices) + ")");
  out = static_cast<int>(v);
  return Status::success();
}

Status read_indices(const Json& obj, const std::string& key, const std::string& where,
                    int num_vertices, std::vector<int>& out) {
  const Json* j = member(obj, key);
  const std::string field = where + key;
  if (!j) return invalid(field, "missing");
  if (!j->is_array()) return invalid(field, "must be an array of vertex indices");
  out.clear();
  for (size_t k = 0; k < j->size(); ++k) {
    int v = 0;
    Status s = read_index((*j)[k], field + "[" + std::to_string(k) + "]", num_vertices, v);
    if (!s.ok()) return s;
    out.push_back(v);
  }
  return Status::success();
}

Status read_plane(const Json& obj, const std::string& key, ClipPlane& out) {
  const Json* j = member(obj, key);
  if (!j) return invalid(key, "missing");
  if (!j->is_object()) return invalid(key, "must be an object with point and normal");
  Status s = read_vec3(*j, "point", key + ".", out.point);
  if (s.ok()) s = read_vec3(*j, "normal", key + ".", out.normal);
  if (!s.ok()) return s;
  if (out.normal.norm() < 1e-9) return invalid(key + ".normal", "must not be zero");
  out.normal.normalize();
  return Status::success();
}

Status read_eye(const Json& obj, const std::string& key, int num_vertices, EyeSocket& out) {
  const Json* j = member(obj, key);
  if (!j) return invalid(key, "missing");
  if (!j->is_object()) return invalid(key, "must be an object with center, radius and rim");
  Status s = read_vec3(*j, "center", key + ".", out.center);
  if (s.ok()) s = read_number(*j, "radius", key + ".", out.radius);
  if (s.ok()) s = read_indices(*j, "rim", key + ".", num_vertices, out.rim);
  if (!s.ok()) return s;
  if (!(out.radius > 0)) return invalid(key + ".radius", "must be positive");
  if (out.rim.size() < 3) return invalid(key + ".rim", "needs at least 3 vertices");
  return Status::success();
}

}  // namespace

std::vector<char> vertex_mask(const std::vector<int>& vertices, int num_vertices) {
  std::vector<char> mask(std::max(0, num_vertices), 0);
  for (int v : vertices)
    if (v >= 0 && v < num_vertices) mask[v] = 1;
  return mask;
}

Status parse_head_annotations(const std::string& text, int num_vertices, HeadAnnotations& out) {
  if (num_vertices <= 0) return invalid("num_vertices", "the mesh has no vertices");
  const Json root = Json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (root.is_discarded()) return invalid("document", "not valid JSON");
  if (!root.is_object()) return invalid("document", "must be a JSON object");
  HeadAnnotations a;
  {
    const Json* f = member(root, "format");
    if (!f || !f->is_string() || f->get<std::string>() != kFormat)
      return invalid("format", std::string("must be \"") + kFormat + "\"");
    const Json* v = member(root, "version");
    if (!v || !v->is_number_integer() || v->get<int>() != kVersion)
      return invalid("version", "must be " + std::to_string(kVersion));
    const Json* n = member(root, "num_vertices");
    if (n && (!n->is_number_integer() || n->get<long long>() != num_vertices))
      return invalid("num_vertices", "does not match the mesh's " + std::to_string(num_vertices) +
                                         " vertices");
  }
  Status s = read_vec3(root, "look", "", a.look);
  if (s.ok()) s = read_vec3(root, "up", "", a.up);
  if (!s.ok()) return s;
  if (a.look.norm() < 1e-9 || a.up.norm() < 1e-9) return invalid("look/up", "must not be zero");

  // Feature boxes: exactly these four, each with its landmark count.
  const std::vector<std::pair<std::string, size_t>> expected = {
      {"ear_left", 3}, {"ear_right", 3}, {"nose", 4}, {"mouth", 4}};
  const Json* boxes = member(root, "boxes");
  if (!boxes || !boxes->is_array()) return invalid("boxes", "missing or not an array");
  if (boxes->size() != expected.size()) return invalid("boxes", "must hold exactly 4 boxes");
  std::set<std::string> seen;
  for (size_t k = 0; k < boxes->size(); ++k) {
    const Json& jb = (*boxes)[k];
    const std::string where = "boxes[" + std::to_string(k) + "].";
    if (!jb.is_object()) return invalid(where, "must be an object");
    FeatureBox box;
    const Json* name = member(jb, "name");
    if (!name || !name->is_string()) return invalid(where + "name", "missing or not a string");
    box.name = name->get<std::string>();
    size_t want = 0;
    for (const auto& e : expected)
      if (e.first == box.name) want = e.second;
    if (want == 0) return invalid(where + "name", "unknown box \"" + box.name + "\"");
    if (!seen.insert(box.name).second) return invalid(where + "name", "duplicate box \"" + box.name + "\"");
    s = read_vec3(jb, "min", where, box.min);
    if (s.ok()) s = read_vec3(jb, "max", where, box.max);
    if (s.ok()) s = read_indices(jb, "landmarks", where, num_vertices, box.landmarks);
    if (!s.ok()) return s;
    if (!(box.max.array() > box.min.array()).all()) return invalid(where + "max", "must exceed min on every axis");
    if (box.landmarks.size() != want)
      return invalid(where + "landmarks", "box \"" + box.name + "\" needs " + std::to_string(want) +
                                              " landmarks, has " + std::to_string(box.landmarks.size()));
    a.boxes.push_back(box);
  }

  const Json* edges = member(root, "binding_edges");
  if (!edges || !edges->is_array()) return invalid("binding_edges", "missing or not an array");
  for (size_t k = 0; k < edges->size(); ++k) {
    const Json& je = (*edges)[k];
    const std::string field = "binding_edges[" + std::to_string(k) + "]";
    if (!je.is_array() || je.size() != 2) return invalid(field, "must be a pair of vertex indices");
    std::array<int, 2> e{};
    for (int i = 0; i < 2; ++i) {
      s = read_index(je[i], field, num_vertices, e[i]);
      if (!s.ok()) return s;
    }
    if (e[0] == e[1]) return invalid(field, "joins a vertex to itself");
    a.binding_edges.push_back(e);
  }
  s = read_indices(root, "constrained_vertices", "", num_vertices, a.constrained_vertices);
  if (s.ok()) s = read_plane(root, "neck_clip", a.neck_clip);
  if (s.ok()) s = read_plane(root, "back_clip", a.back_clip);
  if (s.ok()) s = read_eye(root, "eye_left", num_vertices, a.eye_left);
  if (s.ok()) s = read_eye(root, "eye_right", num_vertices, a.eye_right);
  if (!s.ok()) return s;

  const Json* mouth = member(root, "mouth");
  if (!mouth || !mouth->is_object()) return invalid("mouth", "missing or not an object");
  s = read_vec3(*mouth, "center", "mouth.", a.mouth_center);
  if (s.ok()) s = read_number(*mouth, "width", "mouth.", a.mouth_width);
  if (!s.ok()) return s;
  if (!(a.mouth_width > 0)) return invalid("mouth.width", "must be positive");

  // Crease curves: optional (older files have none).
  if (const Json* creases = member(root, "creases")) {
    if (!creases->is_array()) return invalid("creases", "must be an array of curves");
    for (size_t k = 0; k < creases->size(); ++k) {
      const Json& jc = (*creases)[k];
      const std::string where = "creases[" + std::to_string(k) + "].";
      if (!jc.is_object()) return invalid(where, "must be an object with name, closed and vertices");
      CreaseCurve c;
      const Json* name = member(jc, "name");
      if (!name || !name->is_string()) return invalid(where + "name", "missing or not a string");
      c.name = name->get<std::string>();
      const Json* closed = member(jc, "closed");
      if (!closed || !closed->is_boolean()) return invalid(where + "closed", "missing or not true/false");
      c.closed = closed->get<bool>();
      s = read_indices(jc, "vertices", where, num_vertices, c.vertices);
      if (!s.ok()) return s;
      if (c.vertices.size() < (c.closed ? 3u : 2u))
        return invalid(where + "vertices", c.closed ? "a closed curve needs at least 3 vertices"
                                                    : "an open curve needs at least 2 vertices");
      a.creases.push_back(std::move(c));
    }
  }

  const Json* regions = member(root, "regions");
  if (!regions || !regions->is_object()) return invalid("regions", "missing or not an object");
  for (auto it = regions->begin(); it != regions->end(); ++it) {
    std::vector<int> ids;
    s = read_indices(*regions, it.key(), "regions.", num_vertices, ids);
    if (!s.ok()) return s;
    a.regions[it.key()] = ids;
  }
  for (const std::string& name : required_head_regions()) {
    auto it = a.regions.find(name);
    if (it == a.regions.end()) return invalid("regions." + name, "missing");
    if (it->second.empty()) return invalid("regions." + name, "is empty");
  }
  out = std::move(a);
  return Status::success();
}

std::string head_annotations_to_json(const HeadAnnotations& a, int num_vertices) {
  Json root = Json::object();
  root["format"] = kFormat;
  root["version"] = kVersion;
  if (num_vertices >= 0) root["num_vertices"] = num_vertices;
  root["look"] = vec_json(a.look);
  root["up"] = vec_json(a.up);
  Json boxes = Json::array();
  for (const FeatureBox& b : a.boxes)
    boxes.push_back({{"name", b.name}, {"min", vec_json(b.min)}, {"max", vec_json(b.max)},
                     {"landmarks", b.landmarks}});
  root["boxes"] = boxes;
  Json edges = Json::array();
  for (const auto& e : a.binding_edges) edges.push_back(Json::array({e[0], e[1]}));
  root["binding_edges"] = edges;
  root["constrained_vertices"] = a.constrained_vertices;
  root["neck_clip"] = {{"point", vec_json(a.neck_clip.point)}, {"normal", vec_json(a.neck_clip.normal)}};
  root["back_clip"] = {{"point", vec_json(a.back_clip.point)}, {"normal", vec_json(a.back_clip.normal)}};
  auto eye = [](const EyeSocket& e) {
    return Json{{"center", vec_json(e.center)}, {"radius", e.radius}, {"rim", e.rim}};
  };
  root["eye_left"] = eye(a.eye_left);
  root["eye_right"] = eye(a.eye_right);
  root["mouth"] = {{"center", vec_json(a.mouth_center)}, {"width", a.mouth_width}};
  if (!a.creases.empty()) {
    Json creases = Json::array();
    for (const CreaseCurve& c : a.creases)
      creases.push_back({{"name", c.name}, {"closed", c.closed}, {"vertices", c.vertices}});
    root["creases"] = creases;
  }
  Json regions = Json::object();
  for (const auto& [name, ids] : a.regions) regions[name] = ids;
  root["regions"] = regions;
  // One line per field (per box, per region): diffable and still compact.
  std::string text = "{\n";
  size_t i = 0;
  for (auto it = root.begin(); it != root.end(); ++it, ++i) {
    text += " " + Json(it.key()).dump() + ": ";
    const Json& v = it.value();
    if ((v.is_array() && !v.empty() && v[0].is_object()) || (v.is_object() && it.key() == "regions")) {
      const bool arr = v.is_array();
      text += arr ? "[\n" : "{\n";
      size_t k = 0;
      for (auto jt = v.begin(); jt != v.end(); ++jt, ++k) {
        text += "  " + (arr ? std::string() : Json(jt.key()).dump() + ": ") + jt.value().dump();
        text += k + 1 < v.size() ? ",\n" : "\n";
      }
      text += arr ? " ]" : " }";
    } else {
      text += v.dump();
    }
    text += i + 1 < root.size() ? ",\n" : "\n";
  }
  return text + "}\n";
}

std::string generic_head_obj_text() {
  return std::string(reinterpret_cast<const char*>(likeness_embedded::head_generic_head_obj),
                     likeness_embedded::head_generic_head_obj_size);
}
std::string generic_head_json_text() {
  return std::string(reinterpret_cast<const char*>(likeness_embedded::head_generic_head_json),
                     likeness_embedded::head_generic_head_json_size);
}
std::string mediapipe_landmark_map_text() {
  return std::string(reinterpret_cast<const char*>(likeness_embedded::head_mediapipe_landmark_map_json),
                     likeness_embedded::head_mediapipe_landmark_map_json_size);
}

Status load_generic_head(GenericHead& out) {
  GenericHead head;
  GeometryKind kind = GeometryKind::PointCloud;
  Status s = read_obj(likeness_embedded::head_generic_head_obj, likeness_embedded::head_generic_head_obj_size,
                      head.mesh, kind);
  if (s.ok() && kind != GeometryKind::Mesh) s = Status::error(ErrorCode::InvalidInput, "has no triangles");
  if (!s.ok()) return with_context(s, "embedded generic_head.obj");
  head.mesh.normals.clear();  // the asset's shape is its positions; normals are recomputed by users
  s = parse_head_annotations(generic_head_json_text(), head.mesh.num_vertices(), head.annotations);
  if (!s.ok()) return with_context(s, "embedded generic_head.json");
  out = std::move(head);
  return Status::success();
}

}  // namespace lk
