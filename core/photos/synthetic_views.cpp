#include "photos/synthetic_views.h"

#include "common/prng.h"
#include "raycast/bvh.h"
#include "texture/synthetic_photo.h"

#include <cmath>
#include <cstdio>
#include <limits>

namespace lk {
namespace {

constexpr double kPi = 3.14159265358979323846;

Vec3 face_center(const GenericHead& head) {
  auto it = head.annotations.regions.find("face");
  Vec3 c = Vec3::Zero();
  int n = 0;
  if (it != head.annotations.regions.end())
    for (int v : it->second)
      if (v >= 0 && v < head.mesh.num_vertices()) { c += head.mesh.positions[size_t(v)]; ++n; }
  if (n == 0) {
    for (const Vec3& p : head.mesh.positions) c += p;
    n = std::max(1, head.mesh.num_vertices());
  }
  return c / double(n);
}

// Visible from camera centre C: facing it and nothing in between.
bool visible(const MeshBvh& bvh, const Vec3& X, const Vec3& normal, int triangle, const Vec3& C) {
  if ((C - X).dot(normal) <= 0) return false;
  Ray ray;
  ray.origin = X;
  ray.direction = C - X;
  ray.t_min = 1e-6;
  ray.t_max = 1.0;
  return !intersect_any(bvh, ray, triangle);
}

Vec3 triangle_normal(const TriMesh& m, int f) {
  const Tri& t = m.triangles[size_t(f)];
  return (m.positions[size_t(t[1])] - m.positions[size_t(t[0])])
      .cross(m.positions[size_t(t[2])] - m.positions[size_t(t[0])])
      .normalized();
}

}  // namespace

Status placeholder_landmark_map(const GenericHead& generic, int count, LandmarkMap& out) {
  out = {};
  out.detector = kPlaceholderDetector;
  auto it = generic.annotations.regions.find("face");
  if (it == generic.annotations.regions.end() || count < 6)
    return Status::error(ErrorCode::InvalidInput, "placeholder map: no face region, or count < 6");
  MeshBvh bvh;
  Status s = build_bvh(generic.mesh, bvh);
  if (!s) return s;
  const Vec3 look = generic.annotations.look.normalized();
  const Vec3 C = face_center(generic) + 1.0 * look;
  // Vertex normals (area-weighted) for the facing test.
  std::vector<Vec3> vn(size_t(generic.mesh.num_vertices()), Vec3::Zero());
  for (const Tri& t : generic.mesh.triangles) {
    const Vec3 n = (generic.mesh.positions[size_t(t[1])] - generic.mesh.positions[size_t(t[0])])
                       .cross(generic.mesh.positions[size_t(t[2])] - generic.mesh.positions[size_t(t[0])]);
    for (int v : t) vn[size_t(v)] += n;
  }
  std::vector<int> candidates;
  for (int v : it->second) {
    const Vec3& X = generic.mesh.positions[size_t(v)];
    if (vn[size_t(v)].norm() == 0 || vn[size_t(v)].normalized().dot(look) < 0.2) continue;
    Ray ray;
    ray.origin = X;
    ray.direction = C - X;
    ray.t_min = 1e-4;
    ray.t_max = 1.0;
    if (!intersect_any(bvh, ray)) candidates.push_back(v);
  }
  if (int(candidates.size()) < 6) return Status::error(ErrorCode::InvalidInput, "placeholder map: too few face vertices");
  // Farthest-point sampling, starting from the vertex nearest the face centre.
  const Vec3 fc = face_center(generic);
  std::vector<double> dist(candidates.size(), std::numeric_limits<double>::infinity());
  size_t pick = 0;
  for (size_t i = 1; i < candidates.size(); ++i)
    if ((generic.mesh.positions[size_t(candidates[i])] - fc).norm() <
        (generic.mesh.positions[size_t(candidates[pick])] - fc).norm())
      pick = i;
  const int n = std::min(count, int(candidates.size()));
  for (int k = 0; k < n; ++k) {
    const Vec3& X = generic.mesh.positions[size_t(candidates[pick])];
    out.points.push_back(X);
    out.present.push_back(1);
    dist[pick] = -1;
    size_t next = pick;
    double best = -1;
    for (size_t i = 0; i < candidates.size(); ++i) {
      if (dist[i] < 0) continue;
      dist[i] = std::min(dist[i], (generic.mesh.positions[size_t(candidates[i])] - X).norm());
      if (dist[i] > best) { best = dist[i]; next = i; }
    }
    pick = next;
  }
  // Unfilled indices (fewer face vertices than count) stay null.
  out.points.resize(size_t(count), Vec3::Zero());
  out.present.resize(size_t(count), 0);
  return Status::success();
}

Status make_synthetic_views(const GenericHead& head, const std::vector<SurfacePoint>& landmarks,
                            std::uint32_t seed, const SyntheticViewsOptions& o, SyntheticSession& out) {
  out = {};
  if (o.num_cameras < 1 || o.width < 16 || o.height < 16 || !(o.focal_px > 0) || !(o.distance_m > 0) ||
      !(o.noise_px >= 0))
    return Status::error(ErrorCode::InvalidInput, "synthetic views: an option is out of range");
  for (const SurfacePoint& p : landmarks)
    if (p.valid() && p.triangle >= head.mesh.num_triangles())
      return Status::error(ErrorCode::InvalidInput, "synthetic views: a landmark's triangle is out of range");
  MeshBvh bvh;
  Status s = build_bvh(head.mesh, bvh);
  if (!s) return s;
  const Vec3 look = head.annotations.look.normalized();
  const Vec3 up0 = head.annotations.up.normalized();
  const Vec3 side = up0.cross(look).normalized();
  const Vec3 up = look.cross(side);
  const Vec3 target = face_center(head);
  SplitMix64 rng(hash_mix(seed, 0x70686f746f73ull));
  for (int c = 0; c < o.num_cameras; ++c) {
    const double a = o.num_cameras == 1 ? 0.0 : (-1.0 + 2.0 * c / (o.num_cameras - 1)) * o.azimuth_deg;
    const double e = (c % 2 ? -1.0 : 1.0) * o.elevation_deg * rng.uniform(0.5, 1.0);
    const double d = o.distance_m * rng.uniform(0.9, 1.1);
    const double az = a * kPi / 180, el = e * kPi / 180;
    const Vec3 dir = std::cos(el) * (std::sin(az) * side + std::cos(az) * look) + std::sin(el) * up;
    const Vec3 aim = target + Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)) * 0.01;
    Camera cam = look_at_camera(target + d * dir, aim, up, o.focal_px, o.width, o.height);
    const double roll = rng.uniform(-1, 1) * o.roll_deg * kPi / 180;
    cam.R = Eigen::AngleAxisd(roll, Vec3::UnitZ()).toRotationMatrix() * cam.R;
    cam.t = Eigen::AngleAxisd(roll, Vec3::UnitZ()).toRotationMatrix() * cam.t;
    out.cameras.push_back(cam);

    LandmarkPhoto ph;
    char name[32];
    std::snprintf(name, sizeof name, "view_%02d.png", c);
    ph.name = name;
    ph.width = o.width;
    ph.height = o.height;
    ph.detector = kPlaceholderDetector;
    ph.points.assign(landmarks.size(), Vec2::Zero());
    ph.present.assign(landmarks.size(), 0);
    const Vec3 C = cam.center();
    for (size_t m = 0; m < landmarks.size(); ++m) {
      const double nu = rng.gaussian(), nv = rng.gaussian();  // drawn for every index: stable noise
      if (!landmarks[m].valid()) continue;
      const Vec3 X = surface_position(head.mesh, landmarks[m]);
      if (!visible(bvh, X, triangle_normal(head.mesh, landmarks[m].triangle), landmarks[m].triangle, C)) continue;
      Vec2 uv;
      if (!cam.project(X, uv)) continue;
      uv += o.noise_px * Vec2(nu, nv);
      if (uv.x() < 0 || uv.y() < 0 || uv.x() > o.width || uv.y() > o.height) continue;
      ph.points[m] = uv;
      ph.present[m] = 1;
    }
    out.photos.push_back(ph);
  }
  return Status::success();
}

}  // namespace lk
