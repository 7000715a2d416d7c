// Procedural skin albedo, camera ring and feature vertices (see skin_field.h).
#include "synth/skin_field.h"

#include "common/prng.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace lk {
namespace {

constexpr double kPi = 3.14159265358979323846;

double smoothstep(double e0, double e1, double x) {
  const double t = std::clamp((x - e0) / (e1 - e0), 0.0, 1.0);
  return t * t * (3 - 2 * t);
}

// Lattice value in [-1, 1] at integer coordinates.
double lattice(std::uint64_t seed, std::int64_t x, std::int64_t y, std::int64_t z) {
  const std::uint64_t h = hash_mix(seed, static_cast<std::uint64_t>(x), static_cast<std::uint64_t>(y),
                                   static_cast<std::uint64_t>(z));
  return static_cast<double>(h >> 11) * (2.0 / 9007199254740992.0) - 1.0;
}

// Value noise: trilinear interpolation of lattice values with a quintic
// fade, so the field and its gradient are continuous. Output in [-1, 1].
double value_noise(std::uint64_t seed, const Vec3& p) {
  const double fx = std::floor(p.x()), fy = std::floor(p.y()), fz = std::floor(p.z());
  const auto ix = static_cast<std::int64_t>(fx), iy = static_cast<std::int64_t>(fy),
             iz = static_cast<std::int64_t>(fz);
  auto fade = [](double t) { return t * t * t * (t * (t * 6 - 15) + 10); };
  const double u = fade(p.x() - fx), v = fade(p.y() - fy), w = fade(p.z() - fz);
  double acc = 0;
  for (int c = 0; c < 8; ++c) {
    const int dx = c & 1, dy = (c >> 1) & 1, dz = (c >> 2) & 1;
    const double weight = (dx ? u : 1 - u) * (dy ? v : 1 - v) * (dz ? w : 1 - w);
    acc += weight * lattice(seed, ix + dx, iy + dy, iz + dz);
  }
  return acc;
}

// Two octaves at the given wavelength (the second at 0.47x, half amplitude).
double fractal_noise(std::uint64_t seed, const Vec3& p, double wavelength) {
  return (value_noise(seed, p / wavelength) + 0.5 * value_noise(seed + 17, p / (0.47 * wavelength))) / 1.5;
}

// Darkening in [0, 1] from the freckles of the 27 cells around p.
double freckles(const SkinField& f, const Vec3& p) {
  const SkinFieldOptions& o = f.options;
  if (o.freckle_probability <= 0 || o.freckle_spacing_m <= 0) return 0;
  const double s = o.freckle_spacing_m;
  const double gx = std::floor(p.x() / s), gy = std::floor(p.y() / s), gz = std::floor(p.z() / s);
  // Denser on the face (cheeks, nose), sparse elsewhere.
  const double face_weight = 1.0 - smoothstep(0.6 * f.face_radius, 1.2 * f.face_radius, (p - f.face_center).norm());
  const double probability = o.freckle_probability * (1.0 / 3.0 + 2.0 / 3.0 * face_weight);
  double dark = 0;
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const auto cx = static_cast<std::int64_t>(gx) + dx, cy = static_cast<std::int64_t>(gy) + dy,
                   cz = static_cast<std::int64_t>(gz) + dz;
        SplitMix64 rng(hash_mix(f.seed ^ 0xF4EC1E5ull, static_cast<std::uint64_t>(cx),
                                static_cast<std::uint64_t>(cy), static_cast<std::uint64_t>(cz)));
        if (rng.uniform01() >= probability) continue;
        const Vec3 centre((cx + rng.uniform01()) * s, (cy + rng.uniform01()) * s, (cz + rng.uniform01()) * s);
        const double radius = o.freckle_radius_m * rng.uniform(0.6, 1.4);
        const double strength = rng.uniform(0.5, 1.0);
        const double d = (p - centre).norm();
        if (d >= radius) continue;
        dark = std::max(dark, strength * (1.0 - smoothstep(0.3 * radius, radius, d)));
      }
  return dark;
}

// Weight in [0, 1] of the lips: a rounded box (superellipse of exponent 4,
// whose corners reach the box's corners, where the lip outline's ends are)
// across the face, fading in depth; soft edges.
double lip_weight(const SkinField& f, const Vec3& p) {
  const Vec3 d = p - f.lip_center;
  const Vec3& half = f.lip_half_extent;
  const double a = d.dot(f.side) / half.x(), b = d.dot(f.up) / half.y(), c = d.dot(f.look) / half.z();
  const double r = std::sqrt(std::sqrt(a * a * a * a + b * b * b * b));
  return (1.0 - smoothstep(0.9, 1.2, r)) * (1.0 - smoothstep(1.0, 1.6, std::abs(c)));
}

// An eyebrow: an arched band over the eye, denser towards its inner half,
// with hair-like streaks (noise stretched along the brow).
double brow_weight(const SkinField& f, const Vec3& p, int which) {
  const Vec3 d = p - f.brow_center[which];
  const double across = d.dot(f.side) * (which == 0 ? 1.0 : -1.0);  // + = towards the temple
  const double t = across / f.brow_half_width;                      // -1 inner end .. 1 outer end
  // Fades out in depth (the band would otherwise run on round the head).
  const double depth = 1.0 - smoothstep(0.015, 0.03, std::abs(d.dot(f.look)));
  if (std::abs(t) > 1.3 || depth <= 0) return 0;
  const double arch = f.brow_arch * (1.0 - (t - 0.2) * (t - 0.2));   // highest a little outside the middle
  const double thickness = f.brow_half_height * (1.15 - 0.35 * t);   // tapers towards the temple
  const double v = (d.dot(f.up) - arch) / thickness;
  const double band = (1.0 - smoothstep(0.6, 1.0, std::abs(v))) * (1.0 - smoothstep(0.85, 1.15, std::abs(t)));
  const Vec3 stretched(across / 0.010, d.dot(f.up) / 0.0009, d.dot(f.look) / 0.0009);
  const double hairs = std::clamp(0.9 + 0.35 * value_noise(f.seed + 91 + which, stretched), 0.0, 1.0);
  return std::clamp(band * hairs * depth, 0.0, 1.0);
}

}  // namespace

Status make_skin_field(const GenericHead& head, std::uint32_t seed, const SkinFieldOptions& options,
                       SkinField& out) {
  const TriMesh& mesh = head.mesh;
  const HeadAnnotations& a = head.annotations;
  if (mesh.num_vertices() == 0) return Status::error(ErrorCode::InvalidInput, "skin field: the head mesh is empty");
  auto region = [&](const std::string& name, const std::vector<int>*& vs) -> Status {
    auto it = a.regions.find(name);
    if (it == a.regions.end() || it->second.empty())
      return Status::error(ErrorCode::InvalidInput, "skin field: the head has no '" + name + "' region");
    for (int v : it->second)
      if (v < 0 || v >= mesh.num_vertices())
        return Status::error(ErrorCode::InvalidInput, "skin field: region '" + name + "' has vertex " +
                                                          std::to_string(v) + " out of range");
    vs = &it->second;
    return Status::success();
  };
  const std::vector<int> *upper = nullptr, *lower = nullptr, *face = nullptr;
  Status s = region("upper_lip", upper);
  if (s) s = region("lower_lip", lower);
  if (s) s = region("face", face);
  if (!s) return s;

  SkinField f;
  f.seed = hash_mix(seed, 0x5C1Full);
  f.options = options;
  f.look = a.look.normalized();
  f.up = (a.up - a.up.dot(f.look) * f.look).normalized();
  f.side = f.up.cross(f.look);  // +x for the generic head (its left)

  SplitMix64 rng(f.seed);
  // Tone: overall brightness and a warm/cool shift, both from the seed.
  const double bright = 1.0 + options.tone_range * rng.uniform(-1, 1);
  const double warm = 0.5 * options.tone_range * rng.uniform(-1, 1);
  f.base = Vec3(0.50 * (1 + warm), 0.29, 0.21 * (1 - warm)) * bright;
  f.lip_color = Vec3(0.38, 0.12, 0.11) * (1.0 + 0.5 * options.tone_range * rng.uniform(-1, 1));
  f.brow_color = Vec3(0.07, 0.045, 0.03) * (1.0 + 2.0 * options.tone_range * rng.uniform(-1, 1));

  // Lips: the box of both lips' vertices in the head frame.
  Vec3 lo = Vec3::Constant(1e300), hi = Vec3::Constant(-1e300);
  for (const std::vector<int>* vs : {upper, lower})
    for (int v : *vs) {
      const Vec3& p = mesh.positions[v];
      const Vec3 q(p.dot(f.side), p.dot(f.up), p.dot(f.look));
      lo = lo.cwiseMin(q);
      hi = hi.cwiseMax(q);
    }
  const Vec3 mid = 0.5 * (lo + hi);
  f.lip_center = mid.x() * f.side + mid.y() * f.up + mid.z() * f.look;
  f.lip_half_extent = Vec3(0.5 * (hi.x() - lo.x()) * 1.05, 0.5 * (hi.y() - lo.y()) * 1.05,
                           std::max(0.5 * (hi.z() - lo.z()), 0.01));

  // Face centre: the face region's centroid, radius its RMS spread.
  Vec3 c = Vec3::Zero();
  for (int v : *face) c += mesh.positions[v];
  c /= static_cast<double>(face->size());
  double r2 = 0;
  for (int v : *face) r2 += (mesh.positions[v] - c).squaredNorm();
  f.face_center = c;
  f.face_radius = std::sqrt(r2 / face->size());

  // Brows: above each eye socket, on the brow ridge in front of the eyeball.
  const EyeSocket* eyes[2] = {&a.eye_left, &a.eye_right};
  for (int i = 0; i < 2; ++i) {
    const double r = eyes[i]->radius > 0 ? eyes[i]->radius : 0.012;
    f.brow_center[i] = eyes[i]->center + 1.55 * r * f.up + 1.0 * r * f.look +
                       (i == 0 ? 1.0 : -1.0) * 0.15 * r * f.side;
  }
  f.brow_half_width = 2.0 * (eyes[0]->radius > 0 ? eyes[0]->radius : 0.012);
  out = f;
  return Status::success();
}

Vec3 skin_albedo(const SkinField& f, const Vec3& p) {
  const SkinFieldOptions& o = f.options;
  const double blotch = o.blotch_amplitude * fractal_noise(f.seed + 1, p, o.blotch_wavelength_m);
  const double mottle = o.mottle_amplitude * fractal_noise(f.seed + 2, p, o.mottle_wavelength_m) +
                        o.pore_amplitude * value_noise(f.seed + 3, p / o.pore_wavelength_m);
  // Blotches are redder (blood), mottling is plain brightness.
  Vec3 c(f.base.x() * (1 + blotch * 0.8 + mottle), f.base.y() * (1 + blotch * 1.1 + mottle),
         f.base.z() * (1 + blotch * 1.2 + mottle));
  const double dark = o.freckle_darkening * freckles(f, p);
  c = c.cwiseProduct(Vec3(1 - dark * 0.8, 1 - dark, 1 - dark * 1.1).cwiseMax(0.0));
  if (o.lip_strength > 0) {
    const double w = o.lip_strength * lip_weight(f, p);
    const Vec3 lip = f.lip_color * (1 + 0.5 * mottle);
    c = (1 - w) * c + w * lip;
  }
  if (o.brow_strength > 0) {
    const double w = o.brow_strength * std::max(brow_weight(f, p, 0), brow_weight(f, p, 1));
    c = (1 - w) * c + w * f.brow_color;
  }
  return c.cwiseMax(0.02).cwiseMin(0.7);
}

std::vector<Vec3> skin_albedo(const SkinField& field, const std::vector<Vec3>& points) {
  std::vector<Vec3> out(points.size());
  for (size_t i = 0; i < points.size(); ++i) out[i] = skin_albedo(field, points[i]);
  return out;
}

std::vector<RingView> default_ring_views(int n) {
  static const RingView all[] = {{0, 0}, {45, 4}, {-45, 4}, {80, -3}, {-80, -3}, {0, 30}, {0, -25}};
  std::vector<RingView> out;
  for (int i = 0; i < std::clamp(n, 0, 7); ++i) out.push_back(all[i]);
  return out;
}

RingView held_out_view() { return {25, 6}; }

Camera look_at(const Vec3& eye, const Vec3& target, const Vec3& up, double focal, int width, int height) {
  Camera cam;
  const Vec3 z = (target - eye).normalized();
  const Vec3 x = z.cross(up).normalized();  // image right
  const Vec3 y = z.cross(x);                // image down
  cam.R.row(0) = x.transpose();
  cam.R.row(1) = y.transpose();
  cam.R.row(2) = z.transpose();
  cam.t = -cam.R * eye;
  cam.fx = cam.fy = focal;
  cam.cx = 0.5 * width;
  cam.cy = 0.5 * height;
  cam.width = width;
  cam.height = height;
  return cam;
}

Status camera_ring(const std::vector<Vec3>& points, const Vec3& look, const Vec3& up,
                   const std::vector<RingView>& views, std::uint32_t seed, const CameraRingOptions& options,
                   std::vector<Camera>& cameras) {
  if (points.empty()) return Status::error(ErrorCode::InvalidInput, "camera ring: no head points");
  if (options.width < 16 || options.height < 16 || !(options.distance_m > 0) || !(options.fill > 0))
    return Status::error(ErrorCode::InvalidInput, "camera ring: image size, distance and fill must be positive");
  Vec3 lo = points[0], hi = points[0];
  for (const Vec3& p : points) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const Vec3 centre = 0.5 * (lo + hi);
  double radius = 0;
  for (const Vec3& p : points) radius = std::max(radius, (p - centre).norm());
  if (options.distance_m <= 1.05 * radius)
    return Status::error(ErrorCode::InvalidInput, "camera ring: distance " + std::to_string(options.distance_m) +
                                                      " m is inside the head (radius " + std::to_string(radius) + " m)");
  // The bounding sphere spans `fill` of the height: its tangent cone's half
  // angle is asin(radius / distance).
  const double half = std::asin(radius / options.distance_m);
  const double focal = options.fill * 0.5 * options.height / std::tan(half);

  const Vec3 f = look.normalized();
  const Vec3 u = (up - up.dot(f) * f).normalized();
  const Vec3 s = u.cross(f);  // the head's left
  SplitMix64 rng(hash_mix(seed, 0xCA3E7Aull));
  cameras.clear();
  for (const RingView& v : views) {
    const double yaw = (v.yaw_deg + options.jitter_deg * rng.uniform(-1, 1)) * kPi / 180;
    const double pitch = (v.pitch_deg + options.jitter_deg * rng.uniform(-1, 1)) * kPi / 180;
    const double roll = options.jitter_deg * rng.uniform(-1, 1) * kPi / 180;
    const Vec3 dir = std::cos(pitch) * (std::cos(yaw) * f + std::sin(yaw) * s) + std::sin(pitch) * u;
    const Vec3 aim = centre + options.aim_jitter_m * Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
    const Vec3 eye = centre + options.distance_m * dir;
    // Roll: turn the up hint around the viewing direction.
    const Vec3 z = (aim - eye).normalized();
    const Vec3 up_hint = (std::cos(roll) * u + std::sin(roll) * z.cross(u)).normalized();
    cameras.push_back(look_at(eye, aim, up_hint, focal, options.width, options.height));
  }
  return Status::success();
}

std::vector<int> feature_vertices(const GenericHead& head) {
  const TriMesh& mesh = head.mesh;
  const HeadAnnotations& a = head.annotations;
  const Vec3 f = a.look.normalized();
  const Vec3 u = (a.up - a.up.dot(f) * f).normalized();
  const Vec3 s = u.cross(f);
  std::vector<int> out;
  auto add = [&](int v) {
    if (v >= 0 && v < mesh.num_vertices() && std::find(out.begin(), out.end(), v) == out.end()) out.push_back(v);
  };
  // The vertex of a set that maximizes a direction.
  auto extreme = [&](const std::vector<int>& vs, const Vec3& dir) {
    int best = -1;
    double best_value = -1e300;
    for (int v : vs) {
      if (v < 0 || v >= mesh.num_vertices()) continue;
      const double value = mesh.positions[v].dot(dir);
      if (value > best_value) {
        best_value = value;
        best = v;
      }
    }
    return best;
  };
  for (const EyeSocket* eye : {&a.eye_left, &a.eye_right}) {
    add(extreme(eye->rim, s));   // corners
    add(extreme(eye->rim, -s));
    add(extreme(eye->rim, u));   // top of the rim
  }
  for (const FeatureBox& box : a.boxes)
    for (int v : box.landmarks) add(v);
  auto region = [&](const char* name) -> const std::vector<int>& {
    static const std::vector<int> none;
    auto it = a.regions.find(name);
    return it == a.regions.end() ? none : it->second;
  };
  add(extreme(region("chin"), f - 1.5 * u));  // front and low
  add(extreme(region("face"), u + 0.3 * f));  // forehead top, towards the front
  // What a side photo shows: the ear's outline, cheekbone, jaw angle, temple.
  for (double side : {1.0, -1.0}) {
    const std::vector<int>& ear = region(side > 0 ? "ear_left" : "ear_right");
    add(extreme(ear, u));
    add(extreme(ear, -u));
    add(extreme(ear, -f));
    add(extreme(ear, f + side * s));
    add(extreme(region("cheeks"), side * s + 0.3 * f));
    add(extreme(region("cheeks"), side * s - u));
    add(extreme(region("jaw"), side * s - u));
    add(extreme(region("jaw"), side * s + f));
    add(extreme(region("face"), side * s + u));
    add(extreme(region("scalp"), side * s + u));
    add(extreme(region("scalp"), side * s - f));
    add(extreme(region("neck"), side * s + 0.5 * f));
  }
  return out;
}

}  // namespace lk
