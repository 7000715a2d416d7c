#include "photos/landmarks.h"

#include "common/json_depth.h"
#include "raycast/bvh.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>

namespace lk {
namespace {

using Json = nlohmann::json;

Status invalid(const std::string& field, const std::string& what) {
  return Status::error(ErrorCode::InvalidInput, field + ": " + what);
}

// Our documents nest 3 deep ({"points": [[x, y]]}).
constexpr int kMaxDepth = 16;

Json parse_document(const std::string& text) {
  if (json_nested_deeper(text, kMaxDepth)) return Json(Json::value_t::discarded);
  return Json::parse(text, nullptr, /*allow_exceptions=*/false);
}

Status check_header(const Json& root, const char* format, std::string& detector, int max_version = 1) {
  if (!root.is_object()) return invalid("document", "not a JSON object");
  auto f = root.find("format");
  if (f == root.end() || !f->is_string() || f->get<std::string>() != format)
    return invalid("format", std::string("must be \"") + format + "\"");
  auto v = root.find("version");
  if (v == root.end() || !v->is_number_integer() || v->get<long long>() < 1 || v->get<long long>() > max_version)
    return invalid("version", max_version == 1 ? "must be 1 (the only version this build reads)"
                                               : "must be 1.." + std::to_string(max_version) + " (the versions this build reads)");
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
static Status read_document(const std::string& text, const char* what, const char* format, Json& root, std::string& detector,
                            int max_version = 1) {
  if (text.size() > kMaxLandmarkFileBytes)
    return Status::error(ErrorCode::TooLarge, std::string(what) + " of " + std::to_string(text.size()) +
                                                  " bytes, at most " + std::to_string(kMaxLandmarkFileBytes));
  root = parse_document(text);
  if (root.is_discarded()) return invalid("document", "not valid JSON, or nested deeper than " + std::to_string(kMaxDepth));
  return check_header(root, format, detector, max_version);
}

// A finite number, |x| <= limit.
static bool finite_number(const Json& j, double limit, double& x) {
  if (!j.is_number()) return false;
  x = j.get<double>();
  return std::isfinite(x) && std::abs(x) <= limit;
}

// The map's "slide" (version 2), for #M landmarks.
static Status parse_slide(const Json& js, size_t M, LandmarkSlide& out) {
  out = {};
  if (!js.is_object()) return invalid("slide", "must be an object");
  constexpr double kDeg = 3.14159265358979323846 / 180;
  double y = 0, p = 0;
  if (!js.contains("yaw_range_deg") || !finite_number(js["yaw_range_deg"], 180, y) || !(y > 0) ||
      !js.contains("pitch_range_deg") || !finite_number(js["pitch_range_deg"], 90, p) || !(p > 0))
    return invalid("slide", "needs yaw_range_deg in (0, 180] and pitch_range_deg in (0, 90]");
  out.yaw_range = y * kDeg;
  out.pitch_range = p * kDeg;
  if (!js.contains("terms") || !js["terms"].is_array() || js["terms"].empty() || js["terms"].size() > 20)
    return invalid("slide.terms", "must be an array of 1..20 [i, j] exponent pairs");
  for (const Json& t : js["terms"]) {
    if (!t.is_array() || t.size() != 2 || !t[0].is_number_integer() || !t[1].is_number_integer() ||
        t[0].get<int>() < 0 || t[1].get<int>() < 0 || t[0].get<int>() + t[1].get<int>() > 6 ||
        t[0].get<int>() + t[1].get<int>() == 0)
      return invalid("slide.terms", "each must be [i, j], integers >= 0, 1 <= i + j <= 6");
    out.terms.push_back({t[0].get<int>(), t[1].get<int>()});
  }
  const size_t K = out.terms.size();
  if (!js.contains("shifts") || !js["shifts"].is_array() || js["shifts"].size() != M)
    return invalid("slide.shifts", "must hold one entry per map point (" + std::to_string(M) + ")");
  out.shifts.assign(M, {});
  for (size_t m = 0; m < M; ++m) {
    const Json& e = js["shifts"][m];
    if (e.is_null()) continue;
    const std::string field = "slide.shifts[" + std::to_string(m) + "]";
    if (!e.is_array() || e.size() != K) return invalid(field, "must be null or " + std::to_string(K) + " [x, y, z]");
    for (size_t k = 0; k < K; ++k) {
      Vec3 d;
      for (int c = 0; c < 3; ++c)
        if (!e[k].is_array() || e[k].size() != 3 || !finite_number(e[k][size_t(c)], 0.1, d[c]))
          return invalid(field, "each must be [x, y, z], finite, at most 0.1 m");
      out.shifts[m].push_back(d);
    }
  }
  if (js.contains("sigma_yaw_deg") || js.contains("sigma")) {
    if (!js.contains("sigma_yaw_deg") || !js["sigma_yaw_deg"].is_array() || js["sigma_yaw_deg"].empty() ||
        js["sigma_yaw_deg"].size() > 90)
      return invalid("slide.sigma_yaw_deg", "must be an array of 1..90 angles");
    for (const Json& a : js["sigma_yaw_deg"]) {
      double d = 0;
      if (!finite_number(a, 180, d) || (!out.sigma_yaw.empty() && !(d * kDeg > out.sigma_yaw.back())))
        return invalid("slide.sigma_yaw_deg", "must be increasing angles within +-180");
      out.sigma_yaw.push_back(d * kDeg);
    }
    if (!js.contains("sigma") || !js["sigma"].is_array() || js["sigma"].size() != M)
      return invalid("slide.sigma", "must hold one entry per map point (" + std::to_string(M) + ")");
    out.sigma.assign(M, {});
    for (size_t m = 0; m < M; ++m) {
      const Json& e = js["sigma"][m];
      if (e.is_null()) continue;
      const std::string field = "slide.sigma[" + std::to_string(m) + "]";
      if (!e.is_array() || e.size() != out.sigma_yaw.size())
        return invalid(field, "must be null or " + std::to_string(out.sigma_yaw.size()) + " numbers");
      for (const Json& a : e) {
        double d = 0;
        if (!finite_number(a, 0.1, d) || !(d > 0)) return invalid(field, "each must be in (0, 0.1] m");
        out.sigma[m].push_back(d);
      }
    }
  }
  return Status::success();
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
  Status s = read_document(text, "landmark map", "likeness-landmark-map", root, out.detector, 2);
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
  auto sl = root.find("slide");
  if (root["version"].get<int>() >= 2 && sl != root.end()) {
    s = parse_slide(*sl, out.points.size(), out.slide);
    if (!s) return s;
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
  const LandmarkSlide& sl = map.slide;
  j["format"] = "likeness-landmark-map";
  j["version"] = sl.has_slide() ? 2 : 1;
  j["detector"] = map.detector;
  Json pts = Json::array();
  for (size_t i = 0; i < map.points.size(); ++i)
    pts.push_back(map.present[i] ? point_json(map.points[i].data(), 3) : Json(nullptr));
  j["points"] = pts;
  if (sl.has_slide()) {
    constexpr double kDeg = 180 / 3.14159265358979323846;
    // Shifts and scatter to 0.01 mm: the file stays small.
    auto r5 = [](double x) { return std::round(x * 1e5) / 1e5; };
    Json js;
    js["yaw_range_deg"] = sl.yaw_range * kDeg;
    js["pitch_range_deg"] = sl.pitch_range * kDeg;
    Json terms = Json::array();
    for (const auto& t : sl.terms) terms.push_back({t[0], t[1]});
    js["terms"] = terms;
    Json shifts = Json::array();
    for (size_t m = 0; m < map.points.size(); ++m) {
      if (m >= sl.shifts.size() || sl.shifts[m].size() != sl.terms.size()) {
        shifts.push_back(nullptr);
        continue;
      }
      Json e = Json::array();
      for (const Vec3& d : sl.shifts[m]) e.push_back({r5(d.x()), r5(d.y()), r5(d.z())});
      shifts.push_back(e);
    }
    js["shifts"] = shifts;
    if (sl.has_sigma()) {
      Json ys = Json::array();
      for (double y : sl.sigma_yaw) ys.push_back(y * kDeg);
      js["sigma_yaw_deg"] = ys;
      Json sg = Json::array();
      for (size_t m = 0; m < map.points.size(); ++m) {
        if (m >= sl.sigma.size() || sl.sigma[m].size() != sl.sigma_yaw.size()) {
          sg.push_back(nullptr);
          continue;
        }
        Json e = Json::array();
        for (double v : sl.sigma[m]) e.push_back(std::max(1e-5, r5(v)));
        sg.push_back(e);
      }
      js["sigma"] = sg;
    }
    j["slide"] = js;
  }
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
