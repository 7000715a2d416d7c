// core/common/parallel.h: parallel_for. Every item runs exactly once, a
// worker index is never used by two threads at once, thousands of short
// back-to-back loops lose and repeat nothing and are counted, and loops
// nested in a body or started from two threads at once run every item.
// HelperThread (common/helper_thread.h) runs both parts of every job.
#include <catch2/catch.hpp>

#include "common/helper_thread.h"
#include "common/parallel.h"

#include <atomic>
#include <functional>
#include <memory>
#include <thread>
#include <vector>

namespace {

// Runs one loop and checks it: each item once, worker indices in range and
// never held by two threads at the same time.
bool check_loop(int begin, int end, int grain) {
  const int workers = lk::parallel_workers();
  std::vector<std::atomic<int>> visits(static_cast<size_t>(std::max(0, end - begin)));
  std::unique_ptr<std::atomic<int>[]> holding(new std::atomic<int>[workers]);
  for (int w = 0; w < workers; ++w) holding[w] = 0;
  std::atomic<int> bad{0};
  lk::parallel_for(begin, end, grain, [&](int i, int worker) {
    if (worker < 0 || worker >= workers || i < begin || i >= end) {
      ++bad;
      return;
    }
    if (holding[worker].fetch_add(1) != 0) ++bad;  // another thread has this worker index now
    ++visits[i - begin];
    holding[worker].fetch_sub(1);
  });
  bool ok = bad == 0;
  for (const auto& v : visits) ok = ok && v == 1;
  return ok;
}

}  // namespace

TEST_CASE("parallel_for: every item exactly once, worker indices exclusive", "[parallel]") {
  for (const int n : {0, 1, 7, 64, 1000, 4099, 100000})
    for (const int grain : {1, 3, 64, 1024}) {
      INFO("n " << n << ", grain " << grain);
      CHECK(check_loop(0, n, grain));
      CHECK(check_loop(5, 5 + n, grain));
    }
}

TEST_CASE("parallel_for: back-to-back short loops lose and repeat nothing, and are counted", "[parallel]") {
  const long loops_before = lk::parallel_loops_run().load();
  std::vector<int> counts(512, 0);
  const int kLoops = 2000;
  for (int l = 0; l < kLoops; ++l) lk::parallel_for(0, 512, 16, [&](int i, int) { ++counts[i]; });
  bool all = true;
  for (int c : counts) all = all && c == kLoops;
  CHECK(all);
  // Loops that can use more than one thread are counted (bench --only
  // parallel multiplies the count by the per-loop cost); one block is not.
  lk::parallel_for(0, 10, 16, [&](int i, int) { ++counts[i]; });
  const long counted = lk::parallel_loops_run().load() - loops_before;
  CHECK(counted == (lk::parallel_workers() > 1 ? kLoops : 0));
}

TEST_CASE("parallel_for: a loop nested in a body runs all its items", "[parallel]") {
  const int outer = 40, inner = 300;
  std::vector<std::atomic<int>> visits(outer * inner);
  lk::parallel_for(0, outer, 1, [&](int o, int) {
    lk::parallel_for(0, inner, 8, [&](int i, int) { ++visits[o * inner + i]; });
  });
  bool all = true;
  for (const auto& v : visits) all = all && v == 1;
  CHECK(all);
}

TEST_CASE("parallel_for: loops started from two threads at once both complete", "[parallel]") {
  std::vector<int> a(20000, 0), b(20000, 0);
  std::thread other([&] {
    for (int l = 0; l < 100; ++l) lk::parallel_for(0, 20000, 256, [&](int i, int) { ++b[i]; });
  });
  for (int l = 0; l < 100; ++l) lk::parallel_for(0, 20000, 256, [&](int i, int) { ++a[i]; });
  other.join();
  bool all = true;
  for (int i = 0; i < 20000; ++i) all = all && a[i] == 100 && b[i] == 100;
  CHECK(all);
}

TEST_CASE("parallel_for: a reduction in item order is the serial one, bit for bit", "[parallel]") {
  std::vector<double> x(100000);
  lk::parallel_for(0, 100000, 128, [&](int i, int) { x[i] = 1.0 / (1.0 + i) * (i % 3 ? 1 : -1); });
  double parallel_sum = 0, serial_sum = 0;
  for (double v : x) parallel_sum += v;
  for (int i = 0; i < 100000; ++i) serial_sum += 1.0 / (1.0 + i) * (i % 3 ? 1 : -1);
  CHECK(parallel_sum == serial_sum);
}


TEST_CASE("HelperThread: every job runs both parts once, many jobs in a row", "[parallel]") {
  lk::HelperThread helper;
  CHECK(helper.threaded() == (lk::parallel_workers() > 1));
  // Short jobs back to back (the alignment's evaluations): each part sees
  // the data the caller wrote before run(), and the caller sees both parts'
  // results after it.
  std::vector<long> input(2), output(2);
  std::atomic<int> bad{0};
  const std::thread::id caller = std::this_thread::get_id();
  const std::function<void(int)> job = [&](int part) {
    if (part < 0 || part > 1) ++bad;
    if (part == 0 && std::this_thread::get_id() != caller) ++bad;  // part 0 runs on the caller
    if (helper.threaded() && part == 1 && std::this_thread::get_id() == caller) ++bad;
    output[part] = 3 * input[part] + part;
  };
  long sum = 0;
  for (long k = 0; k < 5000; ++k) {
    input[0] = k;
    input[1] = 2 * k;
    helper.run(job);
    if (output[0] != 3 * k || output[1] != 6 * k + 1) ++bad;
    sum += output[0] + output[1];
  }
  CHECK(bad == 0);
  CHECK(sum == 9L * (4999L * 5000L / 2) + 5000L);
}

TEST_CASE("HelperThread: made and dropped many times, never hangs", "[parallel]") {
  int total = 0;
  for (int k = 0; k < 200; ++k) {
    lk::HelperThread helper;  // (destroyed with and without a job run)
    int parts[2] = {0, 0};
    if (k % 2) helper.run([&](int part) { parts[part] = 1; });
    total += parts[0] + parts[1];
  }
  CHECK(total == 200);
}
