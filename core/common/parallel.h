// A minimal parallel loop for independent per-item work (closest points,
// per-vertex displacement measurements). Items are handed out in blocks from
// a shared counter, so uneven work balances; each item must write only its
// own outputs, and any reduction is done afterwards in item order, so results
// do not depend on the number of threads. Native builds use std::thread; with
// LK_SINGLE_THREADED (the wasm build) everything runs on the calling thread.
#pragma once
#include <algorithm>
#include <atomic>
#include <thread>
#include <vector>

namespace lk {

// Threads a loop may use (1 when single-threaded).
inline int parallel_workers() {
#ifdef LK_SINGLE_THREADED
  return 1;
#else
  const unsigned n = std::thread::hardware_concurrency();
  return n == 0 ? 1 : static_cast<int>(std::min(n, 8u));
#endif
}

// Calls body(i, worker) for every i in [begin, end), worker in
// [0, parallel_workers()), in blocks of `grain` items; a worker index is used
// by one thread at a time (per-worker scratch). Loops shorter than two blocks
// run on the calling thread.
template <class Body>
void parallel_for(int begin, int end, int grain, const Body& body) {
  grain = std::max(1, grain);
  const int n = end - begin;
  const int workers = std::min(parallel_workers(), n / grain);
  if (workers <= 1) {
    for (int i = begin; i < end; ++i) body(i, 0);
    return;
  }
#ifndef LK_SINGLE_THREADED  // (single-threaded: parallel_workers() is 1, the loop above ran)
  std::atomic<int> next{begin};
  auto run = [&](int worker) {
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
