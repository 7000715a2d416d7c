// likeness bench --only parallel: what one parallel_for costs beyond its
// items (core/common/parallel.h starts and joins its threads per loop),
// against the serial loop, for loops of 256 to 16k small items; then how
// many multi-threaded loops a seed-1 fit runs (300k-point synthetic scan),
// which times the per-loop cost is what starting threads costs a fit
// (docs/journal.md, "What one parallel loop costs": about 30 loops, so well under 1 %).
// --quick: fewer repetitions, no fit.
#include "command.h"
#include "timing.h"

#include "common/parallel.h"
#include "head/generic_head.h"
#include "pipeline/fit_head.h"
#include "synthetic_scan.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

namespace lk::cli {
namespace {

// A few hundred flops per item, written to the item's own slot (like the
// fit's per-point loops, only cheaper, so the loop's fixed cost shows).
struct Work {
  std::vector<double> out;
  explicit Work(int n) : out(n) {}
  void item(int i) {
    double x = i * 1e-3;
    for (int k = 0; k < 32; ++k) x = std::sin(x) + 0.5 * x;
    out[i] = x;
  }
};

void row(const char* what, int loops, double wall_ms, double cpu_ms, double serial_wall_ms) {
  std::printf("   %-42s %9.2f us wall %9.2f us CPU per loop; %+8.2f us wall vs serial\n", what, 1e3 * wall_ms / loops,
              1e3 * cpu_ms / loops, 1e3 * (wall_ms - serial_wall_ms) / loops);
}

int run(const Args& args) {
  const bool quick = args.has("quick");
  std::string load = "?";
  std::ifstream("/proc/loadavg") >> load;
  std::printf("   %d threads per loop (load average %s: the wall figures include waiting for busy cores)\n",
              parallel_workers(), load.c_str());
  const int reps = quick ? 1 : 3;
  for (const int items : {256, 2048, 16384}) {
    const int loops = std::max(50, 400000 / items);
    Work work(items);
    std::printf("   %d loops of %d items (grain 64):\n", loops, items);
    bool ok = true;
    const Timing serial = median_ms(reps, [&] {
      for (int l = 0; l < loops; ++l)
        for (int i = 0; i < items; ++i) work.item(i);
      return true;
    }, ok);
    const Timing parallel = median_ms(reps, [&] {
      for (int l = 0; l < loops; ++l) parallel_for(0, items, 64, [&](int i, int) { work.item(i); });
      return true;
    }, ok);
    row("serial", loops, serial.wall_ms, serial.cpu_ms, serial.wall_ms);
    row("parallel_for", loops, parallel.wall_ms, parallel.cpu_ms, serial.wall_ms);
  }
  if (quick) return 0;

  GenericHead generic;
  Status st = load_generic_head(generic);
  SyntheticScan data;
  if (st) st = make_synthetic_scan(generic, 1, 300000, data);
  const PointCloud& cloud = data.cloud;
  if (!st) {
    std::printf("   seed-1 scan failed: %s\n", st.message.c_str());
    return 1;
  }
  FitHeadResult r;
  const long loops_before = parallel_loops_run().load();
  bool ok = true;
  const Timing fit = median_ms(1, [&] { return fit_head(cloud, generic, FitHeadOptions{}, r, FitStageObserver{}).ok(); }, ok);
  const long loops = parallel_loops_run().load() - loops_before;
  std::printf("   seed-1 fit (300k points): %ld multi-threaded parallel_for loops, fit %.0f ms wall %.0f ms CPU%s\n", loops,
              fit.wall_ms, fit.cpu_ms, ok ? "" : " (FAILED)");
  return ok ? 0 : 1;
}

BenchRegistrar reg({"parallel", "parallel_for's cost per loop (threads started and joined) and loops per seed-1 fit", run});

}  // namespace
}  // namespace lk::cli
