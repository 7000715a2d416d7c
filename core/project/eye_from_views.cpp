#include "project/eye_from_views.h"

#include "project/parts.h"

#include <algorithm>
#include <cmath>

namespace lk {
namespace {

struct Candidate {
  int photo = 0, eye = 0;
  double angle_deg = 0;
};

// The square [x0, x0 + side) x [y0, y0 + side) of im, clamped to the image.
Image crop(const Image& im, int x0, int y0, int side) {
  const int x1 = std::min(im.width, x0 + side), y1 = std::min(im.height, y0 + side);
  x0 = std::max(0, x0);
  y0 = std::max(0, y0);
  Image out = Image::make(std::max(0, x1 - x0), std::max(0, y1 - y0), im.channels);
  for (int y = y0; y < y1; ++y)
    std::copy(im.at(x0, y), im.at(x0, y) + static_cast<size_t>(x1 - x0) * im.channels, out.at(0, y - y0));
  return out;
}

constexpr double kDegPerRad = 180 / 3.14159265358979323846;

std::string eye_name(int eye) { return eye == 0 ? "left eye" : "right eye"; }

}  // namespace

Status eye_texture_from_views(const TriMesh& control, const GenericHead& generic, const HeadFrame& frame,
                              const std::vector<const Image*>& images, const std::vector<Camera>& cameras,
                              const std::vector<std::string>& names, const EyeFromViewsOptions& options,
                              EyeFromViewsResult& out) {
  out = EyeFromViewsResult{};
  if (images.size() != cameras.size())
    return Status::error(ErrorCode::InvalidInput, "eye from photos: the photos and cameras differ in number");
  HeadParts parts;
  if (Status s = place_head_parts(control, generic, parts); !s) return s;

  // The head's forward direction in the cameras' frame.
  const Vec3 forward = (frame.to_scan(Vec3(0, 0, 1)) - frame.to_scan(Vec3::Zero())).normalized();
  std::vector<Candidate> candidates;
  const auto photo_name = [&](int i) {
    return size_t(i) < names.size() ? names[size_t(i)] : "photo " + std::to_string(i + 1);
  };
  if (options.only_photo >= static_cast<int>(cameras.size()))
    return Status::error(ErrorCode::InvalidInput, "eye from photos: no photo " + std::to_string(options.only_photo + 1));
  for (size_t i = 0; i < cameras.size(); ++i) {
    if (options.only_photo >= 0 && static_cast<int>(i) != options.only_photo) continue;
    if (!images[i] || images[i]->empty()) continue;
    for (int e = 0; e < 2; ++e) {
      const Vec3 c = frame.to_scan(parts.placement.eye_center[e]);
      const Vec3 to_camera = (cameras[i].center() - c).normalized();
      const double angle = std::acos(std::clamp(to_camera.dot(forward), -1.0, 1.0)) * kDegPerRad;
      if (angle <= options.max_view_angle_deg) candidates.push_back({static_cast<int>(i), e, angle});
    }
  }
  std::sort(candidates.begin(), candidates.end(),
            [](const Candidate& a, const Candidate& b) { return a.angle_deg < b.angle_deg; });
  const std::string within = std::to_string(static_cast<int>(options.max_view_angle_deg)) + " deg of the front";
  if (candidates.empty() && options.only_photo >= 0)
    return Status::error(ErrorCode::NotAHead, photo_name(options.only_photo) +
                                                  " does not look at either eye from within " + within +
                                                  ": the generic iris is kept");
  if (candidates.empty())
    return Status::error(ErrorCode::NotAHead, "no photo looks at the eyes from within " + within +
                                                  ": the generic iris is kept");

  const int attempts = std::min<int>(options.max_attempts, static_cast<int>(candidates.size()));
  for (int k = 0; k < attempts; ++k) {
    const Candidate& cand = candidates[size_t(k)];
    const Camera& cam = cameras[size_t(cand.photo)];
    const Image& photo = *images[size_t(cand.photo)];
    const std::string where = eye_name(cand.eye) + " in " + photo_name(cand.photo);
    const Vec3 centre = frame.to_scan(parts.placement.eye_center[cand.eye]);
    // The eyeball's radius in pixels, across the line of sight.
    const Vec3 side = frame.to_scan(parts.placement.eye_center[cand.eye] + Vec3(parts.placement.eye_radius[cand.eye], 0, 0));
    Vec2 p, q;
    if (!cam.project(centre, p) || !cam.project(side, q)) {
      out.tried.push_back(where + ": behind the camera");
      continue;
    }
    const double eyeball_px = (q - p).norm();
    const double iris_px = 0.5 * eyeball_px;  // about: an iris is half the eyeball's diameter across
    if (iris_px < options.min_iris_radius_px) {
      out.tried.push_back(where + ": the iris is about " + std::to_string(static_cast<int>(std::lround(iris_px))) +
                          " px across its radius, too small");
      continue;
    }
    // A close-up of the eye: lids, corners and some skin around the iris.
    const int half = static_cast<int>(std::ceil(2.2 * eyeball_px));
    const int x0 = static_cast<int>(std::lround(p.x())) - half, y0 = static_cast<int>(std::lround(p.y())) - half;
    const Image closeup = crop(photo, x0, y0, 2 * half + 1);
    const Vec2 offset(std::max(0, x0), std::max(0, y0));
    if (closeup.width < half || closeup.height < half) {
      out.tried.push_back(where + ": the eye is at the photo's edge");
      continue;
    }
    const Vec2 guess = p - offset;
    // The limbus near the eyeball's place: an iris is about half the
    // eyeball's diameter across; the search allows for the eyeball's
    // placement and size being off by a third.
    IrisCircle circle;
    if (Status s = find_iris_near(closeup, guess, 0.35 * eyeball_px, 0.3 * eyeball_px, 0.8 * eyeball_px, circle); !s) {
      out.tried.push_back(where + ": " + s.message);
      continue;
    }
    // The iris as large on the eyeball as in the photo (its angular radius
    // seen from the eyeball's centre), within the range of real eyes.
    EyeballTextureOptions texture_options;
    texture_options.iris_angle_deg = std::clamp(std::asin(std::min(1.0, circle.radius / eyeball_px)) * kDegPerRad,
                                                options.min_iris_angle_deg, options.max_iris_angle_deg);
    IrisResult iris;
    if (Status s = iris_texture_from_circle(closeup, circle, iris, texture_options); !s) {
      out.tried.push_back(where + ": " + s.message);
      continue;
    }
    out.texture = std::move(iris.texture);
    out.photo = cand.photo;
    out.eye = cand.eye;
    out.circle = iris.circle;
    out.circle.center += offset;
    out.view_angle_deg = cand.angle_deg;
    out.iris_angle_deg = texture_options.iris_angle_deg;
    return Status::success();
  }
  std::string why;
  for (const std::string& t : out.tried) why += (why.empty() ? "" : "; ") + t;
  return Status::error(ErrorCode::NotAHead, "no iris found in the photos (" + why + "): the generic iris is kept");
}

Status find_project_iris(HeadProject& project, const GenericHead& generic, const std::vector<const Image*>& images,
                         const std::vector<Camera>& cameras, const std::vector<std::string>& names,
                         EyeFromViewsResult& out, const EyeFromViewsOptions& options) {
  const Status s = eye_texture_from_views(project.fit.control, generic, project.frame, images, cameras, names, options, out);
  if (s.ok()) {
    project.parts.eye_texture = out.texture;
    project.parts.eye_source = size_t(out.photo) < names.size() ? names[size_t(out.photo)] : "";
  }
  return s;
}

int find_photo_name(const std::vector<std::string>& names, const std::string& name) {
  const auto stem = [](const std::string& n) {
    const size_t slash = n.find_last_of("/\\");
    std::string s = slash == std::string::npos ? n : n.substr(slash + 1);
    const size_t dot = s.find_last_of('.');
    return dot == std::string::npos || dot == 0 ? s : s.substr(0, dot);
  };
  for (size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) return static_cast<int>(i);
  for (size_t i = 0; i < names.size(); ++i)
    if (stem(names[i]) == stem(name)) return static_cast<int>(i);
  return -1;
}

}  // namespace lk
