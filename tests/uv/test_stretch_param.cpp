// One-chart stretch-minimizing parameterization (tarini2002 Sec. 3.1, Sander
// et al. 2001): flip-free, lower stretch than the initial map, ~1 on
// developable patches, view weighting gives the face more texture space.
#include "head/generic_head.h"
#include "mesh/primitives.h"
#include "uv/stretch_param.h"

#include <catch2/catch.hpp>
#include <cmath>

using namespace lk;

namespace {

// An n x n grid over [0,1]^2 mapped through f: a disk with one boundary loop.
template <class F>
TriMesh grid(int n, F f) {
  TriMesh m = make_regular_grid(n, n);  // vertex (i, j) at (i, j, 0)
  for (Vec3& p : m.positions) p = f(p.x() / n, p.y() / n);
  return m;
}

const double kPi = 3.14159265358979323846;

void check_chart(const TriMesh& m, const std::vector<Vec2>& uv) {
  REQUIRE(uv.size() == m.positions.size());
  for (const auto& p : uv) {
    CHECK(p.x() >= 0);
    CHECK(p.x() <= 1);
    CHECK(p.y() >= 0);
    CHECK(p.y() <= 1);
  }
}

}  // namespace

TEST_CASE("developable patches get stretch close to 1") {
  UvOptions opt;
  opt.view_weighted = false;
  opt.local_sweeps = 200;
  const TriMesh flat = grid(12, [](double u, double v) { return Vec3(0.3 * u, 0.2 * v, 0); });
  // Half a cylinder, radius 0.1: developable, curved.
  const TriMesh cyl = grid(12, [](double u, double v) {
    return Vec3(0.1 * std::cos(kPi * u), 0.25 * v, 0.1 * std::sin(kPi * u));
  });
  for (const TriMesh* m : {&flat, &cyl}) {
    std::vector<Vec2> uv, init;
    UvStats st, st0;
    REQUIRE(parameterize_stretch(*m, opt, uv, st).ok());
    check_chart(*m, uv);
    REQUIRE(parameterize_tutte(*m, opt, init).ok());
    REQUIRE(measure_stretch(*m, init, opt, st0).ok());
    WARN("developable: Tutte L2 " << st0.l2_stretch << ", optimized L2 " << st.l2_stretch
         << " Linf " << st.linf_stretch << " after " << st.iterations << " iterations");
    CHECK(st.flipped == 0);
    CHECK(st0.l2_stretch > 1.05);  // the circle boundary distorts the square
    CHECK(st.l2_stretch < 1.02);
    CHECK(st.linf_stretch < 1.2);
  }
}

TEST_CASE("a hemisphere and a bumpy disk: no flips, less stretch than Tutte") {
  const TriMesh hemi = grid(20, [](double u, double v) {
    const double x = 2 * u - 1, y = 2 * v - 1;  // square -> disk (Shirley-like squash)
    const double r = std::max(std::abs(x), std::abs(y)), a = std::atan2(y, x);
    const double th = 0.5 * kPi * 0.95 * r;
    return Vec3(std::sin(th) * std::cos(a), std::sin(th) * std::sin(a), std::cos(th));
  });
  const TriMesh bumpy = grid(20, [](double u, double v) {
    return Vec3(u, v, 0.15 * std::sin(3 * kPi * u) * std::sin(2 * kPi * v));
  });
  for (const TriMesh* m : {&hemi, &bumpy}) {
    UvOptions opt;
    std::vector<Vec2> uv, init;
    UvStats st, st0;
    REQUIRE(parameterize_stretch(*m, opt, uv, st).ok());
    REQUIRE(parameterize_tutte(*m, opt, init).ok());
    REQUIRE(measure_stretch(*m, init, opt, st0).ok());
    check_chart(*m, uv);
    CHECK(st.flipped == 0);
    CHECK(st.l2_stretch < st0.l2_stretch);
    CHECK(std::abs(st.initial_l2_stretch - st0.l2_stretch) < 1e-6 * st0.l2_stretch);
  }
}

TEST_CASE("generic head: flip-free, better than Tutte, the face gets more space with k = 1.2") {
  GenericHead head;
  REQUIRE(load_generic_head(head).ok());
  UvOptions opt;
  opt.face_vertices = head.annotations.regions.at("face");
  std::vector<Vec2> uv, init, uv_plain;
  UvStats st, st0, plain;
  REQUIRE(parameterize_stretch(head.mesh, opt, uv, st).ok());
  check_chart(head.mesh, uv);
  CHECK(st.flipped == 0);
  REQUIRE(parameterize_tutte(head.mesh, opt, init).ok());
  REQUIRE(measure_stretch(head.mesh, init, opt, st0).ok());
  CHECK(st.l2_stretch < 0.9 * st0.l2_stretch);

  UvOptions unweighted = opt;
  unweighted.k = 1e6;  // w(T) ~ 1/k for every triangle: Sander's plain norm
  REQUIRE(parameterize_stretch(head.mesh, unweighted, uv_plain, plain).ok());
  CHECK(plain.flipped == 0);
  WARN("generic head: Tutte L2 " << st0.l2_stretch << "; k=1.2: L2 " << st.l2_stretch << " Linf "
       << st.linf_stretch << " face texture share " << st.face_texture_share << " (3-D share "
       << st.face_area_share << "); k=1e6: L2 " << plain.l2_stretch << " face share "
       << plain.face_texture_share);
  CHECK(st.face_texture_share > plain.face_texture_share + 0.02);  // measured 0.283 vs 0.248
  CHECK(st.face_texture_share > st.face_area_share);
}

TEST_CASE("parameterization refuses what is not a disk") {
  UvOptions opt;
  std::vector<Vec2> uv;
  UvStats st;
  // A closed tetrahedron: no boundary.
  TriMesh tet;
  tet.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};
  tet.triangles = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};
  Status s = parameterize_stretch(tet, opt, uv, st);
  CHECK(s.code == ErrorCode::InvalidInput);
  CHECK(s.message.find("boundary loop") != std::string::npos);

  TriMesh flat = grid(3, [](double u, double v) { return Vec3(u, v, 0); });
  flat.positions[5].x() = std::nan("");
  s = parameterize_stretch(flat, opt, uv, st);
  CHECK(s.code == ErrorCode::InvalidInput);
  CHECK(s.message.find("NaN") != std::string::npos);

  TriMesh empty;
  CHECK(parameterize_stretch(empty, opt, uv, st).code == ErrorCode::Empty);

  opt.k = 0.5;
  CHECK(parameterize_stretch(grid(3, [](double u, double v) { return Vec3(u, v, 0); }), opt, uv, st).code ==
        ErrorCode::InvalidInput);
}

TEST_CASE("parameterization stops when the progress callback cancels") {
  const TriMesh flat = grid(8, [](double u, double v) { return Vec3(u, v, 0); });
  std::vector<Vec2> uv;
  UvStats st;
  int calls = 0;
  const Status s = parameterize_stretch(flat, UvOptions{}, uv, st, [&](const char*, double) { return ++calls < 3; });
  CHECK(s.code == ErrorCode::Cancelled);
  CHECK(calls == 3);
}
