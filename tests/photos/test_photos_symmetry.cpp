// The shape fit's mirror-symmetry term (photos/shape_fit.h,
// ShapeFitOptions::symmetry_weight; on in the photos job): the generic
// head's mirror pairs and the rows against finite differences (what it does
// to a fit on the detector's points: test_photos_detected.cpp).
#include "head/generic_head.h"
#include "photos/photos_job.h"
#include "photos/shape_fit.h"
#include "photos_scenario.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <random>
#include <set>

namespace lk {
namespace {

TEST_CASE("the generic head's mirror pairs cover every vertex once, each the other's mirror image", "[photos][symmetry]") {
  GenericHead g;
  REQUIRE(load_generic_head(g));
  const std::vector<std::array<int, 2>> pairs = mirror_vertex_pairs(g.mesh);
  std::multiset<int> seen;
  int on_plane = 0;
  for (const auto& [a, b] : pairs) {
    CHECK(a <= b);
    const Vec3 &p = g.mesh.positions[size_t(a)], &q = g.mesh.positions[size_t(b)];
    CHECK((Vec3(-p.x(), p.y(), p.z()) - q).norm() < 1e-6);
    seen.insert(a);
    if (a != b) seen.insert(b);
    on_plane += a == b;
  }
  CHECK(int(seen.size()) == g.mesh.num_vertices());
  CHECK(int(std::set<int>(seen.begin(), seen.end()).size()) == g.mesh.num_vertices());
  CHECK(on_plane > 20);  // the midline: nose, lips, chin, the scalp's crest
  // One vertex moved off its mirror place: no pairing at all.
  TriMesh bent = g.mesh;
  bent.positions[size_t(pairs.back()[0])].x() += 0.002;
  CHECK(mirror_vertex_pairs(bent).empty());
}

TEST_CASE("the symmetry rows: zero on a mirrored displacement, their Jacobian against finite differences", "[photos][symmetry]") {
  GenericHead g;
  REQUIRE(load_generic_head(g));
  const std::vector<std::array<int, 2>> pairs = mirror_vertex_pairs(g.mesh);
  REQUIRE(!pairs.empty());
  const std::vector<Vec3>& start = g.mesh.positions;
  std::mt19937 rng(11);
  std::normal_distribution<double> N(0.0, 0.002);
  // A displacement the same on both sides, mirrored: no residual.
  std::vector<Vec3> sym = start;
  for (const auto& [a, b] : pairs) {
    const Vec3 d(N(rng), N(rng), N(rng));
    if (a == b) {
      sym[size_t(a)] += Vec3(0, d.y(), d.z());
    } else {
      sym[size_t(a)] += d;
      sym[size_t(b)] += Vec3(-d.x(), d.y(), d.z());
    }
  }
  Eigen::VectorXd r;
  symmetry_residuals(start, sym, pairs, 2.0, r, nullptr);
  CHECK(r.size() == 3 * long(pairs.size()));
  CHECK(r.norm() < 1e-12);
  // One side pushed out along x alone: its residual is sqrt(w) times twice the push on the plane, the push elsewhere.
  std::vector<Vec3> one = start;
  const bool plane = pairs.front()[0] == pairs.front()[1];
  one[size_t(pairs.front()[0])].x() += 0.001;
  symmetry_residuals(start, one, pairs, 4.0, r, nullptr);
  CHECK(r.norm() == Approx((plane ? 2 : 1) * 2.0 * 0.001).epsilon(1e-9));
  // Random positions: the Jacobian's columns against central differences.
  std::vector<Vec3> x = start;
  for (Vec3& p : x) p += Vec3(N(rng), N(rng), N(rng));
  std::vector<Eigen::Triplet<double>> trip;
  symmetry_residuals(start, x, pairs, 0.7, r, &trip);
  SparseMat J(r.size(), 3 * long(x.size()));
  J.setFromTriplets(trip.begin(), trip.end());
  double worst = 0;
  for (int col = 0; col < 3 * int(x.size()); col += 7) {
    const double h = 1e-6;
    std::vector<Vec3> xp = x, xm = x;
    xp[size_t(col / 3)][col % 3] += h;
    xm[size_t(col / 3)][col % 3] -= h;
    Eigen::VectorXd rp, rm;
    symmetry_residuals(start, xp, pairs, 0.7, rp, nullptr);
    symmetry_residuals(start, xm, pairs, 0.7, rm, nullptr);
    const Eigen::VectorXd fd = (rp - rm) / (2 * h), an = J.col(col);
    worst = std::max(worst, (fd - an).norm() / (1 + an.norm()));
  }
  std::printf("symmetry rows: worst relative difference to finite differences %.2e\n", worst);
  CHECK(worst < 1e-8);
}


TEST_CASE("a generic head that is not mirror-symmetric is fitted without the symmetry term, and the job says so", "[photos][symmetry]") {
  const test::PhotoScenario s = test::make_photo_scenario(1);
  GenericHead bent = s.generic;
  int back = 0;  // the vertex farthest back, away from every landmark
  for (int v = 0; v < bent.mesh.num_vertices(); ++v)
    if (bent.mesh.positions[size_t(v)].z() < bent.mesh.positions[size_t(back)].z()) back = v;
  bent.mesh.positions[size_t(back)].x() += 0.002;
  REQUIRE(mirror_vertex_pairs(bent.mesh).empty());
  const std::string note = "the generic head is not mirror-symmetric: the shape fit does without its symmetry term";
  auto has_note = [&](const PhotosJobResult& r) {
    for (const std::string& n : r.notes)
      if (n == note) return true;
    return false;
  };
  PhotosJobResult on_bent, on_generic;
  REQUIRE(run_photos_job(bent, s.map, s.session.photos, PhotosJobOptions{}, on_bent));
  CHECK(has_note(on_bent));
  REQUIRE(run_photos_job(s.generic, s.map, s.session.photos, PhotosJobOptions{}, on_generic));
  CHECK_FALSE(has_note(on_generic));
}

}  // namespace
}  // namespace lk
