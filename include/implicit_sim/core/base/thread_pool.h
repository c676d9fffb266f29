// A fixed set of worker threads that run the indices of a loop (the step's islands, step/islands.h). Which thread runs
// which index must not matter to the results: each index owns the data it writes.
#pragma once

#include <atomic>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace implicit_sim {

class ThreadPool {
 public:
  // threads >= 1: the caller of Run is one of them, so threads - 1 workers are started.
  explicit ThreadPool(int threads);
  ~ThreadPool();
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;
  int threads() const { return static_cast<int>(workers_.size()) + 1; }
  // Calls task(context, i) once for every i in [0, n) on the pool's threads and returns when all calls have returned.
  // An exception thrown by a call is rethrown here (the first one caught) after the others finished. Allocates
  // nothing unless a call throws.
  void Run(int n, void (*task)(void* context, int index), void* context);

 private:
  void WorkerLoop();
  void RunIndices();  // takes indices until none is left
  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable work_ready_, work_done_;
  long generation_ = 0;  // incremented by every Run
  bool stopping_ = false;
  int busy_workers_ = 0;
  // The loop in progress.
  int n_ = 0;
  void (*task_)(void*, int) = nullptr;
  void* context_ = nullptr;
  std::atomic<int> next_index_{0};
  std::exception_ptr error_;
};

// The number of threads for a `threads` option: itself when positive; 0 means the hardware's cores (at least 1).
int ResolveThreadCount(int threads);

}  // namespace implicit_sim
