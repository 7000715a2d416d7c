// One photo per region (texture/labeling.h) against ground truth: a plane
// with one dark vertical stripe photographed by two cameras at +-30 deg; the
// mesh handed to texturing lies 3 mm in front of the photographed plane, so
// each photo puts the stripe at a different place on it (the mm-off fitted
// surface behind Kira's doubled brows). Where the two photos meet in the
// texture, a blend shows the stripe twice; the labelling must keep a single
// full-contrast stripe, and obey its invariants (one common photo per
// triangle, the energy not above the largest-<N,V> start).
#include "fixtures.h"
#include "mesh/geometry.h"
#include "raycast/bvh.h"
#include "texture/chart_raster.h"
#include "texture/color.h"
#include "texture/labeling.h"
#include "texture/texture.h"

#include <catch2/catch.hpp>

using namespace lk;
using namespace lk::test;

namespace {

constexpr double kHalf = 0.05;       // plane half-size, metres
constexpr double kOffset = 0.003;    // texturing surface in front of the true one
constexpr double kStripe = 0.00075;  // stripe half-width

Vec3 stripe_color(const Vec3& p, const Vec3&) {
  return std::abs(p.x()) < kStripe ? Vec3(0.03, 0.03, 0.03) : Vec3(0.6, 0.55, 0.5);
}

struct Scene {
  TriMesh mesh;  // the offset plane, with uvs
  std::vector<TexturePhoto> photos;
};

const Scene& scene() {
  static const Scene s = [] {
    Scene sc;
    const TriMesh truth = plane_grid(40, -kHalf, kHalf, -kHalf, kHalf, 0.0);
    sc.mesh = plane_grid(40, -kHalf, kHalf, -kHalf, kHalf, kOffset);
    for (double a : {0.52, -0.52}) {
      TexturePhoto ph;
      const Vec3 eye(0.5 * std::sin(a), 0.0, 0.5 * std::cos(a));
      ph.camera = look_at_camera(eye, Vec3::Zero(), Vec3::UnitY(), 2400, 800, 600);
      REQUIRE(render_synthetic_photo(truth, ph.camera, stripe_color, Vec3(0, 0, 0), ph.image).ok());
      sc.photos.push_back(std::move(ph));
    }
    return sc;
  }();
  return s;
}

// Dark runs (linear luminance < 0.25) across the middle texel rows of the
// plane, and the darkest value found: a single stripe gives one run near 0.03.
void stripe_profile(const TexturedHead& out, int size, double& runs_per_row, double& darkest) {
  long runs = 0, rows = 0;
  darkest = 1;
  for (int y = size / 4; y < 3 * size / 4; y += 8) {
    bool in = false;
    for (int x = size / 8; x < 7 * size / 8; ++x) {
      const unsigned char* p = &out.skin.pixels[(size_t(y) * size + x) * 3];
      const double l = (srgb8_to_linear(p[0]) + srgb8_to_linear(p[1]) + srgb8_to_linear(p[2])) / 3;
      darkest = std::min(darkest, l);
      if (l < 0.25 && !in) ++runs;
      in = l < 0.25;
    }
    ++rows;
  }
  runs_per_row = double(runs) / rows;
}

// The labelling's inputs: the binding of the photos to the mesh and
// classify_triangles' cases and largest-<N,V> regions.
struct Inputs {
  VertexBinding binding;
  std::vector<TriangleCase> cases;
  std::vector<int> region;
};

Inputs labeling_inputs(const TriMesh& mesh, const std::vector<TexturePhoto>& photos) {
  Inputs in;
  const std::vector<Vec3> normals = vertex_normals(mesh);
  MeshBvh bvh;
  REQUIRE(build_bvh(mesh, bvh).ok());
  std::vector<Camera> cameras;
  for (const TexturePhoto& ph : photos) cameras.push_back(ph.camera);
  REQUIRE(bind_vertices(mesh, normals, bvh, cameras, BindingOptions(), in.binding).ok());
  classify_triangles(mesh, in.binding, in.cases, in.region);
  return in;
}

}  // namespace

TEST_CASE("the region labelling keeps a feature single where a mm-off surface doubles it") {
  const Scene& s = scene();
  TextureOptions opt;
  opt.size = 512;
  TexturedHead plain, labelled;
  REQUIRE(texture_head(s.mesh, s.photos, opt, plain).ok());
  opt.label_regions = true;
  REQUIRE(texture_head(s.mesh, s.photos, opt, labelled).ok());
  REQUIRE(labelled.report.labeled);
  WARN("labelling energy " << labelled.report.labeling.energy_before << " -> " << labelled.report.labeling.energy_after << " boundary " << labelled.report.labeling.boundary_edges_before << " -> " << labelled.report.labeling.boundary_edges_after << " changed " << labelled.report.labeling.triangles_changed);
  double runs_plain, dark_plain, runs_lab, dark_lab;
  stripe_profile(plain, 512, runs_plain, dark_plain);
  stripe_profile(labelled, 512, runs_lab, dark_lab);
  WARN("dark runs per row / darkest linear value: blended " << runs_plain << " / " << dark_plain << ", labelled "
                                                             << runs_lab << " / " << dark_lab << "; texels blending "
                                                             << ">= 2 photos " << plain.report.texels_blended
                                                             << " -> " << labelled.report.texels_blended);
  // Without the labelling the stripe is not a single dark line.
  CHECK_FALSE((runs_plain == Approx(1.0) && dark_plain < 0.1));
  CHECK(runs_lab == Approx(1.0));
  CHECK(dark_lab < 0.1);
  CHECK(labelled.report.texels_blended < plain.report.texels_blended / 4);
}

TEST_CASE("the region labelling gives each triangle one common photo and never raises the energy") {
  const Scene& s = scene();
  const TriMesh& mesh = s.mesh;
  const Inputs in = labeling_inputs(mesh, s.photos);
  const VertexBinding& binding = in.binding;
  const std::vector<TriangleCase>& cases = in.cases;
  std::vector<int> region = in.region;
  const std::vector<int> start = region;
  LabelingReport rep;
  REQUIRE(label_regions(mesh, binding, s.photos, cases, LabelingOptions(), region, rep).ok());
  CHECK(rep.energy_after <= rep.energy_before + 1e-9);
  CHECK(rep.boundary_edges_after > 0);  // both photos keep a region: each is more frontal on its side
  for (int f = 0; f < mesh.num_triangles(); ++f) {
    if (cases[f] != TriangleCase::CommonPhoto) {
      CHECK(region[f] == start[f]);
      continue;
    }
    REQUIRE(region[f] >= 0);
    for (int v : mesh.triangles[f]) REQUIRE(binding.is_valid(v, region[f]));
  }
  // No boundary edge on the stripe's band, where the photos disagree.
  for (int f = 0; f < mesh.num_triangles(); ++f) {
    const Tri& t = mesh.triangles[f];
    for (int k = 0; k < 3; ++k) {
      const Vec3& a = mesh.positions[t[k]];
      const Vec3& b = mesh.positions[t[(k + 1) % 3]];
      if (std::max(std::abs(a.x()), std::abs(b.x())) > 0.004) continue;
      for (int g = 0; g < mesh.num_triangles(); ++g) {
        if (g == f || region[g] == region[f]) continue;
        int shared = 0;
        for (int v : mesh.triangles[g]) shared += v == t[k] || v == t[(k + 1) % 3];
        CHECK(shared < 2);
      }
    }
  }
  // Sizes are checked.
  std::vector<int> wrong(3, 0);
  CHECK_FALSE(label_regions(mesh, binding, s.photos, cases, LabelingOptions(), wrong, rep).ok());
}

TEST_CASE("the region labelling's expansion by Boost's max-flow ends no higher than ICM") {
  const Scene& s = scene();
  const TriMesh& mesh = s.mesh;
  const Inputs in = labeling_inputs(mesh, s.photos);
  const VertexBinding& binding = in.binding;
  const std::vector<TriangleCase>& cases = in.cases;
  const std::vector<int>& start = in.region;
  // Plain and with the face-scale data term; a stronger seam weight makes
  // the energy's minimum far from the start, where ICM's one-triangle moves
  // stop early (a boundary moves only if each single step pays).
  for (double face_weight : {0.0, 0.5})
    for (double smoothness : {1.0, 8.0}) {
      LabelingOptions opt;
      opt.face_weight = face_weight;
      opt.smoothness = smoothness;
      opt.max_passes = 20;
      std::vector<int> expansion = start, icm = start;
      LabelingReport rep_expansion, rep_icm;
      REQUIRE(label_regions(mesh, binding, s.photos, cases, opt, expansion, rep_expansion).ok());
      opt.icm = true;
      REQUIRE(label_regions(mesh, binding, s.photos, cases, opt, icm, rep_icm).ok());
      WARN("face weight " << face_weight << " smoothness " << smoothness << ": start " << rep_expansion.energy_before
                          << ", ICM " << rep_icm.energy_after << ", expansion " << rep_expansion.energy_after);
      CHECK(rep_icm.energy_after <= rep_icm.energy_before + 1e-9);
      CHECK(rep_expansion.energy_after <= rep_icm.energy_after + 1e-9);
      CHECK(rep_expansion.energy_after < rep_expansion.energy_before);
    }
}

// A ridge (a nose 1 cm high, 5 mm wide) on a plane, seen from the front and
// from +-35 deg with the true surface: the largest-<N,V> rule gives each
// flank of the ridge to the side photo it faces, islands a mm-off surface
// would show as doubled edges. The face-scale data term must hand the whole
// ridge to the frontal photo; the per-triangle one alone does not.
TEST_CASE("the region labelling's face-scale data term gives a ridge one photo") {
  TriMesh mesh = plane_grid(60, -0.04, 0.04, -0.04, 0.04, 0.0);
  for (Vec3& p : mesh.positions) p.z() = 0.01 * std::exp(-p.x() * p.x() / (2 * 0.005 * 0.005));
  std::vector<TexturePhoto> photos;
  for (double a : {0.0, 0.6, -0.6}) {
    TexturePhoto ph;
    const Vec3 eye(0.5 * std::sin(a), 0.0, 0.5 * std::cos(a));
    ph.camera = look_at_camera(eye, Vec3::Zero(), Vec3::UnitY(), 2400, 800, 600);
    REQUIRE(render_synthetic_photo(mesh, ph.camera, stripe_color, Vec3(0, 0, 0), ph.image).ok());
    photos.push_back(std::move(ph));
  }
  const Inputs in = labeling_inputs(mesh, photos);
  const VertexBinding& binding = in.binding;
  const std::vector<TriangleCase>& cases = in.cases;
  const std::vector<int>& start = in.region;
  // Share of the ridge's case-1 triangles (|x| < 8 mm) labelled frontal.
  auto frontal_share = [&](const std::vector<int>& region) {
    int ridge = 0, frontal = 0;
    for (int f = 0; f < mesh.num_triangles(); ++f) {
      double x = 0;
      for (int v : mesh.triangles[f]) x += mesh.positions[v].x() / 3;
      if (std::abs(x) >= 0.008 || cases[f] != TriangleCase::CommonPhoto) continue;
      ++ridge;
      frontal += region[f] == 0;
    }
    REQUIRE(ridge > 100);
    return double(frontal) / ridge;
  };
  LabelingOptions opt;
  opt.face_radius = 0.03;
  opt.face_weight = 0;
  std::vector<int> local = start, broad = start;
  LabelingReport rep;
  REQUIRE(label_regions(mesh, binding, photos, cases, opt, local, rep).ok());
  opt.face_weight = 1;
  REQUIRE(label_regions(mesh, binding, photos, cases, opt, broad, rep).ok());
  WARN("ridge triangles from the frontal photo: largest <N,V> " << frontal_share(start) << ", labelled per triangle "
                                                                << frontal_share(local) << ", face-scale "
                                                                << frontal_share(broad));
  CHECK(frontal_share(local) < 0.8);
  CHECK(frontal_share(broad) > 0.98);
}
