// The sparse LM's steps solved by conjugate gradients preconditioned with an
// earlier factorization (sparse_lm.h) reach the same minimum as factoring
// every step, with fewer factorizations; so do steps factored by vertex
// blocks.
#include "photos/sparse_lm.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <random>

namespace lk {
namespace {

// A sheet of n x n points in space pulled by springs (residual: length -
// rest, a nonlinear function of the positions) towards rest lengths 1.1
// times the start's, every point tied to its start by a tether (residual
// 0.1 (x - start) in the sheet's plane, 1.0 across it, so that it stretches
// and does not buckle): a sparse normal matrix of 3x3 vertex blocks like
// the shape fit's. blocks: factored by blocks (vertex_blocks()).
class SpringSheet : public LeastSquaresProblem {
 public:
  Eigen::VectorXd x, start, tether;  // x, y, z per point
  std::vector<std::array<int, 2>> springs;
  std::vector<double> rest;
  bool blocks = false;
  explicit SpringSheet(int n) : x(3 * n * n), tether(3 * n * n) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> jitter(-0.05, 0.05);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        x.segment<3>(3 * (i * n + j)) = Eigen::Vector3d(i + jitter(rng), j + jitter(rng), jitter(rng));
        tether.segment<3>(3 * (i * n + j)) = Eigen::Vector3d(0.1, 0.1, 1.0);
      }
    start = x;
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        const int a = i * n + j;
        if (j + 1 < n) springs.push_back({a, a + 1});
        if (i + 1 < n) springs.push_back({a, a + n});
        if (i + 1 < n && j + 1 < n) springs.push_back({a, a + n + 1});
      }
    for (const auto& s : springs) rest.push_back(1.1 * (x.segment<3>(3 * s[0]) - x.segment<3>(3 * s[1])).norm());
  }
  Eigen::VectorXd residual(const Eigen::VectorXd& p) const {
    Eigen::VectorXd r(long(springs.size()) + p.size());
    for (size_t k = 0; k < springs.size(); ++k)
      r[long(k)] = (p.segment<3>(3 * springs[k][0]) - p.segment<3>(3 * springs[k][1])).norm() - rest[k];
    r.tail(p.size()) = tether.cwiseProduct(p - start);
    return r;
  }
  int num_parameters() const override { return int(x.size()); }
  bool vertex_blocks() const override { return blocks; }
  void linearize(Eigen::VectorXd& r, SparseMat& J) override {
    r = residual(x);
    std::vector<Eigen::Triplet<double>> t;
    for (size_t k = 0; k < springs.size(); ++k) {
      const Eigen::Vector3d d = x.segment<3>(3 * springs[k][0]) - x.segment<3>(3 * springs[k][1]);
      const Eigen::Vector3d u = d / d.norm();
      for (int c = 0; c < 3; ++c) {
        t.emplace_back(int(k), 3 * springs[k][0] + c, u[c]);
        t.emplace_back(int(k), 3 * springs[k][1] + c, -u[c]);
      }
    }
    for (int k = 0; k < int(x.size()); ++k) t.emplace_back(int(springs.size()) + k, k, tether[k]);
    J.resize(long(springs.size()) + x.size(), x.size());
    J.setFromTriplets(t.begin(), t.end());
  }
  double cost_after(const Eigen::VectorXd& step) override { return residual(x + step).squaredNorm(); }
  void apply(const Eigen::VectorXd& step) override { x += step; }
};

TEST_CASE("sparse LM: steps by preconditioned conjugate gradients reach the factored steps' minimum", "[photos]") {
  SpringSheet direct(20), with_cg(20);
  LmOptions o;
  o.relative_tolerance = 1e-10;
  o.cg_max_iterations = 0;  // every step factored
  const LmReport a = levenberg_marquardt(direct, o);
  o.cg_max_iterations = 40;
  const LmReport b = levenberg_marquardt(with_cg, o);
  INFO("factored: " << a.iterations << " steps, " << a.factorizations << " factorizations; with CG: " << b.iterations
                    << " steps, " << b.factorizations << " factorizations, " << b.cg_solves << " CG solves");
  REQUIRE(a.iterations > 3);
  CHECK(a.cg_solves == 0);
  CHECK(a.factorizations >= a.iterations);
  CHECK(b.cg_solves > 0);
  CHECK(b.factorizations < a.factorizations);
  CHECK(a.iterations < o.max_iterations);  // converged, both
  CHECK(b.iterations < o.max_iterations);
  CHECK(b.final_cost < 0.75 * b.initial_cost);
  CHECK(b.final_cost == Approx(a.final_cost).epsilon(1e-6).margin(1e-12));
  CHECK((direct.x - with_cg.x).cwiseAbs().maxCoeff() < 1e-5);
}

TEST_CASE("sparse LM: steps factored by 3x3 vertex blocks reach the scalar factor's minimum", "[photos]") {
  SpringSheet scalar(20), blocks(20);
  blocks.blocks = true;
  LmOptions o;
  o.relative_tolerance = 1e-10;
  for (int cg : {0, 40}) {
    o.cg_max_iterations = cg;
    SpringSheet a = scalar, b = blocks;
    const LmReport ra = levenberg_marquardt(a, o), rb = levenberg_marquardt(b, o);
    INFO("CG up to " << cg << " iterations: " << ra.iterations << " and " << rb.iterations << " steps");
    REQUIRE(ra.iterations > 3);
    CHECK(!ra.vertex_blocks);
    CHECK(rb.vertex_blocks);
    CHECK(rb.iterations < o.max_iterations);
    CHECK(rb.final_cost == Approx(ra.final_cost).epsilon(1e-9).margin(1e-12));
    CHECK((a.x - b.x).cwiseAbs().maxCoeff() < 1e-6);
  }
}

}  // namespace
}  // namespace lk
