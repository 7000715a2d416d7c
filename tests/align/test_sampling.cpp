// Portable subsets and stratified samples (common/sampling.h), used by the
// face alignment: fixed bits for a fixed seed (the same natively and in
// wasm), unbiased draws, and an even cover of a surface.
#include "common/sampling.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <numeric>
#include <set>

using namespace lk;

TEST_CASE("SplitMix64 and portable_shuffle give fixed results for a seed") {
  // splitmix64's published first output for state 0 (Vigna's reference code).
  SplitMix64 zero(0);
  CHECK(zero.next() == 0xE220A8397B1DCDAFull);
  // A shuffle is a permutation, and the same one for the same seed.
  std::vector<int> a(50), b(50);
  std::iota(a.begin(), a.end(), 0);
  std::iota(b.begin(), b.end(), 0);
  SplitMix64 ra(7), rb(7);
  portable_shuffle(a.begin(), a.end(), ra);
  portable_shuffle(b.begin(), b.end(), rb);
  CHECK(a == b);
  CHECK(std::set<int>(a.begin(), a.end()).size() == 50);
  std::vector<int> identity(50);
  std::iota(identity.begin(), identity.end(), 0);
  CHECK(a != identity);
  // Unbiased: each of 3 values about a third of 30,000 draws (a 2^64 % 3
  // bias would be invisible; a broken reduction such as next() & 1 is not).
  SplitMix64 r(11);
  int counts[3] = {0, 0, 0};
  for (int i = 0; i < 30000; ++i) ++counts[r.below(3)];
  for (int c : counts) CHECK(std::abs(c - 10000) < 400);
  // Every position reachable: element 0 ends in each of 4 slots.
  std::set<int> where;
  for (std::uint64_t seed = 0; seed < 64; ++seed) {
    std::vector<int> v = {0, 1, 2, 3};
    SplitMix64 rs(seed);
    portable_shuffle(v.begin(), v.end(), rs);
    where.insert(static_cast<int>(std::find(v.begin(), v.end(), 0) - v.begin()));
  }
  CHECK(where.size() == 4);
}

TEST_CASE("stratified_sample covers a surface evenly, whatever its density") {
  // A unit square in z = 0 sampled 40x more densely on its left tenth:
  // half the points lie in x < 0.1.
  std::vector<Vec3> points;
  SplitMix64 r(3);
  const auto u = [&] { return double(r.next() >> 11) / 9007199254740992.0; };
  for (int i = 0; i < 20000; ++i) points.emplace_back(0.1 * u(), u(), 0);
  for (int i = 0; i < 20000; ++i) points.emplace_back(0.1 + 0.9 * u(), u(), 0);
  const std::vector<int> s = stratified_sample(points, 1000, 5);
  INFO("samples " << s.size());
  CHECK(s.size() > 900);
  CHECK(s.size() < 1100);
  CHECK(std::set<int>(s.begin(), s.end()).size() == s.size());
  int left = 0;
  for (int i : s) {
    REQUIRE(i >= 0);
    REQUIRE(i < static_cast<int>(points.size()));
    left += points[i].x() < 0.1;
  }
  // A random subset would put half its samples in the left tenth; an even
  // cover about a tenth.
  CHECK(left < 0.15 * s.size());
  // Every point is near a sample: no more than about a cell's diagonal (a
  // cell is about 1/sqrt(1000) wide).
  double worst = 0;
  for (size_t p = 0; p < points.size(); p += 37) {
    double nearest = 1e300;
    for (int i : s) nearest = std::min(nearest, (points[i] - points[p]).norm());
    worst = std::max(worst, nearest);
  }
  CHECK(worst < 2.5 / std::sqrt(1000.0));
  // Deterministic; another seed picks other points of the same cells.
  CHECK(stratified_sample(points, 1000, 5) == s);
  const std::vector<int> other = stratified_sample(points, 1000, 6);
  CHECK(other.size() == s.size());
  CHECK(other != s);
  // Few points: all of them.
  const std::vector<Vec3> few(points.begin(), points.begin() + 10);
  CHECK(stratified_sample(few, 1000, 5) == std::vector<int>({0, 1, 2, 3, 4, 5, 6, 7, 8, 9}));
}

TEST_CASE("mt19937_shuffle is libstdc++'s std::shuffle") {
  // Written out so that libc++ (the wasm build) draws the same subsets as
  // the native build; checked here where the native library is libstdc++.
  for (int n : {1, 2, 3, 10, 11, 600, 5001, 70000}) {
    std::vector<int> ours(n);
    std::iota(ours.begin(), ours.end(), 0);
    std::vector<int> theirs = ours;
    std::mt19937 a(7u + n), b(7u + n);
    mt19937_shuffle(ours.begin(), ours.end(), a);
#ifdef __GLIBCXX__
    std::shuffle(theirs.begin(), theirs.end(), b);
    INFO("n " << n);
    CHECK(ours == theirs);
    CHECK(a() == b());  // the same number of draws
#else
    CHECK(std::set<int>(ours.begin(), ours.end()).size() == static_cast<size_t>(n));
#endif
  }
}
