// Stereo (fua1998 Sec. 3.1): rectification, disparity on rendered textured
// planes with known cameras, the left-right check on an occluder, bad input,
// and the attractors' facet distance against finite differences.
#include "common/prng.h"
#include "mesh/primitives.h"
#include "observation_fd.h"
#include "photos/rectify.h"
#include "photos/stereo.h"
#include "photos/stereo_obs.h"
#include "raycast/bvh.h"
#include "texture/synthetic_photo.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <climits>
#include <cmath>

namespace lk {
namespace {

// A size x size square of the z = z0 plane centred on the axis, n x n cells, normal +z.
TriMesh square(double size, double z0, int n) {
  TriMesh m = make_regular_grid(n, n);
  for (Vec3& p : m.positions) p = Vec3((p.x() / n - 0.5) * size, (p.y() / n - 0.5) * size, z0);
  return m;
}

TriMesh merged(const TriMesh& a, const TriMesh& b) {
  TriMesh m = a;
  const int off = a.num_vertices();
  m.positions.insert(m.positions.end(), b.positions.begin(), b.positions.end());
  for (Tri t : b.triangles) m.triangles.push_back({t[0] + off, t[1] + off, t[2] + off});
  return m;
}

Image render(const TriMesh& scene, const Camera& c) {
  Image im;
  REQUIRE(render_synthetic_photo(
      scene, c, [](const Vec3& p, const Vec3&) { return procedural_color_field(p, 0.006); }, Vec3(0.5, 0.5, 0.5), im));
  return im;
}

// Two cameras 0.6 m from the origin, `angle` degrees apart about the y axis, looking at it.
void camera_pair(double angle_deg, Camera& a, Camera& b, int w = 640, int h = 480, double f = 800) {
  const double t = angle_deg * 3.14159265358979 / 360;
  a = look_at_camera(Vec3(-0.6 * std::sin(t), 0.03, 0.6 * std::cos(t)), Vec3::Zero(), Vec3::UnitY(), f, w, h);
  b = look_at_camera(Vec3(0.6 * std::sin(t), 0.03, 0.6 * std::cos(t)), Vec3::Zero(), Vec3::UnitY(), f, w, h);
}

// The disparities of the points in the rectified pair, widened by 2 pixels.
void disparity_range(const RectifiedCameras& rc, const std::vector<Vec3>& points, int& d_min, int& d_max) {
  d_min = INT_MAX;
  d_max = INT_MIN;
  for (const Vec3& X : points) {
    Vec2 ua = Vec2::Zero(), ub = Vec2::Zero();
    REQUIRE(rc.a.project(X, ua));
    REQUIRE(rc.b.project(X, ub));
    d_min = std::min(d_min, int(std::floor(ua.x() - ub.x())) - 2);
    d_max = std::max(d_max, int(std::ceil(ua.x() - ub.x())) + 2);
  }
}

double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + long(v.size() / 2), v.end());
  return v[v.size() / 2];
}

TEST_CASE("rectified cameras put a world point on the same row in both photos", "[photos][stereo]") {
  Camera a, b;
  camera_pair(25, a, b);
  a.R = Eigen::AngleAxisd(0.08, Vec3(0.3, 0.2, 1).normalized()).toRotationMatrix() * a.R;  // rolled, tilted
  a.t = a.R * -Vec3(-0.13, 0.05, 0.58);
  b.fx = b.fy = 760;  // another focal
  SplitMix64 rng(3);
  std::vector<Vec3> roi;
  for (int i = 0; i < 200; ++i) roi.emplace_back(rng.uniform(-0.1, 0.1), rng.uniform(-0.1, 0.1), rng.uniform(-0.1, 0.1));
  RectifiedCameras rc;
  REQUIRE(rectified_cameras(a, b, roi, 400, 5, rc));
  CHECK(std::max(rc.a.width, rc.a.height) <= 400);
  CHECK((rc.a.center() - a.center()).norm() < 1e-12);
  CHECK((rc.b.center() - b.center()).norm() < 1e-12);
  double worst_row = 0;
  int inside = 0;
  for (const Vec3& X : roi) {
    Vec2 ua = Vec2::Zero(), ub = Vec2::Zero();
    REQUIRE(rc.a.project(X, ua));
    REQUIRE(rc.b.project(X, ub));
    worst_row = std::max(worst_row, std::abs(ua.y() - ub.y()));
    inside += ua.x() >= 0 && ua.x() <= rc.a.width && ua.y() >= 0 && ua.y() <= rc.a.height && ub.x() >= 0 &&
              ub.x() <= rc.b.width;
    // The disparity's depth is the point's depth.
    Vec3 Y;
    REQUIRE(triangulate_rectified(rc, ua.x() - 0.5, ua.y() - 0.5, ua.x() - ub.x(), Y));
    CHECK((Y - X).norm() < 1e-9);
  }
  CHECK(worst_row < 1e-9);
  CHECK(inside == int(roi.size()));
  // The unrectified photos do not share rows (the test means something).
  double before = 0;
  for (const Vec3& X : roi) {
    Vec2 ua = Vec2::Zero(), ub = Vec2::Zero();
    a.project(X, ua);
    b.project(X, ub);
    before = std::max(before, std::abs(ua.y() - ub.y()));
  }
  CHECK(before > 5);
  // The resampled photo shows at a point's rectified pixel what the photo shows at its pixel.
  const TriMesh plane = square(0.4, 0, 40);
  const Image photo = render(plane, a);
  ImageF rect;
  std::vector<std::uint8_t> valid;
  REQUIRE(resample_rectified(photo, a, rc.a, rect, &valid));
  const ImageF g = gray_levels(photo);
  double diff = 0;
  int n = 0;
  for (int i = 0; i < 300; ++i) {
    const Vec3 X(rng.uniform(-0.08, 0.08), rng.uniform(-0.08, 0.08), 0);
    Vec2 u = Vec2::Zero(), r = Vec2::Zero();
    a.project(X, u);
    rc.a.project(X, r);
    const int rx = int(r.x()), ry = int(r.y());
    if (rx < 0 || ry < 0 || rx >= rect.width || ry >= rect.height || !valid[size_t(ry * rect.width + rx)]) continue;
    diff += std::abs(*rect.at(rx, ry) - *g.at(int(u.x()), int(u.y())));
    ++n;
  }
  REQUIRE(n > 200);
  CHECK(diff / n < 0.03);
}

TEST_CASE("disparity on a rendered textured plane recovers its depth", "[photos][stereo]") {
  Camera a, b;
  camera_pair(20, a, b);
  // The plane tilted 25 deg about y and 10 about x, through (0, 0, 0.02).
  TriMesh plane = square(0.5, 0, 30);
  const Mat3 tilt = (Eigen::AngleAxisd(0.44, Vec3::UnitY()) * Eigen::AngleAxisd(0.17, Vec3::UnitX())).toRotationMatrix();
  for (Vec3& p : plane.positions) p = tilt * p + Vec3(0, 0, 0.02);
  const Vec3 n = tilt * Vec3::UnitZ(), p0(0, 0, 0.02);
  const Image ia = render(plane, a), ib = render(plane, b);
  StereoView va{&ia, a, {}, "a"}, vb{&ib, b, {}, "b"};
  // The region: the middle of photo a.
  va.region = {Vec2(160, 120), Vec2(480, 120), Vec2(480, 360), Vec2(160, 360)};
  StereoOptions o;
  StereoResult r;
  REQUIRE(stereo_pair(va, vb, plane, o, r));
  REQUIRE(r.pairs.size() == 1);
  const StereoPairReport& rep = r.pairs[0];
  INFO("searched " << rep.disparity.searched << " valid " << rep.disparity.valid << " lr " << rep.disparity.lr_rejected
                   << " low score " << rep.disparity.low_score << " patches " << rep.patches);
  CHECK(rep.disparity.valid > 0.8 * rep.disparity.searched);
  // Every patch centre on the plane, its normal the plane's.
  std::vector<double> dist, ang;
  for (const StereoPatch& p : r.patches) {
    dist.push_back(std::abs(n.dot(p.centre - p0)));
    ang.push_back(std::acos(std::min(1.0, std::abs(n.dot(p.normal)))) * 180 / 3.14159265358979);
  }
  REQUIRE(r.patches.size() > 100);
  std::sort(dist.begin(), dist.end());
  std::sort(ang.begin(), ang.end());
  INFO("patch distance median " << dist[dist.size() / 2] * 1000 << " mm, p95 " << dist[dist.size() * 95 / 100] * 1000
                                << " mm; normal median " << ang[ang.size() / 2] << " deg, p95 "
                                << ang[ang.size() * 95 / 100]);
  CHECK(dist[dist.size() / 2] < 0.0002);
  CHECK(dist[dist.size() * 95 / 100] < 0.0008);
  CHECK(ang[ang.size() / 2] < 4.0);  // 8-pixel patches of about 5 mm
  // Each pixel's depth (before the patches): against the true plane along its ray.
  RectifiedCameras rc;
  std::vector<Vec3> roi = plane.positions;
  REQUIRE(rectified_cameras(a, b, roi, o.max_size, o.disparity.radius + 2, rc));
  ImageF ra, rb;
  REQUIRE(resample_rectified(ia, a, rc.a, ra, nullptr));
  REQUIRE(resample_rectified(ib, b, rc.b, rb, nullptr));
  int d_min, d_max;
  disparity_range(rc, plane.positions, d_min, d_max);
  DisparityMap dm;
  REQUIRE(compute_disparity(ra, rb, {}, d_min, d_max, o.disparity, dm));
  std::vector<double> depth_err;
  const Vec3 Ca = rc.a.center();
  for (int y = 0; y < dm.height; ++y)
    for (int x = 0; x < dm.width; ++x) {
      const float d = dm.at(x, y);
      if (std::isnan(d)) continue;
      Vec3 X;
      REQUIRE(triangulate_rectified(rc, x, y, d, X));
      // The ray's true point on the plane; away from the plane's edges (there the
      // window straddles the grey background).
      const Vec3 dir = X - Ca;
      const double s = n.dot(p0 - Ca) / n.dot(dir);
      if ((Ca + s * dir - p0).norm() > 0.18) continue;
      depth_err.push_back(std::abs(1 - s) * (rc.a.R * dir).z());
    }
  REQUIRE(depth_err.size() > 1000);
  std::sort(depth_err.begin(), depth_err.end());
  INFO("pixel depth error median " << depth_err[depth_err.size() / 2] * 1000 << " mm, p95 "
                                   << depth_err[depth_err.size() * 95 / 100] * 1000 << " mm over "
                                   << depth_err.size());
  CHECK(depth_err[depth_err.size() / 2] < 0.0005);
  CHECK(depth_err[depth_err.size() * 95 / 100] < 0.0015);
}

TEST_CASE("the left-right check removes the background an occluder hides from the right photo", "[photos][stereo]") {
  Camera a, b;
  camera_pair(20, a, b);
  const TriMesh scene = merged(square(0.5, 0, 30), square(0.08, 0.12, 4));
  const Image ia = render(scene, a), ib = render(scene, b);
  RectifiedCameras rc;
  REQUIRE(rectified_cameras(a, b, square(0.2, 0, 4).positions, 400, 5, rc));
  ImageF ra, rb;
  REQUIRE(resample_rectified(ia, a, rc.a, ra, nullptr));
  REQUIRE(resample_rectified(ib, b, rc.b, rb, nullptr));
  // Truth per left pixel: the surface it sees, and whether b sees that point.
  MeshBvh bvh;
  REQUIRE(build_bvh(scene, bvh));
  const Vec3 Ca = rc.a.center(), Cb = rc.b.center();
  std::vector<int> hidden(size_t(ra.width) * size_t(ra.height), -1);  // -1 no surface, 1 hidden from b, 0 seen
  for (int y = 0; y < ra.height; ++y)
    for (int x = 0; x < ra.width; ++x) {
      Ray ray;
      ray.origin = Ca;
      ray.direction = rc.a.R.transpose() * Vec3((x + 0.5 - rc.a.cx) / rc.a.fx, (y + 0.5 - rc.a.cy) / rc.a.fy, 1);
      const RayHit h = intersect_first(bvh, ray);
      if (!h.hit()) continue;
      const Vec3 X = Ca + h.t * ray.direction;
      Ray back;
      back.origin = X;
      back.direction = Cb - X;
      back.t_min = 1e-6;
      back.t_max = 1;
      Vec2 ub = Vec2::Zero();
      if (!rc.b.project(X, ub) || ub.x() < 8 || ub.x() > rc.b.width - 8) continue;  // outside b's frame
      hidden[size_t(y) * size_t(ra.width) + size_t(x)] = intersect_any(bvh, back, h.triangle) ? 1 : 0;
    }
  auto counts = [&](int tolerance, int& occluded_valid, int& occluded, int& seen_valid, int& seen) {
    DisparityOptions o;
    o.lr_tolerance = tolerance;
    DisparityMap dm;
    int d_min, d_max;
    disparity_range(rc, scene.positions, d_min, d_max);
    REQUIRE(compute_disparity(ra, rb, {}, d_min, d_max, o, dm));
    occluded_valid = occluded = seen_valid = seen = 0;
    for (size_t i = 0; i < hidden.size(); ++i) {
      const int x = int(i % size_t(ra.width)), y = int(i / size_t(ra.width));
      if (x < 8 || y < 8 || x >= ra.width - 8 || y >= ra.height - 8 || hidden[i] < 0) continue;
      (hidden[i] ? occluded : seen) += 1;
      if (!std::isnan(dm.d[i])) (hidden[i] ? occluded_valid : seen_valid) += 1;
    }
  };
  int ov, oc, sv, sn;
  counts(1, ov, oc, sv, sn);
  int ov_off, oc_off, sv_off, sn_off;
  counts(100000, ov_off, oc_off, sv_off, sn_off);
  INFO("occluded " << oc << ": valid with the check " << ov << ", without " << ov_off << "; seen " << sn
                   << ": valid " << sv << " / " << sv_off);
  REQUIRE(oc > 500);  // the occluder hides a real strip
  CHECK(ov < 0.15 * oc);
  CHECK(ov_off > 0.5 * oc_off);   // without the check those pixels get (wrong) disparities
  CHECK(sv > 0.75 * sn);          // and the check keeps the seen ones
}

TEST_CASE("stereo refuses bad input with a message", "[photos][stereo]") {
  Camera a, b;
  camera_pair(20, a, b);
  const TriMesh plane = square(0.3, 0, 10);
  const Image ia = render(plane, a), ib = render(plane, b);
  StereoOptions o;
  auto refusal = [&](const StereoView& va, const StereoView& vb) {
    StereoResult r;
    const Status s = stereo_pair(va, vb, plane, o, r);
    REQUIRE_FALSE(s);
    REQUIRE(r.pairs.size() == 1);
    CHECK(r.patches.empty());
    CHECK(s.message.find(r.pairs[0].refusal) != std::string::npos);
    return r.pairs[0].refusal;
  };
  CHECK(refusal({nullptr, a, {}, "a"}, {&ib, b, {}, "b"}) == "a has no image");
  Image tiny = Image::make(20, 16, 3, 128);
  Camera ct = a;
  ct.width = 20;
  ct.height = 16;
  CHECK(refusal({&tiny, ct, {}, "tiny"}, {&ib, b, {}, "b"}).find("too small") != std::string::npos);
  CHECK(refusal({&ia, b, {}, "a"}, {&ib, b, {}, "b"}).find("share one centre") != std::string::npos);
  Camera away = b;  // b turned round: the head is behind it
  away.R = Eigen::AngleAxisd(3.14159265358979, Vec3::UnitY()).toRotationMatrix() * b.R;
  away.t = -away.R * b.center();
  CHECK(refusal({&ia, a, {}, "a"}, {&ib, away, {}, "b"}).find("no overlap") != std::string::npos);
  Image wrong = Image::make(320, 240, 3, 0);
  CHECK(refusal({&ia, a, {}, "a"}, {&wrong, b, {}, "b"}) == "b is 320x240, its camera 640x480");
  // A flat grey pair: no texture, no patch, said so.
  const Image grey = Image::make(640, 480, 3, 128);
  StereoResult r;
  const Status s = stereo_pair({&grey, a, {}, "a"}, {&grey, b, {}, "b"}, plane, o, r);
  CHECK_FALSE(s);
  CHECK(s.message.find("no surface patch") != std::string::npos);
  CHECK(r.pairs.at(0).disparity.low_texture == r.pairs[0].disparity.searched);
  // Photos too far apart form no pair; that is not an error.
  Camera c, d;
  camera_pair(80, c, d);
  StereoResult none;
  REQUIRE(run_stereo({{&ia, c, {}, "c"}, {&ib, d, {}, "d"}}, plane, o, none));
  CHECK(none.pairs.empty());
}

TEST_CASE("the attractor's facet distance and its Jacobian match finite differences", "[photos][stereo]") {
  SplitMix64 rng(11);
  for (int trial = 0; trial < 50; ++trial) {
    Vec3 x[3], a(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
    for (Vec3& p : x) p = Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
    double d;
    Eigen::Matrix<double, 1, 9> g;
    REQUIRE(point_facet_distance(a, x[0], x[1], x[2], d, &g));
    // d is eq. 9's D / |C|: the 4x4 determinant over the cross product's norm.
    Eigen::Matrix4d D;
    for (int i = 0; i < 3; ++i) D.row(i) << x[i].transpose(), 1;
    D.row(3) << a.transpose(), 1;
    CHECK(std::abs(std::abs(d) - std::abs(D.determinant()) / (x[1] - x[0]).cross(x[2] - x[0]).norm()) < 1e-9);
    const double h = 1e-6;
    for (int k = 0; k < 9; ++k) {
      Vec3 xp[3] = {x[0], x[1], x[2]}, xm[3] = {x[0], x[1], x[2]};
      xp[k / 3][k % 3] += h;
      xm[k / 3][k % 3] -= h;
      double dp, dm;
      point_facet_distance(a, xp[0], xp[1], xp[2], dp, nullptr);
      point_facet_distance(a, xm[0], xm[1], xm[2], dm, nullptr);
      CHECK(std::abs((dp - dm) / (2 * h) - g[k]) < 1e-6 * (1 + std::abs(g[k])));
    }
  }
  // The whole set's Jacobian over a mesh's vertex positions.
  TriMesh sphere = make_icosphere(2);
  for (Vec3& p : sphere.positions) p *= 0.1;
  std::vector<StereoPatch> patches;
  for (int i = 0; i < 40; ++i) {
    StereoPatch p;
    const Vec3 dir = Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)).normalized();
    p.centre = dir * rng.uniform(0.095, 0.105);
    p.normal = dir;
    patches.push_back(p);
  }
  StereoAttractorSet set(sphere, patches, sphere.positions);
  std::vector<int> cols(size_t(3 * sphere.num_vertices()));
  for (size_t c = 0; c < cols.size(); ++c) cols[c] = int(c);
  const test::FdJacobian fd = test::check_fd_jacobian(set, sphere.positions, cols);
  REQUIRE(fd.jacobian.norm() > 0);
  const double worst = fd.worst_abs;
  CHECK(worst < 1e-6);
}

TEST_CASE("attractors attach to their closest facet, and eq. 10 drops outliers", "[photos][stereo]") {
  TriMesh sphere = make_icosphere(3);
  for (Vec3& p : sphere.positions) p *= 0.1;
  SplitMix64 rng(5);
  std::vector<StereoPatch> patches;
  for (int i = 0; i < 200; ++i) {
    StereoPatch p;
    const Vec3 dir = Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)).normalized();
    p.centre = dir * 0.101;  // 1 mm outside the sphere (the facets lie a little inside it)
    p.normal = dir;
    patches.push_back(p);
  }
  StereoPatch far = patches[0], flipped = patches[1];
  far.centre *= 1.3;          // 3 cm off: an outlier
  flipped.normal *= -1;       // facing into the head
  patches.push_back(far);
  patches.push_back(flipped);
  StereoAttractorSet set(sphere, patches, sphere.positions);
  const auto& att = set.attractors();
  Eigen::VectorXd r(set.num_residuals());
  REQUIRE(set.evaluate(sphere.positions, r, 0, nullptr));
  std::vector<double> d;
  for (int i = 0; i < 200; ++i) {
    REQUIRE(att[size_t(i)].triangle >= 0);
    CHECK(att[size_t(i)].weight > 0.2);
    d.push_back(r[i] / std::sqrt(att[size_t(i)].weight));
  }
  CHECK(median(d) > 0.001);
  CHECK(median(d) < 0.0015);
  CHECK(att[200].weight < 1e-6);
  CHECK(att[201].weight == 0);
  // Moving the surface onto the attractors lowers their distances.
  std::vector<Vec3> grown = sphere.positions;
  for (Vec3& p : grown) p *= 1.01;
  const std::vector<double> before = set.surface_distances(sphere.positions), after = set.surface_distances(grown);
  CHECK(median(after) < 0.5 * median(before));
}

}  // namespace
}  // namespace lk
