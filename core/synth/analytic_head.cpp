#include "synth/analytic_head.h"

#include "mesh/geometry.h"

#include <algorithm>
#include <cmath>

namespace lk {

namespace {

constexpr double kPi = 3.14159265358979323846;
// Ellipsoid half-axes (x: width, y: height, z: depth), metres.
constexpr double kA = 0.078, kB = 0.115, kC = 0.098;

double gauss(double d, double sigma) { return std::exp(-0.5 * (d * d) / (sigma * sigma)); }

// The feature heights (metres, along the ellipsoid normal) at base point p.
struct Features {
  double nose = 0, ear_left = 0, ear_right = 0, other = 0;
};

Features features_at(const Vec3& p) {
  Features f;
  const double x = p.x(), y = p.y(), z = p.z();
  const double front = z > 0 ? std::min(1.0, z / 0.05) : 0.0;
  // Nose: a ridge from the root (y 0.015) growing to the tip (y -0.03), then a
  // steep underside, so a projector above the camera leaves a shadow below it.
  const double tip_y = -0.03;
  const double along = y > tip_y ? gauss(y - tip_y, 0.03) : gauss(y - tip_y, 0.007);
  f.nose = 0.022 * along * gauss(x, 0.009 + 0.004 * std::max(0.0, tip_y - y + 0.01) / 0.01) * front;
  // Ears: thin fins (super-Gaussian across their thickness) on the sides.
  auto ear = [&](double side) {
    if (side * x <= 0) return 0.0;
    const double dz = (z + 0.006) / 0.0045, dy = (y + 0.005) / 0.024;
    return 0.022 * std::exp(-dz * dz * dz * dz) * std::exp(-dy * dy * dy * dy) *
           std::min(1.0, side * x / 0.05);
  };
  f.ear_left = ear(1.0);
  f.ear_right = ear(-1.0);
  // Brow ridge, eye hollows, cheeks, lips and chin: gentle relief.
  f.other = front * (0.004 * gauss(y - 0.03, 0.008) * gauss(x, 0.03)            // brow
                     - 0.008 * (gauss(x - 0.032, 0.011) + gauss(x + 0.032, 0.011)) *
                           gauss(y - 0.016, 0.008)                              // eye hollows
                     + 0.004 * (gauss(x - 0.046, 0.012) + gauss(x + 0.046, 0.012)) *
                           gauss(y + 0.02, 0.014)                              // cheeks
                     + 0.005 * gauss(x, 0.016) * (gauss(y + 0.05, 0.004) + gauss(y + 0.062, 0.004))  // lips
                     + 0.008 * gauss(x, 0.02) * gauss(y + 0.088, 0.01));       // chin
  return f;
}

Vec3 base_point(double theta, double phi) {
  return Vec3(kA * std::sin(theta) * std::sin(phi), kB * std::cos(theta),
              kC * std::sin(theta) * std::cos(phi));
}

Vec3 ellipsoid_normal(const Vec3& p) {
  return Vec3(p.x() / (kA * kA), p.y() / (kB * kB), p.z() / (kC * kC)).normalized();
}

}  // namespace

GenericHead analytic_head(const AnalyticHeadOptions& options) {
  const int nu = std::max(8, options.segments_around);
  const int nv = std::max(8, options.segments_down);
  const double theta_max = 150.0 / 180.0 * kPi;  // the neck opening
  GenericHead head;
  TriMesh& m = head.mesh;
  std::vector<Vec3> base;
  base.push_back(base_point(0, 0));
  for (int j = 1; j <= nv; ++j)
    for (int i = 0; i < nu; ++i) base.push_back(base_point(theta_max * j / nv, 2 * kPi * i / nu));
  std::vector<Features> feat(base.size());
  for (size_t v = 0; v < base.size(); ++v) {
    feat[v] = features_at(base[v]);
    const Features& f = feat[v];
    const Vec3 n = ellipsoid_normal(base[v]);
    const double ear = f.ear_left + f.ear_right;
    // Ears lean backwards (as real ones do), hiding the skin behind them.
    m.positions.push_back(base[v] + (f.nose + ear + f.other) * n - 0.6 * ear * Vec3::UnitZ());
  }
  auto id = [nu](int j, int i) { return 1 + (j - 1) * nu + ((i % nu) + nu) % nu; };
  for (int i = 0; i < nu; ++i) m.triangles.push_back({0, id(1, i), id(1, i + 1)});
  for (int j = 1; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      m.triangles.push_back({id(j, i), id(j + 1, i), id(j + 1, i + 1)});
      m.triangles.push_back({id(j, i), id(j + 1, i + 1), id(j, i + 1)});
    }
  // Orient counter-clockwise seen from outside.
  const Vec3 n0 = face_normal_area(m, m.num_triangles() / 2);
  const Tri& t0 = m.triangles[m.num_triangles() / 2];
  if (n0.dot(m.positions[t0[0]]) < 0)
    for (Tri& t : m.triangles) std::swap(t[1], t[2]);

  HeadAnnotations& a = head.annotations;
  auto& r = a.regions;
  for (int v = 0; v < m.num_vertices(); ++v) {
    const Vec3& p = base[v];
    const Features& f = feat[v];
    const double ax = std::abs(p.x());
    const bool front = p.z() > 0.0;
    const bool ear_l = f.ear_left > 0.002, ear_r = f.ear_right > 0.002;
    if (ear_l) r["ear_left"].push_back(v);
    if (ear_r) r["ear_right"].push_back(v);
    if (ear_l || ear_r) r["ears"].push_back(v);
    if (f.nose > 0.003) r["nose"].push_back(v);
    const bool lips = front && ax < 0.026 && p.y() > -0.068 && p.y() < -0.044 && p.z() > 0.06;
    if (lips) {
      r["lips"].push_back(v);
      r[p.y() > -0.056 ? "upper_lip" : "lower_lip"].push_back(v);
    }
    if (front && ax < 0.03 && p.y() < -0.072 && p.y() > -0.105 && p.z() > 0.04) r["chin"].push_back(v);
    if (ax > 0.03 && p.y() < -0.045 && p.y() > -0.105 && p.z() > -0.02) r["jaw"].push_back(v);
    if (front && ax < 0.05 && p.y() > 0.02 && p.y() < 0.045 && p.z() > 0.05) r["brow"].push_back(v);
    if (front && ax > 0.025 && ax < 0.068 && p.y() > -0.045 && p.y() < 0.005) r["cheeks"].push_back(v);
    const bool scalp = !(ear_l || ear_r) && (p.y() > 0.06 || (p.z() < -0.03 && p.y() > -0.045));
    if (scalp) r["scalp"].push_back(v);
    if (p.y() < -0.09) r["neck"].push_back(v);
    if (!scalp && front && p.y() > -0.1) r["face"].push_back(v);
  }

  auto box_of = [&](const std::string& name, const std::vector<int>& verts, double margin) {
    FeatureBox b;
    b.name = name;
    BBox bb;
    for (int v : verts) bb.extend(m.positions[v]);
    b.min = bb.min - Vec3::Constant(margin);
    b.max = bb.max + Vec3::Constant(margin);
    auto extreme = [&](int axis, double sign) {
      int best = verts.front();
      for (int v : verts)
        if (sign * m.positions[v][axis] > sign * m.positions[best][axis]) best = v;
      return best;
    };
    if (name == "nose" || name == "mouth")
      b.landmarks = {extreme(0, -1), extreme(0, 1), extreme(1, 1), name == "nose" ? extreme(2, 1) : extreme(1, -1)};
    else
      b.landmarks = {extreme(1, 1), extreme(1, -1), extreme(2, -1)};
    return b;
  };
  a.boxes.push_back(box_of("ear_left", r["ear_left"], 0.005));
  a.boxes.push_back(box_of("ear_right", r["ear_right"], 0.005));
  a.boxes.push_back(box_of("nose", r["nose"], 0.005));
  a.boxes.push_back(box_of("mouth", r["lips"], 0.005));

  a.neck_clip.point = Vec3(0, -0.095, 0);
  a.neck_clip.normal = Vec3::UnitY();
  a.back_clip.point = Vec3(0, 0, -0.04);
  a.back_clip.normal = Vec3::UnitZ();
  const double eye_z = base_point(std::acos(0.016 / kB), std::asin(0.032 / kA)).z();
  a.eye_left.center = Vec3(0.032, 0.016, eye_z - 0.02);
  a.eye_right.center = Vec3(-0.032, 0.016, eye_z - 0.02);
  const double mouth_z = base_point(std::acos(-0.056 / kB), 0).z();
  a.mouth_center = Vec3(0, -0.056, mouth_z - 0.004);
  a.mouth_width = 0.05;
  return head;
}

}  // namespace lk
