// Generic component meshes and their placement (Tarini et al. 2002, Sec. 4).
#include "components/components.h"

#include "iris/iris.h"
#include "raycast/bvh.h"

#include <algorithm>
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
  const auto add = [&m](const Vec3& d) {
    m.positions.push_back(d);
    m.normals.push_back(d);
    m.uvs.push_back(eyeball_uv(d));
  };
  add(Vec3(0, 0, 1));
  for (int r = 1; r < rings; ++r) {
    const double theta = kPi * r / rings;
    for (int s = 0; s < segments; ++s) {
      const double phi = 2 * kPi * s / segments;
      add(Vec3(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)));
    }
  }
  const int back = static_cast<int>(m.positions.size());
  add(Vec3(0, 0, -1));  // uv on the rim: sclera
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

namespace {

double smoothstep(double a, double b, double x) {
  if (b <= a) return x < a ? 0.0 : 1.0;
  const double t = std::clamp((x - a) / (b - a), 0.0, 1.0);
  return t * t * (3 - 2 * t);
}

// x positions along z = -depth (2x)^2, x in [-0.5, 0.5], at the given
// normalized arc lengths (from a fine cumulative-length table).
std::vector<double> arc_length_to_x(double depth, const std::vector<double>& s_values) {
  const int n = 4096;
  std::vector<double> len(n + 1, 0.0);
  auto point = [&](int i) {
    const double x = -0.5 + static_cast<double>(i) / n;
    return Vec2(x, -depth * 4 * x * x);
  };
  for (int i = 1; i <= n; ++i) len[static_cast<size_t>(i)] = len[static_cast<size_t>(i - 1)] + (point(i) - point(i - 1)).norm();
  std::vector<double> xs;
  for (double sv : s_values) {
    const double target = std::clamp(sv, 0.0, 1.0) * len[static_cast<size_t>(n)];
    const auto it = std::lower_bound(len.begin(), len.end(), target);
    const int i = std::clamp(static_cast<int>(it - len.begin()), 1, n);
    const double l0 = len[static_cast<size_t>(i - 1)], l1 = len[static_cast<size_t>(i)];
    const double f = l1 > l0 ? (target - l0) / (l1 - l0) : 0.0;
    xs.push_back(-0.5 + (i - 1 + f) / n);
  }
  return xs;
}

}  // namespace

TeethModel make_teeth_model(const TeethModelOptions& o) {
  TeethModel model;
  TriMesh& m = model.mesh;
  const int segments = std::max(o.segments, 8), rows = std::max(o.rows, 2);
  const double mid = std::clamp(o.middle_width, 0.05, 0.95);
  // Rings uniform in arc length, plus the front/side boundaries exactly.
  std::vector<double> s_values;
  for (int i = 0; i <= segments; ++i) s_values.push_back(static_cast<double>(i) / segments);
  s_values.push_back(0.5 - mid / 2);
  s_values.push_back(0.5 + mid / 2);
  std::sort(s_values.begin(), s_values.end());
  s_values.erase(std::unique(s_values.begin(), s_values.end(), [](double a, double b) { return std::abs(a - b) < 1e-9; }),
                 s_values.end());
  const int rings = static_cast<int>(s_values.size());
  const std::vector<double> xs = arc_length_to_x(o.depth, s_values);

  auto add_quad = [&](int a, int b, int c, int d, const Vec3& outward, TeethPart part) {
    // Winding from the wanted outward direction, so every piece faces out.
    const Vec3 n = (m.positions[static_cast<size_t>(b)] - m.positions[static_cast<size_t>(a)])
                       .cross(m.positions[static_cast<size_t>(c)] - m.positions[static_cast<size_t>(a)]);
    if (n.dot(outward) >= 0) {
      m.triangles.push_back({a, b, c});
      m.triangles.push_back({a, c, d});
    } else {
      m.triangles.push_back({a, c, b});
      m.triangles.push_back({a, d, c});
    }
    model.part.push_back(part);
    model.part.push_back(part);
  };

  for (int arch = 0; arch < 2; ++arch) {  // 0 upper, 1 lower
    const double scale = arch == 0 ? 1.0 : o.lower_scale, back = arch == 0 ? 0.0 : o.lower_inset;
    const double height = arch == 0 ? o.upper_height : o.lower_height, up = arch == 0 ? 1.0 : -1.0;
    const int base = static_cast<int>(m.positions.size());
    std::vector<double> thickness(static_cast<size_t>(rings) * (rows + 1));
    std::vector<double> side(static_cast<size_t>(rings));
    std::vector<Vec3> outward(static_cast<size_t>(rings));
    // Front vertices [ring][row], then back vertices.
    for (int pass = 0; pass < 2; ++pass)
      for (int i = 0; i < rings; ++i) {
        const double x = xs[static_cast<size_t>(i)];
        const Vec3 p(scale * x, 0, scale * (-o.depth * 4 * x * x) - back);
        const Vec3 tangent = Vec3(1, 0, -o.depth * 8 * x).normalized();
        const Vec3 n(-tangent.z(), 0, tangent.x());  // +z at the front
        outward[static_cast<size_t>(i)] = n;
        const double s = s_values[static_cast<size_t>(i)];
        const double beyond = std::abs(s - 0.5) - mid / 2;  // < 0 inside the six front teeth
        const double sigma = smoothstep(-o.transition / 2, o.transition / 2, beyond);
        side[static_cast<size_t>(i)] = sigma;
        for (int j = 0; j <= rows; ++j) {
          const double f = static_cast<double>(j) / rows;
          const double t = o.side_thickness * sigma +
                           (1 - sigma) * o.root_thickness * smoothstep(o.billboard_fraction, 1.0, f);
          thickness[static_cast<size_t>(i) * (rows + 1) + j] = t;
          const Vec3 q = p + Vec3(0, up * f * height, 0) - (pass == 0 ? 0.0 : t) * n;
          m.positions.push_back(q);
          m.uvs.push_back(Vec2(s, 0.5 + 0.5 * up * f));
        }
      }
    auto F = [&](int i, int j) { return base + i * (rows + 1) + j; };
    auto B = [&](int i, int j) { return base + (rings + i) * (rows + 1) + j; };
    auto T = [&](int i, int j) { return thickness[static_cast<size_t>(i) * (rows + 1) + j]; };
    auto part_of = [&](double tmax, double sigma) {
      return tmax < 1e-12 ? TeethPart::Billboard : sigma < 0.5 ? TeethPart::FrontVolume : TeethPart::Side;
    };
    const Vec3 y_up(0, up, 0);
    auto copy = [&](int v) {
      m.positions.push_back(m.positions[static_cast<size_t>(v)]);
      m.uvs.push_back(m.uvs[static_cast<size_t>(v)]);
      return static_cast<int>(m.positions.size()) - 1;
    };
    for (int i = 0; i + 1 < rings; ++i) {
      const Vec3 n = (outward[static_cast<size_t>(i)] + outward[static_cast<size_t>(i + 1)]).normalized();
      const double sigma = 0.5 * (side[static_cast<size_t>(i)] + side[static_cast<size_t>(i + 1)]);
      for (int j = 0; j < rows; ++j) {
        const double tmax = std::max({T(i, j), T(i + 1, j), T(i, j + 1), T(i + 1, j + 1)});
        add_quad(F(i, j), F(i + 1, j), F(i + 1, j + 1), F(i, j + 1), n, part_of(tmax, sigma));
        // The back sheet only where the teeth have thickness (no second,
        // coincident sheet behind the billboard).
        if (tmax > 1e-12) add_quad(B(i, j), B(i, j + 1), B(i + 1, j + 1), B(i + 1, j), -n, part_of(tmax, sigma));
      }
      // Caps: the gum end and the bite edge, where there is thickness. Own
      // vertex copies, so the crown edges stay sharp in smooth shading.
      if (std::max(T(i, rows), T(i + 1, rows)) > 1e-12)
        add_quad(copy(F(i, rows)), copy(B(i, rows)), copy(B(i + 1, rows)), copy(F(i + 1, rows)), y_up, part_of(1, sigma));
      if (std::max(T(i, 0), T(i + 1, 0)) > 1e-12)
        add_quad(copy(F(i, 0)), copy(F(i + 1, 0)), copy(B(i + 1, 0)), copy(B(i, 0)), -y_up, part_of(1, sigma));
    }
    // The arch's two back ends: close the crown band's cross-section.
    for (int end = 0; end < 2; ++end) {
      const int i = end == 0 ? 0 : rings - 1;
      const double x = xs[static_cast<size_t>(i)];
      const Vec3 along = Vec3(1, 0, -o.depth * 8 * x).normalized() * (end == 0 ? -1.0 : 1.0);
      for (int j = 0; j < rows; ++j)
        if (std::max(T(i, j), T(i, j + 1)) > 1e-12)
          add_quad(copy(F(i, j)), copy(F(i, j + 1)), copy(B(i, j + 1)), copy(B(i, j)), along, TeethPart::Side);
    }
  }
  return model;
}

TriMesh make_tongue(int rings, int segments) {
  TriMesh m = make_eyeball(std::max(rings, 4), std::max(segments, 6));
  // Flatten and stretch the sphere: 0.8 wide, 0.25 high, 1 long (along -z).
  for (Vec3& p : m.positions) p = Vec3(0.4 * p.x(), 0.125 * p.y(), 0.5 * p.z() - 0.5);
  m.normals.clear();
  m.uvs.clear();
  return m;
}

namespace {

// The mouth of a head with the generic head's annotations: the slit between
// the lip lines' middle vertices, the width between their ends (the
// corners) and the rearmost z of the lines' other vertices.
struct MouthFrame {
  Vec3 slit = Vec3::Zero();
  double width = 0, back = 0;
};

bool mouth_frame(const GenericHead& head, MouthFrame& f) {
  const std::vector<int>* lines[2] = {nullptr, nullptr};
  for (const CreaseCurve& c : head.annotations.creases) {
    if (c.name == "upper_lip_line") lines[0] = &c.vertices;
    if (c.name == "lower_lip_line") lines[1] = &c.vertices;
  }
  if (!lines[0] || !lines[1] || lines[0]->size() < 3 || lines[0]->size() != lines[1]->size()) return false;
  const auto& P = head.mesh.positions;
  const int n = static_cast<int>(P.size());
  for (const auto* l : lines)
    for (int v : *l)
      if (v < 0 || v >= n || !P[static_cast<size_t>(v)].allFinite()) return false;
  const auto at = [&](int v) { return P[static_cast<size_t>(v)]; };
  const std::vector<int>& up = *lines[0];
  const std::vector<int>& low = *lines[1];
  const size_t mid = up.size() / 2;
  f.slit = 0.5 * (at(up[mid]) + at(low[mid]));
  f.width = (at(up.front()) - at(up.back())).norm();
  if (!(f.width > 0)) return false;
  f.back = 1e300;
  for (const auto* l : lines)
    for (size_t k = 1; k + 1 < l->size(); ++k) f.back = std::min(f.back, at((*l)[k]).z());
  return true;
}

// The placed teeth's frame (build_placed_components): the model's origin
// (the upper arch's front at the bite) and its width.
void teeth_frame(const ComponentPlacement& p, Vec3& origin, double& width) {
  width = 0.9 * p.mouth_width;
  origin = p.mouth_center - Vec3(0, 0, 0.1 * p.mouth_width);
}

// The least height an arch keeps (of the generic relation), whatever the
// skin in front: below it the crowns would vanish.
constexpr double kLeastTeethHeight = 0.3;
// The lips at the bite (within this share of an arch's height of it) are
// kept clear by the depth behind the lip lines instead.
constexpr double kBiteBand = 0.1;
// The skin's least depth in front of an arch, as a share of the generic
// head's least there: room for the lips' and the chin's inward travel
// under the shapes (mouthRollLower, viseme_PP).
constexpr double kClearance = 0.5;
// The skin's travel towards the arches' ends under the shapes (the
// mentalis lifts the chin), as a share of an arch's height: the skin is
// looked at that far beyond each arch's end, and an arch ends that far
// short of skin too close in front of it.
constexpr double kTravel = 0.4;
// Samples across and up each arch (skin_in_front).
constexpr int kSamples = 16;

// The skin around the mouth in front of each arch (0 upper, 1 lower),
// sampled on a grid over the arch's front (at the generic relation,
// teeth_height 1) and kTravel beyond its end, but for the band at the
// bite: at each sample (x, height) the outermost z of the triangles of the
// lip and chin regions outside the mouth bag there, as depth in front of
// the arch's front face (make_teeth_model's parabola at x; negative: the
// skin is behind it). Samples with no such triangle are left out.
using Room = std::vector<std::pair<double, double>>;  // (height, depth)

void skin_in_front(const GenericHead& head, const ComponentPlacement& p, Room room[2]) {
  const TeethModelOptions t;
  Vec3 o;
  double w = 0;
  teeth_frame(p, o, w);
  const auto& P = head.mesh.positions;
  std::vector<char> bag(P.size(), 0), skin(P.size(), 0);
  for (int v : head.annotations.constrained_vertices)
    if (v >= 0 && v < static_cast<int>(P.size())) bag[static_cast<size_t>(v)] = 1;
  for (const char* name : {"lips", "upper_lip", "lower_lip", "chin"}) {
    auto it = head.annotations.regions.find(name);
    if (it == head.annotations.regions.end()) continue;
    for (int v : it->second)
      if (v >= 0 && v < static_cast<int>(P.size())) skin[static_cast<size_t>(v)] = 1;
  }
  // The lip and chin triangles outside the bag, in the teeth's frame; the
  // outermost z at (x, y) is the first hit of a ray cast along -z from in
  // front of them all.
  TriMesh skin_mesh;
  skin_mesh.positions.reserve(P.size());
  for (const Vec3& q : P) skin_mesh.positions.push_back(q - o);
  for (const Tri& f : head.mesh.triangles) {
    if (f[0] < 0 || f[1] < 0 || f[2] < 0 || f[0] >= static_cast<int>(P.size()) || f[1] >= static_cast<int>(P.size()) ||
        f[2] >= static_cast<int>(P.size()))
      continue;
    bool any = false, inside = false;
    for (int k = 0; k < 3; ++k) any |= skin[static_cast<size_t>(f[k])] != 0, inside |= bag[static_cast<size_t>(f[k])] != 0;
    if (any && !inside) skin_mesh.triangles.push_back(f);
  }
  double front_z = 0;
  for (const Tri& f : skin_mesh.triangles)
    for (int k = 0; k < 3; ++k) front_z = std::max(front_z, skin_mesh.positions[static_cast<size_t>(f[k])].z());
  MeshBvh bvh;
  if (!build_bvh(skin_mesh, bvh).ok()) return;  // a non-finite vertex: no room measured
  for (int k = 0; k < 2; ++k) {
    const double half = 0.5 * w * (k ? t.lower_scale : 1.0);
    const double h = (k ? t.lower_height : t.upper_height) * w;
    for (int i = 0; i <= kSamples; ++i)
      for (int j = 0; j <= kSamples; ++j) {
        const double q = -0.9 + 1.8 * i / kSamples;  // across 90 % of the arch's width
        const double dy = h * (kBiteBand + (1 + kTravel - kBiteBand) * j / kSamples);
        const double x = q * half, y = k ? -dy : dy;
        Ray ray;
        ray.origin = Vec3(x, y, front_z + w);
        ray.direction = -Vec3::UnitZ();
        const RayHit hit = intersect_first(bvh, ray);
        if (!hit.hit()) continue;
        const double z = ray.origin.z() - hit.t;
        const double front = -(k ? t.lower_inset * w : 0.0) - t.depth * 2 * half * q * q;
        room[k].push_back({dy, z - front});
      }
  }
}

}  // namespace

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
  MouthFrame mg, mf;
  if (!mouth_frame(generic, mg) || !mouth_frame(fitted, mf))
    return Status::error(ErrorCode::InvalidInput, "the head's lip lines are missing or unusable");
  // Each measure of the mouth from its own fitted feature, keeping the
  // generic head's relation to it (so the generic head places exactly its
  // annotated mouth): across from the slit between the lips' middles, depth
  // from the lips' rearmost column (the teeth keep the generic clearance
  // behind the whole lip line, not only behind its middle), size from the
  // mouth's width.
  const double s = mf.width / mg.width;
  out.mouth_center = mf.slit + s * (generic.annotations.mouth_center - mg.slit);
  out.mouth_center.z() = mf.back + s * (generic.annotations.mouth_center.z() - mg.back);
  out.mouth_width = s * generic.annotations.mouth_width;
  // Each arch's height: it ends kTravel short of the first skin (lips,
  // chin) that comes within kClearance of the generic head's least depth
  // (over its own samples) of the arch's front face; a receding chin, e.g.
  // Demosthenes' bust, would otherwise meet the lower gums as it moves.
  ComponentPlacement pg;
  pg.mouth_center = generic.annotations.mouth_center;
  pg.mouth_width = generic.annotations.mouth_width;
  Room rg[2], rf[2];
  skin_in_front(generic, pg, rg);
  skin_in_front(fitted, out, rf);
  const TeethModelOptions t;
  for (int k = 0; k < 2; ++k) {
    double least = 1e300;
    for (const auto& [dy, depth] : rg[k]) least = std::min(least, depth);
    const double full = (k ? t.lower_height : t.upper_height) * 0.9 * out.mouth_width;
    double h = full;
    for (const auto& [dy, depth] : rf[k])
      if (depth < kClearance * s * least) h = std::min(h, dy - kTravel * full);
    out.teeth_height[k] = std::max(kLeastTeethHeight, h / full);
  }
  return Status::success();
}

PlacedComponents build_placed_components(const ComponentPlacement& p) {
  PlacedComponents c;
  for (int e = 0; e < 2; ++e) {
    c.eye[e] = make_eyeball();
    transform(c.eye[e], Vec3::Constant(p.eye_radius[e]), p.eye_center[e]);
  }
  // Teeth: 90% of the mouth width, set back behind the lips by 10% of it
  // (teeth_frame); each arch's height as place_components allows.
  Vec3 origin;
  double w = 0;
  teeth_frame(p, origin, w);
  c.teeth = make_teeth_model().mesh;
  for (Vec3& q : c.teeth.positions) q.y() *= q.y() > 0 ? p.teeth_height[0] : p.teeth_height[1];
  transform(c.teeth, Vec3(w, w, w), origin);
  c.tongue = make_tongue();
  transform(c.tongue, Vec3(0.8 * w, w, w), p.mouth_center - Vec3(0, 0.1 * w, 0.25 * p.mouth_width));
  return c;
}

}  // namespace lk
