// One helper thread for many short jobs in a row: started once, parked
// between jobs, so each job costs a wake-up and a join instead of a thread
// start (parallel_for starts its threads per loop, ~25 us natively and
// ~0.2 ms in the threaded wasm build, more than a silhouette evaluation of
// the initial alignment gains by running on two threads).
//
// run(job) calls job(0) on the calling thread and job(1) on the helper, and
// returns when both are done. Without a second thread (one worker,
// LK_SINGLE_THREADED, or inside another loop of the threaded wasm build)
// both parts run on the calling thread, one after the other: results never
// depend on the threads. The helper holds a thread of the wasm pool while it
// lives, so keep no parallel_for running beside it there (the pool is sized
// for one level of loops).
#pragma once
#include "common/parallel.h"

#include <condition_variable>
#include <functional>
#include <mutex>
#include <thread>

namespace lk {

class HelperThread {
 public:
  HelperThread() {
#ifndef LK_SINGLE_THREADED
    bool nested = false;
#ifdef LK_MAX_WORKERS
    nested = parallel_for_running_here();
#endif
    if (parallel_workers() > 1 && !nested) helper_ = std::thread([this] { serve(); });
#endif
  }
  ~HelperThread() {
#ifndef LK_SINGLE_THREADED
    if (helper_.joinable()) {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        stop_ = true;
      }
      wake_.notify_one();
      helper_.join();
    }
#endif
  }
  HelperThread(const HelperThread&) = delete;
  HelperThread& operator=(const HelperThread&) = delete;

  bool threaded() const {
#ifndef LK_SINGLE_THREADED
    return helper_.joinable();
#else
    return false;
#endif
  }

  void run(const std::function<void(int)>& job) {
#ifndef LK_SINGLE_THREADED
    if (helper_.joinable()) {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        job_ = &job;
        ++posted_;
      }
      wake_.notify_one();
      job(0);
      std::unique_lock<std::mutex> lock(mutex_);
      done_.wait(lock, [&] { return finished_ == posted_; });
      job_ = nullptr;
      return;
    }
#endif
    job(0);
    job(1);
  }

 private:
#ifndef LK_SINGLE_THREADED
  void serve() {
    long seen = 0;
    for (;;) {
      const std::function<void(int)>* job = nullptr;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        wake_.wait(lock, [&] { return stop_ || posted_ != seen; });
        if (stop_) return;
        seen = posted_;
        job = job_;
      }
      (*job)(1);
      {
        std::lock_guard<std::mutex> lock(mutex_);
        finished_ = seen;
      }
      done_.notify_one();
    }
  }

  std::thread helper_;
  std::mutex mutex_;
  std::condition_variable wake_, done_;
  const std::function<void(int)>* job_ = nullptr;
  long posted_ = 0, finished_ = 0;
  bool stop_ = false;
#endif
};

}  // namespace lk
