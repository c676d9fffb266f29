// Step jobs: the ~step service (short runs, blocks until done) and the ~run_steps action (long runs, with feedback,
// cancellable). Both run while paused; the physics thread takes one job step per loop turn and answers every other
// command between them, so services, /clock and shutdown stay responsive during a job of any length.
#include "implicit_sim/ros/sim_node.h"  // first: its generated service type Step precedes the core's function Step

#include <chrono>

#include "implicit_sim/core/base/format.h"

namespace implicit_sim {
namespace {

constexpr uint64_t kMaxServiceSteps = 1000000;       // ~step
constexpr uint64_t kMaxActionSteps = 1000000000000;  // ~run_steps: 1e12
constexpr double kFeedbackPeriodS = 0.1;             // wall time between two feedback messages of ~run_steps

}  // namespace

bool SimNode::StartJob(uint64_t steps, uint64_t max_steps, std::string* refusal) {
  if (!paused_) {
    *refusal = "refused: the simulation is running; call ~pause first";
  } else if (steps < 1 || steps > max_steps) {
    *refusal = "steps must be in [1, " + std::to_string(max_steps) + "], got " + std::to_string(steps);
  }
  std::lock_guard<std::mutex> lock(mailbox_mutex_);
  if (refusal->empty() && job_.active) *refusal = "refused: another ~step or ~run_steps job is running";
  if (!refusal->empty()) return false;
  job_ = StepJob();
  job_.active = true;
  job_.requested = steps;
  job_.sim_time = SimTime();
  return true;
}

void SimNode::RunJobStep() {
  StepOnce(0.0);  // a failed step finishes the job itself
  std::lock_guard<std::mutex> lock(mailbox_mutex_);
  if (!job_.active) return;
  ++job_.done;
  job_.sim_time = SimTime();
  if (job_.done == job_.requested) FinishJobLocked(true, "ran " + std::to_string(job_.done) + " steps");
}

void SimNode::FinishJobLocked(bool success, const std::string& message) {
  job_.active = false;
  job_.finished = true;
  job_.success = success;
  job_.message = message;
  mailbox_cv_.notify_all();
}

bool SimNode::OnStep(implicit_sim::Step::Request& req, implicit_sim::Step::Response& res) {
  std::string refusal;
  bool started = false;
  if (!RunBetweenSteps([&] {
        res.sim_time = SimTime();
        started = StartJob(req.steps, kMaxServiceSteps, &refusal);
      })) {
    res.success = false;
    res.message = "refused: the node is shutting down";
    return true;
  }
  if (!started) {
    res.success = false;
    res.message = refusal;
    return true;
  }
  std::unique_lock<std::mutex> lock(mailbox_mutex_);
  mailbox_cv_.wait(lock, [this] { return job_.finished || stopping_; });
  if (!job_.finished) {
    res.success = false;
    res.message = "stopped after " + std::to_string(job_.done) + " steps: the node is shutting down";
  } else {
    res.success = job_.success;
    res.message = job_.message;
  }
  res.sim_time = job_.sim_time;
  job_.finished = false;
  lock.unlock();
  publisher_->PublishClock(res.sim_time);  // the final time at once, whatever the clock throttle sent
  return true;
}

void SimNode::OnRunStepsGoal(const implicit_sim::RunStepsGoalConstPtr& goal) {
  implicit_sim::RunStepsResult result;
  std::string refusal;
  bool started = false;
  const bool ran = RunBetweenSteps([&] {
    result.sim_time = SimTime();
    started = StartJob(goal->steps, kMaxActionSteps, &refusal);
  });
  if (!ran || !started) {
    result.success = false;
    result.message = ran ? refusal : "refused: the node is shutting down";
    run_steps_server_->setAborted(result, result.message);
    return;
  }
  std::unique_lock<std::mutex> lock(mailbox_mutex_);
  bool cancel_sent = false;
  while (!job_.finished && !stopping_) {
    mailbox_cv_.wait_for(lock, std::chrono::duration<double>(kFeedbackPeriodS));
    if (!cancel_sent && (run_steps_server_->isPreemptRequested() || !ros::ok())) {
      job_.cancel = true;  // the physics thread takes no further job step
      cancel_sent = true;
      if (job_.active) FinishJobLocked(false, "cancelled after " + std::to_string(job_.done) + " steps");
    }
    implicit_sim::RunStepsFeedback feedback;
    feedback.steps_done = job_.done;
    feedback.sim_time = job_.sim_time;
    lock.unlock();
    run_steps_server_->publishFeedback(feedback);
    lock.lock();
  }
  result.steps_done = job_.done;
  result.sim_time = job_.sim_time;
  result.success = job_.finished && job_.success;
  result.message = job_.finished ? job_.message : "stopped: the node is shutting down";
  if (!job_.finished && job_.active) job_.active = false;
  job_.finished = false;
  lock.unlock();
  publisher_->PublishClock(result.sim_time);
  if (cancel_sent) {
    run_steps_server_->setPreempted(result, result.message);
  } else if (result.success) {
    run_steps_server_->setSucceeded(result, result.message);
  } else {
    run_steps_server_->setAborted(result, result.message);
  }
}

}  // namespace implicit_sim
