// The virtual scanner: count, noise, outliers, holes where a structured-light
// scanner has them, empty hair, determinism, clear errors.
#include "synth/scanner.h"
#include "test_scan.h"

#include "mesh/geometry.h"
#include "raycast/bvh.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <unordered_map>

using namespace lk;

namespace {

struct Scene : test::TestScan {
  MeshBvh bvh;  // of the truth surface
};

// One synthetic head (from the embedded generic head) scanned with the
// defaults (300k points), shared by the tests below: it takes about a second.
const Scene& scene() {
  static const Scene s = [] {
    Scene sc{test::make_test_scan(21, ScannerOptions{}.target_points), {}};
    REQUIRE(build_bvh(sc.truth.mesh, sc.bvh).ok());
    return sc;
  }();
  return s;
}

// Points near a query, by a uniform grid of cell `r`.
struct PointGrid {
  double r;
  std::unordered_map<std::uint64_t, std::vector<int>> cells;
  const std::vector<Vec3>& pts;
  static std::uint64_t key(long x, long y, long z) {
    return (static_cast<std::uint64_t>(x & 0x1FFFFF) << 42) | (static_cast<std::uint64_t>(y & 0x1FFFFF) << 21) |
           static_cast<std::uint64_t>(z & 0x1FFFFF);
  }
  PointGrid(const std::vector<Vec3>& p, double cell) : r(cell), pts(p) {
    for (size_t i = 0; i < p.size(); ++i)
      cells[key(std::lround(std::floor(p[i].x() / r)), std::lround(std::floor(p[i].y() / r)),
                std::lround(std::floor(p[i].z() / r)))]
          .push_back(static_cast<int>(i));
  }
  bool any_within(const Vec3& q) const {
    const long cx = std::lround(std::floor(q.x() / r)), cy = std::lround(std::floor(q.y() / r)),
               cz = std::lround(std::floor(q.z() / r));
    for (long dx = -1; dx <= 1; ++dx)
      for (long dy = -1; dy <= 1; ++dy)
        for (long dz = -1; dz <= 1; ++dz) {
          auto it = cells.find(key(cx + dx, cy + dy, cz + dz));
          if (it == cells.end()) continue;
          for (int i : it->second)
            if ((pts[i] - q).norm() <= r) return true;
        }
    return false;
  }
};

double robust_std(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const double med = v[v.size() / 2];
  for (double& x : v) x = std::abs(x - med);
  std::sort(v.begin(), v.end());
  return 1.4826 * v[v.size() / 2];
}

// Depth error of each surface point along its camera ray, against the truth.
std::vector<double> depth_errors(const Scene& s, const PointCloud& cloud, const ScanStats& stats) {
  std::vector<double> err;
  for (int k = 0; k < cloud.size(); ++k) {
    if (stats.point_kind[k] != 0) continue;
    const Vec3 cam = stats.stations[stats.point_station[k]].camera;
    Ray ray;
    ray.origin = cam;
    ray.direction = (cloud.positions[k] - cam).normalized();
    const RayHit h = intersect_first(s.bvh, ray);
    if (!h.hit()) continue;
    err.push_back((cloud.positions[k] - cam).norm() - h.t);
  }
  return err;
}

// Share of `probes` (points on the truth) with a scan point within r.
double coverage(const PointGrid& grid, const std::vector<Vec3>& probes) {
  int covered = 0;
  for (const Vec3& p : probes) covered += grid.any_within(p);
  return probes.empty() ? 0.0 : double(covered) / probes.size();
}

// Control vertices of a region, projected onto the truth surface.
std::vector<Vec3> probes_where(const Scene& s, const std::function<bool(int, const Vec3&)>& pick) {
  std::vector<Vec3> out;
  for (int v = 0; v < s.head.mesh.num_vertices(); ++v)
    if (pick(v, s.head.mesh.positions[v])) out.push_back(closest_point(s.bvh, s.head.mesh.positions[v]).point);
  return out;
}

}  // namespace

TEST_CASE("the scan has about the requested number of points", "[synth][scanner]") {
  const Scene& s = scene();
  CHECK(s.scan.size() >= 0.97 * 300000);
  CHECK(s.scan.size() <= 300000);
  CHECK(s.stats.points == s.scan.size());
  CHECK(s.scan.normals.size() == s.scan.positions.size());
  CHECK(s.stats.stations.size() == 6);
  int sum = 0, shadowed = 0;
  for (const auto& st : s.stats.stations) {
    CHECK(st.points > 0.05 * s.scan.size());  // every station contributes
    sum += st.points;
    shadowed += st.shadowed;
  }
  CHECK(sum == s.scan.size());
  CHECK(shadowed > 0);  // the projectors cast shadows
}

TEST_CASE("depth noise along the ray has the requested sigma", "[synth][scanner]") {
  const Scene& s = scene();
  const std::vector<double> err = depth_errors(s, s.scan, s.stats);
  REQUIRE(err.size() > 100000);
  CHECK(robust_std(err) == Approx(0.0002).epsilon(0.2));
  // And with another sigma, on a smaller scan.
  ScannerOptions o = s.scanner;
  o.noise_sigma_m = 0.0005;
  o.target_points = 40000;
  PointCloud c;
  ScanStats st;
  REQUIRE(scan_virtual(s.truth.mesh, o, 3, c, &st).ok());
  CHECK(robust_std(depth_errors(s, c, st)) == Approx(0.0005).epsilon(0.2));
  o.noise_sigma_m = 0;
  REQUIRE(scan_virtual(s.truth.mesh, o, 3, c, &st).ok());
  for (double e : depth_errors(s, c, st)) REQUIRE(std::abs(e) < 1e-9);
}

TEST_CASE("outliers: the requested share, off the surface, where scans overlap", "[synth][scanner]") {
  const Scene& s = scene();
  const int want = static_cast<int>(std::lround(0.005 * s.scan.size()));
  CHECK(s.stats.outliers == want);
  // Measured independently: skin points farther than 5 sigma from the truth.
  int far = 0, skin = 0, outliers_far = 0;
  for (int k = 0; k < s.scan.size(); ++k) {
    const ClosestPoint cp = closest_point(s.bvh, s.scan.positions[k]);
    if (s.truth.hair[cp.triangle]) continue;
    ++skin;
    if (cp.distance > 0.001) {
      ++far;
      CHECK(s.stats.point_kind[k] != 0);
    }
    if (s.stats.point_kind[k] == 1) outliers_far += cp.distance > 0.001;
  }
  // Misregistered points lie off the surface (a few land near another part,
  // e.g. an offset beside the ear that comes close to the ear itself).
  CHECK(outliers_far >= 0.97 * s.stats.outliers);
  CHECK(double(far) / skin == Approx(0.005).epsilon(0.3));
}

TEST_CASE("the scanner leaves holes behind the ears and under the chin", "[synth][scanner]") {
  const Scene& s = scene();
  const PointGrid grid(s.scan.positions, 0.002);
  const auto& regions = s.head.annotations.regions;
  std::vector<char> in_ear(s.head.mesh.positions.size(), 0), in_cheek(in_ear.size(), 0);
  for (int v : regions.at("ears")) in_ear[v] = 1;
  for (int v : regions.at("cheeks")) in_cheek[v] = 1;
  // Skin in the groove behind the left ear: not ear, not hair, and the ear
  // overhangs it (a ray from it straight out to the side hits the ear).
  std::vector<char> ear_tri(s.truth.mesh.triangles.size(), 0);
  for (size_t f = 0; f < ear_tri.size(); ++f) {
    const Tri& t = s.head.mesh.triangles[s.truth.parent_triangle[f]];
    ear_tri[f] = in_ear[t[0]] || in_ear[t[1]] || in_ear[t[2]];
  }
  const Vec3 side_axis = s.head.annotations.up.cross(s.head.annotations.look).normalized();
  std::vector<char> near_ear(s.truth.mesh.positions.size(), 0), near_hair(near_ear.size(), 0);
  for (size_t f = 0; f < ear_tri.size(); ++f)
    for (int v : s.truth.mesh.triangles[f]) {
      near_ear[v] |= ear_tri[f];
      near_hair[v] |= s.truth.hair[f];
    }
  Vec3 ear_centre = Vec3::Zero();
  for (int v : regions.at("ear_left")) ear_centre += s.head.mesh.positions[v] / regions.at("ear_left").size();
  const Vec3 look = s.head.annotations.look.normalized();
  std::vector<Vec3> behind_ear;
  for (int v = 0; v < s.truth.mesh.num_vertices(); ++v) {
    const Vec3& p = s.truth.mesh.positions[v];
    if (near_ear[v] || near_hair[v] || side_axis.dot(p - s.head.annotations.mouth_center) <= 0) continue;
    if (look.dot(p - ear_centre) > 0) continue;  // under the front of the ear is visible from the front
    Ray ray;
    ray.origin = p;
    ray.direction = side_axis;
    ray.t_min = 1e-4;
    const RayHit h = intersect_first(s.bvh, ray);
    if (h.hit() && ear_tri[h.triangle] && h.t < 0.04) behind_ear.push_back(p);
  }
  // Under the chin: skin facing down, in front, below the mouth.
  const std::vector<Vec3> normals = vertex_normals(s.truth.mesh);
  const Vec3 c = bounding_box(s.head.mesh.positions).center();
  const Vec3 up = s.head.annotations.up.normalized();
  std::vector<Vec3> under_chin;
  for (int v = 0; v < s.truth.mesh.num_vertices(); ++v) {
    const Vec3& p = s.truth.mesh.positions[v];
    if (normals[v].dot(up) < -0.85 && look.dot(p - c) > 0.02 && !near_hair[v] &&
        up.dot(p - s.head.annotations.mouth_center) < -0.02)
      under_chin.push_back(p);
  }
  const auto cheeks = probes_where(s, [&](int v, const Vec3&) { return in_cheek[v] != 0; });
  // Hair: truth vertices whose triangles are all hair (away from the hairline).
  std::vector<char> all_hair(s.truth.mesh.positions.size(), 1);
  for (size_t f = 0; f < s.truth.hair.size(); ++f)
    if (!s.truth.hair[f])
      for (int v : s.truth.mesh.triangles[f]) all_hair[v] = 0;
  std::vector<Vec3> scalp;
  for (int v = 0; v < s.truth.mesh.num_vertices(); ++v)
    if (all_hair[v]) scalp.push_back(s.truth.mesh.positions[v]);
  REQUIRE(behind_ear.size() >= 5);
  REQUIRE(under_chin.size() >= 5);
  REQUIRE(cheeks.size() >= 20);
  INFO("behind ear " << behind_ear.size() << ", under chin " << under_chin.size() << ", cheeks "
                     << cheeks.size() << ", scalp " << scalp.size());
  const double cov_cheek = coverage(grid, cheeks), cov_ear = coverage(grid, behind_ear),
               cov_chin = coverage(grid, under_chin), cov_scalp = coverage(grid, scalp);
  INFO("coverage: cheeks " << cov_cheek << ", behind ear " << cov_ear << ", under chin " << cov_chin
                           << ", scalp " << cov_scalp);
  CHECK(cov_cheek > 0.95);
  CHECK(cov_ear < 0.25);
  CHECK(cov_chin < 0.25);
  CHECK(cov_scalp < 0.2);  // hair returns only sparse junk
  CHECK(s.stats.junk > 0);
  CHECK(s.stats.junk < 0.05 * s.scan.size());
}

TEST_CASE("scans are deterministic per seed", "[synth][scanner]") {
  const Scene& s = scene();
  ScannerOptions o = s.scanner;
  o.target_points = 20000;
  PointCloud a, b, c;
  REQUIRE(scan_virtual(s.truth.mesh, o, 5, a).ok());
  REQUIRE(scan_virtual(s.truth.mesh, o, 5, b).ok());
  REQUIRE(scan_virtual(s.truth.mesh, o, 6, c).ok());
  REQUIRE(a.size() == b.size());
  CHECK(std::memcmp(a.positions.data(), b.positions.data(), a.positions.size() * sizeof(Vec3)) == 0);
  CHECK(std::memcmp(a.normals.data(), b.normals.data(), a.normals.size() * sizeof(Vec3)) == 0);
  const size_t n = std::min(a.positions.size(), c.positions.size());
  CHECK(std::memcmp(a.positions.data(), c.positions.data(), n * sizeof(Vec3)) != 0);
}

TEST_CASE("bad scanner input gives clear errors", "[synth][scanner]") {
  const Scene& s = scene();
  PointCloud out;
  ScannerOptions o;
  CHECK(scan_virtual(TriMesh{}, o, 1, out).code == ErrorCode::Empty);
  o.hair_triangles = {1, 0, 1};
  Status st = scan_virtual(s.truth.mesh, o, 1, out);
  CHECK(st.code == ErrorCode::InvalidInput);
  CHECK(st.message.find("hair_triangles") != std::string::npos);
  o = ScannerOptions{};
  o.target_points = 0;
  CHECK(scan_virtual(s.truth.mesh, o, 1, out).code == ErrorCode::InvalidInput);
  o = ScannerOptions{};
  o.noise_sigma_m = std::nan("");
  CHECK(scan_virtual(s.truth.mesh, o, 1, out).code == ErrorCode::InvalidInput);
  o = ScannerOptions{};
  o.distance_m = 0.05;  // inside the head
  st = scan_virtual(s.truth.mesh, o, 1, out);
  CHECK(st.code == ErrorCode::InvalidInput);
  CHECK(st.message.find("metres") != std::string::npos);
  TriMesh mm = s.truth.mesh;  // a head in millimetres is too big for the defaults
  for (Vec3& p : mm.positions) p *= 1000;
  CHECK(scan_virtual(mm, ScannerOptions{}, 1, out).code == ErrorCode::InvalidInput);
  o = ScannerOptions{};
  o.target_points = 5000;
  st = scan_virtual(s.truth.mesh, o, 1, out, nullptr, [](const char*, double f) { return f < 0.5; });
  CHECK(st.code == ErrorCode::Cancelled);
  CHECK(out.size() == 0);
}
