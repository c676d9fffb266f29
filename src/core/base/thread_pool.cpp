#include "implicit_sim/core/base/thread_pool.h"

#include <algorithm>

namespace implicit_sim {

ThreadPool::ThreadPool(int threads) {
  for (int i = 1; i < threads; ++i) workers_.emplace_back([this] { WorkerLoop(); });
}

ThreadPool::~ThreadPool() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  work_ready_.notify_all();
  for (std::thread& worker : workers_) worker.join();
}

void ThreadPool::RunIndices() {
  for (int i = next_index_.fetch_add(1); i < n_; i = next_index_.fetch_add(1)) {
    try {
      task_(context_, i);
    } catch (...) {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!error_) error_ = std::current_exception();
    }
  }
}

void ThreadPool::WorkerLoop() {
  long seen = 0;
  for (;;) {
    {
      std::unique_lock<std::mutex> lock(mutex_);
      work_ready_.wait(lock, [&] { return stopping_ || generation_ != seen; });
      if (stopping_) return;
      seen = generation_;
      ++busy_workers_;
    }
    RunIndices();
    {
      std::lock_guard<std::mutex> lock(mutex_);
      --busy_workers_;
    }
    work_done_.notify_all();
  }
}

void ThreadPool::Run(int n, void (*task)(void*, int), void* context) {
  if (workers_.empty() || n <= 1) {
    for (int i = 0; i < n; ++i) task(context, i);
    return;
  }
  {
    // A worker that woke late for the previous loop may still be looking for an index: let it finish first.
    std::unique_lock<std::mutex> lock(mutex_);
    work_done_.wait(lock, [&] { return busy_workers_ == 0; });
    n_ = n;
    task_ = task;
    context_ = context;
    next_index_.store(0);
    error_ = nullptr;
    ++generation_;
  }
  work_ready_.notify_all();
  RunIndices();
  std::exception_ptr error;
  {
    // Every index has been taken; wait for the workers still running theirs (and for those that woke late, which
    // find no index left).
    std::unique_lock<std::mutex> lock(mutex_);
    work_done_.wait(lock, [&] { return busy_workers_ == 0; });
    std::swap(error, error_);
  }
  if (error) std::rethrow_exception(error);
}

int ResolveThreadCount(int threads) {
  if (threads > 0) return threads;
  // Asked once: glibc reads /sys on every call (three system calls), which was a tenth of a small scene's step.
  static const int kHardwareThreads = std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  return kHardwareThreads;
}

}  // namespace implicit_sim
