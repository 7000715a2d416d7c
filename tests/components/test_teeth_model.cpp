// The paper's teeth model (tarini2002 Sec. 4.2, Fig. 7): a billboard for the
// six front teeth, 3-D side teeth, a smooth transition, and uvs that put the
// photo's teeth (teeth_composite_generic) on the billboard. Thickness is
// measured by casting rays through the mesh, not read from the generator.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

#include "components/components.h"
#include "teeth/synthetic_smile.h"
#include "teeth/teeth.h"

namespace {

// Distances along the ray to every triangle it crosses (Moller-Trumbore).
std::vector<double> hits(const lk::TriMesh& m, const lk::Vec3& o, const lk::Vec3& d) {
  std::vector<double> t_hits;
  for (const lk::Tri& tri : m.triangles) {
    const lk::Vec3 a = m.positions[static_cast<size_t>(tri[0])], b = m.positions[static_cast<size_t>(tri[1])],
                   c = m.positions[static_cast<size_t>(tri[2])];
    const lk::Vec3 e1 = b - a, e2 = c - a, p = d.cross(e2);
    const double det = e1.dot(p);
    if (std::abs(det) < 1e-14) continue;
    const lk::Vec3 s = o - a;
    const double u = s.dot(p) / det;
    if (u < 0 || u > 1) continue;
    const lk::Vec3 q = s.cross(e1);
    const double v = d.dot(q) / det;
    if (v < 0 || u + v > 1) continue;
    const double t = e2.dot(q) / det;
    if (t > 0) t_hits.push_back(t);
  }
  std::sort(t_hits.begin(), t_hits.end());
  // A ray through a shared edge hits both triangles: merge equal distances.
  t_hits.erase(std::unique(t_hits.begin(), t_hits.end(), [](double x, double y) { return std::abs(x - y) < 1e-9; }),
               t_hits.end());
  return t_hits;
}

// Point on the upper arch's front curve at normalized arc length s, and its
// outward normal, by integrating the parabola independently of the model.
void arch_point(double depth, double s, lk::Vec3& p, lk::Vec3& n) {
  const int steps = 20000;
  auto at = [&](double x) { return lk::Vec3(x, 0, -depth * 4 * x * x); };
  double total = 0;
  for (int i = 0; i < steps; ++i) total += (at(-0.5 + (i + 1.0) / steps) - at(-0.5 + double(i) / steps)).norm();
  double acc = 0, x = -0.5;
  for (int i = 0; i < steps && acc < s * total; ++i) {
    acc += (at(-0.5 + (i + 1.0) / steps) - at(-0.5 + double(i) / steps)).norm();
    x = -0.5 + (i + 1.0) / steps;
  }
  p = at(x);
  const lk::Vec3 t = lk::Vec3(1, 0, -depth * 8 * x).normalized();
  n = lk::Vec3(-t.z(), 0, t.x());
}

// Thickness of the upper teeth at arc length s and height fraction f: the
// distance between the first two surfaces a ray from outside meets.
double thickness_at(const lk::TeethModel& model, const lk::TeethModelOptions& o, double s, double f, int* count = nullptr) {
  lk::Vec3 p, n;
  arch_point(o.depth, s, p, n);
  p.y() = f * o.upper_height;
  const std::vector<double> t = hits(model.mesh, p + 0.2 * n, -n);
  if (count) *count = static_cast<int>(t.size());
  return t.size() >= 2 ? t[1] - t[0] : 0.0;
}

}  // namespace

TEST_CASE("teeth model: billboard in the middle, 3-D side teeth, smooth transition", "[components][teeth_model]") {
  const lk::TeethModelOptions o;
  const lk::TeethModel model = lk::make_teeth_model(o);
  const lk::TriMesh& m = model.mesh;
  REQUIRE(m.uvs.size() == m.positions.size());
  REQUIRE(model.part.size() == m.triangles.size());
  for (const lk::Vec2& uv : m.uvs) {
    CHECK(uv.x() >= 0);
    CHECK(uv.x() <= 1);
    CHECK(uv.y() >= 0);
    CHECK(uv.y() <= 1);
  }
  int parts[3] = {0, 0, 0};
  for (lk::TeethPart p : model.part) ++parts[static_cast<int>(p)];
  CHECK(parts[0] > 0);
  CHECK(parts[1] > 0);
  CHECK(parts[2] > 0);

  // The central incisors' lower half is a single sheet: a ray meets one
  // surface (the billboard), nothing behind it within the arch.
  int count = -1;
  CHECK(thickness_at(model, o, 0.5, 0.25, &count) == 0.0);
  CHECK(count == 1);
  // Their upper part gains width towards the gum end.
  const double t_root = thickness_at(model, o, 0.5, 0.95, &count);
  CHECK(count == 2);
  CHECK(t_root > 0.5 * o.root_thickness);
  CHECK(t_root < 1.2 * o.root_thickness);
  // A side tooth is a volume of the side thickness (measured along the
  // normal of the bent arch: within 10 %).
  const double t_side = thickness_at(model, o, 0.08, 0.3, &count);
  CHECK(count == 2);
  CHECK(std::abs(t_side / o.side_thickness - 1) < 0.1);
  // Smooth transition: along the arch at the billboard height, the
  // thickness grows from 0 to the side thickness without jumps.
  double previous = thickness_at(model, o, 0.5, 0.25), max_jump = 0;
  for (double s = 0.5; s >= 0.06; s -= 0.005) {
    const double t = thickness_at(model, o, s, 0.25);
    max_jump = std::max(max_jump, std::abs(t - previous));
    previous = t;
  }
  INFO("largest thickness step between arc-length samples 0.005 apart: " << max_jump);
  CHECK(previous > 0.9 * o.side_thickness);
  CHECK(max_jump < 0.2 * o.side_thickness);

  // Texture coordinates: u is the normalized arc length (the front six
  // teeth get the middle middle_width of it), v = 0.5 at the bite.
  for (size_t i = 0; i < m.positions.size(); ++i) {
    const lk::Vec3& q = m.positions[i];
    // Upper arch only (at y = 0 both arches meet the bite plane).
    if (q.y() < 1e-9 || std::abs(m.uvs[i].y() - (0.5 + 0.5 * q.y() / o.upper_height)) > 1e-9) continue;
    lk::Vec3 p, n;
    arch_point(o.depth, m.uvs[i].x(), p, n);
    const lk::Vec3 front(q.x(), 0, q.z());
    // Front-sheet vertices lie on the curve at their u; back ones behind it.
    const double along = (front - p).dot(n);
    CHECK(std::abs((front - p - along * n).norm()) < 2e-3);
    CHECK(along < 1e-3);
    CHECK(along > -o.side_thickness - 1e-3);
  }
  // The lower arch sits behind the upper one at the middle.
  const std::vector<double> upper = hits(m, lk::Vec3(0, 0.5 * o.upper_height, 1), lk::Vec3(0, 0, -1));
  const std::vector<double> lower = hits(m, lk::Vec3(0, -0.5 * o.lower_height, 1), lk::Vec3(0, 0, -1));
  REQUIRE(!upper.empty());
  REQUIRE(!lower.empty());
  CHECK(lower[0] > upper[0] + 0.5 * o.lower_inset);
}

TEST_CASE("teeth model: the composited smile texture puts teeth on the billboard", "[components][teeth_model]") {
  // A synthetic smile -> teeth texture -> generic composite; then look the
  // texture up at the model's uvs.
  lk::SyntheticSmileOptions so;
  so.width = 480;
  so.height = 240;
  const lk::SyntheticSmile smile = lk::make_synthetic_smile(so);
  lk::TeethResult r;
  const lk::TeethOptions to;
  REQUIRE(lk::teeth_texture_from_photo(smile.image, to, r).ok());
  CHECK(std::abs(r.bite_row - smile.bite_row) <= 2);
  lk::Image tex;
  lk::TeethCompositeOptions co;
  REQUIRE(lk::teeth_composite_generic(r, to, co, tex).ok());
  const lk::TeethModelOptions o;
  REQUIRE(o.middle_width == co.middle_width);  // one layout
  auto texel = [&](const lk::Vec2& uv) {
    const int x = std::clamp(static_cast<int>(uv.x() * tex.width), 0, tex.width - 1);
    const int y = std::clamp(static_cast<int>((1 - uv.y()) * tex.height), 0, tex.height - 1);  // OBJ v: up
    return tex.at(x, y);
  };
  // The billboard's middle, a quarter up the upper and lower teeth: an
  // opaque, bright tooth texel (at u = 0.5 + 0.02, off the central gap).
  for (double v : {0.5 + 0.5 * 0.3, 0.5 - 0.5 * 0.3}) {
    const std::uint8_t* p = texel(lk::Vec2(0.52, v));
    INFO("v " << v << ": " << int(p[0]) << "," << int(p[1]) << "," << int(p[2]) << "," << int(p[3]));
    CHECK(p[3] == 255);
    CHECK(p[1] > 150);
  }
  // The bite line between the arches is a void: transparent.
  CHECK(texel(lk::Vec2(0.52, 0.5))[3] == 0);
  // The gum ends (v = 1 and 0) are gum coloured (red dominant), not teeth.
  for (double v : {0.99, 0.01}) {
    const std::uint8_t* p = texel(lk::Vec2(0.52, v));
    CHECK(p[0] > p[1] + 40);
  }
}
