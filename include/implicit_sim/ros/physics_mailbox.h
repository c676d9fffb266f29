// How the node's other threads reach its physics thread, which alone owns the World: commands it runs between two
// steps (a service waits for its command, a command topic does not) and the one step job of ~step or ~run_steps.
// One lock, never held across a step. The physics thread calls the methods marked so; any thread calls the others.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace implicit_sim {

// A ~step or ~run_steps request: steps the physics thread runs while paused.
struct StepJob {
  bool active = false, cancel = false, finished = false, success = false;
  uint64_t requested = 0, done = 0;
  double sim_time = 0.0;  // s, after the last step done
  std::string message;
};

class PhysicsMailbox {
 public:
  // What the physics thread does next.
  enum class Work { kStop, kRun, kJobStep };

  // Runs fn on the physics thread between two steps and waits for it; false (fn not run) once stopping. After waiting
  // the step cutter's time it calls the cutter once (a long step in progress is cut, so fn runs at once).
  bool RunBetweenSteps(std::function<void()> fn);
  // What a command that has waited `after` for the step in progress calls (SimNode::CutStepForCommand). Set before
  // the threads start; without one, commands wait for the step to end.
  void SetStepCutter(std::chrono::milliseconds after, std::function<void()> cut_step);
  // Queues fn for the physics thread without waiting.
  void Post(std::function<void()> fn);
  // Ends every wait; later RunBetweenSteps calls refuse.
  void Stop();
  // Commands queued and not yet taken by the physics thread.
  size_t QueuedCommands() const;

  // Physics thread: waits until there is something to do (`running`: the simulation is not paused), runs the
  // commands that came, and says what next.
  Work WaitForWork(bool running);
  // Physics thread: runs the commands that arrive until `until` (a paced step's due time); returns early when
  // stopping or when after a command `interrupted()` holds.
  void RunUntil(std::chrono::steady_clock::time_point until, const std::function<bool()>& interrupted);
  // Physics thread: the commands queued so far.
  void RunCommands();

  // The step job. StartJob (physics thread, through RunBetweenSteps) refuses with *refusal when one is active.
  bool StartJob(uint64_t steps, double sim_time, std::string* refusal);
  bool JobActive() const;
  void CountJobStep(double sim_time);                            // physics thread, after a job step
  void FailJob(double sim_time, const std::string& why);          // physics thread: a refused step ends the job
  // Waits until the job finishes or the mailbox stops; every feedback_period (s) calls feedback(job) and, when
  // cancel_requested() holds, ends the job as cancelled. Returns the job as it ended and marks its end collected.
  StepJob WaitForJob(double feedback_period, const std::function<void(const StepJob&)>& feedback,
                     const std::function<bool()>& cancel_requested);

 private:
  struct Command {
    std::function<void()> run;
    bool done = false;
  };
  bool JobRunnableLocked() const { return job_.active && !job_.cancel; }
  void FinishJobLocked(bool success, const std::string& message);

  mutable std::mutex mutex_;
  std::condition_variable cv_;  // wakes the physics thread and the waiters of commands and jobs
  std::vector<std::shared_ptr<Command>> commands_;
  StepJob job_;
  bool stopping_ = false;
  std::chrono::milliseconds cut_after_{0};
  std::function<void()> cut_step_;
};

}  // namespace implicit_sim
