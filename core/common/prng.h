// A small deterministic PRNG: splitmix64 (Steele, Lea, Flood 2014), for
// synthetic data and for the fit's portable samples (common/sampling.h).
// The standard distributions (std::normal_distribution, ...) give different
// numbers under libstdc++ and emscripten's libc++, and libm's log/cos may
// differ in the last bit, so everything here uses only integer ops and
// +,-,*,/ : the same seed yields the same bits natively and in wasm.
#pragma once
#include <cstdint>

namespace lk {

struct SplitMix64 {
  std::uint64_t state = 0;

  explicit SplitMix64(std::uint64_t seed) : state(seed) {}

  std::uint64_t next() {
    std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  // Uniform in [0, n), n >= 1, without modulo bias (rejection of the
  // incomplete last block of 2^64).
  std::uint64_t below(std::uint64_t n) {
    const std::uint64_t limit = ~std::uint64_t(0) - (~std::uint64_t(0) % n);
    std::uint64_t r = next();
    while (r >= limit) r = next();
    return r % n;
  }
  // Uniform in [0, 1) with 53 random bits.
  double uniform01() { return static_cast<double>(next() >> 11) * (1.0 / 9007199254740992.0); }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform01(); }
  // Bell-shaped in [-1, 1]: the mean of three uniforms (variance 1/9).
  double bell() { return (uniform(-1, 1) + uniform(-1, 1) + uniform(-1, 1)) / 3.0; }
  // Approximately standard normal (Irwin-Hall: sum of 12 uniforms - 6), in
  // [-6, 6]; close enough for sensor noise and free of libm.
  double gaussian() {
    double s = 0;
    for (int i = 0; i < 12; ++i) s += uniform01();
    return s - 6.0;
  }
};

// A stateless hash of a few integers (for lattice noise and per-item streams).
inline std::uint64_t hash_mix(std::uint64_t a, std::uint64_t b = 0, std::uint64_t c = 0,
                              std::uint64_t d = 0) {
  SplitMix64 r(a * 0x9E3779B97F4A7C15ull ^ (b + 0x632BE59BD9B4E019ull) * 0xC2B2AE3D27D4EB4Full ^
               (c + 0x85EBCA77C2B2AE63ull) * 0x165667B19E3779F9ull ^ (d + 0x27D4EB2F165667C5ull));
  r.next();
  return r.next();
}

}  // namespace lk
