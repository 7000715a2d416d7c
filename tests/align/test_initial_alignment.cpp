// Initial alignment (core/align/initial_alignment.h): recovers known affine
// transforms of clouds sampled from a head-like mesh, with sparse clouds,
// longer necks, missing backs and scans in millimetres; refuses bad input.
#include "align/initial_alignment.h"
#include "fit/closest_point.h"
#include "head/generic_head.h"
#include "io/io.h"
#include "mesh/geometry.h"
#include "synth/analytic_head.h"
#include "synthetic_head.h"
#include "test_data.h"
#include "test_scan.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <random>

using namespace lk;

namespace {

struct Affine {
  Mat3 linear;
  Vec3 translation;
  Vec3 apply(const Vec3& p) const { return linear * p + translation; }
};

// Rotation up to max_deg about a random axis, scale 1 +- max_scale per
// axis, translation up to +-max_shift of the head size, times units.
Affine random_affine(unsigned seed, double max_deg, double max_scale, double max_shift, double units) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Vec3 axis = Vec3(u(rng), u(rng), u(rng)).normalized();
  const double angle = max_deg * 3.14159265358979 / 180.0 * u(rng);
  const Vec3 scale(1 + max_scale * u(rng), 1 + max_scale * u(rng), 1 + max_scale * u(rng));
  const double head = 0.3;  // the synthetic head's size in metres
  Affine a;
  a.linear = units * Eigen::AngleAxisd(angle, axis).toRotationMatrix() * scale.asDiagonal();
  a.translation = units * head * max_shift * Vec3(u(rng), u(rng), u(rng)) + units * Vec3(0.5, 1.6, -0.2);
  return a;
}

PointCloud transformed(const PointCloud& c, const Affine& a) {
  PointCloud out;
  for (const Vec3& p : c.positions) out.positions.push_back(a.apply(p));
  return out;
}

// RMS distance between the aligned generic and the ground truth, over the
// vertices above the neck cut, as a fraction of the true head's bbox diagonal.
double relative_rms(const GenericHead& g, const AlignResult& r, const Affine& truth) {
  double sum = 0;
  int n = 0;
  BBox box;
  for (const Vec3& p : g.mesh.positions) {
    if (!g.annotations.neck_clip.keeps(p)) continue;
    const Vec3 t = truth.apply(p);
    box.extend(t);
    sum += (r.linear * p + r.translation - t).squaredNorm();
    ++n;
  }
  return std::sqrt(sum / n) / box.diagonal();
}

void check_monotone(const AlignResult& r) {
  for (const AlignLevel& level : r.levels) {
    for (size_t i = 1; i < level.xor_per_iteration.size(); ++i)
      CHECK(level.xor_per_iteration[i] <= level.xor_per_iteration[i - 1]);
    CHECK(total_xor(level.xor_after) <= total_xor(level.xor_before));
  }
}

}  // namespace

TEST_CASE("align recovers random affine transforms of a sampled head", "[align]") {
  const GenericHead generic = test::synthetic_head();
  const PointCloud samples = test::sample_surface(generic.mesh, 60000, 7);
  for (unsigned seed : {1u, 2u, 3u, 4u}) {
    INFO("seed " << seed);
    const Affine truth = random_affine(seed, 10.0, 0.15, 0.2, seed % 2 ? 1000.0 : 1.0);
    AlignResult r;
    const Status st = align_initial(generic.mesh, generic.annotations, transformed(samples, truth),
                                    AlignOptions{}, r);
    REQUIRE(st.ok());
    const double before = total_xor(r.xor_before), after = total_xor(r.xor_after);
    INFO("XOR before " << before << " after " << after << " evaluations " << r.evaluations);
    const double err = relative_rms(generic, r, truth);
    INFO("relative RMS " << err);
    CHECK(err < 0.01);
    CHECK(after < 0.35 * before);
    check_monotone(r);
    CHECK(r.aligned.num_vertices() == generic.mesh.num_vertices());
    CHECK((r.aligned.positions[5] - (r.linear * generic.mesh.positions[5] + r.translation)).norm() < 1e-9);
  }
}

TEST_CASE("align works on a sparse cloud of 2000 points by closing holes", "[align]") {
  const GenericHead generic = test::synthetic_head();
  const Affine truth = random_affine(11, 8.0, 0.1, 0.2, 1.0);
  const PointCloud sparse = transformed(test::sample_surface(generic.mesh, 2000, 5), truth);
  AlignResult r;
  REQUIRE(align_initial(generic.mesh, generic.annotations, sparse, AlignOptions{}, r).ok());
  // At 256^2 a 2000-point head has gaps of several pixels: closing must grow.
  CHECK(r.levels.back().cloud.closing_radius_px[0] >= 1.5);
  const double err = relative_rms(generic, r, truth);
  INFO("relative RMS " << err);
  CHECK(err < 0.02);
  check_monotone(r);

  // Without hole filling the sparse silhouette is mostly holes: the fit is worse.
  AlignOptions raw;
  raw.splat.closing_radii_px = {0.0};
  AlignResult rr;
  REQUIRE(align_initial(generic.mesh, generic.annotations, sparse, raw, rr).ok());
  CHECK(relative_rms(generic, rr, truth) > err);
}

TEST_CASE("align ignores a longer neck and a missing back behind the clip planes", "[align]") {
  GenericHead generic = test::synthetic_head();
  // The scan: a much longer neck, and nothing behind z = -0.06 (hair).
  const GenericHead scan_shape = test::synthetic_head(-0.32);
  PointCloud samples = test::sample_surface(scan_shape.mesh, 60000, 3);
  PointCloud front_only;
  for (const Vec3& p : samples.positions)
    if (p.z() > -0.06) front_only.positions.push_back(p);
  generic.annotations.back_clip.point = Vec3(0, 0, -0.05);
  const Affine truth = random_affine(21, 10.0, 0.15, 0.2, 1000.0);
  AlignResult r;
  REQUIRE(align_initial(generic.mesh, generic.annotations, transformed(front_only, truth), AlignOptions{}, r).ok());
  const double err = relative_rms(generic, r, truth);
  INFO("relative RMS " << err << " XOR " << total_xor(r.xor_before) << " -> " << total_xor(r.xor_after));
  CHECK(err < 0.02);
  REQUIRE(r.frame.clips.size() == 2);

  // Without the clip planes the long neck and the missing back pull the fit away.
  AlignOptions no_clip;
  no_clip.use_neck_clip = no_clip.use_back_clip = false;
  AlignResult rn;
  REQUIRE(align_initial(generic.mesh, generic.annotations, transformed(front_only, truth), no_clip, rn).ok());
  CHECK(relative_rms(generic, rn, truth) > 2 * err);
}

TEST_CASE("align is not misled by shoulders in the scan", "[align]") {
  // A bust: the head on a long neck over wide shoulders. The bounding box of
  // such a scan is twice the head's size; the initialization must still
  // measure the head.
  const GenericHead generic = test::synthetic_head();
  GenericHead bust = test::synthetic_head(-0.33);
  test::add_ellipsoid(bust.mesh, Vec3(0, -0.36, -0.02), Vec3(0.22, 0.07, 0.11));
  const Affine truth = random_affine(31, 8.0, 0.1, 0.2, 1000.0);
  AlignResult r;
  REQUIRE(align_initial(generic.mesh, generic.annotations, transformed(test::sample_surface(bust.mesh, 60000, 4), truth),
                        AlignOptions{}, r).ok());
  const double err = relative_rms(generic, r, truth);
  INFO("relative RMS " << err);
  CHECK(err < 0.015);
}

TEST_CASE("align difference images show the XOR the optimizer counts", "[align]") {
  const GenericHead generic = test::synthetic_head();
  const Affine truth = random_affine(5, 10.0, 0.15, 0.2, 1.0);
  const PointCloud cloud = transformed(test::sample_surface(generic.mesh, 30000, 9), truth);
  AlignOptions o;
  o.resolution = 128;
  o.coarse_resolutions = {64};
  AlignResult r;
  REQUIRE(align_initial(generic.mesh, generic.annotations, cloud, o, r).ok());
  std::array<Image, kSilhouetteViews> before, after;
  REQUIRE(align_difference_images(generic.mesh, r.initial_linear, r.initial_translation, cloud, r.frame, o, before).ok());
  REQUIRE(align_difference_images(generic.mesh, r.linear, r.translation, cloud, r.frame, o, after).ok());
  for (int v = 0; v < kSilhouetteViews; ++v) {
    REQUIRE(before[v].width == 128);
    REQUIRE(before[v].channels == 3);
    int white_before = 0, white_after = 0;
    for (int i = 0; i < 128 * 128; ++i) {
      white_before += before[v].pixels[3 * i] == 255;
      white_after += after[v].pixels[3 * i] == 255;
    }
    CHECK(white_before == r.xor_before[v]);
    CHECK(white_after == r.xor_after[v]);
  }
  const Image strip = concat_views(after);
  CHECK(strip.width == 3 * 128 + 4);
  CHECK(strip.height == 128);
}

TEST_CASE("align refuses degenerate input with a clear error", "[align]") {
  const GenericHead generic = test::synthetic_head();
  AlignResult r;
  const AlignOptions o;
  PointCloud empty;
  CHECK(align_initial(generic.mesh, generic.annotations, empty, o, r).code == ErrorCode::Empty);

  PointCloud same;
  same.positions.assign(5000, Vec3(1, 2, 3));
  Status st = align_initial(generic.mesh, generic.annotations, same, o, r);
  CHECK(st.code == ErrorCode::InvalidInput);
  CHECK(st.message.find("single point") != std::string::npos);

  PointCloud three;
  three.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0.5), Vec3(0, 1, 0.2)};
  st = align_initial(generic.mesh, generic.annotations, three, o, r);
  CHECK(st.code == ErrorCode::InvalidInput);
  CHECK(st.message.find("only 3 points") != std::string::npos);

  PointCloud with_nan = test::sample_surface(generic.mesh, 1000, 1);
  with_nan.positions[17].y() = std::nan("");
  st = align_initial(generic.mesh, generic.annotations, with_nan, o, r);
  CHECK(st.code == ErrorCode::InvalidInput);
  CHECK(st.message.find("point 17") != std::string::npos);

  PointCloud flat = test::sample_surface(generic.mesh, 1000, 1);
  for (Vec3& p : flat.positions) p.z() = 0.0;
  CHECK(align_initial(generic.mesh, generic.annotations, flat, o, r).code == ErrorCode::InvalidInput);

  const PointCloud good = test::sample_surface(generic.mesh, 1000, 1);
  CHECK(align_initial(TriMesh{}, generic.annotations, good, o, r).code == ErrorCode::Empty);
  TriMesh broken = generic.mesh;
  broken.triangles[3][1] = broken.num_vertices() + 4;
  CHECK(align_initial(broken, generic.annotations, good, o, r).code == ErrorCode::InvalidInput);

  AlignOptions bad_res;
  bad_res.resolution = 3;
  CHECK(align_initial(generic.mesh, generic.annotations, good, bad_res, r).code == ErrorCode::InvalidInput);

  // Clip planes that remove the whole generic head.
  HeadAnnotations away = generic.annotations;
  away.neck_clip.point = Vec3(0, 5, 0);
  CHECK(align_initial(generic.mesh, away, good, o, r).code == ErrorCode::NotAHead);

  // Cancellation from the progress callback.
  lk::ProgressFn stop = [](const char*, double) { return false; };
  CHECK(align_initial(generic.mesh, generic.annotations, good, o, r, stop).code == ErrorCode::Cancelled);
}

TEST_CASE("align puts the generic on a virtual structured-light scan of another head", "[align]") {
  // A different person (synthesized proportions), scanned with shadows,
  // holes, hair junk and outliers, then posed in millimetres: the aligned
  // generic must land on that person's own control vertices.
  const GenericHead generic = analytic_head();
  test::TestScanOptions setup;
  setup.generic = &generic;
  setup.truth.subdivision_levels = 1;
  const test::TestScan scanned = test::make_test_scan(3, 60000, setup);
  const GenericHead& person = scanned.head;
  const PointCloud& scan = scanned.scan;
  const Affine pose = random_affine(8, 8.0, 0.1, 0.2, 1000.0);
  AlignResult r;
  REQUIRE(align_initial(generic.mesh, generic.annotations, transformed(scan, pose), AlignOptions{}, r).ok());
  double sum = 0, sum_initial = 0;
  int n = 0;
  BBox box;
  for (int i = 0; i < generic.mesh.num_vertices(); ++i) {
    const Vec3& g = generic.mesh.positions[i];
    if (!generic.annotations.neck_clip.keeps(g)) continue;
    const Vec3 t = pose.apply(person.mesh.positions[i]);
    box.extend(t);
    sum += (r.linear * g + r.translation - t).squaredNorm();
    sum_initial += (r.initial_linear * g + r.initial_translation - t).squaredNorm();
    ++n;
  }
  const double err = std::sqrt(sum / n) / box.diagonal(), err_initial = std::sqrt(sum_initial / n) / box.diagonal();
  INFO("relative RMS " << err << " (initial " << err_initial << "), XOR " << total_xor(r.xor_before) << " -> "
                       << total_xor(r.xor_after));
  // For people to look at: build/test_scratch/align/virtual_scan_xor_{before,after}.png
  std::array<Image, kSilhouetteViews> before, after;
  REQUIRE(align_difference_images(generic.mesh, r.initial_linear, r.initial_translation, transformed(scan, pose),
                                  r.frame, AlignOptions{}, before).ok());
  REQUIRE(align_difference_images(generic.mesh, r.linear, r.translation, transformed(scan, pose), r.frame,
                                  AlignOptions{}, after).ok());
  const std::string dir = test::scratch_dir("align");
  CHECK(save_png_file(dir + "/virtual_scan_xor_before.png", concat_views(before)).ok());
  CHECK(save_png_file(dir + "/virtual_scan_xor_after.png", concat_views(after)).ok());
  CHECK(err < 0.02);
  CHECK(err < 0.6 * err_initial);
  // The hair leaves holes in the scan's silhouettes that no pose can fill,
  // so D drops less than on clean samples.
  CHECK(total_xor(r.xor_after) < 0.7 * total_xor(r.xor_before));
  check_monotone(r);
}

TEST_CASE("align reports progress in order and survives absurd coordinates", "[align]") {
  const GenericHead generic = test::synthetic_head();
  const PointCloud cloud = transformed(test::sample_surface(generic.mesh, 5000, 2), random_affine(4, 5, 0.1, 0.1, 1.0));
  AlignOptions o;
  o.resolution = 64;
  o.coarse_resolutions = {32};
  std::vector<double> fractions;
  lk::ProgressFn record = [&](const char* stage, double f) {
    CHECK(std::string(stage) == "align");
    fractions.push_back(f);
    return true;
  };
  AlignResult r;
  REQUIRE(align_initial(generic.mesh, generic.annotations, cloud, o, r, record).ok());
  REQUIRE(!fractions.empty());
  for (size_t i = 0; i < fractions.size(); ++i) {
    CHECK(fractions[i] >= 0.0);
    CHECK(fractions[i] <= 1.0);
    if (i > 0) CHECK(fractions[i] >= fractions[i - 1]);
  }
  CHECK(fractions.back() == 1.0);
  CHECK(r.levels.size() == 2);

  // Coordinates near the limits of double: an error or a result, never a crash.
  PointCloud huge = cloud;
  for (Vec3& p : huge.positions) p *= 1e300;
  const Status st = align_initial(generic.mesh, generic.annotations, huge, o, r);
  INFO(st.message);
  CHECK((st.ok() || !st.message.empty()));

  // A generic head whose look and up are parallel cannot be faced.
  HeadAnnotations bad = generic.annotations;
  bad.up = bad.look;
  CHECK(align_initial(generic.mesh, bad, cloud, o, r).code == ErrorCode::InvalidInput);
}


namespace {

// Mean distance from the scan points kept by the frame's clip planes to a
// mesh, as a fraction of those points' bounding-box diagonal.
double mean_distance_to(const TriMesh& mesh, const PointCloud& cloud, const AlignFrame& frame) {
  ClosestPointTree tree(mesh);
  std::vector<Vec3> kept;
  for (const Vec3& p : cloud.positions) {
    bool keep = true;
    for (const ClipPlane& c : frame.clips) keep = keep && c.keeps(p);
    if (keep) kept.push_back(p);
  }
  double sum = 0;
  BBox box;
  for (const Vec3& p : kept) {
    box.extend(p);
    sum += std::sqrt(tree.closest(p).squared_distance);
  }
  return kept.empty() ? 1.0 : sum / kept.size() / box.diagonal();
}

}  // namespace

TEST_CASE("align places the generic head on the real James scan", "[align][real]") {
  LK_REQUIRE_SHARED("head_scans/james_menpo3d/james.obj");
  // A real 3dMD-style capture in millimetres (6393 vertices, front of head):
  // sparse for 256^2, so hole filling matters; the scan's own frame faces +z.
  GenericHead generic;
  REQUIRE(load_generic_head(generic).ok());
  PointCloud scan;
  REQUIRE(load_point_cloud_file(test::shared_data_dir() + "/head_scans/james_menpo3d/james.obj", scan).ok());
  AlignResult r;
  REQUIRE(align_initial(generic.mesh, generic.annotations, scan, AlignOptions{}, r).ok());
  TriMesh initial = generic.mesh;
  transform(initial, r.initial_linear, r.initial_translation);
  const double before = mean_distance_to(initial, scan, r.frame);
  const double after = mean_distance_to(r.aligned, scan, r.frame);
  INFO("mean scan-to-generic distance " << 100 * before << "% -> " << 100 * after << "% of the diagonal; XOR "
                                        << total_xor(r.xor_before) << " -> " << total_xor(r.xor_after));
  CHECK(total_xor(r.xor_after) < 0.8 * total_xor(r.xor_before));
  CHECK(after < 0.8 * before);
  CHECK(after < 0.02);
  CHECK(r.levels.back().cloud.closing_radius_px[0] > 0.0);  // 6k points leave gaps at 256^2
  check_monotone(r);
}

TEST_CASE("align with several starts keeps the one with the least D on the coarse levels", "[align]") {
  // AlignOptions::pitch_starts_deg: start 0 runs exactly as a single start,
  // so the start kept has a coarse D no larger than the single start's, and
  // the progress still runs from 0 to 1 in order.
  const GenericHead generic = test::synthetic_head();
  const PointCloud cloud = transformed(test::sample_surface(generic.mesh, 5000, 2), random_affine(7, 5, 0.1, 0.1, 1.0));
  AlignOptions one;
  one.resolution = 64;
  one.coarse_resolutions = {32};
  one.pitch_starts_deg = {0.0};
  one.choose_at_final = false;  // the coarse levels' D chooses (the default chooses after the polish)
  one.polish = false;
  AlignOptions three = one;
  three.pitch_starts_deg = {0.0, 15.0, -15.0};
  std::vector<double> fractions;
  lk::ProgressFn record = [&](const char*, double f) {
    fractions.push_back(f);
    return true;
  };
  AlignResult r1, r3;
  REQUIRE(align_initial(generic.mesh, generic.annotations, cloud, one, r1).ok());
  REQUIRE(align_initial(generic.mesh, generic.annotations, cloud, three, r3, record).ok());
  REQUIRE(r1.levels.size() == 2);
  REQUIRE(r3.levels.size() == 2);
  CHECK(total_xor(r3.levels[0].xor_after) <= total_xor(r1.levels[0].xor_after));
  CHECK(r3.evaluations > r1.evaluations);
  REQUIRE(!fractions.empty());
  for (size_t i = 1; i < fractions.size(); ++i) CHECK(fractions[i] >= fractions[i - 1]);
  CHECK(fractions.back() == 1.0);
}
