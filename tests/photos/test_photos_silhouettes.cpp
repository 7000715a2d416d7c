// Outlines from masks and silhouette observations (fua1998 Sec. 3.2, eq. 11).
#include "photos/ground_truth.h"
#include "photos/outline.h"
#include "photos/photos_job.h"
#include "photos/silhouette_obs.h"
#include "photos/synthetic_outlines.h"
#include "observation_fd.h"
#include "photos_scenario.h"
#include "synth/skin_field.h"
#include "texture/synthetic_photo.h"

#include <cmath>
#include <cstdio>

namespace lk {
namespace {

std::vector<std::uint8_t> disk_mask(int w, int h, Vec2 c, double r) {
  std::vector<std::uint8_t> m(size_t(w) * size_t(h), 0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      if ((Vec2(x + 0.5, y + 0.5) - c).norm() <= r) m[size_t(y) * size_t(w) + size_t(x)] = 1;
  return m;
}

TEST_CASE("the outline is the largest component's border, holes and specks ignored, normals outward", "[photos]") {
  const int w = 200, h = 160;
  const Vec2 c(90, 80);
  std::vector<std::uint8_t> m = disk_mask(w, h, c, 50);
  // A hole inside, a speck outside.
  for (int y = 70; y < 80; ++y)
    for (int x = 80; x < 95; ++x) m[size_t(y) * w + size_t(x)] = 0;
  for (int y = 10; y < 16; ++y)
    for (int x = 180; x < 186; ++x) m[size_t(y) * w + size_t(x)] = 1;
  PhotoOutline o;
  REQUIRE(extract_outline(m, w, h, w, h, {}, o));
  REQUIRE(o.points.size() > 30);
  double worst_r = 0, worst_cos = 1;
  for (const OutlinePoint& p : o.points) {
    worst_r = std::max(worst_r, std::abs((p.pixel - c).norm() - 50));
    worst_cos = std::min(worst_cos, p.normal.dot((p.pixel - c).normalized()));
  }
  CHECK(worst_r < 1.0);
  CHECK(worst_cos > 0.9);

  // A mask cut by the bottom border: no outline point along the border.
  std::vector<std::uint8_t> cut = disk_mask(w, h, Vec2(100, 150), 60);
  REQUIRE(extract_outline(cut, w, h, w, h, {}, o));
  for (const OutlinePoint& p : o.points) CHECK(p.pixel.y() < h - 3);
}

TEST_CASE("bad masks are refused with a message", "[photos]") {
  const int w = 120, h = 100;
  PhotoOutline o;
  Status s = extract_outline(std::vector<std::uint8_t>(size_t(w * h), 0), w, h, w, h, {}, o);
  CHECK(!s);
  CHECK(s.message.find("no foreground") != std::string::npos);
  s = extract_outline(std::vector<std::uint8_t>(size_t(w * h), 1), w, h, w, h, {}, o);
  CHECK(!s);
  CHECK(s.message.find("all white") != std::string::npos);
  s = extract_outline(disk_mask(w, h, Vec2(60, 50), 30), w, h, 1200, 1600, {}, o);
  CHECK(!s);
  CHECK(s.message == "mask is 120x100, its photo is 1200x1600");
  std::vector<std::uint8_t> speck(size_t(w * h), 0);
  speck[size_t(50 * w + 60)] = 1;
  s = extract_outline(speck, w, h, w, h, {}, o);
  CHECK(!s);
  CHECK(s.message.find("not a head's outline") != std::string::npos);
  // An RGBA image: the alpha channel is the mask.
  Image rgba = Image::make(w, h, 4, 255);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) rgba.at(x, y)[3] = (Vec2(x + 0.5, y + 0.5) - Vec2(60, 50)).norm() < 30 ? 255 : 0;
  REQUIRE(outline_from_mask_image(rgba, w, h, {}, o));
  CHECK(std::abs(o.foreground_share - 3.14159 * 900 / (w * h)) < 0.01);
}

// The set on a scenario's generic head, seen by the true cameras, with the person's exact outlines.
struct SilhouetteScenario {
  test::PhotoScenario s;
  std::vector<PhotoOutline> outlines;
  std::vector<char> neck;
  ChinLine chin;
};

SilhouetteScenario make_silhouette_scenario(std::uint32_t seed) {
  SilhouetteScenario x{test::make_photo_scenario(seed), {}, {}, {}};
  REQUIRE(synthetic_outlines(x.s.person.mesh, x.s.session.cameras, {}, x.outlines));
  x.neck.assign(size_t(x.s.generic.mesh.num_vertices()), 0);
  for (int v : x.s.generic.annotations.regions.at("neck")) x.neck[size_t(v)] = 1;
  x.chin.vertices = x.s.generic.annotations.regions.at("chin");
  x.chin.up = x.s.generic.annotations.up;
  return x;
}

TEST_CASE("the silhouette observations' Jacobian over vertex positions matches finite differences", "[photos]") {
  SilhouetteScenario x = make_silhouette_scenario(3);
  for (bool facet : {false, true}) {
    SilhouetteOptions so;
    so.facet_equations = facet;
    SilhouetteSet set(x.s.generic.mesh, x.s.session.cameras, x.outlines, x.neck, x.chin, so);
    REQUIRE(set.matches().size() > 200);
    std::vector<int> cols;
    for (size_t i = 0; i < set.matches().size(); i += 23)
      for (int v : {set.matches()[i].a, set.matches()[i].b, set.matches()[i].c})
        for (int k = 0; k < 3; ++k) cols.push_back(3 * v + k);
    const test::FdJacobian fd = test::check_fd_jacobian(set, x.s.generic.mesh.positions, cols);
    CHECK(fd.residuals.norm() > 0);
    const double worst = fd.worst_relative;
    std::printf("silhouettes (%s): %zu matches, worst FD mismatch %.2e\n", facet ? "facet" : "rim edge",
                set.matches().size(), worst);
    // The facet's short pairs curve more: their central differences carry more truncation error.
    CHECK(worst < (facet ? 1e-3 : 1e-4));
  }
}

TEST_CASE("silhouettes alone grow a shrunken head back to its outlines", "[photos]") {
  // The generic head's own outlines; the start is the same head shrunk 4 %
  // about its centre, so every rim lies inside its outline. A Jacobian of
  // the wrong sign leaves LM no downhill step: the head would stay shrunk.
  SilhouetteScenario x = make_silhouette_scenario(2);
  const TriMesh& truth = x.s.generic.mesh;
  std::vector<PhotoOutline> outlines;
  REQUIRE(synthetic_outlines(truth, x.s.session.cameras, {}, outlines));
  Vec3 centre = Vec3::Zero();
  for (const Vec3& p : truth.positions) centre += p;
  centre /= double(truth.positions.size());
  TriMesh start = truth;
  for (Vec3& p : start.positions) p = centre + 0.96 * (p - centre);
  std::vector<std::unique_ptr<ObservationSet>> sets;
  sets.push_back(std::make_unique<SilhouetteSet>(start, x.s.session.cameras, outlines, x.neck, x.chin, SilhouetteOptions{}));
  auto* sil = static_cast<SilhouetteSet*>(sets[0].get());
  const SilhouetteStats before = sil->stats(start.positions);
  ShapeFitResult fit;
  REQUIRE(fit_shape(start, sets, {0.3}, ShapeFitOptions{}, fit));
  const SilhouetteStats after = sil->stats(fit.mesh.positions);
  std::vector<int> head;
  for (const char* region : {"face", "scalp", "ears"})
    for (int v : x.s.generic.annotations.regions.at(region)) head.push_back(v);
  const DistanceStats d0 = surface_distances(truth, head, start), d1 = surface_distances(truth, head, fit.mesh);
  // Outward: the mean displacement along the direction from the centre.
  double outward = 0;
  for (int v : head)
    outward += (fit.mesh.positions[size_t(v)] - start.positions[size_t(v)]).dot((start.positions[size_t(v)] - centre).normalized());
  outward /= double(head.size());
  std::printf("shrunk head: rim to outline %.2f px (%d matched) -> %.2f px (%d); truth->head %.2f -> %.2f mm; "
              "mean outward move %.2f mm\n", before.mean_px, before.matched, after.mean_px, after.matched,
              1000 * d0.mean, 1000 * d1.mean, 1000 * outward);
  CHECK(after.mean_px < 0.5 * before.mean_px);
  CHECK(d1.mean < 0.7 * d0.mean);
  CHECK(outward > 0.002);
}

TEST_CASE("silhouettes lower the outline distance and the head error on a synthetic session", "[photos]") {
  SilhouetteScenario x = make_silhouette_scenario(1);
  PhotosJobOptions opt;
  // The whole head's outline (a bald person, near-exact cameras: here the
  // scalp's outline helps; the job's default leaves it out for real photos).
  opt.silhouettes.excluded_regions = {"neck"};
  SelfCalibResult calib;
  REQUIRE(self_calibrate(x.s.session.photos, x.s.generic.mesh, x.s.landmarks, opt.calib, calib));
  ShapeFitResult plain, with;
  REQUIRE(fit_photos_shape(x.s.generic, x.s.landmarks, x.s.session.photos, calib, opt, plain));
  REQUIRE(fit_photos_shape(x.s.generic, x.s.landmarks, x.s.session.photos, calib, opt, with, &x.outlines));
  const auto sil = make_silhouette_set(x.s.generic, x.s.generic.mesh, calib, x.outlines, opt.silhouettes);
  REQUIRE(sil);
  const SilhouetteStats sp = sil->stats(plain.mesh.positions), sw = sil->stats(with.mesh.positions);
  std::vector<int> head;
  for (const char* region : {"face", "scalp", "ears"})
    for (int v : x.s.generic.annotations.regions.at(region)) head.push_back(v);
  const std::vector<int>& face = x.s.generic.annotations.regions.at("face");
  auto head_error = [&](const TriMesh& m) {
    TriMesh a = m;
    const Similarity sim = fit_similarity(a.positions, x.s.person.mesh.positions, face);
    for (Vec3& p : a.positions) p = sim.apply(p);
    return surface_distances(x.s.person.mesh, head, a);
  };
  const DistanceStats hp = head_error(plain.mesh), hw = head_error(with.mesh);
  std::printf("seed 1: rim to outline %.2f / %.2f px (%d) -> %.2f / %.2f px (%d); head %.2f / %.2f -> %.2f / %.2f mm\n",
              sp.mean_px, sp.p95_px, sp.matched, sw.mean_px, sw.p95_px, sw.matched, 1000 * hp.mean, 1000 * hp.p95,
              1000 * hw.mean, 1000 * hw.p95);
  CHECK(sw.mean_px < 0.7 * sp.mean_px);
  CHECK(sw.matched >= sp.matched * 9 / 10);
  CHECK(hw.mean < hp.mean);
  CHECK(hw.p95 < hp.p95);
}

// A view as synth-photos renders it (shaded skin on a plain grey-blue
// backdrop) and the renderer's exact mask of it.
void render_plain_view(const test::PhotoScenario& s, const SkinField& skin, const Camera& cam, Image& photo, Image& exact) {
  const Vec3 light = (cam.R.transpose() * Vec3(-0.4, -0.6, -1.0)).normalized();
  REQUIRE(render_synthetic_photo(
      s.person.mesh, cam,
      [&](const Vec3& p, const Vec3& n) -> Vec3 { return skin_albedo(skin, p) * (0.35 + 0.65 * std::max(0.0, n.dot(light))); },
      Vec3(0.55, 0.6, 0.65), photo));
  REQUIRE(synthetic_mask(s.person.mesh, cam, exact));
}

TEST_CASE("a plain background gives the renderer's mask and a busy one is refused", "[photos]") {
  test::PhotoScenario s = test::make_photo_scenario(4);
  SkinField skin;
  REQUIRE(make_skin_field(s.person, 4, {}, skin));
  for (size_t c : {size_t(0), size_t(4), size_t(9)}) {
    Image photo, exact;
    render_plain_view(s, skin, s.session.cameras[c], photo, exact);
    std::vector<std::uint8_t> derived;
    REQUIRE(mask_from_plain_background(photo, {}, derived));
    const std::vector<std::uint8_t> truth = mask_from_image(exact);
    size_t inter = 0, uni = 0;
    for (size_t i = 0; i < truth.size(); ++i) {
      inter += truth[i] && derived[i];
      uni += truth[i] || derived[i];
    }
    // Before the largest component and hole filling: what the threshold alone gets right.
    std::printf("plain background, view %zu: IoU with the renderer's mask %.4f\n", c, double(inter) / double(uni));
    CHECK(double(inter) / double(uni) > 0.98);
  }
  // A busy background: every pixel a different colour.
  Image busy = Image::make(200, 150, 3);
  std::uint32_t state = 12345;
  for (auto& b : busy.pixels) b = std::uint8_t((state = state * 1664525u + 1013904223u) >> 24);
  std::vector<std::uint8_t> m;
  const Status st = mask_from_plain_background(busy, {}, m);
  CHECK(!st);
  CHECK(st.message.find("the background is not plain") != std::string::npos);
}

// The page finds each outline on the detector's shrunk copy of the photo,
// the CLI on the photo shrunk to the same size: either way the points must
// land on the photo's own outline, in the photo's pixels.
TEST_CASE("an outline found on a shrunk photo lies on the full photo's outline", "[photos]") {
  test::PhotoScenario s = test::make_photo_scenario(4);
  SkinField skin;
  REQUIRE(make_skin_field(s.person, 4, {}, skin));
  Image photo, exact;
  render_plain_view(s, skin, s.session.cameras[4], photo, exact);
  OutlineOptions dense;
  dense.spacing_px = 1;
  PhotoOutline truth;
  REQUIRE(outline_from_mask_image(exact, photo.width, photo.height, dense, truth));
  auto farthest = [&](const PhotoOutline& o) {
    double worst = 0;
    for (const OutlinePoint& p : o.points) {
      double best = 1e9;
      for (const OutlinePoint& t : truth.points) best = std::min(best, (t.pixel - p.pixel).norm());
      worst = std::max(worst, best);
    }
    return worst;
  };
  const int w = photo.width, h = photo.height;  // 1200 x 1600
  PhotoOutline full, shrunk_here, shrunk_by_caller;
  REQUIRE(outline_from_plain_photo(photo, w, h, 0, {}, {}, full));
  REQUIRE(outline_from_plain_photo(photo, w, h, 400, {}, {}, shrunk_here));
  REQUIRE(outline_from_plain_photo(resized(photo, 300, 400), w, h, kPlainOutlineMaxSide, {}, {}, shrunk_by_caller));
  for (const PhotoOutline* o : {&full, &shrunk_here, &shrunk_by_caller}) {
    CHECK(o->width == w);
    CHECK(o->height == h);
  }
  const double e_full = farthest(full), e_here = farthest(shrunk_here), e_caller = farthest(shrunk_by_caller);
  std::printf("outline on a shrunk photo: farthest from the full photo's outline %.2f px (full size), %.2f px (shrunk "
              "to 400 px here), %.2f px (shrunk to 400 px by the caller); %zu, %zu, %zu points\n",
              e_full, e_here, e_caller, full.points.size(), shrunk_here.points.size(), shrunk_by_caller.points.size());
  CHECK(e_full < 1.5);
  // A pixel of the 400-px copy is 4 of the photo's.
  CHECK(e_here < 4.0);
  CHECK(e_caller < 4.0);
  // About a quarter as many points: 6 px apart in the copy, 24 in the photo.
  CHECK(shrunk_here.points.size() * 3 < full.points.size());
  CHECK(shrunk_here.points.size() * 6 > full.points.size());
  // A copy larger than its photo is a caller's mistake.
  PhotoOutline bad;
  CHECK(!outline_from_plain_photo(photo, w / 2, h / 2, 0, {}, {}, bad));
}

TEST_CASE("the photos job refuses outlines that do not fit its photos", "[photos]") {
  test::PhotoScenario s = test::make_photo_scenario(1);
  std::vector<PhotoOutline> outlines(s.session.photos.size() - 1);
  PhotosJobResult r;
  Status st = run_photos_job(s.generic, s.map, s.session.photos, {}, r, &outlines);
  CHECK(!st);
  CHECK(st.message.find("masks for") != std::string::npos);
  outlines.assign(s.session.photos.size(), PhotoOutline{});
  outlines[2].width = 640;
  outlines[2].height = 480;
  outlines[2].points.resize(30);
  st = run_photos_job(s.generic, s.map, s.session.photos, {}, r, &outlines);
  CHECK(!st);
  CHECK(st.message.find("view_02.png: its mask is 640x480") != std::string::npos);
}

}  // namespace
}  // namespace lk
