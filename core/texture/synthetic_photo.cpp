#include "texture/synthetic_photo.h"

#include "mesh/geometry.h"
#include "texture/color.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace lk {

Camera look_at_camera(const Vec3& eye, const Vec3& target, const Vec3& up, double focal, int width, int height) {
  // Camera axes in world: z forward, x right, y down (image rows).
  const Vec3 z = (target - eye).normalized();
  const Vec3 x = z.cross(up).normalized();
  const Vec3 y = z.cross(x);
  Camera cam;
  cam.R.row(0) = x.transpose();
  cam.R.row(1) = y.transpose();
  cam.R.row(2) = z.transpose();
  cam.t = -cam.R * eye;
  cam.fx = cam.fy = focal;
  cam.cx = width / 2.0;
  cam.cy = height / 2.0;
  cam.width = width;
  cam.height = height;
  return cam;
}

Vec3 procedural_color_field(const Vec3& p, double scale) {
  // Sums of sines along skewed directions: no axis-aligned structure that a
  // chart could reproduce by accident, detail at 1x, 2.7x and 8x the scale.
  const double s = 2 * 3.14159265358979323846 / scale;
  const double a = std::sin(s * (0.8 * p.x() + 0.5 * p.y() - 0.3 * p.z()));
  const double b = std::sin(s / 2.7 * (-0.4 * p.x() + 0.9 * p.y() + 0.2 * p.z()) + 1.3);
  const double c = std::sin(s / 8.0 * (0.3 * p.x() - 0.2 * p.y() + 0.9 * p.z()) + 0.4);
  const double d = std::sin(s / 8.0 * (0.9 * p.x() + 0.1 * p.y() + 0.4 * p.z()) + 2.1);
  Vec3 rgb(0.45 + 0.12 * a + 0.10 * c + 0.08 * d, 0.30 + 0.10 * b + 0.08 * c - 0.05 * a,
           0.25 + 0.08 * b + 0.10 * d + 0.04 * a);
  return rgb.cwiseMax(0.02).cwiseMin(0.98);
}

Status render_synthetic_photo(const TriMesh& mesh, const Camera& camera, const SurfaceColorFn& color,
                              const Vec3& background, Image& photo, const std::vector<SyntheticSphere>& spheres) {
  const int w = camera.width, h = camera.height;
  if (w <= 0 || h <= 0) return Status::error(ErrorCode::InvalidInput, "synthetic photo: camera has no image size");
  std::string why;
  if (!is_valid(mesh, &why)) return Status::error(ErrorCode::InvalidInput, "synthetic photo: " + why);
  for (const SyntheticSphere& sp : spheres)
    if (!(sp.radius > 0) || !sp.color || !sp.center.allFinite())
      return Status::error(ErrorCode::InvalidInput, "synthetic photo: a sphere needs a centre, radius and colour");
  const std::vector<Vec3> normals = vertex_normals(mesh);
  // Per pixel: nearest depth, its triangle and perspective-correct weights.
  std::vector<float> depth(static_cast<size_t>(w) * h, std::numeric_limits<float>::infinity());
  std::vector<int> tri(static_cast<size_t>(w) * h, -1);
  std::vector<Vec3> cam_pos(mesh.positions.size());
  std::vector<Vec2> px(mesh.positions.size());
  std::vector<char> front(mesh.positions.size());
  for (size_t v = 0; v < mesh.positions.size(); ++v) {
    cam_pos[v] = camera.to_camera(mesh.positions[v]);
    front[v] = cam_pos[v].z() > 1e-9;
    if (front[v])
      px[v] = Vec2(camera.fx * cam_pos[v].x() / cam_pos[v].z() + camera.cx,
                   camera.fy * cam_pos[v].y() / cam_pos[v].z() + camera.cy);
  }
  for (int f = 0; f < mesh.num_triangles(); ++f) {
    const Tri& t = mesh.triangles[f];
    if (!front[t[0]] || !front[t[1]] || !front[t[2]]) continue;  // clipped (none in our scenes)
    const Vec2 &a = px[t[0]], &b = px[t[1]], &c = px[t[2]];
    const double area = (b - a).x() * (c - a).y() - (c - a).x() * (b - a).y();
    if (std::abs(area) < 1e-12) continue;
    const int x0 = std::max(0, static_cast<int>(std::floor(std::min({a.x(), b.x(), c.x()}))));
    const int x1 = std::min(w - 1, static_cast<int>(std::ceil(std::max({a.x(), b.x(), c.x()}))));
    const int y0 = std::max(0, static_cast<int>(std::floor(std::min({a.y(), b.y(), c.y()}))));
    const int y1 = std::min(h - 1, static_cast<int>(std::ceil(std::max({a.y(), b.y(), c.y()}))));
    const double iz0 = 1 / cam_pos[t[0]].z(), iz1 = 1 / cam_pos[t[1]].z(), iz2 = 1 / cam_pos[t[2]].z();
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        const Vec2 p(x + 0.5, y + 0.5);
        const double l1 = ((p - a).x() * (c - a).y() - (c - a).x() * (p - a).y()) / area;
        const double l2 = ((b - a).x() * (p - a).y() - (p - a).x() * (b - a).y()) / area;
        const double l0 = 1 - l1 - l2;
        if (l0 < 0 || l1 < 0 || l2 < 0) continue;
        const double z = 1 / (l0 * iz0 + l1 * iz1 + l2 * iz2);
        const size_t i = static_cast<size_t>(y) * w + x;
        if (z >= depth[i]) continue;
        depth[i] = static_cast<float>(z);
        tri[i] = f;
      }
    }
  }
  photo = Image::make(w, h, 3);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const size_t i = static_cast<size_t>(y) * w + x;
      Vec3 rgb = background;
      const Vec3 dir_cam((x + 0.5 - camera.cx) / camera.fx, (y + 0.5 - camera.cy) / camera.fy, 1.0);
      const Vec3 eye = camera.center();
      const Vec3 dir = camera.R.transpose() * dir_cam;
      // The nearest sphere in front of the triangles (dir's camera z is 1,
      // so the ray parameter is the depth the z-buffer holds).
      const SyntheticSphere* hit = nullptr;
      double hit_s = depth[i];
      for (const SyntheticSphere& sp : spheres) {
        const Vec3 oc = eye - sp.center;
        const double a = dir.squaredNorm(), b = oc.dot(dir), c = oc.squaredNorm() - sp.radius * sp.radius;
        const double disc = b * b - a * c;
        if (disc < 0) continue;
        const double s = (-b - std::sqrt(disc)) / a;
        if (s > 1e-9 && s < hit_s) hit = &sp, hit_s = s;
      }
      if (hit) {
        const Vec3 P = eye + hit_s * dir;
        rgb = hit->color(P, (P - hit->center).normalized());
      } else if (tri[i] >= 0) {
        // The exact surface point: the pixel's ray meets the triangle's plane.
        const Tri& t = mesh.triangles[tri[i]];
        const Vec3 &A = mesh.positions[t[0]], &B = mesh.positions[t[1]], &C = mesh.positions[t[2]];
        const Vec3 n = (B - A).cross(C - A);
        const double denom = n.dot(dir);
        const double s = std::abs(denom) > 1e-300 ? n.dot(A - eye) / denom : depth[i];
        const Vec3 P = eye + s * dir;
        // Barycentric weights of P for the normal.
        const double area2 = n.squaredNorm();
        const double wa = n.dot((B - P).cross(C - P)) / area2, wb = n.dot((C - P).cross(A - P)) / area2;
        Vec3 normal = wa * normals[t[0]] + wb * normals[t[1]] + (1 - wa - wb) * normals[t[2]];
        if (normal.norm() > 0) normal.normalize();
        rgb = color(P, normal);
      }
      std::uint8_t* o = photo.at(x, y);
      for (int k = 0; k < 3; ++k) o[k] = linear_to_srgb8(static_cast<float>(rgb[k]));
    }
  }
  return Status::success();
}

}  // namespace lk
