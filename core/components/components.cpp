// Generic component meshes and their placement (Tarini et al. 2002, Sec. 4).
#include "components/components.h"

#include <cmath>

namespace lk {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Centroid and mean distance to it of a vertex set.
bool set_frame(const TriMesh& m, const std::vector<int>& ids, Vec3& centroid, double& size) {
  if (ids.empty()) return false;
  centroid.setZero();
  for (int i : ids) {
    if (i < 0 || i >= static_cast<int>(m.positions.size())) return false;
    centroid += m.positions[static_cast<size_t>(i)];
  }
  centroid /= static_cast<double>(ids.size());
  size = 0;
  for (int i : ids) size += (m.positions[static_cast<size_t>(i)] - centroid).norm();
  size /= static_cast<double>(ids.size());
  return size > 0 && std::isfinite(size);
}

void transform(TriMesh& m, const Vec3& scale, const Vec3& offset) {
  for (Vec3& p : m.positions) p = p.cwiseProduct(scale) + offset;
  for (Vec3& n : m.normals) n = n.cwiseQuotient(scale).normalized();
}

}  // namespace

TriMesh make_eyeball(int rings, int segments) {
  TriMesh m;
  rings = std::max(rings, 4);
  segments = std::max(segments, 6);
  // theta from the front axis (+z): ring 0 is the front pole.
  m.positions.push_back(Vec3(0, 0, 1));
  m.normals.push_back(Vec3(0, 0, 1));
  m.uvs.push_back(Vec2(0.5, 0.5));
  for (int r = 1; r < rings; ++r) {
    const double theta = kPi * r / rings;
    for (int s = 0; s < segments; ++s) {
      const double phi = 2 * kPi * s / segments;
      const Vec3 d(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
      m.positions.push_back(d);
      m.normals.push_back(d);
      const double rho = std::min(1.0, theta / (kPi / 2));
      m.uvs.push_back(Vec2(0.5 + 0.5 * rho * std::cos(phi), 0.5 - 0.5 * rho * std::sin(phi)));
    }
  }
  const int back = static_cast<int>(m.positions.size());
  m.positions.push_back(Vec3(0, 0, -1));
  m.normals.push_back(Vec3(0, 0, -1));
  m.uvs.push_back(Vec2(1.0, 0.5));  // sclera
  auto v = [&](int r, int s) { return 1 + (r - 1) * segments + (s % segments); };
  for (int s = 0; s < segments; ++s) m.triangles.push_back({0, v(1, s), v(1, s + 1)});
  for (int r = 1; r + 1 < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      m.triangles.push_back({v(r, s), v(r + 1, s), v(r + 1, s + 1)});
      m.triangles.push_back({v(r, s), v(r + 1, s + 1), v(r, s + 1)});
    }
  for (int s = 0; s < segments; ++s) m.triangles.push_back({v(rings - 1, s), back, v(rings - 1, s + 1)});
  return m;
}

TriMesh make_teeth_arch(int segments) {
  TriMesh m;
  segments = std::max(segments, 4);
  // Each arch: a closed band (front, bottom/top edge, back) of thickness t
  // along the parabola z = -depth * (2x)^2.
  const double depth = 0.6, height = 0.35, t = 0.06;
  for (int arch = 0; arch < 2; ++arch) {  // 0 upper, 1 lower
    const double y0 = arch == 0 ? 0.0 : -height, y1 = arch == 0 ? height : 0.0;
    const int base = static_cast<int>(m.positions.size());
    for (int i = 0; i <= segments; ++i) {
      const double x = -0.5 + static_cast<double>(i) / segments;
      const double z = -depth * 4 * x * x;
      const Vec3 tangent = Vec3(1, 0, -depth * 8 * x).normalized();
      const Vec3 out = Vec3(-tangent.z(), 0, tangent.x()) * -1.0;  // points forward/outwards
      const Vec3 front(x, 0, z), backp = front - t * (out.z() < 0 ? -out : out);
      const double u = static_cast<double>(i) / segments;
      // Ring of 4 vertices: front-top, front-bottom, back-bottom, back-top.
      const Vec3 ring[4] = {Vec3(front.x(), y1, front.z()), Vec3(front.x(), y0, front.z()),
                            Vec3(backp.x(), y0, backp.z()), Vec3(backp.x(), y1, backp.z())};
      for (int k = 0; k < 4; ++k) {
        m.positions.push_back(ring[k]);
        const double vv = arch == 0 ? (k == 0 || k == 3 ? 0.0 : 0.5) : (k == 0 || k == 3 ? 0.5 : 1.0);
        m.uvs.push_back(Vec2(u, vv));
      }
    }
    for (int i = 0; i < segments; ++i)
      for (int k = 0; k < 4; ++k) {
        const int a = base + i * 4 + k, b = base + i * 4 + (k + 1) % 4;
        const int c = a + 4, d = b + 4;
        m.triangles.push_back({a, b, d});
        m.triangles.push_back({a, d, c});
      }
  }
  return m;
}

TriMesh make_tongue(int rings, int segments) {
  TriMesh m = make_eyeball(std::max(rings, 4), std::max(segments, 6));
  // Flatten and stretch the sphere: 0.8 wide, 0.25 high, 1 long (along -z).
  for (Vec3& p : m.positions) p = Vec3(0.4 * p.x(), 0.125 * p.y(), 0.5 * p.z() - 0.5);
  m.normals.clear();
  m.uvs.clear();
  return m;
}

Status place_components(const GenericHead& fitted, const GenericHead& generic, ComponentPlacement& out) {
  if (fitted.mesh.positions.size() != generic.mesh.positions.size())
    return Status::error(ErrorCode::InvalidInput,
                         "the head does not share the generic head's topology (vertex counts differ)");
  const char* rims[2] = {"eye_rim_left", "eye_rim_right"};
  const EyeSocket* sockets[2] = {&generic.annotations.eye_left, &generic.annotations.eye_right};
  for (int e = 0; e < 2; ++e) {
    auto it = generic.annotations.regions.find(rims[e]);
    std::vector<int> ids = it != generic.annotations.regions.end() ? it->second : sockets[e]->rim;
    if (ids.empty()) ids = sockets[e]->rim;
    Vec3 cg, cf;
    double sg, sf;
    if (!set_frame(generic.mesh, ids, cg, sg) || !set_frame(fitted.mesh, ids, cf, sf))
      return Status::error(ErrorCode::InvalidInput, std::string("the head has no usable ") + rims[e] + " vertices");
    const double s = sf / sg;
    out.eye_center[e] = cf + s * (sockets[e]->center - cg);
    out.eye_radius[e] = s * sockets[e]->radius;
  }
  auto lips = generic.annotations.regions.find("lips");
  if (lips == generic.annotations.regions.end())
    return Status::error(ErrorCode::InvalidInput, "the head has no 'lips' vertex set");
  Vec3 cg, cf;
  double sg, sf;
  if (!set_frame(generic.mesh, lips->second, cg, sg) || !set_frame(fitted.mesh, lips->second, cf, sf))
    return Status::error(ErrorCode::InvalidInput, "the head's lip vertices are unusable");
  const double s = sf / sg;
  out.mouth_center = cf + s * (generic.annotations.mouth_center - cg);
  out.mouth_width = s * generic.annotations.mouth_width;
  return Status::success();
}

PlacedComponents build_placed_components(const ComponentPlacement& p) {
  PlacedComponents c;
  for (int e = 0; e < 2; ++e) {
    c.eye[e] = make_eyeball();
    transform(c.eye[e], Vec3::Constant(p.eye_radius[e]), p.eye_center[e]);
  }
  // Teeth: 90% of the mouth width, set back behind the lips by 10% of it.
  const double w = 0.9 * p.mouth_width;
  c.teeth = make_teeth_arch();
  transform(c.teeth, Vec3(w, w, w), p.mouth_center - Vec3(0, 0, 0.1 * p.mouth_width));
  c.tongue = make_tongue();
  transform(c.tongue, Vec3(0.8 * w, w, w), p.mouth_center - Vec3(0, 0.1 * w, 0.25 * p.mouth_width));
  return c;
}

}  // namespace lk
