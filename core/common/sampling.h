// Portable random subsets and stratified (voxel-grid) samples of point sets.
//
// std::shuffle's algorithm and std::uniform_int_distribution are
// implementation-defined: libstdc++ (native) and libc++ (the wasm build) turn
// the same std::mt19937 seed into different subsets, so a fit that samples
// with them differs between the CLI and the page. Everything here uses only
// integer operations and IEEE +,-,*,/ on doubles, so the same seed gives the
// same bits natively and in wasm, on any number of threads.
//
// std::mt19937 itself is fully specified by the standard; what differs is
// how std::shuffle consumes it. mt19937_shuffle below is libstdc++'s
// (GCC 12) std::shuffle written out, so native results stay exactly what
// they were while wasm (libc++) gets the same permutation.
//
// Shapes: points #P by 3; results are indices into points.
#pragma once
#include "common/prng.h"
#include "common/types.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <utility>
#include <vector>

namespace lk {

// Fisher-Yates shuffle of [first, last) with rng: the same order everywhere.
template <class RandomIt>
void portable_shuffle(RandomIt first, RandomIt last, SplitMix64& rng) {
  const auto n = last - first;
  for (auto i = n - 1; i > 0; --i) {
    const auto j = static_cast<decltype(i)>(rng.below(static_cast<std::uint64_t>(i) + 1));
    using std::swap;
    swap(first[i], first[j]);
  }
}

// Uniform in [0, range), 1 <= range < 2^32, from 32-bit draws: libstdc++'s
// uniform_int_distribution for a 32-bit engine (Lemire's nearly
// divisionless method, ACM TOMACS 29(1), 2019).
inline std::uint32_t mt19937_below(std::mt19937& g, std::uint32_t range) {
  std::uint64_t product = std::uint64_t(std::uint32_t(g())) * range;
  std::uint32_t low = std::uint32_t(product);
  if (low < range) {
    const std::uint32_t threshold = std::uint32_t(-range) % range;
    while (low < threshold) {
      product = std::uint64_t(std::uint32_t(g())) * range;
      low = std::uint32_t(product);
    }
  }
  return std::uint32_t(product >> 32);
}

// std::shuffle(first, last, g) as libstdc++ (GCC 12) does it, on any
// standard library: for short ranges two swap positions are drawn from one
// number. Fewer than 2^32 elements. tests/align/test_sampling.cpp checks it
// against std::shuffle when built with libstdc++.
template <class RandomIt>
void mt19937_shuffle(RandomIt first, RandomIt last, std::mt19937& g) {
  using std::swap;
  const std::uint64_t n = static_cast<std::uint64_t>(last - first);
  if (n == 0) return;
  const std::uint64_t engine_range = 0xFFFFFFFFull;
  if (engine_range / n >= n) {
    std::uint64_t i = 1;
    if (n % 2 == 0) {
      swap(first[i], first[mt19937_below(g, 2)]);
      ++i;
    }
    while (i != n) {
      const std::uint64_t swap_range = i + 1;
      const std::uint64_t x = mt19937_below(g, std::uint32_t(swap_range * (swap_range + 1)));
      swap(first[i], first[x / (swap_range + 1)]);
      ++i;
      swap(first[i], first[x % (swap_range + 1)]);
      ++i;
    }
    return;
  }
  for (std::uint64_t i = 1; i != n; ++i) swap(first[i], first[mt19937_below(g, std::uint32_t(i + 1))]);
}

// About `target` indices of points, one per occupied cell of a cubic grid
// whose cell size is chosen so that about `target` cells are occupied (a
// surface sampled evenly, however densely the scanner covered each part);
// which point of a cell is taken depends on seed. All indices, in order,
// when there are no more than target points. Returned in the order of their
// cells (x, then y, then z), independent of the order of equal keys.
inline std::vector<int> stratified_sample(const std::vector<Vec3>& points, int target, std::uint64_t seed) {
  const int n = static_cast<int>(points.size());
  std::vector<int> all(n);
  for (int i = 0; i < n; ++i) all[i] = i;
  if (target <= 0 || n <= target) return all;
  Vec3 lo = points[0], hi = points[0];
  for (const Vec3& p : points) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const Vec3 size = hi - lo;
  const double extent = std::max({size.x(), size.y(), size.z(), 1e-300});
  // (cell key, point) sorted by key then point: cells and their members in a
  // fixed order. Keys pack 21 bits per axis.
  std::vector<std::pair<std::uint64_t, int>> keyed(n);
  const auto bin = [&](double cell) {
    const double cells_per_axis = std::min(2097151.0, std::floor(extent / cell) + 1);
    for (int i = 0; i < n; ++i) {
      std::uint64_t key = 0;
      for (int a = 0; a < 3; ++a) {
        const double c = std::min(cells_per_axis - 1, std::floor((points[i][a] - lo[a]) / cell));
        key = (key << 21) | static_cast<std::uint64_t>(std::max(0.0, c));
      }
      keyed[i] = {key, i};
    }
    std::sort(keyed.begin(), keyed.end());
    int cells = 0;
    for (int i = 0; i < n; ++i) cells += (i == 0 || keyed[i].first != keyed[i - 1].first);
    return cells;
  };
  // A surface occupies about area / cell^2 cells: start from a cell that
  // would give `target` cells on a square of the box's largest side, then
  // correct by the square root of the miss a few times (each step halves the
  // relative error or better; the count need not be exact).
  double cell = extent / std::sqrt(static_cast<double>(target));
  int cells = bin(cell);
  for (int step = 0; step < 6 && std::abs(cells - target) > target / 10; ++step) {
    cell *= std::sqrt(static_cast<double>(cells) / target);
    cells = bin(cell);
  }
  std::vector<int> out;
  out.reserve(cells);
  SplitMix64 rng(seed);
  for (int begin = 0; begin < n;) {
    int end = begin + 1;
    while (end < n && keyed[end].first == keyed[begin].first) ++end;
    out.push_back(keyed[begin + static_cast<int>(rng.below(static_cast<std::uint64_t>(end - begin)))].second);
    begin = end;
  }
  return out;
}

}  // namespace lk
