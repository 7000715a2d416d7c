// Photometric re-registration (texture/register.h) against ground truth: the
// generic head (refined once) under a procedural colour field, photographed
// by known cameras; one camera handed to the registration turned and moved
// by a known amount. The residual's Jacobian against central differences;
// the perturbed pose recovered; unperturbed photos stay put; the texture's
// error against the field drops.
#include "fixtures.h"
#include "mesh/geometry.h"
#include "raycast/bvh.h"
#include "subdiv/butterfly.h"
#include "texture/chart_raster.h"
#include "texture/color.h"
#include "texture/register.h"
#include "texture/texture.h"

#include <Eigen/Geometry>
#include <catch2/catch.hpp>

using namespace lk;
using namespace lk::test;

namespace {

constexpr double kScale = 0.02;  // finest wavelength of the colour field, metres

struct Scene {
  TriMesh mesh;
  std::vector<Vec3> normals;
  std::vector<TexturePhoto> photos;  // true cameras
};

const Scene& scene() {
  static const Scene s = [] {
    Scene sc;
    GenericHead head;
    REQUIRE(load_generic_head(head).ok());
    std::vector<ButterflyLevel> levels;
    REQUIRE(build_butterfly_levels(head.mesh, 2, levels).ok());
    UvStats st;
    std::vector<Vec2> uv;
    REQUIRE(parameterize_stretch(head.mesh, UvOptions(), uv, st).ok());
    std::vector<Vec3> positions = head.mesh.positions;
    for (const ButterflyLevel& level : levels) {
      std::vector<Vec3> fine;
      REQUIRE(apply(level, positions, fine).ok());
      positions.swap(fine);
      uv.resize(level.num_fine_vertices);
      for (int k = 0; k < level.num_new_vertices(); ++k) {
        const auto& e = level.edge_endpoints[k];
        uv[level.num_coarse_vertices + k] = 0.5 * (uv[e[0]] + uv[e[1]]);
      }
    }
    sc.mesh.positions = positions;
    sc.mesh.triangles = levels.back().fine_triangles;
    sc.mesh.uvs = uv;
    sc.normals = vertex_normals(sc.mesh);
    const SurfaceColorFn field = [](const Vec3& p, const Vec3&) { return procedural_color_field(p, kScale); };
    for (const Camera& cam : head_cameras(bounding_box(sc.mesh.positions), 800, 600, 3)) {
      TexturePhoto ph;
      ph.camera = cam;
      REQUIRE(render_synthetic_photo(sc.mesh, cam, field, Vec3(0.05, 0.05, 0.05), ph.image).ok());
      sc.photos.push_back(std::move(ph));
    }
    return sc;
  }();
  return s;
}

// Camera turned by `deg` about `axis` through its centre, then moved by `move` (world, metres).
Camera perturbed(const Camera& c, double deg, const Vec3& axis, const Vec3& move) {
  Camera p = c;
  const Vec3 centre = c.center() + move;
  p.R = Eigen::AngleAxisd(deg * M_PI / 180, axis.normalized()).toRotationMatrix() * c.R;
  p.t = -p.R * centre;
  return p;
}

// Mean |a - b| of two projections over the vertices a camera faces.
double mean_projection_gap(const Scene& s, const Camera& truth, const std::function<bool(const Vec3&, Vec2&)>& other) {
  double sum = 0;
  long n = 0;
  for (int v = 0; v < s.mesh.num_vertices(); ++v) {
    if (s.normals[v].dot((truth.center() - s.mesh.positions[v]).normalized()) < 0.3) continue;
    Vec2 a, b;
    if (!truth.project(s.mesh.positions[v], a) || !other(s.mesh.positions[v], b)) continue;
    sum += (a - b).norm();
    ++n;
  }
  REQUIRE(n > 100);
  return sum / n;
}

VertexBinding bind_all(const Scene& s, const std::vector<TexturePhoto>& photos) {
  MeshBvh bvh;
  REQUIRE(build_bvh(s.mesh, bvh).ok());
  std::vector<Camera> cams;
  for (const auto& p : photos) cams.push_back(p.camera);
  VertexBinding b;
  REQUIRE(bind_vertices(s.mesh, s.normals, bvh, cams, BindingOptions(), b).ok());
  return b;
}

// Linear-light PSNR of a texture's photo-region texels against the field.
double texture_psnr(const TexturedHead& out, int size) {
  ChartRaster r;
  REQUIRE(rasterize_chart(out.mesh.uvs, out.mesh.triangles, size, size, r, 0.0).ok());
  double se = 0;
  long n = 0;
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const size_t j = size_t(y) * size + x;
      const int f = r.triangle[j];
      if (f < 0 || out.region[j] < 0) continue;
      const Tri& t = out.mesh.triangles[f];
      Vec3 b;
      if (!uv_barycentric(texel_uv(x, y, size, size), out.mesh.uvs[t[0]], out.mesh.uvs[t[1]], out.mesh.uvs[t[2]], b))
        continue;
      const Vec3 p = b[0] * out.mesh.positions[t[0]] + b[1] * out.mesh.positions[t[1]] + b[2] * out.mesh.positions[t[2]];
      const Vec3 want = procedural_color_field(p, kScale);
      for (int k = 0; k < 3; ++k) se += std::pow(srgb8_to_linear(out.skin.pixels[j * 3 + k]) - want[k], 2);
      n += 3;
    }
  REQUIRE(n > 1000);
  return psnr_from_mse(se / n);
}

}  // namespace

TEST_CASE("the photometric residual's Jacobian matches central differences") {
  const Scene& s = scene();
  const ImageF g = photo_luminance(s.photos[1].image, 2.0);
  PhotoRegistration reg;
  reg.camera = s.photos[1].camera;
  reg.camera.k1 = 0.05;  // the distortion's derivative is part of the chain
  reg.camera.k2 = -0.02;
  reg.gain = 1.1;
  reg.bias = 0.02;
  reg.nodes = 4;
  reg.field.resize(16);
  for (int k = 0; k < 16; ++k) reg.field[k] = Vec2(std::sin(1.3 * k) * 2, std::cos(0.7 * k) * 1.5);
  // Perturbing parameter j the way the optimizer updates it.
  auto moved = [&](int j, double h) {
    PhotoRegistration r = reg;
    if (j < 3) {
      const Mat3 dR = Eigen::AngleAxisd(h, Vec3::Unit(j)).toRotationMatrix();
      r.camera.R = dR * reg.camera.R;
      r.camera.t = dR * reg.camera.t;
    } else if (j < 6) {
      r.camera.t[j - 3] += h;
    } else if (j == 6) {
      r.gain += h;
    } else if (j == 7) {
      r.bias += h;
    } else {
      r.field[(j - 8) / 2][(j - 8) % 2] += h;
    }
    return r;
  };
  int checked = 0;
  for (int v = 0; v < s.mesh.num_vertices() && checked < 40; v += 97) {
    if (s.normals[v].dot((reg.camera.center() - s.mesh.positions[v]).normalized()) < 0.3) continue;
    double r0;
    std::vector<double> jac;
    if (!photometric_residual(g, reg, s.mesh.positions[v], 0.4, r0, jac)) continue;
    REQUIRE(jac.size() == 8u + 32u);
    for (int j = 0; j < static_cast<int>(jac.size()); ++j) {
      const double h = j < 3 ? 1e-7 : j < 6 ? 1e-7 : j < 8 ? 1e-6 : 1e-4;
      double rp, rm;
      std::vector<double> unused;
      REQUIRE(photometric_residual(g, moved(j, h), s.mesh.positions[v], 0.4, rp, unused));
      REQUIRE(photometric_residual(g, moved(j, -h), s.mesh.positions[v], 0.4, rm, unused));
      const double fd = (rp - rm) / (2 * h);
      INFO("vertex " << v << " parameter " << j << ": analytic " << jac[j] << " finite differences " << fd);
      CHECK(std::abs(fd - jac[j]) <= 1e-3 * std::max(1.0, std::abs(fd)) + 2e-3 * std::abs(fd));
    }
    ++checked;
  }
  CHECK(checked >= 20);
}

TEST_CASE("registration recovers a turned and moved camera and leaves true ones in place") {
  const Scene& s = scene();
  std::vector<TexturePhoto> photos = s.photos;
  // Photo 1 (three-quarter): 0.6 deg and 4 mm off, about 10 px on the face.
  photos[1].camera = perturbed(s.photos[1].camera, 0.6, Vec3(0.3, 1, 0.2), Vec3(0.004, -0.002, 0.001));
  const double gap_before = mean_projection_gap(s, s.photos[1].camera, [&](const Vec3& X, Vec2& q) {
    return photos[1].camera.project(X, q);
  });
  REQUIRE(gap_before > 4);
  const VertexBinding binding = bind_all(s, photos);

  SECTION("pose only") {
    RegisterOptions opt;
    opt.field_nodes = 0;
    opt.reference = 0;
    RegisterReport rep;
    REQUIRE(register_photos(s.mesh, s.normals, binding, photos, opt, rep).ok());
    const double gap_after = mean_projection_gap(s, s.photos[1].camera, [&](const Vec3& X, Vec2& q) {
      return registered_project(rep.photos[1], X, q);
    });
    const double angle = Eigen::AngleAxisd(rep.photos[1].camera.R * s.photos[1].camera.R.transpose()).angle() * 180 / M_PI;
    WARN("pose only: vertex gap " << gap_before << " -> " << gap_after << " px, rotation error " << angle
                                  << " deg, luminance rms " << rep.rms_before << " -> " << rep.rms_after);
    // The projection is what texturing uses; the pose itself is pinned only
    // up to the trade of a turn against a sideways move at 0.9 m (measured
    // 0.35 deg left with the vertices within 0.59 px; the pose prior of
    // 10 px holds back a little of a 10 px error), so it is not checked
    // tighter than "most of the turn undone".
    CHECK(gap_after < 0.8);
    CHECK(angle < 0.45);
    CHECK(rep.rms_after < 0.5 * rep.rms_before);
    // The reference is held; the other true camera stays within a fraction of a pixel.
    CHECK(rep.photos[0].camera.R == s.photos[0].camera.R);
    const double drift = mean_projection_gap(s, s.photos[2].camera, [&](const Vec3& X, Vec2& q) {
      return registered_project(rep.photos[2], X, q);
    });
    WARN("unperturbed photo 2 moved by " << drift << " px");
    CHECK(drift < 0.4);
    CHECK(std::abs(rep.photos[2].gain - 1) < 0.02);
  }

  SECTION("pose and correction field") {
    RegisterOptions opt;
    opt.field_nodes = 6;
    RegisterReport rep;
    REQUIRE(register_photos(s.mesh, s.normals, binding, photos, opt, rep).ok());
    CHECK(rep.reference == 0);  // the frontal photo is the main one of most vertices
    const double gap_after = mean_projection_gap(s, s.photos[1].camera, [&](const Vec3& X, Vec2& q) {
      return registered_project(rep.photos[1], X, q);
    });
    const double drift = mean_projection_gap(s, s.photos[2].camera, [&](const Vec3& X, Vec2& q) {
      return registered_project(rep.photos[2], X, q);
    });
    WARN("pose + field: vertex gap " << gap_before << " -> " << gap_after << " px, unperturbed photo 2 moved "
                                     << drift << " px");
    CHECK(gap_after < 0.8);
    CHECK(drift < 0.4);
  }
}

TEST_CASE("registration lowers the texture's error against the truth when a camera is off") {
  const Scene& s = scene();
  std::vector<TexturePhoto> photos = s.photos;
  photos[1].camera = perturbed(s.photos[1].camera, 0.6, Vec3(0.3, 1, 0.2), Vec3(0.004, -0.002, 0.001));
  photos[2].camera = perturbed(s.photos[2].camera, 0.5, Vec3(-1, 0.4, 0.1), Vec3(-0.002, 0.003, 0));
  TextureOptions opt;
  opt.size = 512;
  // Both perturbed cameras are ~10 px off: a prior wider than that (the
  // default 10 px keeps 3-4 dB of the error here: 34.5 dB).
  opt.registration.pose_prior_px = 30;
  TexturedHead truth_cams, off, fixed;
  REQUIRE(texture_head(s.mesh, s.photos, opt, truth_cams).ok());
  REQUIRE(texture_head(s.mesh, photos, opt, off).ok());
  opt.register_photos = true;
  std::vector<std::string> steps;
  REQUIRE(texture_head(s.mesh, photos, opt, fixed, [&](const char* step, double f) {
            if (f == 0) steps.push_back(step);
            return true;
          }).ok());
  CHECK(steps == std::vector<std::string>{"parameterize", "bind", "register", "fill holes", "resample", "spline",
                                          "dilate"});
  REQUIRE(fixed.report.registered);
  const double p_true = texture_psnr(truth_cams, 512), p_off = texture_psnr(off, 512), p_fixed = texture_psnr(fixed, 512);
  WARN("texture vs field, PSNR dB: true cameras " << p_true << ", two cameras off " << p_off << ", registered "
                                                  << p_fixed);
  CHECK(p_fixed > p_off + 15);
  CHECK(p_fixed > p_true - 4);
}

