#include "implicit_sim/ros/physics_mailbox.h"

namespace implicit_sim {

bool PhysicsMailbox::RunBetweenSteps(std::function<void()> fn) {
  auto command = std::make_shared<Command>();
  command->run = std::move(fn);
  std::unique_lock<std::mutex> lock(mutex_);
  if (stopping_) return false;
  commands_.push_back(command);
  cv_.notify_all();
  const auto done_or_stopping = [&] { return command->done || stopping_; };
  if (cut_step_ && !cv_.wait_for(lock, cut_after_, done_or_stopping)) {
    lock.unlock();
    cut_step_();
    lock.lock();
  }
  cv_.wait(lock, done_or_stopping);
  return command->done;
}

void PhysicsMailbox::SetStepCutter(std::chrono::milliseconds after, std::function<void()> cut_step) {
  std::lock_guard<std::mutex> lock(mutex_);
  cut_after_ = after;
  cut_step_ = std::move(cut_step);
}

void PhysicsMailbox::Post(std::function<void()> fn) {
  auto command = std::make_shared<Command>();
  command->run = std::move(fn);
  std::lock_guard<std::mutex> lock(mutex_);
  commands_.push_back(command);
  cv_.notify_all();
}

void PhysicsMailbox::Stop() {
  std::lock_guard<std::mutex> lock(mutex_);  // the waiters check stopping_ under it
  stopping_ = true;
  cv_.notify_all();
}

size_t PhysicsMailbox::QueuedCommands() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return commands_.size();
}

PhysicsMailbox::Work PhysicsMailbox::WaitForWork(bool running) {
  bool job_step = false;
  {
    std::unique_lock<std::mutex> lock(mutex_);
    cv_.wait(lock, [&] { return stopping_ || !commands_.empty() || running || JobRunnableLocked(); });
    if (stopping_) return Work::kStop;
    job_step = JobRunnableLocked();
  }
  RunCommands();
  return job_step ? Work::kJobStep : Work::kRun;
}

void PhysicsMailbox::RunUntil(std::chrono::steady_clock::time_point until, const std::function<bool()>& interrupted) {
  std::unique_lock<std::mutex> lock(mutex_);
  while (cv_.wait_until(lock, until, [this] { return stopping_ || !commands_.empty(); })) {
    if (stopping_) return;
    lock.unlock();
    RunCommands();
    lock.lock();
    if (interrupted()) return;
  }
}

void PhysicsMailbox::RunCommands() {
  std::vector<std::shared_ptr<Command>> commands;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    commands.swap(commands_);
  }
  if (commands.empty()) return;
  for (const auto& command : commands) command->run();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& command : commands) command->done = true;
  }
  cv_.notify_all();
}

bool PhysicsMailbox::StartJob(uint64_t steps, double sim_time, std::string* refusal) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (job_.active) {
    *refusal = "refused: another ~step or ~run_steps job is running";
    return false;
  }
  job_ = StepJob();
  job_.active = true;
  job_.requested = steps;
  job_.sim_time = sim_time;
  return true;
}

bool PhysicsMailbox::JobActive() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return job_.active;
}

void PhysicsMailbox::CountJobStep(double sim_time) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!job_.active) return;  // the step was refused and ended the job
  ++job_.done;
  job_.sim_time = sim_time;
  if (job_.done == job_.requested) FinishJobLocked(true, "ran " + std::to_string(job_.done) + " steps");
}

void PhysicsMailbox::FailJob(double sim_time, const std::string& why) {
  std::lock_guard<std::mutex> lock(mutex_);
  job_.sim_time = sim_time;
  if (job_.active) FinishJobLocked(false, "stopped after " + std::to_string(job_.done) + " steps: " + why);
}

void PhysicsMailbox::FinishJobLocked(bool success, const std::string& message) {
  job_.active = false;
  job_.finished = true;
  job_.success = success;
  job_.message = message;
  cv_.notify_all();
}

StepJob PhysicsMailbox::WaitForJob(double feedback_period, const std::function<void(const StepJob&)>& feedback,
                                   const std::function<bool()>& cancel_requested) {
  std::unique_lock<std::mutex> lock(mutex_);
  while (!job_.finished && !stopping_) {
    cv_.wait_for(lock, std::chrono::duration<double>(feedback_period));
    if (!job_.cancel && cancel_requested()) {
      job_.cancel = true;  // the physics thread takes no further job step
      if (job_.active) FinishJobLocked(false, "cancelled after " + std::to_string(job_.done) + " steps");
    }
    const StepJob now = job_;
    lock.unlock();
    feedback(now);
    lock.lock();
  }
  const StepJob ended = job_;
  job_.active = false;  // a job left by a stopping node takes no further step
  job_.finished = false;
  return ended;
}

}  // namespace implicit_sim
