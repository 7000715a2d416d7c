// Face-only alignment, coverage and orientation (core/align/face_alignment.h):
// a patch cut from the generic head itself, moved by a known similarity,
// must be put back exactly; the orientation search must find the axes a
// head was turned by; bad input is refused.
#include "align/face_alignment.h"
#include "mesh/geometry.h"
#include "test_scan.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <random>

using namespace lk;

namespace {

const GenericHead& generic() { return test::generic_head(); }

// Points sampled on the generic head's triangles (area-uniform), the ones
// within `depth` m behind the nose tip and above the chin (a face patch).
PointCloud face_patch(double depth, int count, unsigned seed) {
  const TriMesh& m = generic().mesh;
  double tip = -1e300;
  for (const Vec3& p : m.positions) tip = std::max(tip, p.z());
  std::vector<double> cumulative;
  double total = 0;
  for (int f = 0; f < m.num_triangles(); ++f) {
    total += 0.5 * face_normal_area(m, f).norm();
    cumulative.push_back(total);
  }
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  PointCloud cloud;
  while (cloud.size() < count) {
    const int f = static_cast<int>(std::lower_bound(cumulative.begin(), cumulative.end(), u(rng) * total) -
                                   cumulative.begin());
    double a = u(rng), b = u(rng);
    if (a + b > 1) {
      a = 1 - a;
      b = 1 - b;
    }
    const Tri& t = m.triangles[std::min(f, m.num_triangles() - 1)];
    const Vec3 p = m.positions[t[0]] + a * (m.positions[t[1]] - m.positions[t[0]]) +
                   b * (m.positions[t[2]] - m.positions[t[0]]);
    // The outer skin only: the eye and mouth pockets are not scanned.
    if (p.z() > tip - depth && p.y() > -0.11 && std::abs(p.x()) < 0.075) cloud.positions.push_back(p);
  }
  return cloud;
}

}  // namespace

TEST_CASE("coverage: a face patch is shallow, the whole generic head is deep") {
  ScanCoverage c;
  PointCloud whole;
  whole.positions = generic().mesh.positions;
  REQUIRE(estimate_coverage(whole, CoverageOptions{}, c).ok());
  INFO("whole head depth/width " << c.depth_to_width);
  CHECK_FALSE(c.face_only);
  CHECK(c.depth_to_width > 1.0);
  REQUIRE(estimate_coverage(face_patch(0.08, 3000, 1), CoverageOptions{}, c).ok());
  INFO("face patch depth/width " << c.depth_to_width);
  CHECK(c.face_only);
  PointCloud bad = whole;
  bad.positions[3].y() = std::nan("");
  CHECK(estimate_coverage(bad, CoverageOptions{}, c).code == ErrorCode::InvalidInput);
  CHECK(estimate_coverage(PointCloud{}, CoverageOptions{}, c).code == ErrorCode::Empty);
}

TEST_CASE("align_face puts a moved face patch of the generic head back") {
  const PointCloud patch = face_patch(0.07, 4000, 2);
  // Millimetres, 1.08x larger, turned 30 degrees to the left and 8 down.
  const Mat3 R = (Eigen::AngleAxisd(30 * M_PI / 180, Vec3::UnitY()) *
                  Eigen::AngleAxisd(8 * M_PI / 180, Vec3::UnitX())).toRotationMatrix();
  const double s = 1080;
  const Vec3 t(40, -1700, 250);
  PointCloud moved;
  for (const Vec3& p : patch.positions) moved.positions.push_back(s * (R * p) + t);
  FaceAlignResult r;
  const Status st = align_face(generic().mesh, generic().annotations, moved, FaceAlignOptions{}, r);
  INFO(st.message);
  REQUIRE(st.ok());
  INFO("scale " << r.scale << " rms " << r.rms << " mm, facing " << r.facing.transpose());
  CHECK(r.scale == Approx(s).epsilon(0.01));
  CHECK((r.linear - s * R).norm() < 0.02 * s);
  // Every generic vertex of the face lands within 1 mm of where it belongs.
  double worst = 0;
  for (const Vec3& g : generic().mesh.positions)
    if (g.z() > 0.03) worst = std::max(worst, (r.linear * g + r.translation - (s * (R * g) + t)).norm());
  CHECK(worst < 1.0);
  CHECK(r.rms < 0.2);
  CHECK(r.facing.isApprox(R * Vec3::UnitZ(), 1e-2));
}

TEST_CASE("guess_orientation finds the axes a head was turned by") {
  PointCloud whole;
  whole.positions = generic().mesh.positions;
  OrientationGuess g;
  REQUIRE(guess_orientation(generic().mesh, generic().annotations, whole, OrientationOptions{}, g).ok());
  CHECK_FALSE(g.differs);
  // Turned about x: the crown towards +z, the face towards -y.
  const Mat3 lying = Eigen::AngleAxisd(M_PI / 2, Vec3::UnitX()).toRotationMatrix();
  REQUIRE((lying * Vec3::UnitY()).isApprox(Vec3::UnitZ()));
  PointCloud turned;
  for (const Vec3& p : face_patch(0.08, 3000, 3).positions) turned.positions.push_back(lying * p);
  REQUIRE(guess_orientation(generic().mesh, generic().annotations, turned, OrientationOptions{}, g).ok());
  INFO("up " << g.up.transpose() << " facing " << g.facing.transpose() << " scores " << g.score_given << " "
             << g.score_best);
  CHECK(g.differs);
  CHECK(g.up.isApprox(Vec3::UnitZ()));
  CHECK(g.facing.isApprox(-Vec3::UnitY()));
  CHECK((g.rotation * lying).isApprox(Mat3::Identity(), 1e-9));
  CHECK(axis_name(g.facing) == "-y");
  CHECK(axis_name(Vec3(0, 0, -2)) == "-z");
}

TEST_CASE("align_face and guess_orientation refuse bad input") {
  FaceAlignResult r;
  OrientationGuess g;
  PointCloud few;
  few.positions.assign(5, Vec3::Zero());
  CHECK(align_face(generic().mesh, generic().annotations, few, FaceAlignOptions{}, r).code ==
        ErrorCode::InvalidInput);
  CHECK(align_face(generic().mesh, generic().annotations, PointCloud{}, FaceAlignOptions{}, r).code ==
        ErrorCode::Empty);
  FaceAlignOptions o;
  o.start_yaws_deg.clear();
  CHECK(align_face(generic().mesh, generic().annotations, face_patch(0.08, 500, 4), o, r).code ==
        ErrorCode::InvalidInput);
  CHECK(align_face(TriMesh{}, generic().annotations, face_patch(0.08, 500, 4), FaceAlignOptions{}, r).code ==
        ErrorCode::Empty);
  PointCloud nan = face_patch(0.08, 500, 5);
  nan.positions[7].z() = std::nan("");
  CHECK(guess_orientation(generic().mesh, generic().annotations, nan, OrientationOptions{}, g).code ==
        ErrorCode::InvalidInput);
  // Asked to stop at its first progress report (a patch of the generic head
  // in the given orientation is accepted after the first start).
  int calls = 0;
  const ProgressFn stop = [&](const char*, double) { return ++calls < 1; };
  CHECK(guess_orientation(generic().mesh, generic().annotations, face_patch(0.08, 500, 6), OrientationOptions{}, g,
                          stop)
            .code == ErrorCode::Cancelled);
}
