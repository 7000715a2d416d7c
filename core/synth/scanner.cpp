#include "synth/scanner.h"

#include "mesh/geometry.h"
#include "raycast/bvh.h"
#include "common/prng.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace lk {

namespace {

constexpr double kDegree = 3.14159265358979323846 / 180.0;
constexpr int kPilotGrid = 48;
constexpr int kMaxGrid = 8192;

struct Candidate {
  Vec3 surface;  // the noise-free surface point
  Vec3 normal;   // the surface normal there (unit)
  Vec3 ray;      // unit camera ray direction
  int station = 0;
  int triangle = -1;
  char kind = 0;  // 0 surface, 1 outlier, 2 hair junk
  std::uint64_t stream = 0;  // per-pixel random stream, so the result ignores visiting order
};

struct Scene {
  const TriMesh& truth;
  const ScannerOptions& opt;
  MeshBvh bvh;
  std::vector<Vec3> vertex_normals;
  double cos_max = 0;
};

Vec3 surface_normal(const Scene& sc, int f, const Vec3& bary) {
  const Tri& t = sc.truth.triangles[f];
  Vec3 n = bary[0] * sc.vertex_normals[t[0]] + bary[1] * sc.vertex_normals[t[1]] +
           bary[2] * sc.vertex_normals[t[2]];
  if (n.norm() < 1e-12) n = face_normal_area(sc.truth, f);
  return n.normalized();
}

// True if p (on triangle f) sees `target` unobstructed.
bool sees(const Scene& sc, const Vec3& p, int f, const Vec3& target) {
  Ray r;
  r.origin = p;
  r.direction = target - p;
  const double len = r.direction.norm();
  r.t_min = 1e-5 / len;  // 10 um: skips neighbours of f that share its point
  r.t_max = 1.0;
  return !intersect_any(sc.bvh, r, f);
}

// Scans one station's grid; appends accepted candidates and counts pixels.
void scan_station(const Scene& sc, int s, ScannerStation& st, int grid, std::uint32_t seed,
                  std::vector<Candidate>* out, int& accepted) {
  const ScannerOptions& o = sc.opt;
  accepted = 0;
  st.rays = st.misses = st.back_facing = st.grazing = st.shadowed = st.hair = 0;
  for (int j = 0; j < grid; ++j)
    for (int i = 0; i < grid; ++i) {
      ++st.rays;
      const double u = (2.0 * (i + 0.5) / grid - 1.0) * st.half_fov_tan;
      const double v = (1.0 - 2.0 * (j + 0.5) / grid) * st.half_fov_tan;
      Ray ray;
      ray.origin = st.camera;
      ray.direction = st.forward + u * st.right + v * st.up;
      const RayHit hit = intersect_first(sc.bvh, ray);
      if (!hit.hit()) {
        ++st.misses;
        continue;
      }
      Candidate c;
      c.station = s;
      c.triangle = hit.triangle;
      c.ray = ray.direction.normalized();
      c.surface = ray.origin + hit.t * ray.direction;
      c.normal = surface_normal(sc, hit.triangle, hit.barycentric);
      c.stream = hash_mix(seed, static_cast<std::uint64_t>(s), static_cast<std::uint64_t>(j) * grid + i,
                          static_cast<std::uint64_t>(grid));
      const double cos_cam = -c.ray.dot(c.normal);
      if (cos_cam <= 0) {  // the inside of the neck opening or an eye pocket
        ++st.back_facing;
        continue;
      }
      if (!o.hair_triangles.empty() && o.hair_triangles[hit.triangle]) {
        ++st.hair;
        SplitMix64 rng(c.stream ^ 0x4A12ull);
        if (rng.uniform01() < o.hair_junk_fraction) {
          c.kind = 2;
          ++accepted;
          if (out) out->push_back(c);
        }
        continue;
      }
      const Vec3 to_projector = st.projector - c.surface;
      if (cos_cam < sc.cos_max || to_projector.normalized().dot(c.normal) < sc.cos_max) {
        ++st.grazing;
        continue;
      }
      if (!sees(sc, c.surface, hit.triangle, st.projector)) {
        ++st.shadowed;
        continue;
      }
      ++accepted;
      if (out) out->push_back(c);
    }
}

Vec3 random_unit(SplitMix64& rng) {
  for (;;) {
    const Vec3 d(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
    const double n2 = d.squaredNorm();
    if (n2 > 1e-4 && n2 <= 1.0) return d / std::sqrt(n2);
  }
}

Status check_options(const TriMesh& truth, const ScannerOptions& o) {
  auto bad = [](const std::string& m) { return Status::error(ErrorCode::InvalidInput, "scan_virtual: " + m); };
  if (truth.triangles.empty()) return Status::error(ErrorCode::Empty, "scan_virtual: the truth mesh is empty");
  std::string why;
  if (!is_valid(truth, &why)) return bad(why);
  if (o.stations < 1 || o.stations > 64) return bad("stations must be in 1..64");
  if (o.target_points < 1 || o.target_points > 20000000) return bad("target_points must be in 1..20,000,000");
  const double finite[] = {o.arc_degrees, o.distance_m, o.baseline_m, o.baseline_angle_deg,
                           o.max_incidence_deg, o.noise_sigma_m, o.outlier_fraction,
                           o.outlier_offset_m, o.hair_junk_fraction, o.hair_junk_range_m,
                           o.normal_noise};
  for (double v : finite)
    if (!std::isfinite(v)) return bad("an option is not finite");
  for (double e : o.elevations_deg)
    if (!std::isfinite(e) || std::abs(e) >= 89) return bad("elevations must be finite and within +-89 degrees");
  if (o.noise_sigma_m < 0 || o.outlier_offset_m < 0 || o.hair_junk_range_m < 0 || o.normal_noise < 0)
    return bad("noise, offsets and ranges must not be negative");
  if (o.outlier_fraction < 0 || o.outlier_fraction > 1 || o.hair_junk_fraction < 0 || o.hair_junk_fraction > 1)
    return bad("fractions must be in [0, 1]");
  if (o.max_incidence_deg <= 0 || o.max_incidence_deg >= 90) return bad("max_incidence_deg must be in (0, 90)");
  if (!o.hair_triangles.empty() && o.hair_triangles.size() != truth.triangles.size())
    return bad("hair_triangles has " + std::to_string(o.hair_triangles.size()) + " entries for " +
               std::to_string(truth.triangles.size()) + " triangles");
  if (o.look.norm() == 0 || o.up.cross(o.look).norm() < 1e-9) return bad("look and up must be independent");
  return Status::success();
}

}  // namespace

Status scan_virtual(const TriMesh& truth, const ScannerOptions& o, std::uint32_t seed,
                    PointCloud& out, ScanStats* stats_out, const ProgressFn& progress) {
  out = PointCloud{};
  Status s = check_options(truth, o);
  if (!s.ok()) return s;
  Scene sc{truth, o, {}, vertex_normals(truth), std::cos(o.max_incidence_deg * kDegree)};
  s = build_bvh(truth, sc.bvh);
  if (!s.ok()) return with_context(s, "scan_virtual");

  // Head frame and bounding sphere.
  const Vec3 look = o.look.normalized();
  const Vec3 up = (o.up - o.up.dot(look) * look).normalized();
  const Vec3 left = up.cross(look);
  const BBox box = bounding_box(truth.positions);
  const Vec3 centre = box.center();
  const double radius = 0.5 * box.diagonal();
  if (!(o.distance_m > radius * 1.05))
    return Status::error(ErrorCode::InvalidInput,
                         "scan_virtual: distance_m " + std::to_string(o.distance_m) +
                             " puts the cameras inside the head's bounding sphere (radius " +
                             std::to_string(radius) + " m); is the mesh in metres?");

  ScanStats stats;
  const int n = o.stations;
  for (int i = 0; i < n; ++i) {
    ScannerStation st;
    st.azimuth_deg = n == 1 ? 0.0 : -0.5 * o.arc_degrees + o.arc_degrees * i / (n - 1);
    const int from_end = std::min(i, n - 1 - i);
    st.elevation_deg = o.elevations_deg.empty() ? 0.0 : o.elevations_deg[from_end % o.elevations_deg.size()];
    const double az = st.azimuth_deg * kDegree, el = st.elevation_deg * kDegree;
    const Vec3 dir = std::cos(el) * (std::sin(az) * left + std::cos(az) * look) + std::sin(el) * up;
    st.camera = centre + o.distance_m * dir;
    st.forward = -dir;
    st.right = st.forward.cross(up).normalized();
    st.up = st.right.cross(st.forward);
    // Toward the face: the projector sits nearer the middle of the arc.
    const Vec3 side = st.azimuth_deg > 0 ? Vec3(-st.right) : st.right;
    const double b = o.baseline_angle_deg * kDegree;
    st.projector = st.camera + o.baseline_m * (std::cos(b) * side + std::sin(b) * st.up);
    st.half_fov_tan = 1.02 * radius / std::sqrt(o.distance_m * o.distance_m - radius * radius);
    stats.stations.push_back(st);
  }

  // Pilot pass: how many pixels of a coarse grid give a point.
  long pilot_points = 0;
  for (int i = 0; i < n; ++i) {
    int acc = 0;
    scan_station(sc, i, stats.stations[i], kPilotGrid, seed, nullptr, acc);
    pilot_points += acc;
  }
  if (!report(progress, "scan_virtual", 0.05))
    return Status::error(ErrorCode::Cancelled, "scan_virtual: cancelled");
  stats.pilot_grid = kPilotGrid;
  if (pilot_points == 0)
    return Status::error(ErrorCode::Empty,
                         "scan_virtual: no station saw the surface (is the mesh closed towards the "
                         "cameras, in metres?)");
  const double per_pixel = static_cast<double>(pilot_points) / (double(n) * kPilotGrid * kPilotGrid);
  // 4% spare: the pilot estimate is a little noisy, surplus points are dropped.
  const int grid = std::clamp(
      static_cast<int>(std::ceil(std::sqrt(1.04 * o.target_points / (n * per_pixel)))), 4, kMaxGrid);

  std::vector<Candidate> cands;
  cands.reserve(static_cast<size_t>(1.1 * o.target_points));
  for (int i = 0; i < n; ++i) {
    stats.stations[i].grid = grid;
    int acc = 0;
    scan_station(sc, i, stats.stations[i], grid, seed, &cands, acc);
    if (!report(progress, "scan_virtual", 0.05 + 0.85 * (i + 1) / n))
      return Status::error(ErrorCode::Cancelled, "scan_virtual: cancelled");
  }

  // Thin to the target: drop a random surplus, keep the scan order.
  if (static_cast<int>(cands.size()) > o.target_points) {
    std::vector<int> idx(cands.size());
    for (size_t k = 0; k < idx.size(); ++k) idx[k] = static_cast<int>(k);
    SplitMix64 rng(hash_mix(seed, 0x7417ull));
    for (int k = 0; k < o.target_points; ++k) {  // partial Fisher-Yates
      const int r = k + static_cast<int>(rng.uniform01() * (idx.size() - k));
      std::swap(idx[k], idx[std::min<size_t>(r, idx.size() - 1)]);
    }
    idx.resize(o.target_points);
    std::sort(idx.begin(), idx.end());
    std::vector<Candidate> kept;
    kept.reserve(idx.size());
    for (int k : idx) kept.push_back(cands[k]);
    cands.swap(kept);
  }

  // Misregistration: each station has its own small rigid shift; a share of
  // its points in overlaps (also seen by another camera) gets it.
  std::vector<Vec3> shift(n);
  {
    SplitMix64 rng(hash_mix(seed, 0x0FF5E7ull));
    for (int i = 0; i < n; ++i) shift[i] = o.outlier_offset_m * rng.uniform(1.0, 2.0) * random_unit(rng);
  }
  const int want_outliers = static_cast<int>(std::lround(o.outlier_fraction * cands.size()));
  if (want_outliers > 0 && n > 1) {
    std::vector<int> order;
    for (size_t k = 0; k < cands.size(); ++k)
      if (cands[k].kind == 0) order.push_back(static_cast<int>(k));
    SplitMix64 rng(hash_mix(seed, 0x0E7ull));
    int made = 0;
    for (size_t k = 0; k < order.size() && made < want_outliers; ++k) {
      const size_t r = k + static_cast<size_t>(rng.uniform01() * (order.size() - k));
      std::swap(order[k], order[std::min(r, order.size() - 1)]);
      Candidate& c = cands[order[k]];
      bool overlap = false;
      for (int other = 0; other < n && !overlap; ++other) {
        if (other == c.station) continue;
        const Vec3 to_cam = stats.stations[other].camera - c.surface;
        overlap = to_cam.normalized().dot(c.normal) >= sc.cos_max &&
                  sees(sc, c.surface, c.triangle, stats.stations[other].camera);
      }
      if (!overlap) continue;
      c.kind = 1;
      ++made;
    }
  }

  // Final points: noise along the ray, offsets for outliers and junk.
  out.positions.resize(cands.size());
  if (o.store_normals) out.normals.resize(cands.size());
  stats.point_station.resize(cands.size());
  stats.point_kind.resize(cands.size());
  for (size_t k = 0; k < cands.size(); ++k) {
    const Candidate& c = cands[k];
    SplitMix64 rng(c.stream);
    Vec3 p = c.surface + o.noise_sigma_m * rng.gaussian() * c.ray;
    if (c.kind == 1) {
      // Misregistered: the station's shift, with its normal part at least
      // outlier_offset_m so the point really is off the surface.
      const Vec3& m = shift[c.station];
      const double a = m.dot(c.normal);
      const double along = (a >= 0 ? 1.0 : -1.0) * std::max(std::abs(a), o.outlier_offset_m);
      p += along * c.normal + (m - a * c.normal);
    } else if (c.kind == 2) {
      p += rng.uniform(0.0, o.hair_junk_range_m) * c.normal;  // stray hairs above the scalp
    }
    out.positions[k] = p;
    if (o.store_normals) {
      const Vec3 g(rng.gaussian(), rng.gaussian(), rng.gaussian());
      out.normals[k] = (c.normal + o.normal_noise * g).normalized();
    }
    stats.point_station[k] = c.station;
    stats.point_kind[k] = c.kind;
    ScannerStation& st = stats.stations[c.station];
    ++st.points;
    if (c.kind == 1) ++st.outliers, ++stats.outliers;
    if (c.kind == 2) ++st.junk, ++stats.junk;
  }
  stats.points = static_cast<int>(cands.size());
  report(progress, "scan_virtual", 1.0);
  if (stats_out) *stats_out = std::move(stats);
  return Status::success();
}

}  // namespace lk
