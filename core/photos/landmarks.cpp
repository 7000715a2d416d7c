#include "photos/landmarks.h"

#include "raycast/bvh.h"

#include <nlohmann/json.hpp>

#include <cmath>

namespace lk {
namespace {

using Json = nlohmann::json;

Status invalid(const std::string& field, const std::string& what) {
  return Status::error(ErrorCode::InvalidInput, field + ": " + what);
}

// Our documents nest 3 deep ({"points": [[x, y]]}); a file of 4 MB of '['
// would make the JSON parser build millions of nested arrays first.
constexpr int kMaxDepth = 16;
bool nested_too_deep(const std::string& text) {
  int depth = 0;
  bool in_string = false, escaped = false;
  for (char c : text) {
    if (in_string) {
      if (escaped) escaped = false;
      else if (c == '\\') escaped = true;
      else if (c == '"') in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > kMaxDepth) return true;
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
  return false;
}

Json parse_document(const std::string& text) {
  if (nested_too_deep(text)) return Json(Json::value_t::discarded);
  return Json::parse(text, nullptr, /*allow_exceptions=*/false);
}

Status check_header(const Json& root, const char* format, std::string& detector) {
  if (!root.is_object()) return invalid("document", "not a JSON object");
  auto f = root.find("format");
  if (f == root.end() || !f->is_string() || f->get<std::string>() != format)
    return invalid("format", std::string("must be \"") + format + "\"");
  auto v = root.find("version");
  if (v == root.end() || !v->is_number_integer() || v->get<long long>() != 1)
    return invalid("version", "must be 1 (the only version this build reads)");
  auto d = root.find("detector");
  if (d == root.end() || !d->is_string() || d->get<std::string>().empty() || d->get<std::string>().size() > 200)
    return invalid("detector", "must be a non-empty string");
  detector = d->get<std::string>();
  auto p = root.find("points");
  if (p == root.end() || !p->is_array()) return invalid("points", "must be an array");
  if (p->size() > size_t(kMaxLandmarks))
    return invalid("points", std::to_string(p->size()) + " points, at most " + std::to_string(kMaxLandmarks));
  return Status::success();
}

// Reads [x, y(, z)] of `dim` finite numbers, or null.
Status read_point(const Json& j, int dim, size_t index, double* xyz, bool& present) {
  present = false;
  if (j.is_null()) return Status::success();
  const std::string field = "points[" + std::to_string(index) + "]";
  if (!j.is_array() || j.size() != size_t(dim))
    return invalid(field, "must be null or " + std::to_string(dim) + " numbers");
  for (int k = 0; k < dim; ++k) {
    if (!j[size_t(k)].is_number()) return invalid(field, "must be null or " + std::to_string(dim) + " numbers");
    xyz[k] = j[size_t(k)].get<double>();
    if (!std::isfinite(xyz[k])) return invalid(field, "is not finite");
  }
  present = true;
  return Status::success();
}

Json point_json(const double* v, int dim) {
  Json a = Json::array();
  for (int k = 0; k < dim; ++k) a.push_back(v[k]);
  return a;
}

}  // namespace

int LandmarkPhoto::num_present() const {
  int n = 0;
  for (char c : present) n += c != 0;
  return n;
}

Vec3 surface_position(const TriMesh& mesh, const SurfacePoint& p) {
  const Tri& t = mesh.triangles[size_t(p.triangle)];
  return p.barycentric[0] * mesh.positions[size_t(t[0])] + p.barycentric[1] * mesh.positions[size_t(t[1])] +
         p.barycentric[2] * mesh.positions[size_t(t[2])] + p.offset;
}

// The document of a landmark file or map (what: "landmark file" / "landmark
// map"), within the size limit, parsed, with its format header checked.
static Status read_document(const std::string& text, const char* what, const char* format, Json& root, std::string& detector) {
  if (text.size() > kMaxLandmarkFileBytes)
    return Status::error(ErrorCode::TooLarge, std::string(what) + " of " + std::to_string(text.size()) +
                                                  " bytes, at most " + std::to_string(kMaxLandmarkFileBytes));
  root = parse_document(text);
  if (root.is_discarded()) return invalid("document", "not valid JSON, or nested deeper than " + std::to_string(kMaxDepth));
  return check_header(root, format, detector);
}

Status parse_landmarks_json(const std::string& text, LandmarkPhoto& out) {
  out = {};
  Json root;
  Status s = read_document(text, "landmark file", "likeness-landmarks", root, out.detector);
  if (!s) return s;
  auto img = root.find("image");
  if (img == root.end() || !img->is_object()) return invalid("image", "must be an object with name, width, height");
  auto name = img->find("name");
  if (name != img->end()) {
    if (!name->is_string() || name->get<std::string>().size() > 4096) return invalid("image.name", "must be a string");
    out.name = name->get<std::string>();
  }
  for (const char* key : {"width", "height"}) {
    auto w = img->find(key);
    if (w == img->end() || !w->is_number_integer() || w->get<long long>() < 1 ||
        w->get<long long>() > kMaxLandmarkImageSide)
      return invalid(std::string("image.") + key, "must be an integer in 1.." + std::to_string(kMaxLandmarkImageSide));
    (std::string(key) == "width" ? out.width : out.height) = int(w->get<long long>());
  }
  const Json& pts = root["points"];
  out.points.assign(pts.size(), Vec2::Zero());
  out.present.assign(pts.size(), 0);
  for (size_t i = 0; i < pts.size(); ++i) {
    double xy[2];
    bool present = false;
    s = read_point(pts[i], 2, i, xy, present);
    if (!s) return s;
    if (!present) continue;
    if (xy[0] < -out.width || xy[0] > 2.0 * out.width || xy[1] < -out.height || xy[1] > 2.0 * out.height)
      return invalid("points[" + std::to_string(i) + "]", "lies far outside the " + std::to_string(out.width) + "x" +
                                                              std::to_string(out.height) + " image");
    out.points[i] = Vec2(xy[0], xy[1]);
    out.present[i] = 1;
  }
  return Status::success();
}

Status parse_landmark_map_json(const std::string& text, LandmarkMap& out) {
  out = {};
  Json root;
  Status s = read_document(text, "landmark map", "likeness-landmark-map", root, out.detector);
  if (!s) return s;
  const Json& pts = root["points"];
  out.points.assign(pts.size(), Vec3::Zero());
  out.present.assign(pts.size(), 0);
  for (size_t i = 0; i < pts.size(); ++i) {
    double xyz[3];
    bool present = false;
    s = read_point(pts[i], 3, i, xyz, present);
    if (!s) return s;
    if (!present) continue;
    // The generic head is ~0.25 m across: a coordinate beyond 10 m is no head point.
    if (std::abs(xyz[0]) > 10 || std::abs(xyz[1]) > 10 || std::abs(xyz[2]) > 10)
      return invalid("points[" + std::to_string(i) + "]", "lies more than 10 m from the head's origin");
    out.points[i] = Vec3(xyz[0], xyz[1], xyz[2]);
    out.present[i] = 1;
  }
  return Status::success();
}

std::string landmarks_to_json(const LandmarkPhoto& photo) {
  Json j;
  j["format"] = "likeness-landmarks";
  j["version"] = 1;
  j["image"] = {{"name", photo.name}, {"width", photo.width}, {"height", photo.height}};
  j["detector"] = photo.detector;
  Json pts = Json::array();
  for (size_t i = 0; i < photo.points.size(); ++i)
    pts.push_back(photo.present[i] ? point_json(photo.points[i].data(), 2) : Json(nullptr));
  j["points"] = pts;
  return j.dump() + "\n";
}

std::string landmark_map_to_json(const LandmarkMap& map) {
  Json j;
  j["format"] = "likeness-landmark-map";
  j["version"] = 1;
  j["detector"] = map.detector;
  Json pts = Json::array();
  for (size_t i = 0; i < map.points.size(); ++i)
    pts.push_back(map.present[i] ? point_json(map.points[i].data(), 3) : Json(nullptr));
  j["points"] = pts;
  return j.dump() + "\n";
}

Status attach_landmark_map(const LandmarkMap& map, const TriMesh& head, double max_distance,
                           std::vector<SurfacePoint>& out) {
  out.assign(map.points.size(), SurfacePoint{});
  MeshBvh bvh;
  Status s = build_bvh(head, bvh);
  if (!s) return with_context(s, "landmark map");
  int count = 0;
  for (size_t i = 0; i < map.points.size(); ++i) {
    if (!map.present[i]) continue;
    const ClosestPoint c = closest_point(bvh, map.points[i]);
    if (!c.found() || c.distance > max_distance)
      return invalid("landmark map points[" + std::to_string(i) + "]",
                     "lies " + std::to_string(c.distance * 1000) + " mm from the head's surface (made for another head?)");
    out[i].triangle = c.triangle;
    out[i].barycentric = c.barycentric;
    out[i].offset = map.points[i] - c.point;
    ++count;
  }
  if (count < 6)
    return Status::error(ErrorCode::Empty, "landmark map: " + std::to_string(count) + " mapped points, at least 6 needed");
  return Status::success();
}

}  // namespace lk
