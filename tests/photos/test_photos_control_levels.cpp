// Coarse control triangulations (photos/control_levels.h, fua1998 Sec. 2.1
// eq. 3): the attachment, its Jacobian against finite differences, and the
// coarse level's smoother fit of a smooth deformation.
#include "photos/added_folds.h"
#include "mesh/geometry.h"
#include "photos/control_levels.h"
#include "photos/shape_fit.h"
#include "observation_fd.h"
#include "photos_scenario.h"

#include <cmath>

namespace lk {
namespace {

TEST_CASE("a coarse control level attaches every vertex by barycentric weights", "[photos]") {
  GenericHead generic;
  REQUIRE(load_generic_head(generic));
  const TriMesh& m = generic.mesh;
  ControlLevel level;
  REQUIRE(build_control_level(m, 150, level));
  REQUIRE(level.num_nodes() == 150);
  CHECK(!level.identity);
  CHECK(level.triangles.size() > 200);
  // Each row: at most 3 weights, >= 0, summing to 1; a node's own vertex on it alone.
  Eigen::VectorXd row_sum = level.attachment * Eigen::VectorXd::Ones(level.num_nodes());
  CHECK((row_sum.array() - 1).abs().maxCoeff() < 1e-12);
  CHECK(level.attachment.coeffs().minCoeff() >= 0);
  for (int k = 0; k < level.num_nodes(); ++k) CHECK(level.attachment.coeff(level.nodes[size_t(k)], k) == 1.0);
  std::vector<int> per_row(size_t(m.num_vertices()), 0);
  for (int k = 0; k < level.attachment.outerSize(); ++k)
    for (SparseMat::InnerIterator it(level.attachment, k); it; ++it) ++per_row[size_t(it.row())];
  CHECK(*std::max_element(per_row.begin(), per_row.end()) <= 3);
  // Most vertices lie inside their triangle (more than one weight): the field is interpolated, not a patchwork.
  int interpolated = 0;
  for (int n : per_row) interpolated += n > 1;
  CHECK(interpolated > m.num_vertices() / 2);
  // A constant displacement moves every vertex by it (weights sum to 1); the Laplacian ignores it.
  Eigen::VectorXd delta(3 * level.num_nodes());
  for (int k = 0; k < level.num_nodes(); ++k) delta.segment<3>(3 * k) = Vec3(0.01, -0.02, 0.005);
  const std::vector<Vec3> moved = attached_positions(level, m.positions, delta);
  double worst = 0;
  for (size_t v = 0; v < moved.size(); ++v)
    worst = std::max(worst, (moved[v] - m.positions[v] - Vec3(0.01, -0.02, 0.005)).norm());
  CHECK(worst < 1e-12);
  CHECK((level.laplacian * Eigen::VectorXd::Ones(level.num_nodes())).cwiseAbs().maxCoeff() < 1e-12);
  // Nodes are spread: no vertex farther than ~3 cm (in a straight line) from its own node.
  double far = 0;
  for (int v = 0; v < m.num_vertices(); ++v)
    far = std::max(far, (m.positions[size_t(v)] - m.positions[size_t(level.nodes[size_t(level.cell[size_t(v)])])]).norm());
  CHECK(far < 0.035);
  // As many nodes as vertices: the control mesh itself.
  ControlLevel full;
  REQUIRE(build_control_level(m, m.num_vertices(), full));
  CHECK(full.identity);
  CHECK(full.attachment.nonZeros() == m.num_vertices());
  // Bad input.
  CHECK(build_control_level(m, 3, level).code == ErrorCode::InvalidInput);
  CHECK(build_control_level(TriMesh{}, 100, level).code == ErrorCode::InvalidInput);
}

TEST_CASE("the features' Jacobian through a coarse level's attachment matches finite differences", "[photos]") {
  test::PhotoScenario s = test::make_photo_scenario(3);
  std::vector<FeatureObservation> obs;
  for (size_t c = 0; c < s.session.photos.size(); ++c)
    for (size_t m = 0; m < s.landmarks.size(); m += 11)
      if (s.session.photos[c].present[m]) obs.push_back({int(c), s.landmarks[m], s.session.photos[c].points[m], 0.7, 0.7});
  REQUIRE(obs.size() > 50);
  FeatureSet set(s.generic.mesh, s.session.cameras, obs, 4.0);
  ControlLevel level;
  REQUIRE(build_control_level(s.generic.mesh, 120, level));
  // At a deformed state, not at zero: the chain rule must hold anywhere.
  Eigen::VectorXd delta(3 * level.num_nodes());
  for (long i = 0; i < delta.size(); ++i) delta[i] = 0.002 * std::sin(0.7 * double(i));
  const std::vector<Vec3>& base = s.generic.mesh.positions;
  Eigen::VectorXd r(set.num_residuals());
  std::vector<Eigen::Triplet<double>> trip;
  REQUIRE(set.evaluate(attached_positions(level, base, delta), r, 0, &trip));
  SparseMat Jv(r.size(), 3 * long(base.size()));
  Jv.setFromTriplets(trip.begin(), trip.end());
  const SparseMat J = attach_jacobian(level, Jv);
  REQUIRE(J.cols() == delta.size());
  double worst = 0;
  int columns_seen = 0;
  const double h = 1e-7;
  for (long col = 0; col < delta.size(); ++col) {
    Eigen::VectorXd a = delta, b = delta;
    a[col] += h;
    b[col] -= h;
    Eigen::VectorXd ra(r.size()), rb(r.size());
    REQUIRE(set.evaluate(attached_positions(level, base, a), ra, 0, nullptr));
    REQUIRE(set.evaluate(attached_positions(level, base, b), rb, 0, nullptr));
    const Eigen::VectorXd fd = (ra - rb) / (2 * h), an = J.col(col);
    columns_seen += an.norm() > 0;
    worst = std::max(worst, (fd - an).norm() / (1 + an.norm()));
  }
  CHECK(columns_seen > 60);  // many nodes carry landmarks: the check is not vacuous
  CHECK(worst < 1e-4);
}

TEST_CASE("added folds: none on the generic head itself, a dent on a cheek found there", "[photos]") {
  GenericHead generic;
  REQUIRE(load_generic_head(generic));
  std::vector<AddedFolds> folds;
  REQUIRE(measure_added_folds(generic, generic.mesh.positions, 3, 15.0, folds));
  REQUIRE(folds.size() == 7);
  for (const AddedFolds& f : folds) {
    CHECK(f.edges > 20);
    CHECK(f.crossings == f.generic_crossings);
    CHECK(f.max_deg == Approx(0.0).margin(1e-9));
    CHECK(f.creased == 0);
  }
  // One cheek vertex pushed 6 mm into the head: a pit that a person would see.
  const std::vector<int>& cheeks = generic.annotations.regions.at("cheeks");
  const int v = cheeks[cheeks.size() / 2];
  std::vector<Vec3> dented = generic.mesh.positions;
  dented[size_t(v)] -= 0.006 * vertex_normals(generic.mesh)[size_t(v)];
  REQUIRE(measure_added_folds(generic, dented, 3, 5.0, folds));
  for (const AddedFolds& f : folds) {
    INFO(f.region << ": max " << f.max_deg << ", " << f.creased << " edges");
    if (f.region == "cheeks" || f.region == "face") {
      CHECK(f.max_deg > 10);
      CHECK(f.creased > 0);
    }
    if (f.region == "nose" || f.region == "brow") CHECK(f.creased == 0);
  }
  CHECK(!measure_added_folds(generic, std::vector<Vec3>(10), 3, 15.0, folds).ok());
}

// The generic head plus a smooth, low-frequency deformation (a broad bulge
// of the left cheek and a wider jaw), seen by the synthetic session's
// cameras with 2 px landmark noise; the shape fitted from the true cameras.
struct BulgeCase {
  test::PhotoScenario s;
  GenericHead truth;
};

BulgeCase make_bulge_case() {
  BulgeCase b{test::make_photo_scenario(5), {}};
  b.truth = b.s.generic;
  const std::vector<Vec3> normals = vertex_normals(b.s.generic.mesh);
  const Vec3 centre(0.045, -0.02, 0.06);
  for (size_t v = 0; v < b.truth.mesh.positions.size(); ++v) {
    Vec3& p = b.truth.mesh.positions[v];
    const double bump = 0.006 * std::exp(-(p - centre).squaredNorm() / (2 * 0.035 * 0.035));
    p += bump * normals[v];
    p.x() *= 1.0 + 0.06 * std::max(0.0, -p.y() / 0.1);  // wider below the eyes' height
  }
  SyntheticViewsOptions vo;
  REQUIRE(make_synthetic_views(b.truth, b.s.landmarks, 5, vo, b.s.session));
  return b;
}

struct FitFigures {
  double mean_mm = 0;                     // vertex to same vertex over the face, no alignment (the cameras are true)
  double face_p95 = 0, face_max = 0;      // growth of level 3's dihedral angles over the generic's, face (deg)
  int face_creased = 0;                   // face edges grown by more than 10 deg
};

FitFigures fit_and_measure(const BulgeCase& b, const ShapeFitOptions& opt) {
  std::vector<FeatureObservation> obs;
  for (size_t c = 0; c < b.s.session.photos.size(); ++c)
    for (size_t m = 0; m < b.s.landmarks.size(); ++m)
      if (b.s.session.photos[c].present[m] && b.s.landmarks[m].valid())
        obs.push_back({int(c), b.s.landmarks[m], b.s.session.photos[c].points[m], 1, 1});
  std::vector<std::unique_ptr<ObservationSet>> sets;
  sets.push_back(std::make_unique<FeatureSet>(b.s.generic.mesh, b.s.session.cameras, obs, 4.0));
  ShapeFitResult r;
  REQUIRE(fit_shape(b.s.generic.mesh, sets, {0.3}, opt, r));
  FitFigures f;
  const std::vector<int>& face = b.s.generic.annotations.regions.at("face");
  for (int v : face) f.mean_mm += 1000 * (r.mesh.positions[size_t(v)] - b.truth.mesh.positions[size_t(v)]).norm();
  f.mean_mm /= double(face.size());
  std::vector<AddedFolds> folds;
  REQUIRE(measure_added_folds(b.s.generic, r.mesh.positions, 3, 10.0, folds));
  for (const AddedFolds& g : folds)
    if (g.region == "face") {
      f.face_p95 = g.p95_deg;
      f.face_max = g.max_deg;
      f.face_creased = g.creased;
    }
  return f;
}

TEST_CASE("a coarse control level fits a smooth deformation with fewer folds than the stiffness alone", "[photos]") {
  const BulgeCase b = make_bulge_case();
  double generic_mean = 0;
  const std::vector<int>& face = b.s.generic.annotations.regions.at("face");
  for (int v : face) generic_mean += 1000 * (b.s.generic.mesh.positions[size_t(v)] - b.truth.mesh.positions[size_t(v)]).norm();
  generic_mean /= double(face.size());
  // The same stiffness (the schedule's last, 3) on the control mesh alone and on a coarse level alone.
  ShapeFitOptions fine;
  fine.stiffness_schedule = {3.0};
  ShapeFitOptions coarse;
  coarse.stiffness_schedule.clear();
  coarse.coarse_levels = {{150, 3.0}};
  const FitFigures stiff = fit_and_measure(b, ShapeFitOptions{}), f = fit_and_measure(b, fine),
                   c = fit_and_measure(b, coarse);
  auto say = [](const FitFigures& x) {
    return std::to_string(x.mean_mm) + " mm, face folds p95 " + std::to_string(x.face_p95) + " max " +
           std::to_string(x.face_max) + " deg, " + std::to_string(x.face_creased) + " edges > 10 deg";
  };
  INFO("generic " << generic_mean << " mm; schedule 100,10,3: " << say(stiff) << "; control mesh at 3: " << say(f)
                  << "; 150 nodes at 3: " << say(c));
  // Measured: the schedule 0.61 mm with 151 edges creased by > 10 deg (max 69 deg), the control
  // mesh at 3 the same; 150 nodes at 3: 0.70 mm with 22 (max 29 deg); the generic head 1.65 mm.
  CHECK(c.face_creased < 0.3 * stiff.face_creased);
  CHECK(c.face_creased < 0.3 * f.face_creased);
  CHECK(c.face_max < 0.6 * stiff.face_max);
  CHECK(c.mean_mm < 0.5 * generic_mean);
  CHECK(c.mean_mm < stiff.mean_mm + 0.15);
}

}  // namespace
}  // namespace lk
