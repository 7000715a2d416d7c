// A minimal parallel loop for independent per-item work (closest points,
// per-vertex displacement measurements). Items are handed out in blocks from
// a shared counter, so uneven work balances; each item must write only its
// own outputs, and any reduction is done afterwards in item order, so results
// do not depend on the number of threads. Native builds use std::thread; with
// LK_SINGLE_THREADED (the wasm build) everything runs on the calling thread;
// the threaded wasm build (LK_WASM_THREADS) uses Emscripten pthreads, at most
// LK_MAX_WORKERS of them.
#pragma once
#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <thread>
#include <vector>

namespace lk {

// Native runs: the environment variable LK_THREADS=N (N >= 1) sets the
// number of threads, e.g. LK_THREADS=1 times natively what the
// single-threaded wasm build does. Read once; 0 when unset or invalid.
inline int parallel_workers_from_environment() {
  static const int workers = [] {
    const char* value = std::getenv("LK_THREADS");
    const int n = value ? std::atoi(value) : 0;
    return n >= 1 ? n : 0;
  }();
  return workers;
}

// Threads a loop may use (1 when single-threaded).
inline int parallel_workers() {
#ifdef LK_SINGLE_THREADED
  return 1;
#else
#ifndef LK_MAX_WORKERS  // (a threaded wasm build has no more threads than its pool)
  if (const int asked = parallel_workers_from_environment()) return asked;
#endif
  const unsigned n = std::thread::hardware_concurrency();
#ifdef LK_MAX_WORKERS  // threaded wasm: no more threads than its pre-made pthread pool + the caller
  const unsigned cap = LK_MAX_WORKERS;
#else
  const unsigned cap = 8u;
#endif
  return n == 0 ? 1 : static_cast<int>(std::min(n, cap));
#endif
}

// How many parallel_for calls this process made that could use more than
// one thread (a measurement for the benchmarks: each wakes the threads once,
// so this times the per-loop cost is what starting them costs a whole job;
// a seed-1 fit makes about 30, docs/journal.md "What one parallel loop costs").
inline std::atomic<long>& parallel_loops_run() {
  static std::atomic<long> loops{0};
  return loops;
}

#ifdef LK_MAX_WORKERS
// Threaded wasm only: true while this thread runs a parallel_for's items. A
// loop nested in one then runs on its thread: a pthread cannot start another
// while the pool's owner is blocked joining it, and the pool is sized for one
// level of loops. (Native builds nest freely.) Results are the same either way.
inline bool& parallel_for_running_here() {
  static thread_local bool running = false;
  return running;
}
#endif

// Calls body(i, worker) for every i in [begin, end), worker in
// [0, parallel_workers()), in blocks of `grain` items; a worker index is used
// by one thread at a time (per-worker scratch). Loops shorter than two blocks
// run on the calling thread.
template <class Body>
void parallel_for(int begin, int end, int grain, const Body& body) {
  grain = std::max(1, grain);
  const int n = end - begin;
  const int workers = std::min(parallel_workers(), n / grain);
#ifdef LK_MAX_WORKERS
  if (workers > 1 && parallel_for_running_here()) {
    for (int i = begin; i < end; ++i) body(i, 0);
    return;
  }
#endif
  if (workers <= 1) {
    for (int i = begin; i < end; ++i) body(i, 0);
    return;
  }
#ifndef LK_SINGLE_THREADED  // (single-threaded: parallel_workers() is 1, the loop above ran)
  parallel_loops_run().fetch_add(1, std::memory_order_relaxed);
  std::atomic<int> next{begin};
  auto run = [&](int worker) {
#ifdef LK_MAX_WORKERS
    const bool was_running = parallel_for_running_here();
    parallel_for_running_here() = true;
    struct Restore {
      bool value;
      ~Restore() { parallel_for_running_here() = value; }
    } restore{was_running};
#endif
    for (;;) {
      const int b = next.fetch_add(grain);
      if (b >= end) return;
      const int e = std::min(end, b + grain);
      for (int i = b; i < e; ++i) body(i, worker);
    }
  };
  std::vector<std::thread> threads;
  threads.reserve(workers - 1);
  for (int w = 1; w < workers; ++w) threads.emplace_back(run, w);
  run(0);
  for (std::thread& t : threads) t.join();
#endif
}

}  // namespace lk
