// A cooperative stop for a long computation (a step's solves, core/step/time_stepper.h): requested from another
// thread or a signal handler, or due at a deadline. The solvers check it between factorizations; a step that sees it
// ends without advancing (StepFault::kInterrupted), its state as before the step. Request() only stores to a
// lock-free atomic, so a signal handler may call it.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>

namespace implicit_sim {

class StepInterrupt {
 public:
  using Clock = std::chrono::steady_clock;
  // Asks every computation that watches this object to stop (until Clear).
  void Request() { requested_.store(true, std::memory_order_relaxed); }
  // Makes the stop due at `deadline` as well (replacing an earlier deadline).
  void SetDeadline(Clock::time_point deadline) {
    deadline_ns_.store(std::chrono::duration_cast<std::chrono::nanoseconds>(deadline.time_since_epoch()).count(),
                       std::memory_order_relaxed);
  }
  // The same, `seconds` (>= 0) from now.
  void SetDeadlineIn(double seconds) {
    SetDeadline(Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds)));
  }
  void ClearDeadline() { deadline_ns_.store(kNoDeadline, std::memory_order_relaxed); }
  void Clear() {
    requested_.store(false, std::memory_order_relaxed);
    ClearDeadline();
  }
  bool requested() const { return requested_.load(std::memory_order_relaxed); }
  bool deadline_passed() const {
    const int64_t deadline = deadline_ns_.load(std::memory_order_relaxed);
    return deadline != kNoDeadline &&
           std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch()).count() >= deadline;
  }
  // Whether a computation should stop now: requested, or past the deadline.
  bool Due() const { return requested() || deadline_passed(); }

 private:
  static constexpr int64_t kNoDeadline = std::numeric_limits<int64_t>::max();
  static_assert(std::atomic<bool>::is_always_lock_free, "Request() must be async-signal-safe");
  std::atomic<bool> requested_{false};
  std::atomic<int64_t> deadline_ns_{kNoDeadline};
};

// A load (core/model/urdf_loader.h) that saw its interrupt due: nothing was loaded.
struct LoadInterrupted : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Whether `interrupt` (may be null: never) is due.
inline bool InterruptDue(const StepInterrupt* interrupt) { return interrupt != nullptr && interrupt->Due(); }

// For the loader's stages: throws LoadInterrupted ("scene '<name>': loading interrupted") once `interrupt` is due.
inline void ThrowIfLoadInterrupted(const StepInterrupt* interrupt, const std::string& scene_name) {
  if (InterruptDue(interrupt)) throw LoadInterrupted("scene '" + scene_name + "': loading interrupted");
}

// For a main: SIGINT and SIGTERM request `interrupt` (which must outlive the process's use of it); a second signal
// then acts as it would without the handler (the process ends).
void RequestOnStopSignals(StepInterrupt* interrupt);

}  // namespace implicit_sim
