// Timing helpers for the benchmark sections (harness only: core has no clocks).
#pragma once
#include <algorithm>
#include <chrono>
#include <ctime>
#include <functional>
#include <vector>

namespace lk::cli {

// Clock readings in milliseconds: CPU time of the process (the harness is
// single-threaded) and monotonic wall time.
inline double cpu_clock_ms() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return 1e3 * static_cast<double>(ts.tv_sec) + 1e-6 * static_cast<double>(ts.tv_nsec);
}
inline double wall_clock_ms() {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// Medians over repeated runs; CPU time is steadier than wall time on a busy machine.
struct Timing {
  double wall_ms = 0, cpu_ms = 0;
};

// Runs f reps times (reps >= 1); ok becomes false if any run returned false.
inline Timing median_ms(int reps, const std::function<bool()>& f, bool& ok) {
  std::vector<double> wall, cpu;
  ok = true;
  for (int i = 0; i < std::max(1, reps); ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    const std::clock_t c0 = std::clock();
    ok = f() && ok;
    cpu.push_back(1000.0 * double(std::clock() - c0) / CLOCKS_PER_SEC);
    wall.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  std::sort(wall.begin(), wall.end());
  std::sort(cpu.begin(), cpu.end());
  return {wall[wall.size() / 2], cpu[cpu.size() / 2]};
}

// Median CPU time (ms) of reps runs of f (at least one run). The build
// machine is shared (the benches print its load average), so wall time
// would mostly measure the neighbours.
inline double median_cpu_ms(int reps, const std::function<void()>& f) {
  std::vector<double> t;
  for (int i = 0; i < std::max(1, reps); ++i) {
    const double t0 = cpu_clock_ms();
    f();
    t.push_back(cpu_clock_ms() - t0);
  }
  std::sort(t.begin(), t.end());
  return t[t.size() / 2];
}

}  // namespace lk::cli
