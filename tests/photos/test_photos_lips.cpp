// Lips that stay whole in a head made from photos (photos/lips.h).
#include "head/generic_head.h"
#include "head/surface_quality.h"
#include "photos/added_folds.h"
#include "photos/lips.h"
#include "photos/photos_job.h"
#include "photos/synthetic_outlines.h"
#include "photos_scenario.h"

#include <catch2/catch.hpp>

namespace lk {
namespace {

int lips_crossings(const GenericHead& generic, const std::vector<Vec3>& positions) {
  std::vector<AddedFolds> folds;
  REQUIRE(measure_added_folds(generic, positions, 3, 15.0, folds));
  for (const AddedFolds& f : folds)
    if (f.region == "lips") return f.crossings;
  FAIL("no lips region");
  return -1;
}

// Self-crossing pairs of the smooth levels 0..3 of a control mesh with the
// generic head's triangles and creases, summed.
int crossings_all_levels(const GenericHead& generic, const std::vector<Vec3>& positions) {
  GenericHead h = generic;
  h.mesh.positions = positions;
  h.mesh.normals.clear();
  HeadSurfaceQuality q;
  REQUIRE(measure_head_surface(h, 3, q));
  int n = 0;
  for (int c : q.crossing_pairs) n += c;
  return n;
}

TEST_CASE("the lip binding edges join each upper lip line vertex to a lower one", "[photos][lips]") {
  GenericHead generic;
  REQUIRE(load_generic_head(generic));
  const std::vector<std::array<int, 2>> edges = lip_binding_edges(generic);
  const auto& up = generic.annotations.regions.at("upper_lip");
  const auto& lo = generic.annotations.regions.at("lower_lip");
  REQUIRE(edges.size() >= 3);
  for (const auto& e : edges) {
    CHECK(std::count(up.begin(), up.end(), e[0]) == 1);
    CHECK(std::count(lo.begin(), lo.end(), e[1]) == 1);
    // The slit: the two lines under a millimetre apart.
    CHECK((generic.mesh.positions[size_t(e[0])] - generic.mesh.positions[size_t(e[1])]).norm() < 1e-3);
  }
}

TEST_CASE("the mouth bag kept inside clears the generic head's own crossings at the mouth corners", "[photos][lips]") {
  GenericHead generic;
  REQUIRE(load_generic_head(generic));
  // The generic head's level 3 crosses itself at the mouth corners, where
  // the bag's nearest vertices sit 1.5 mm inside the corner (24 pairs).
  const int before = lips_crossings(generic, generic.mesh.positions);
  CHECK(before > 0);
  TriMesh control = generic.mesh;
  MouthBagResult r;
  REQUIRE(keep_mouth_bag_inside(generic, {}, control, r));
  CHECK(r.pairs_before > 0);
  CHECK(r.pairs_after == 0);
  CHECK(r.share > 0);
  CHECK(lips_crossings(generic, control.positions) == 0);
  // Only bag vertices moved (near the corners, not all of them), under 5 % of the way to its centroid.
  std::vector<char> bag(size_t(generic.mesh.num_vertices()), 0);
  for (int v : generic.annotations.constrained_vertices) bag[size_t(v)] = 1;
  for (int v = 0; v < generic.mesh.num_vertices(); ++v)
    if (!bag[size_t(v)]) CHECK(control.positions[size_t(v)] == generic.mesh.positions[size_t(v)]);
  int bag_moved = 0;
  for (int v : generic.annotations.constrained_vertices) bag_moved += control.positions[size_t(v)] != generic.mesh.positions[size_t(v)];
  CHECK(bag_moved > 0);
  CHECK(bag_moved < int(generic.annotations.constrained_vertices.size()));
  CHECK(r.share < 0.05);
  // Off (level 0): the head is left as it is.
  TriMesh same = generic.mesh;
  MouthBagOptions off;
  off.level = 0;
  REQUIRE(keep_mouth_bag_inside(generic, off, same, r));
  CHECK(same.positions == generic.mesh.positions);
  // Bad input.
  TriMesh other;
  CHECK(!keep_mouth_bag_inside(generic, {}, other, r));
  MouthBagOptions bad;
  bad.level = 7;
  CHECK(!keep_mouth_bag_inside(generic, bad, control, r));
}

TEST_CASE("a photos fit with the lips bound does not cross its lips", "[photos][lips]") {
  // Seed 2, exact projections with 2 px noise: 252 level-3 pairs at the
  // lips with the lips free (upper line 0.45 mm down, lower 0.49 mm up at
  // the middle: the slit's sides swapped), 0 bound.
  test::PhotoScenario s = test::make_photo_scenario(2);
  PhotosJobOptions opt;
  SelfCalibResult calib;
  REQUIRE(self_calibrate(s.session.photos, s.generic.mesh, s.landmarks, opt.calib, calib));
  ShapeFitResult bound, free;
  REQUIRE(fit_photos_shape(s.generic, s.landmarks, s.session.photos, calib, opt, bound));
  opt.bind_lips = false;
  opt.keep_mouth_bag = false;
  opt.untangle.level = 0;  // the untangle alone takes the free lips' 252 pairs to 16
  REQUIRE(fit_photos_shape(s.generic, s.landmarks, s.session.photos, calib, opt, free));
  const int pairs_free = lips_crossings(s.generic, free.mesh.positions);
  const int pairs_bound = lips_crossings(s.generic, bound.mesh.positions);
  INFO("level-3 crossing pairs at the lips: free " << pairs_free << ", bound " << pairs_bound);
  CHECK(pairs_free > 100);
  CHECK(pairs_bound == 0);
  // The slit's sides keep their order: each upper line vertex above its lower one.
  for (const auto& e : lip_binding_edges(s.generic))
    CHECK(bound.mesh.positions[size_t(e[0])].y() > bound.mesh.positions[size_t(e[1])].y());
  // The landmarks are met as well as before.
  CHECK(bound.final_rms_px < free.final_rms_px + 0.05);
}

TEST_CASE("a photos head with silhouettes crosses itself on no level", "[photos][lips]") {
  // Seed 1, exact projections and the person's outlines (the bench's
  // "1 +s"): with the bag kept inside by level 3 alone and no untangle (the
  // fit before 2026-12-01) 12 pairs over levels 0..3: 4 over the mouth
  // bag below level 3 and 8 on level 3 where the silhouettes fold an
  // ear's control face into itself. The bag checked on every level and the
  // scan fit's untangle take both to 0.
  test::PhotoScenario s = test::make_photo_scenario(1);
  std::vector<PhotoOutline> outlines;
  REQUIRE(synthetic_outlines(s.person.mesh, s.session.cameras, {}, outlines));
  PhotosJobOptions opt;
  opt.silhouettes.excluded_regions = {"neck"};  // the ears' outline too (a bald person, exact cameras)
  SelfCalibResult calib;
  REQUIRE(self_calibrate(s.session.photos, s.generic.mesh, s.landmarks, opt.calib, calib));
  ShapeFitResult now, old;
  UntangleResult untangled;
  REQUIRE(fit_photos_shape(s.generic, s.landmarks, s.session.photos, calib, opt, now, &outlines, nullptr, nullptr,
                           nullptr, nullptr, nullptr, &untangled));
  PhotosJobOptions before = opt;
  before.mouth_bag.all_levels = false;
  before.untangle.level = 0;
  REQUIRE(fit_photos_shape(s.generic, s.landmarks, s.session.photos, calib, before, old, &outlines));
  const int pairs_old = crossings_all_levels(s.generic, old.mesh.positions);
  const int pairs_now = crossings_all_levels(s.generic, now.mesh.positions);
  INFO("crossing pairs, levels 0..3: level 3 bag check, no untangle " << pairs_old << "; now " << pairs_now
                                                                       << " (untangle: " << untangled.pairs_before
                                                                       << " -> " << untangled.pairs_after << ")");
  CHECK(pairs_old > 0);
  CHECK(pairs_now == 0);
  CHECK(untangled.pairs_before > 0);
  CHECK(untangled.pairs_after == 0);
  // The untangle moves a few control vertices, not the head: every vertex
  // it and the bag step left alone is where the fit put it.
  int moved = 0;
  for (int v = 0; v < s.generic.mesh.num_vertices(); ++v)
    moved += now.mesh.positions[size_t(v)] != old.mesh.positions[size_t(v)];
  CHECK(moved > 0);
  CHECK(moved < 40);
}

TEST_CASE("the shape fit refuses a binding edge outside the mesh", "[photos][lips]") {
  test::PhotoScenario s = test::make_photo_scenario(1);
  std::vector<std::unique_ptr<ObservationSet>> sets;
  ShapeFitOptions o;
  o.binding_edges = {{0, s.generic.mesh.num_vertices()}};
  ShapeFitResult r;
  CHECK(!fit_shape(s.generic.mesh, sets, {}, o, r));
  o.binding_edges = {{3, 3}};
  CHECK(!fit_shape(s.generic.mesh, sets, {}, o, r));
  o.binding_edges.clear();
  o.binding_weight = -1;
  CHECK(!fit_shape(s.generic.mesh, sets, {}, o, r));
}

}  // namespace
}  // namespace lk
