// Renderer tests under OSMesa. Ground truth is analytic: the silhouette of
// an ellipsoid plus a marker sphere is ray-cast exactly per pixel with the
// same camera matrices and compared to the rendered coverage; point sprites
// are found as blobs at their projected positions; a four-colour texture
// must show its quadrants in the right places (catches row flips).
#include <catch2/catch.hpp>

#include "head/generic_head.h"
#include "mesh/geometry.h"
#include "render/camera.h"
#include "render/offscreen.h"
#include "render/renderer.h"

#include <glm/gtc/matrix_transform.hpp>

#include <cmath>
#include <functional>
#include <string>
#include <vector>

using namespace lk;

namespace {

constexpr double kPi = 3.14159265358979323846;

// A UV-tessellated ellipsoid with radii r centred at c, outward CCW faces.
void append_ellipsoid(TriMesh& m, const Vec3& c, const Vec3& r, int rings, int segments) {
  const int base = m.num_vertices();
  for (int i = 0; i <= rings; ++i) {
    const double theta = kPi * i / rings;  // from +y down
    for (int j = 0; j < segments; ++j) {
      const double phi = 2 * kPi * j / segments;
      const Vec3 unit(std::sin(theta) * std::sin(phi), std::cos(theta), std::sin(theta) * std::cos(phi));
      m.positions.push_back(c + unit.cwiseProduct(r));
    }
  }
  auto id = [&](int i, int j) { return base + i * segments + (j % segments); };
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      // Seen from outside, (i,j) -> (i+1,j) -> (i+1,j+1) turns counter-clockwise.
      if (i > 0) m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      if (i < rings - 1) m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
}

// The test "head": an ellipsoid of head-like proportions and a marker sphere
// on its upper LEFT (+x, +y), which must show on the image's right and top.
const Vec3 kHeadRadii(0.075, 0.11, 0.095);
const Vec3 kMarkerCenter(0.06, 0.08, 0.03);
const double kMarkerRadius = 0.03;

TriMesh test_head() {
  TriMesh m;
  append_ellipsoid(m, Vec3::Zero(), kHeadRadii, 96, 128);
  append_ellipsoid(m, kMarkerCenter, Vec3::Constant(kMarkerRadius), 48, 64);
  return m;
}

bool ray_hits_ellipsoid(const glm::dvec3& o, const glm::dvec3& d, const Vec3& c, const Vec3& r) {
  // Scale space so the ellipsoid becomes the unit sphere.
  const glm::dvec3 oc((o.x - c.x()) / r.x(), (o.y - c.y()) / r.y(), (o.z - c.z()) / r.z());
  const glm::dvec3 dd(d.x / r.x(), d.y / r.y(), d.z / r.z());
  const double a = glm::dot(dd, dd), b = 2 * glm::dot(oc, dd), cc = glm::dot(oc, oc) - 1;
  const double disc = b * b - 4 * a * cc;
  return disc >= 0 && (-b + std::sqrt(disc)) > 0;
}

// Exact coverage mask of the test head for pixel centres.
std::vector<char> analytic_mask(const CameraMatrices& cam, int w, int h) {
  const glm::dmat4 inv = glm::inverse(glm::dmat4(cam.projection) * glm::dmat4(cam.view));
  std::vector<char> mask(static_cast<size_t>(w) * h, 0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double nx = (x + 0.5) / w * 2 - 1, ny = 1 - (y + 0.5) / h * 2;  // image rows top-down
      glm::dvec4 a = inv * glm::dvec4(nx, ny, -1, 1), b = inv * glm::dvec4(nx, ny, 1, 1);
      const glm::dvec3 o = glm::dvec3(a) / a.w, e = glm::dvec3(b) / b.w;
      const glm::dvec3 d = e - o;
      mask[static_cast<size_t>(y) * w + x] =
          ray_hits_ellipsoid(o, d, Vec3::Zero(), kHeadRadii) ||
          ray_hits_ellipsoid(o, d, kMarkerCenter, Vec3::Constant(kMarkerRadius));
    }
  return mask;
}

const glm::vec3 kKeyGreen(0.0f, 1.0f, 0.0f);  // background never produced by shading skin

bool is_background(const Image& im, int x, int y) {
  const std::uint8_t* p = im.at(x, y);
  return p[0] == 0 && p[1] == 255 && p[2] == 0;
}

Image render(const SceneSetup& setup, const CameraForAspect& cam, int w, int h) {
  OffscreenOptions o;
  o.width = w;
  o.height = h;
  o.supersample = 1;  // exact coverage, no edge blending
  o.renderer.background_top = o.renderer.background_bottom = kKeyGreen;
  Image im;
  const Status s = render_offscreen(setup, cam, o, im);
  INFO(s.message);
  REQUIRE(s.ok());
  REQUIRE(im.width == w);
  REQUIRE(im.height == h);
  REQUIRE(im.channels == 3);
  return im;
}

SceneSetup mesh_scene(const TriMesh& mesh, bool wireframe = false, DrawableHandle* handle = nullptr) {
  return [mesh, wireframe, handle](Renderer& r) {
    DrawableHandle h;
    Status s = r.upload_mesh(mesh, h);
    if (s) s = r.set_wireframe(h, wireframe);
    if (handle) *handle = h;
    return s;
  };
}

BBox test_head_bbox() { return bounding_box(test_head().positions); }

double luminance(const std::uint8_t* p) { return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]; }

struct MaskStats {
  double fraction = 0;
  int min_x = 1 << 30, max_x = -1, min_y = 1 << 30, max_y = -1;
};

MaskStats foreground_stats(const Image& im) {
  MaskStats s;
  int n = 0;
  for (int y = 0; y < im.height; ++y)
    for (int x = 0; x < im.width; ++x)
      if (!is_background(im, x, y)) {
        ++n;
        s.min_x = std::min(s.min_x, x);
        s.max_x = std::max(s.max_x, x);
        s.min_y = std::min(s.min_y, y);
        s.max_y = std::max(s.max_y, y);
      }
  s.fraction = double(n) / (im.width * im.height);
  return s;
}


// The default orbit camera (on +z, looking at the origin) `distance` away,
// framing a scene of `scene_radius`, for a square image.
CameraMatrices orbit_view(float distance, float scene_radius) {
  OrbitCamera cam;
  cam.distance = distance;
  cam.scene_radius = scene_radius;
  return cam.matrices(1.0f);
}

}  // namespace

TEST_CASE("silhouette matches the analytic ray-cast for every canonical view", "[render]") {
  const int w = 160, h = 120;  // not square: aspect handling is exercised
  const TriMesh mesh = test_head();
  for (const char* name : {"front", "left", "right", "back", "top", "three-quarter"}) {
    CanonicalView v;
    REQUIRE(parse_canonical_view(name, v).ok());
    const OrbitCamera cam = canonical_view(v, mesh.positions, float(w) / h);
    const CameraMatrices m = cam.matrices(float(w) / h);
    const Image im = render(mesh_scene(mesh), [&](float) { return m; }, w, h);
    const std::vector<char> truth = analytic_mask(m, w, h);
    int inter = 0, uni = 0, truth_n = 0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const bool a = !is_background(im, x, y), b = truth[size_t(y) * w + x];
        inter += a && b;
        uni += a || b;
        truth_n += b;
      }
    const double iou = double(inter) / uni;
    INFO("view " << name << ": IoU " << iou << ", truth pixels " << truth_n);
    CHECK(iou > 0.97);
    // Tight framing: the object fills a good part of the frame yet is not cut.
    const MaskStats s = foreground_stats(im);
    CHECK(s.fraction > 0.15);
    CHECK(s.min_x > 0);
    CHECK(s.max_x < w - 1);
    CHECK(s.min_y > 0);
    CHECK(s.max_y < h - 1);
    CHECK((s.max_y - s.min_y > 0.85 * h || s.max_x - s.min_x > 0.85 * w));
  }
}

TEST_CASE("front view shows the head's left (+x) on the image's right, up on top", "[render]") {
  const int w = 128, h = 128;
  OrbitCamera cam = canonical_view(CanonicalView::Front, test_head_bbox(), 1.0f);
  const CameraMatrices m = cam.matrices(1.0f);
  const Image im = render(mesh_scene(test_head()), [&](float) { return m; }, w, h);
  // The marker pokes out beyond the ellipsoid's outline at the upper right;
  // find the foreground's extent per quadrant row band.
  int right_top = 0, left_top = 0;
  for (int y = 0; y < h / 2; ++y)
    for (int x = 0; x < w; ++x)
      if (!is_background(im, x, y)) (x >= w / 2 ? right_top : left_top)++;
  INFO("upper-right coverage " << right_top << ", upper-left " << left_top);
  CHECK(right_top > left_top * 1.05);
}

TEST_CASE("shading varies and the key light comes from the upper left", "[render]") {
  const int w = 128, h = 128;
  TriMesh ellipsoid;
  append_ellipsoid(ellipsoid, Vec3::Zero(), kHeadRadii, 64, 96);
  OrbitCamera cam = canonical_view(CanonicalView::Front, bounding_box(ellipsoid.positions), 1.0f);
  const CameraMatrices m = cam.matrices(1.0f);
  const Image im = render(mesh_scene(ellipsoid), [&](float) { return m; }, w, h);
  double sum = 0, sum2 = 0, left = 0, right = 0;
  int n = 0, nl = 0, nr = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      if (is_background(im, x, y)) continue;
      const double l = luminance(im.at(x, y));
      sum += l;
      sum2 += l * l;
      ++n;
      if (x < w / 2) { left += l; ++nl; } else { right += l; ++nr; }
    }
  REQUIRE(n > 1000);
  const double mean = sum / n, sd = std::sqrt(std::max(sum2 / n - mean * mean, 0.0));
  INFO("mean luminance " << mean << ", sd " << sd << ", left " << left / nl << ", right " << right / nr);
  CHECK(mean > 60);    // lit, not black
  CHECK(mean < 230);   // not blown out
  CHECK(sd > 15);      // shaded, not flat
  CHECK(left / nl > right / nr + 5);
  // Skin tone by default: red above green above blue at the brightest point.
  const std::uint8_t* c = im.at(w / 2 - 10, h / 2 - 10);
  CHECK(c[0] > c[1]);
  CHECK(c[1] > c[2]);
}

TEST_CASE("wireframe overlay draws edges, and edges-only leaves the surface out", "[render]") {
  const int w = 128, h = 128;
  TriMesh coarse;
  append_ellipsoid(coarse, Vec3::Zero(), kHeadRadii, 8, 12);
  OrbitCamera cam = canonical_view(CanonicalView::Front, bounding_box(coarse.positions), 1.0f);
  const CameraMatrices m = cam.matrices(1.0f);
  auto dark = [&](const Image& im) {
    int n = 0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        if (!is_background(im, x, y) && luminance(im.at(x, y)) < 50) ++n;
    return n;
  };
  const Image plain = render(mesh_scene(coarse, false), [&](float) { return m; }, w, h);
  const Image wired = render(mesh_scene(coarse, true), [&](float) { return m; }, w, h);
  const Image edges_only = render(
      [&](Renderer& r) {
        DrawableHandle hd;
        Status s = r.upload_mesh(coarse, hd);
        if (!s) return s;
        r.style(hd)->surface = false;
        r.style(hd)->wireframe = true;
        return Status::success();
      },
      [&](float) { return m; }, w, h);
  INFO("dark pixels: plain " << dark(plain) << ", wired " << dark(wired));
  CHECK(dark(wired) > dark(plain) + 300);
  // Edge pixels are blended over the green background; count the solid ones.
  auto solid_fraction = [&](const Image& im) {
    int n = 0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) n += im.at(x, y)[1] < 128;
    return double(n) / (w * h);
  };
  const double covered = foreground_stats(plain).fraction;
  const double lines = solid_fraction(edges_only);
  INFO("coverage: surface " << covered << ", edges only " << lines);
  CHECK(lines > 0.02);
  CHECK(lines < 0.7 * covered);  // front and back edges both show
  // Inside large front triangles there is surface in the shaded render and
  // background in the edges-only one.
  int big = 0, open_inside = 0;
  for (const Tri& t : coarse.triangles) {
    glm::vec2 q[3];
    for (int c = 0; c < 3; ++c) {
      const Vec3& p = coarse.positions[t[c]];
      const glm::vec4 cl = m.projection * m.view * glm::vec4(p.x(), p.y(), p.z(), 1.0f);
      q[c] = glm::vec2((cl.x / cl.w * 0.5f + 0.5f) * w, (0.5f - cl.y / cl.w * 0.5f) * h);
    }
    const float area2 = (q[1].x - q[0].x) * (q[2].y - q[0].y) - (q[2].x - q[0].x) * (q[1].y - q[0].y);
    if (area2 > -120.0f) continue;  // back-facing or small (image y points down: CCW turns negative)
    const glm::vec2 c = (q[0] + q[1] + q[2]) / 3.0f;
    const int x = int(c.x), y = int(c.y);
    REQUIRE(!is_background(plain, x, y));
    ++big;
    open_inside += is_background(edges_only, x, y);
    // Never skin there (red-dominant): background, or a dark edge from the
    // back showing through, blended over the green.
    CHECK(int(edges_only.at(x, y)[0]) < 60);
    CHECK(int(plain.at(x, y)[0]) > 80);
  }
  INFO(open_inside << " of " << big << " large front triangles are open inside");
  CHECK(big > 20);
  CHECK(open_inside > 0.3 * big);
}

TEST_CASE("points render as round sprites of the requested size where they project", "[render]") {
  const int w = 160, h = 160;
  PointCloud cloud;
  cloud.positions = {Vec3(0, 0, 0), Vec3(0.5, 0.5, 0), Vec3(-0.5, 0.4, 0), Vec3(-0.4, -0.5, 0.2),
                     Vec3(0.45, -0.45, -0.2)};
  cloud.colors.assign(cloud.positions.size(), Vec3(1.0, 0.2, 0.2));
  const float size = 11.0f;
  const CameraMatrices m = orbit_view(3.0f, 1.0f);
  const Image im = render(
      [&](Renderer& r) {
        DrawableHandle hd;
        Status s = r.upload_points(cloud, hd);
        if (s) s = r.set_point_size(hd, size);
        return s;
      },
      [&](float) { return m; }, w, h);
  int total = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) total += !is_background(im, x, y);
  for (const Vec3& p : cloud.positions) {
    glm::vec4 clip = m.projection * m.view * glm::vec4(p.x(), p.y(), p.z(), 1.0f);
    const double px = (clip.x / clip.w * 0.5 + 0.5) * w, py = (0.5 - clip.y / clip.w * 0.5) * h;
    int n = 0;
    double cx = 0, cy = 0;
    for (int y = int(py) - 10; y <= int(py) + 10; ++y)
      for (int x = int(px) - 10; x <= int(px) + 10; ++x)
        if (x >= 0 && y >= 0 && x < w && y < h && !is_background(im, x, y)) {
          ++n;
          cx += x + 0.5;
          cy += y + 0.5;
          const std::uint8_t* c = im.at(x, y);
          CHECK(c[0] > c[1]);  // colored by the cloud's colors
        }
    INFO("point at " << px << "," << py << ": " << n << " pixels");
    REQUIRE(n > 0);
    // A disc of diameter 11 covers ~95 pixels; a square sprite would be 121.
    CHECK(n > 0.75 * kPi * size * size / 4);
    CHECK(n < 0.92 * size * size);
    CHECK(std::abs(cx / n - px) < 1.0);
    CHECK(std::abs(cy / n - py) < 1.0);
  }
  CHECK(total < int(cloud.positions.size() * size * size));  // nothing else drawn
}

TEST_CASE("points without colors are colored by their normals", "[render]") {
  PointCloud cloud;
  cloud.positions = {Vec3(-0.3, 0, 0), Vec3(0.3, 0, 0)};
  cloud.normals = {Vec3(-1, 0, 0), Vec3(1, 0, 0)};  // -x -> cyan-ish, +x -> red-ish
  const CameraMatrices m = orbit_view(2.0f, 1.0f);
  const Image im = render(
      [&](Renderer& r) {
        DrawableHandle hd;
        Status s = r.upload_points(cloud, hd);
        if (s) s = r.set_point_size(hd, 9.0f);
        return s;
      },
      [&](float) { return m; }, 96, 96);
  double left_r = 0, right_r = 0;
  int nl = 0, nr = 0;
  for (int y = 0; y < 96; ++y)
    for (int x = 0; x < 96; ++x)
      if (!is_background(im, x, y)) {
        if (x < 48) { left_r += im.at(x, y)[0]; ++nl; } else { right_r += im.at(x, y)[0]; ++nr; }
      }
  REQUIRE(nl > 20);
  REQUIRE(nr > 20);
  CHECK(right_r / nr > left_r / nl + 80);
}

TEST_CASE("a texture shows up the right way round, per-vertex and per-corner uvs", "[render]") {
  // Quadrants: red top-left, green top-right, blue bottom-left, white
  // bottom-right (image rows top-down, as lk::Image stores them).
  Image tex = Image::make(64, 64, 3);
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) {
      std::uint8_t* p = tex.at(x, y);
      const bool top = y < 32, left_half = x < 32;
      p[0] = (top && left_half) || (!top && !left_half) ? 255 : 0;
      p[1] = (top && !left_half) || (!top && !left_half) ? 255 : 0;
      p[2] = (!top && left_half) || (!top && !left_half) ? 255 : 0;
    }
  TriMesh quad;
  quad.positions = {Vec3(-1, -1, 0), Vec3(1, -1, 0), Vec3(1, 1, 0), Vec3(-1, 1, 0)};
  quad.triangles = {Tri{0, 1, 2}, Tri{0, 2, 3}};
  quad.uvs = {Vec2(0, 0), Vec2(1, 0), Vec2(1, 1), Vec2(0, 1)};  // OBJ: v = 0 at the image bottom
  TriMesh corner_quad = quad;
  corner_quad.uv_per_corner = true;
  corner_quad.uvs = {Vec2(0, 0), Vec2(1, 0), Vec2(1, 1), Vec2(0, 0), Vec2(1, 1), Vec2(0, 1)};

  const CameraMatrices m = orbit_view(4.0f, 1.5f);
  for (const TriMesh* q : {&quad, &corner_quad}) {
    const Image im = render(
        [&](Renderer& r) {
          DrawableHandle hd;
          TextureHandle th;
          Status s = r.upload_mesh(*q, hd);
          if (s) r.style(hd)->specular = 0.0f;  // keep texel colours pure
          if (s) s = r.upload_texture(tex, th);
          if (s) s = r.attach_texture(hd, th);
          return s;
        },
        [&](float) { return m; }, 96, 96);
    auto px = [&](int x, int y) { return im.at(x, y); };
    const std::uint8_t* tl = px(38, 38);
    const std::uint8_t* tr = px(58, 38);
    const std::uint8_t* bl = px(38, 58);
    const std::uint8_t* br = px(58, 58);
    INFO("per corner " << q->uv_per_corner << ": tl " << int(tl[0]) << "," << int(tl[1]) << "," << int(tl[2])
                       << " tr " << int(tr[0]) << "," << int(tr[1]) << "," << int(tr[2]));
    CHECK((tl[0] > 80 && tl[1] < 30 && tl[2] < 30));
    CHECK((tr[1] > 80 && tr[0] < 30 && tr[2] < 30));
    CHECK((bl[2] > 80 && bl[0] < 30 && bl[1] < 30));
    CHECK((br[0] > 80 && br[1] > 80 && br[2] > 80));
  }
}

TEST_CASE("baked occlusion darkens the surface it is given for", "[render][ao]") {
  TriMesh e;
  append_ellipsoid(e, Vec3::Zero(), kHeadRadii, 32, 48);
  const OrbitCamera cam = canonical_view(CanonicalView::Front, e.positions, 1.0f);
  const CameraMatrices m = cam.matrices(1.0f);
  auto mean_luminance = [&](float occlusion) {
    const Image im = render(
        [&](Renderer& r) {
          DrawableHandle hd;
          Status s = r.upload_mesh(e, hd);
          if (s) s = r.set_occlusion(hd, std::vector<float>(e.positions.size(), occlusion));
          return s;
        },
        [&](float) { return m; }, 96, 96);
    double sum = 0;
    int n = 0;
    for (int y = 0; y < 96; ++y)
      for (int x = 0; x < 96; ++x)
        if (!is_background(im, x, y)) {
          sum += luminance(im.at(x, y));
          ++n;
        }
    return sum / n;
  };
  const double open = mean_luminance(1.0f), closed = mean_luminance(0.0f);
  INFO("mean luminance open " << open << ", fully occluded " << closed);
  CHECK(closed < 0.6 * open);
  CHECK(closed > 0.05 * open);  // direct light still reaches a little
}

TEST_CASE("update_mesh moves the drawn mesh", "[render]") {
  TriMesh e;
  append_ellipsoid(e, Vec3::Zero(), Vec3(0.3, 0.3, 0.3), 24, 32);
  const CameraMatrices m = orbit_view(3.0f, 1.0f);
  std::vector<Vec3> moved = e.positions;
  for (Vec3& p : moved) p.x() += 0.4;
  const Image im = render(
      [&](Renderer& r) {
        DrawableHandle hd;
        Status s = r.upload_mesh(e, hd);
        if (s) s = r.update_mesh(hd, moved);
        return s;
      },
      [&](float) { return m; }, 96, 96);
  const MaskStats s = foreground_stats(im);
  CHECK(s.min_x > 48);  // the whole sphere now sits right of centre
}

TEST_CASE("bad input gives clear errors, not crashes", "[render]") {
  OffscreenContext ctx;
  REQUIRE(ctx.create(32, 32).ok());
  CHECK(ctx.create(0, 32).code == ErrorCode::InvalidInput);
  REQUIRE(ctx.create(32, 32).ok());
  Renderer r;
  DrawableHandle h;
  TriMesh empty;
  CHECK(r.upload_mesh(empty, h).code == ErrorCode::InvalidInput);  // before init
  REQUIRE(r.init().ok());
  CHECK(r.upload_mesh(empty, h).code == ErrorCode::Empty);
  TriMesh bad;
  bad.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  bad.triangles = {Tri{0, 1, 3}};
  CHECK(r.upload_mesh(bad, h).code == ErrorCode::InvalidInput);
  bad.triangles = {Tri{0, 1, 2}};
  bad.normals = {Vec3(0, 0, 1)};
  const Status wrong_normals = r.upload_mesh(bad, h);
  CHECK(wrong_normals.code == ErrorCode::InvalidInput);
  CHECK(wrong_normals.message.find("normals") != std::string::npos);
  bad.normals.assign(3, Vec3(0, 0, 1));
  bad.normals[2].y() = std::nan("");
  CHECK(r.upload_mesh(bad, h).code == ErrorCode::InvalidInput);
  bad.normals.clear();
  bad.positions[1].x() = std::nan("");
  CHECK(r.upload_mesh(bad, h).code == ErrorCode::InvalidInput);
  bad.positions[1].x() = 1;
  REQUIRE(r.upload_mesh(bad, h).ok());
  CHECK(r.update_mesh(h, {Vec3(0, 0, 0)}).code == ErrorCode::InvalidInput);
  CHECK(r.update_mesh(h + 100, bad.positions).code == ErrorCode::InvalidInput);
  CHECK(r.set_occlusion(h, {1.0f}).code == ErrorCode::InvalidInput);
  CHECK(r.set_occlusion(h + 100, {1.0f, 1.0f, 1.0f}).code == ErrorCode::InvalidInput);
  CHECK(r.set_occlusion(h, {1.0f, 0.5f, 0.0f}).ok());
  TextureHandle t;
  CHECK(r.upload_texture(Image{}, t).code == ErrorCode::Empty);
  REQUIRE(r.upload_texture(Image::make(4, 4, 3, 128), t).ok());
  CHECK(r.attach_texture(h, t).code == ErrorCode::InvalidInput);  // no uvs
  CHECK(r.attach_texture(h, t + 7).code == ErrorCode::InvalidInput);
  CHECK(r.set_visible(h + 100, false).code == ErrorCode::InvalidInput);
  CHECK(r.set_point_size(h, 0.0f).code == ErrorCode::InvalidInput);
  CHECK(r.style(h + 100) == nullptr);
  PointCloud pc;
  CHECK(r.upload_points(pc, h).code == ErrorCode::Empty);
  pc.positions = {Vec3(0, 0, 0)};
  pc.colors = {Vec3(1, 0, 0), Vec3(0, 1, 0)};
  CHECK(r.upload_points(pc, h).code == ErrorCode::InvalidInput);
  CHECK(r.draw(CameraMatrices{}, Viewport{0, 0, 0, 0}).code == ErrorCode::InvalidInput);
  CanonicalView v;
  const Status bad_view = parse_canonical_view("sideways", v);
  CHECK(bad_view.code == ErrorCode::InvalidInput);
  CHECK(bad_view.message.find("three-quarter") != std::string::npos);
}

TEST_CASE("orbit camera: angles, framing and interaction", "[render][camera]") {
  BBox box;
  box.extend(Vec3(-0.08, -0.12, -0.1));
  box.extend(Vec3(0.08, 0.12, 0.1));
  OrbitCamera left = canonical_view(CanonicalView::Left, box, 1.0f);
  CHECK(left.eye().x > 0.2f);  // the head's left is +x
  CHECK(std::abs(left.eye().z) < 1e-4f);
  OrbitCamera front = canonical_view(CanonicalView::Front, box, 1.5f);
  CHECK(front.eye().z > 0.2f);
  // Every bbox corner inside the frame, and the frame is tight.
  const CameraMatrices m = front.matrices(1.5f);
  double max_extent = 0;
  for (int i = 0; i < 8; ++i) {
    const glm::vec4 p((i & 1) ? 0.08f : -0.08f, (i & 2) ? 0.12f : -0.12f, (i & 4) ? 0.1f : -0.1f, 1.0f);
    const glm::vec4 c = m.projection * m.view * p;
    const double nx = std::abs(c.x / c.w), ny = std::abs(c.y / c.w);
    CHECK(nx <= 1.0);
    CHECK(ny <= 1.0);
    CHECK(std::abs(c.z / c.w) <= 1.0);  // inside near/far
    max_extent = std::max({max_extent, nx, ny});
  }
  CHECK(max_extent > 0.85);
  // Dragging a full viewport height sideways turns by 180 degrees.
  OrbitCamera cam = front;
  cam.orbit(-600.0f, 0.0f, 600.0f);
  CHECK(std::abs(cam.yaw_deg - 180.0f) < 1e-3f);
  cam.orbit(0.0f, 1e5f, 600.0f);
  CHECK(cam.pitch_deg < 90.0f);  // clamped below the pole
  const float d0 = front.distance;
  cam = front;
  cam.zoom(100.0f);
  CHECK(cam.distance < d0);
  cam = front;
  cam.pan(100.0f, 0.0f, 600.0f);
  CHECK(cam.target.x < front.target.x);  // drag right: scene moves right, target left
}

TEST_CASE("canonical views in a head's own frame: a scan that faces elsewhere is seen from its face", "[render][camera]") {
  BBox box;
  box.extend(Vec3(-0.1, -0.12, -0.1));
  box.extend(Vec3(0.1, 0.12, 0.1));
  const auto eye_dir = [&](const OrbitCamera& c) {
    const glm::vec3 e = c.eye() - c.target;
    return Vec3(e.x, e.y, e.z).normalized();
  };
  // The head's own frame is the world's: the plain canonical views.
  for (CanonicalView v : {CanonicalView::Front, CanonicalView::ThreeQuarter, CanonicalView::Left}) {
    const OrbitCamera plain = canonical_view(v, box, 1.3f);
    const OrbitCamera framed = canonical_view(v, box, 1.3f, Vec3(0, 0, 2), Vec3(0, 1, 0));
    CHECK(std::abs(plain.yaw_deg - framed.yaw_deg) < 1e-3f);
    CHECK(std::abs(plain.pitch_deg - framed.pitch_deg) < 1e-3f);
    CHECK(std::abs(plain.distance - framed.distance) < 1e-5f);
  }
  // Fran's scan faces (0.794, 0, -0.608) with +y up: the camera turns with
  // her face (yaw by the same angle), so the front view looks at her face and
  // the three-quarter view sees her face and her left (x = up x facing).
  const Vec3 facing(0.794, 0, -0.608), up(0, 1, 0);
  const Vec3 f = facing.normalized(), left = up.cross(f);
  const OrbitCamera front = canonical_view(CanonicalView::Front, box, 1.3f, facing, up);
  CHECK(eye_dir(front).dot(f) > 0.9999);
  const OrbitCamera tq = canonical_view(CanonicalView::ThreeQuarter, box, 1.3f, facing, up);
  const OrbitCamera tq_plain = canonical_view(CanonicalView::ThreeQuarter, box, 1.3f);
  const Vec3 d = eye_dir(tq), d_plain = eye_dir(tq_plain);
  CHECK(d.dot(f) == Approx(d_plain.z()).margin(1e-5));
  CHECK(d.dot(left) == Approx(d_plain.x()).margin(1e-5));
  CHECK(d.y() == Approx(d_plain.y()).margin(1e-5));
  // A scan lying on its back (up = +z, facing +y): pitched up to see the face
  // from above; the box still fits the frame.
  const OrbitCamera lying = canonical_view(CanonicalView::Front, box, 1.0f, Vec3(0, 1, 0), Vec3(0, 0, 1));
  CHECK(eye_dir(lying).y() > 0.99);
  const CameraMatrices m = lying.matrices(1.0f);
  for (int i = 0; i < 8; ++i) {
    const glm::vec4 p((i & 1) ? 0.1f : -0.1f, (i & 2) ? 0.12f : -0.12f, (i & 4) ? 0.1f : -0.1f, 1.0f);
    const glm::vec4 c = m.projection * m.view * p;
    CHECK(std::abs(c.x / c.w) <= 1.0);
    CHECK(std::abs(c.y / c.w) <= 1.0);
  }
  // ... and seen upright: the head's up (+z) is the screen's up, its left
  // (up x facing = -x) on the screen's right, as a face seen from the front.
  const glm::mat4 v = lying.view();
  const glm::vec3 screen_up = glm::mat3(v) * glm::vec3(0, 0, 1), screen_left = glm::mat3(v) * glm::vec3(-1, 0, 0);
  CHECK(screen_up.y > 0.999f);
  CHECK(screen_left.x > 0.999f);
  // A Blender export (+z up, the face along -y): the three-quarter view
  // is the upright one's, turned with the head.
  const OrbitCamera blender = canonical_view(CanonicalView::ThreeQuarter, box, 1.3f, Vec3(0, -1, 0), Vec3(0, 0, 1));
  const Vec3 db = eye_dir(blender);
  CHECK(db.dot(Vec3(0, -1, 0)) == Approx(d_plain.z()).margin(1e-5));
  CHECK(db.dot(Vec3(1, 0, 0)) == Approx(d_plain.x()).margin(1e-5));
  CHECK(db.z() == Approx(d_plain.y()).margin(1e-5));
  CHECK((glm::mat3(blender.view()) * glm::vec3(0, 0, 1)).y > 0.99f);
  // Degenerate frames fall back to the plain view.
  const OrbitCamera none = canonical_view(CanonicalView::ThreeQuarter, box, 1.3f, Vec3(0, 0, 0), Vec3(0, 1, 0));
  CHECK(none.yaw_deg == tq_plain.yaw_deg);
  const OrbitCamera parallel = canonical_view(CanonicalView::ThreeQuarter, box, 1.3f, Vec3(0, 1, 0), Vec3(0, 2, 0));
  CHECK(parallel.yaw_deg == tq_plain.yaw_deg);
}

TEST_CASE("the generic head renders plausibly from the front and the side", "[render][head]") {
  GenericHead head;
  const Status loaded = load_generic_head(head);
  INFO(loaded.message);
  REQUIRE(loaded.ok());
  const int w = 200, h = 200;
  struct ViewCheck {
    CanonicalView view;
    double min_fraction, max_fraction;
  };
  // A head is taller than wide (front) and about as deep as tall (side),
  // so these ranges separate the views; each bound leaves ~30% slack.
  for (const ViewCheck vc : {ViewCheck{CanonicalView::Front, 0.18, 0.45},
                             ViewCheck{CanonicalView::Left, 0.25, 0.60},
                             ViewCheck{CanonicalView::ThreeQuarter, 0.22, 0.55}}) {
    const OrbitCamera cam = canonical_view(vc.view, head.mesh.positions, 1.0f);
    const CameraMatrices m = cam.matrices(1.0f);
    const Image im = render(mesh_scene(head.mesh), [&](float) { return m; }, w, h);
    const MaskStats s = foreground_stats(im);
    // The drawn extent is the projected vertices' extent (to a pixel).
    float min_x = 1e9f, max_x = -1e9f, min_y = 1e9f, max_y = -1e9f;
    for (const Vec3& p : head.mesh.positions) {
      const glm::vec4 c = m.projection * m.view * glm::vec4(p.x(), p.y(), p.z(), 1.0f);
      const float x = (c.x / c.w * 0.5f + 0.5f) * w, y = (0.5f - c.y / c.w * 0.5f) * h;
      min_x = std::min(min_x, x);
      max_x = std::max(max_x, x);
      min_y = std::min(min_y, y);
      max_y = std::max(max_y, y);
    }
    INFO("view " << to_string(vc.view) << ": fraction " << s.fraction << ", image box x " << s.min_x << ".."
                 << s.max_x << " y " << s.min_y << ".." << s.max_y << ", projected x " << min_x << ".."
                 << max_x << " y " << min_y << ".." << max_y);
    CHECK(s.fraction > vc.min_fraction);
    CHECK(s.fraction < vc.max_fraction);
    CHECK(std::abs(s.min_x - min_x) < 1.5);
    CHECK(std::abs(s.max_x + 1 - max_x) < 1.5);
    CHECK(std::abs(s.min_y - min_y) < 1.5);
    CHECK(std::abs(s.max_y + 1 - max_y) < 1.5);
    if (vc.view == CanonicalView::Front) {
      CHECK(s.max_y - s.min_y > 1.2 * (s.max_x - s.min_x));  // taller than wide
      // Left-right symmetric: foreground pixels per half within 3%.
      int left = 0, right = 0;
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
          if (!is_background(im, x, y)) (x < w / 2 ? left : right)++;
      CHECK(std::abs(left - right) < 0.03 * (left + right));
    }
    // Shaded, not flat: luminance spread over the head.
    double sum = 0, sum2 = 0;
    int n = 0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        if (!is_background(im, x, y)) {
          const double l = luminance(im.at(x, y));
          sum += l;
          sum2 += l * l;
          ++n;
        }
    const double mean = sum / n, sd = std::sqrt(std::max(sum2 / n - mean * mean, 0.0));
    INFO("luminance mean " << mean << " sd " << sd);
    CHECK(mean > 70);
    CHECK(mean < 220);
    CHECK(sd > 12);
  }
}

TEST_CASE("visibility, model matrix and sub-viewports are honoured", "[render]") {
  TriMesh e;
  append_ellipsoid(e, Vec3::Zero(), Vec3(0.3, 0.3, 0.3), 24, 32);
  const CameraMatrices m = orbit_view(3.0f, 1.0f);
  const Image hidden = render(
      [&](Renderer& r) {
        DrawableHandle hd;
        Status s = r.upload_mesh(e, hd);
        if (s) s = r.set_visible(hd, false);
        return s;
      },
      [&](float) { return m; }, 64, 64);
  CHECK(foreground_stats(hidden).fraction == 0.0);
  const Image moved = render(
      [&](Renderer& r) {
        DrawableHandle hd;
        Status s = r.upload_mesh(e, hd);
        if (s) s = r.set_model_matrix(hd, glm::translate(glm::mat4(1.0f), glm::vec3(0.0f, 0.4f, 0.0f)));
        return s;
      },
      [&](float) { return m; }, 64, 64);
  CHECK(foreground_stats(moved).max_y < 32);  // lifted into the upper half (rows top-down)

  // Drawing into the right half leaves the left half untouched.
  OffscreenContext ctx;
  REQUIRE(ctx.create(64, 32).ok());
  Renderer r;
  REQUIRE(r.init().ok());
  glm::vec3 red(1, 0, 0);
  r.set_background(red);
  REQUIRE(r.draw(m, Viewport{0, 0, 64, 32}).ok());
  r.set_background(kKeyGreen);
  DrawableHandle hd;
  REQUIRE(r.upload_mesh(e, hd).ok());
  REQUIRE(r.draw(m, Viewport{32, 0, 32, 32}).ok());
  Image im;
  REQUIRE(ctx.read_image(im).ok());
  int left_red = 0, right_foreground = 0;
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 64; ++x) {
      const std::uint8_t* p = im.at(x, y);
      if (x < 32) left_red += p[0] == 255 && p[1] == 0 && p[2] == 0;
      else right_foreground += !(p[0] == 0 && p[1] == 255 && p[2] == 0);
    }
  CHECK(left_red == 32 * 32);
  CHECK(right_foreground > 50);
}

TEST_CASE("per-vertex mesh colors replace the base color", "[render]") {
  TriMesh e;
  append_ellipsoid(e, Vec3::Zero(), Vec3(0.3, 0.3, 0.3), 24, 32);
  e.colors.assign(e.positions.size(), Vec3(0.05, 0.1, 0.8));  // linear blue
  const CameraMatrices m = orbit_view(3.0f, 1.0f);
  for (const bool use_colors : {true, false}) {
    const Image im = render(
        [&](Renderer& r) {
          DrawableHandle hd;
          Status s = r.upload_mesh(e, hd);
          if (s) r.style(hd)->use_vertex_colors = use_colors;
          return s;
        },
        [&](float) { return m; }, 64, 64);
    const std::uint8_t* c = im.at(30, 30);  // lit side of the sphere
    INFO("use_colors " << use_colors << ": " << int(c[0]) << "," << int(c[1]) << "," << int(c[2]));
    if (use_colors) CHECK((c[2] > c[0] + 60 && c[2] > c[1] + 30));
    else CHECK((c[0] > c[1] && c[1] > c[2]));  // skin tone
  }
}

TEST_CASE("flat shading is constant across each facet, smooth shading is not", "[render]") {
  const int w = 160, h = 160;
  TriMesh coarse;
  append_ellipsoid(coarse, Vec3::Zero(), kHeadRadii, 8, 12);
  const OrbitCamera cam = canonical_view(CanonicalView::Front, coarse.positions, 1.0f);
  const CameraMatrices m = cam.matrices(1.0f);
  auto facet_variation = [&](bool flat, double& max_diff) {
    const Image im = render(
        [&](Renderer& r) {
          DrawableHandle hd;
          Status s = r.upload_mesh(coarse, hd);
          if (s) r.style(hd)->flat_shading = flat;
          if (s) r.style(hd)->specular = 0.0f;  // view-dependent; keep the test about normals
          return s;
        },
        [&](float) { return m; }, w, h);
    double sum = 0;
    int n = 0;
    max_diff = 0;
    for (const Tri& t : coarse.triangles) {
      glm::vec2 q[3];
      for (int c = 0; c < 3; ++c) {
        const Vec3& p = coarse.positions[t[c]];
        const glm::vec4 cl = m.projection * m.view * glm::vec4(p.x(), p.y(), p.z(), 1.0f);
        q[c] = glm::vec2((cl.x / cl.w * 0.5f + 0.5f) * w, (0.5f - cl.y / cl.w * 0.5f) * h);
      }
      const float area2 = (q[1].x - q[0].x) * (q[2].y - q[0].y) - (q[2].x - q[0].x) * (q[1].y - q[0].y);
      if (area2 > -300.0f) continue;  // large front-facing triangles only
      const glm::vec2 c = (q[0] + q[1] + q[2]) / 3.0f;
      for (int k = 0; k < 3; ++k) {
        const glm::vec2 toward = c + 0.6f * (q[k] - c);  // still well inside
        const double d = std::abs(luminance(im.at(int(c.x), int(c.y))) - luminance(im.at(int(toward.x), int(toward.y))));
        sum += d;
        max_diff = std::max(max_diff, d);
        ++n;
      }
    }
    REQUIRE(n > 30);
    return sum / n;
  };
  double flat_max = 0, smooth_max = 0;
  const double flat_mean = facet_variation(true, flat_max), smooth_mean = facet_variation(false, smooth_max);
  INFO("luminance change inside facets: flat mean " << flat_mean << " max " << flat_max << "; smooth mean "
                                                    << smooth_mean << " max " << smooth_max);
  CHECK(flat_max < 3.0);
  CHECK(smooth_mean > 5.0 * std::max(flat_mean, 0.5));
}

TEST_CASE("texture alpha: transparent texels show what lies behind, never their colour code", "[render][alpha]") {
  // Left half opaque light grey, right half transparent and colour-coded
  // blue (as the teeth texture's voids are). Behind the quad, a red quad
  // covers the lower half of the view only.
  Image tex = Image::make(64, 64, 4);
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) {
      std::uint8_t* p = tex.at(x, y);
      const bool opaque = x < 32;
      p[0] = opaque ? 200 : 0;
      p[1] = opaque ? 200 : 0;
      p[2] = opaque ? 200 : 255;
      p[3] = opaque ? 255 : 0;
    }
  TriMesh quad;
  quad.positions = {Vec3(-1, -1, 0), Vec3(1, -1, 0), Vec3(1, 1, 0), Vec3(-1, 1, 0)};
  quad.triangles = {Tri{0, 1, 2}, Tri{0, 2, 3}};
  quad.uvs = {Vec2(0, 0), Vec2(1, 0), Vec2(1, 1), Vec2(0, 1)};
  TriMesh behind;
  behind.positions = {Vec3(-3, -3, -0.5), Vec3(3, -3, -0.5), Vec3(3, 0, -0.5), Vec3(-3, 0, -0.5)};
  behind.triangles = {Tri{0, 1, 2}, Tri{0, 2, 3}};

  const CameraMatrices m = orbit_view(4.0f, 1.5f);
  const Image im = render(
      [&](Renderer& r) {
        DrawableHandle hq, hb;
        TextureHandle th;
        Status s = r.upload_mesh(behind, hb);
        if (s) s = r.set_base_color(hb, glm::vec3(0.9f, 0.05f, 0.05f));
        if (s) s = r.upload_mesh(quad, hq);
        if (s) r.style(hq)->specular = 0.0f;
        if (s) s = r.upload_texture(tex, th);
        if (s) s = r.attach_texture(hq, th);
        return s;
      },
      [&](float) { return m; }, 96, 96);
  auto rgb = [&](int x, int y) {
    const std::uint8_t* p = im.at(x, y);
    return std::to_string(p[0]) + "," + std::to_string(p[1]) + "," + std::to_string(p[2]);
  };
  INFO("left top " << rgb(38, 38) << " right top " << rgb(58, 38) << " right bottom " << rgb(58, 58));
  // Opaque half: the grey texture, over both the background and the red quad.
  for (int y : {38, 58}) {
    const std::uint8_t* p = im.at(38, y);
    CHECK((p[0] > 100 && std::abs(p[0] - p[1]) < 40 && std::abs(p[2] - p[1]) < 40));
  }
  // Transparent half: the key-green background above, the red quad below.
  CHECK(is_background(im, 58, 38));
  const std::uint8_t* red = im.at(58, 58);
  CHECK((red[0] > 80 && red[1] < 40 && red[2] < 40));
  // Nowhere (including the filtered and mipmapped border between the halves)
  // does the blue colour code show.
  int blue = 0;
  for (int y = 0; y < im.height; ++y)
    for (int x = 0; x < im.width; ++x) {
      const std::uint8_t* p = im.at(x, y);
      blue += p[2] > std::max(p[0], p[1]) + 50;
    }
  CHECK(blue == 0);
}
