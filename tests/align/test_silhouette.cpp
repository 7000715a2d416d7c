// Silhouette masks (core/align/silhouette.h): exact pixel counts for known
// shapes, clipping, projection, hole filling of sparse points.
#include "align/silhouette.h"
#include "mesh/geometry.h"
#include "synthetic_head.h"

#include <catch2/catch.hpp>
#include <cmath>

using namespace lk;

TEST_CASE("set_span and count agree across word boundaries", "[silhouette]") {
  SilhouetteMask m = SilhouetteMask::make(200);
  m.set_span(3, 60, 130);  // crosses two word boundaries
  m.set_span(4, 0, 200);
  m.set_span(5, -10, 5);   // clamped
  m.set_span(6, 190, 400);
  m.set_span(7, 10, 10);   // empty
  CHECK(m.count() == 70 + 200 + 5 + 10);
  CHECK(m.get(60, 3));
  CHECK(m.get(129, 3));
  CHECK(!m.get(130, 3));
  CHECK(!m.get(59, 3));
  SilhouetteMask e = SilhouetteMask::make(200);
  CHECK(xor_count(m, e) == m.count());
  CHECK(xor_count(m, m) == 0);
}

TEST_CASE("a square of two triangles covers exactly its pixel centres", "[silhouette]") {
  SilhouetteMask m = SilhouetteMask::make(64);
  // [10, 30) x [20, 50): 20 x 30 pixel centres, whatever the diagonal.
  rasterize_triangle(Vec2(10, 20), Vec2(30, 20), Vec2(30, 50), m);
  rasterize_triangle(Vec2(10, 20), Vec2(30, 50), Vec2(10, 50), m);
  CHECK(m.count() == 600);
  CHECK(m.get(10, 20));
  CHECK(m.get(29, 49));
  CHECK(!m.get(30, 20));
  CHECK(!m.get(10, 50));
  // Shifted by 0.3 pixel the count stays 20 x 30 (centres 10.5..29.5 lie in [10.3, 30.3)).
  SilhouetteMask s = SilhouetteMask::make(64);
  rasterize_triangle(Vec2(10.3, 20.3), Vec2(30.3, 50.3), Vec2(30.3, 20.3), s);  // other winding
  rasterize_triangle(Vec2(10.3, 20.3), Vec2(10.3, 50.3), Vec2(30.3, 50.3), s);
  CHECK(s.count() == 600);
}

TEST_CASE("a right triangle covers the analytic count of pixel centres", "[silhouette]") {
  // Centres (i+.5, j+.5) with x + y < 8, i.e. i + j < 7: 7+6+...+1 = 28.
  SilhouetteMask m = SilhouetteMask::make(16);
  rasterize_triangle(Vec2(0, 0), Vec2(8, 0), Vec2(0, 8), m);
  CHECK(m.count() == 28);
  // A fan of triangles around an interior point covers a polygon without gaps.
  SilhouetteMask fan = SilhouetteMask::make(64);
  const Vec2 c(31.7, 29.2);
  const Vec2 corners[4] = {Vec2(5, 6), Vec2(55, 6), Vec2(55, 46), Vec2(5, 46)};
  for (int k = 0; k < 4; ++k) rasterize_triangle(c, corners[k], corners[(k + 1) % 4], fan);
  CHECK(fan.count() == 50 * 40);
  // Degenerate, NaN and far-away triangles draw nothing / clamp, never crash.
  SilhouetteMask d = SilhouetteMask::make(16);
  rasterize_triangle(Vec2(1, 1), Vec2(5, 5), Vec2(9, 9), d);
  rasterize_triangle(Vec2(std::nan(""), 1), Vec2(5, 5), Vec2(9, 1), d);
  CHECK(d.count() == 0);
  rasterize_triangle(Vec2(-1e30, -1e30), Vec2(1e30, -1e30), Vec2(0, 1e30), d);
  CHECK(d.count() == 16 * 16);
}

TEST_CASE("views project world axes as documented", "[silhouette]") {
  BBox box;
  box.extend(Vec3(-1, -1, -1));
  box.extend(Vec3(1, 1, 1));
  const ViewWindow w = make_view_window(box, 0.0, 100);
  CHECK(w.pixel_size() == Approx(0.02));
  const Vec3 p(0.5, 0.8, -0.3);  // right of centre, high, behind
  const Vec2 front = w.project(p, SilhouetteView::Front);
  CHECK(front.x() == Approx(75));
  CHECK(front.y() == Approx(10));  // high = near the top row
  const Vec2 side = w.project(p, SilhouetteView::Side);
  CHECK(side.x() == Approx(35));
  CHECK(side.y() == Approx(10));
  const Vec2 top = w.project(p, SilhouetteView::Top);
  CHECK(top.x() == Approx(75));
  CHECK(top.y() == Approx(35));
}

TEST_CASE("mesh silhouettes of a box, whole and clipped", "[silhouette]") {
  // A closed box [-0.5,0.5]^3 in a window of half size 1 at 128 pixels: each
  // view sees a 64 x 64 square.
  TriMesh box;
  for (int i = 0; i < 8; ++i) box.positions.push_back(Vec3(i & 1 ? 0.5 : -0.5, i & 2 ? 0.5 : -0.5, i & 4 ? 0.5 : -0.5));
  const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (auto& f : faces) {
    box.triangles.push_back({f[0], f[1], f[2]});
    box.triangles.push_back({f[0], f[2], f[3]});
  }
  ViewWindow w;
  w.center = Vec3::Zero();
  w.half_size = 1.0;
  w.resolution = 128;
  std::array<SilhouetteMask, kSilhouetteViews> masks;
  rasterize_mesh_silhouettes(box.positions, box.triangles, w, {}, masks);
  for (auto& m : masks) CHECK(m.count() == 64 * 64);
  // Cut below y = 0.25: front and side keep 16 rows of 64, top still sees all.
  ClipPlane cut;
  cut.point = Vec3(0, 0.25, 0);
  cut.normal = Vec3(0, 1, 0);
  rasterize_mesh_silhouettes(box.positions, box.triangles, w, {cut}, masks);
  CHECK(masks[0].count() == 16 * 64);
  CHECK(masks[1].count() == 16 * 64);
  CHECK(masks[2].count() == 64 * 64);
  // A second plane removing x < 0 halves what is left in front and top.
  ClipPlane left;
  left.point = Vec3::Zero();
  left.normal = Vec3(1, 0, 0);
  rasterize_mesh_silhouettes(box.positions, box.triangles, w, {cut, left}, masks);
  CHECK(masks[0].count() == 16 * 32);
  CHECK(masks[1].count() == 16 * 64);
  CHECK(masks[2].count() == 32 * 64);
}

TEST_CASE("closing fills holes but keeps a convex outline", "[silhouette]") {
  SilhouetteMask square = SilhouetteMask::make(64);
  for (int y = 10; y < 40; ++y) square.set_span(y, 12, 50);
  CHECK(close_mask(square, 3.0).count() == square.count());
  SilhouetteMask holed = square;
  holed.bits[static_cast<size_t>(20) * holed.words_per_row] &= ~(std::uint64_t(1) << 20);  // a one-pixel hole
  CHECK(holed.count() == square.count() - 1);
  CHECK(close_mask(holed, 1.0).count() == square.count());
}

TEST_CASE("sparse points are closed into a full silhouette of the right size", "[silhouette]") {
  // Points on a square grid of spacing 3 pixels over a disk of radius 40 px:
  // one point per 9 pixels, so the raw splat covers about 1/9 of the disk.
  ViewWindow w;
  w.center = Vec3::Zero();
  w.half_size = 1.0;
  w.resolution = 128;
  const double px = w.pixel_size();
  std::vector<Vec3> pts;
  for (double x = -40; x <= 40; x += 3)
    for (double y = -40; y <= 40; y += 3)
      if (x * x + y * y <= 40 * 40) pts.push_back(Vec3((x + 0.1) * px, (y + 0.1) * px, 0.0));
  std::array<SilhouetteMask, kSilhouetteViews> masks;
  PointSilhouetteInfo info;
  rasterize_point_silhouettes(pts, w, {}, PointSplatOptions{}, masks, &info);
  const double disk = 3.14159265 * 40 * 40;
  CHECK(info.raw_pixels[0] < 0.15 * disk);
  CHECK(info.closing_radius_px[0] >= 1.5);
  // No hole is left inside, and the outline is that of the outermost points
  // (up to one grid spacing inside the disk), not grown beyond the disk.
  int inner_holes = 0;
  for (int y = 0; y < 128; ++y)
    for (int x = 0; x < 128; ++x) {
      const double dx = x + 0.5 - 64, dy = y + 0.5 - 64;
      if (dx * dx + dy * dy < 36 * 36 && !masks[0].get(x, y)) ++inner_holes;
    }
  CHECK(inner_holes == 0);
  CHECK(info.covered_pixels[0] > 0.9 * disk);
  CHECK(info.covered_pixels[0] < 1.01 * disk);
  CHECK(info.points_kept == static_cast<int>(pts.size()));
  // A dense cloud needs no closing.
  std::vector<Vec3> dense;
  for (double x = -40; x <= 40; x += 0.5)
    for (double y = -40; y <= 40; y += 0.5)
      if (x * x + y * y <= 40 * 40) dense.push_back(Vec3(x * px, y * px, 0.0));
  rasterize_point_silhouettes(dense, w, {}, PointSplatOptions{}, masks, &info);
  CHECK(info.closing_radius_px[0] == 0.0);
  CHECK(info.covered_pixels[0] == Approx(disk).epsilon(0.03));
  // Clip planes drop points; NaN points are ignored.
  ClipPlane upper;
  upper.normal = Vec3(0, 1, 0);
  dense.push_back(Vec3(std::nan(""), 0, 0));
  rasterize_point_silhouettes(dense, w, {upper}, PointSplatOptions{}, masks, &info);
  CHECK(info.covered_pixels[0] == Approx(disk / 2).epsilon(0.04));
}

TEST_CASE("back-face culling leaves clipped head silhouettes unchanged", "[silhouette]") {
  // Culling is only a speed-up: for an outward-oriented head cut by a
  // horizontal neck plane and a slanted back plane (whose cut side faces the
  // top view, so one looks into the head from above), every view must come
  // out exactly as without culling, in any pose.
  const GenericHead head = test::synthetic_head();
  ClipPlane neck = head.annotations.neck_clip;
  ClipPlane back;
  back.point = Vec3(0, 0, -0.03);
  back.normal = Vec3(0, -0.3, 1).normalized();
  ViewWindow w;
  w.center = Vec3(0, -0.02, 0);
  w.half_size = 0.2;
  w.resolution = 200;
  for (int k = 0; k < 4; ++k) {
    const Mat3 r = Eigen::AngleAxisd(0.08 * k, Vec3(1, 0.5, 0.2).normalized()).toRotationMatrix();
    std::vector<Vec3> moved;
    for (const Vec3& p : head.mesh.positions) moved.push_back(r * p);
    std::array<SilhouetteMask, kSilhouetteViews> culled, full;
    for (const auto& clips : {std::vector<ClipPlane>{}, std::vector<ClipPlane>{neck}, std::vector<ClipPlane>{neck, back}}) {
      rasterize_mesh_silhouettes(moved, head.mesh.triangles, w, clips, culled, true);
      rasterize_mesh_silhouettes(moved, head.mesh.triangles, w, clips, full, false);
      for (int v = 0; v < kSilhouetteViews; ++v) {
        INFO("pose " << k << ", " << clips.size() << " planes, view " << v);
        CHECK(full[v].count() > 1000);
        CHECK(xor_count(culled[v], full[v]) == 0);
      }
    }
  }
}

TEST_CASE("a mesh drawn in two triangle ranges has the whole mesh's silhouette", "[silhouette]") {
  // The initial alignment draws the two halves of the generic head on two
  // threads into two sets of masks and counts their union against the
  // cloud's: every view must be the whole mesh's, bit for bit, clipped and
  // culled, in any pose and at any split.
  const GenericHead head = test::synthetic_head();
  ClipPlane neck = head.annotations.neck_clip;
  ViewWindow w;
  w.center = Vec3(0, -0.02, 0);
  w.half_size = 0.2;
  w.resolution = 256;
  const int nf = head.mesh.num_triangles();
  std::array<SilhouetteMask, kSilhouetteViews> cloud;
  // Any other mask to count against: the unrotated head's.
  rasterize_mesh_silhouettes(head.mesh.positions, head.mesh.triangles, w, {neck}, cloud, true);
  for (int k = 0; k < 4; ++k) {
    const Mat3 r = Eigen::AngleAxisd(0.07 * (k + 1), Vec3(0.3, 1, 0.4).normalized()).toRotationMatrix();
    std::vector<Vec3> moved;
    for (const Vec3& p : head.mesh.positions) moved.push_back(r * p + Vec3(0.004 * k, 0, 0));
    for (int split : {nf / 2, nf / 3, 0, nf}) {
      std::array<SilhouetteMask, kSilhouetteViews> whole, first, second;
      rasterize_mesh_silhouettes(moved, head.mesh.triangles, w, {neck}, whole, true);
      rasterize_mesh_silhouettes(moved, head.mesh.triangles, w, {neck}, first, true, TriangleRange{0, split});
      rasterize_mesh_silhouettes(moved, head.mesh.triangles, w, {neck}, second, true, TriangleRange{split});
      for (int v = 0; v < kSilhouetteViews; ++v) {
        INFO("pose " << k << ", split at " << split << " of " << nf << ", view " << v);
        SilhouetteMask joined = first[v];
        for (size_t i = 0; i < joined.bits.size(); ++i) joined.bits[i] |= second[v].bits[i];
        CHECK(xor_count(joined, whole[v]) == 0);
        CHECK(union_xor_count(first[v], second[v], cloud[v]) == xor_count(whole[v], cloud[v]));
        if (split > 0 && split < nf) {  // both halves draw something, neither draws all
          CHECK(first[v].count() > 0);
          CHECK(second[v].count() > 0);
          CHECK(xor_count(first[v], whole[v]) > 0);
        }
      }
    }
  }
  // A range past the end or empty draws nothing.
  std::array<SilhouetteMask, kSilhouetteViews> none;
  rasterize_mesh_silhouettes(head.mesh.positions, head.mesh.triangles, w, {}, none, true, TriangleRange{nf, nf + 5});
  for (const SilhouetteMask& m : none) CHECK(m.count() == 0);
}

namespace {

// Chamfer score and XOR count of the synthetic head turned by pitch_deg
// about x (through centre) against the target masks.
void scores_at(const GenericHead& head, double pitch_deg, const Vec3& centre, const ViewWindow& window,
               const std::vector<ClipPlane>& clips, const std::vector<Edge>& edges,
               const std::array<SilhouetteMask, kSilhouetteViews>& target,
               const std::array<OutlineField, kSilhouetteViews>& fields, double& chamfer, int& xor_d) {
  const Mat3 r = Eigen::AngleAxisd(pitch_deg * 3.14159265358979 / 180.0, Vec3::UnitX()).toRotationMatrix();
  std::vector<Vec3> moved;
  for (const Vec3& p : head.mesh.positions) moved.push_back(r * (p - centre) + centre);
  std::array<SilhouetteMask, kSilhouetteViews> masks;
  rasterize_mesh_silhouettes(moved, head.mesh.triangles, window, clips, masks);
  std::array<std::vector<Vec2>, kSilhouetteViews> outline;
  mesh_outline_points(moved, head.mesh.triangles, edges, window, clips, masks, outline);
  chamfer = 0;
  xor_d = 0;
  for (int v = 0; v < kSilhouetteViews; ++v) {
    chamfer += outline_chamfer(fields[v], outline[v]);
    xor_d += xor_count(masks[v], target[v]);
  }
}

}  // namespace

TEST_CASE("the outline chamfer score slopes under small pitches where the XOR count is flat", "[silhouette]") {
  // Target: a dense cloud sampled from the synthetic head at its true pose.
  const GenericHead head = test::synthetic_head();
  const PointCloud cloud = test::sample_surface(head.mesh, 200000, 7);
  const std::vector<ClipPlane> clips = {head.annotations.neck_clip};
  const BBox box = bounding_box(cloud.positions);
  const ViewWindow window = make_view_window(box, 0.12, 256);
  std::array<SilhouetteMask, kSilhouetteViews> target;
  rasterize_point_silhouettes(cloud.positions, window, clips, PointSplatOptions{}, target);
  std::array<OutlineField, kSilhouetteViews> fields;
  for (int v = 0; v < kSilhouetteViews; ++v) fields[v] = make_outline_field(target[v], 16.0);
  MeshTopology topology;
  REQUIRE(build_topology(head.mesh, topology).ok());
  const std::vector<Edge>& edges = topology.edges;
  const Vec3 centre = box.center();
  auto chamfer_at = [&](double pitch, int* xor_d = nullptr) {
    double chamfer = 0;
    int x = 0;
    scores_at(head, pitch, centre, window, clips, edges, target, fields, chamfer, x);
    if (xor_d) *xor_d = x;
    return chamfer;
  };

  // Lowest at the true pose, higher 1 deg off and higher still 2 deg off.
  // (Not monotone at every 0.2 deg: it dips by 0.06 % at -0.2 and 0.3 % at
  // -1.4 deg, as the outline points change; docs/design/align.md.)
  const double at0 = chamfer_at(0.0);
  for (double sign : {1.0, -1.0}) {
    const double at1 = chamfer_at(sign), at2 = chamfer_at(2 * sign);
    INFO("pitch sign " << sign << ": chamfer 0 / 1 / 2 deg " << at0 << " / " << at1 << " / " << at2);
    CHECK(at0 < at1);
    CHECK(at1 < at2);
  }
  // Under 0.002 deg steps (a few thousandths of a pixel at the outline) the
  // chamfer score changes at every step; the integer XOR count stays the
  // same at some of them, so this check would fail for it.
  int xor_previous = 0, xor_flat = 0, chamfer_flat = 0;
  double chamfer_previous = 0;
  for (int k = 0; k <= 10; ++k) {
    int xor_d = 0;
    const double chamfer = chamfer_at(0.002 * k, &xor_d);
    if (k > 0) {
      if (chamfer == chamfer_previous) ++chamfer_flat;
      if (xor_d == xor_previous) ++xor_flat;
    }
    chamfer_previous = chamfer;
    xor_previous = xor_d;
  }
  CHECK(chamfer_flat == 0);
  CHECK(xor_flat > 0);
}
