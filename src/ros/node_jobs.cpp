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
  return refusal->empty() && mailbox_.StartJob(steps, SimTime(), refusal);
}

bool SimNode::OnStep(implicit_sim::Step::Request& req, implicit_sim::Step::Response& res) {
  std::string refusal;
  bool started = false;
  if (!mailbox_.RunBetweenSteps([&] {
        res.sim_time = SimTime();
        started = StartJob(req.steps, kMaxServiceSteps, &refusal);
      })) {
    return ShuttingDownAnswer(res);
  }
  if (!started) {
    res.success = false;
    res.message = refusal;
    return true;
  }
  const StepJob job = mailbox_.WaitForJob(kFeedbackPeriodS, [](const StepJob&) {}, [] { return false; });
  res.success = job.finished && job.success;
  res.message = job.finished ? job.message
                             : "stopped after " + std::to_string(job.done) + " steps: the node is shutting down";
  res.sim_time = job.sim_time;
  publisher_->PublishClock(res.sim_time);  // the final time at once, whatever the clock throttle sent
  return true;
}

void SimNode::OnRunStepsGoal(const implicit_sim::RunStepsGoalConstPtr& goal) {
  implicit_sim::RunStepsResult result;
  std::string refusal;
  bool started = false;
  const bool ran = mailbox_.RunBetweenSteps([&] {
    result.sim_time = SimTime();
    started = StartJob(goal->steps, kMaxActionSteps, &refusal);
  });
  if (!ran || !started) {
    result.success = false;
    result.message = ran ? refusal : "refused: the node is shutting down";
    run_steps_server_->setAborted(result, result.message);
    return;
  }
  const StepJob job = mailbox_.WaitForJob(
      kFeedbackPeriodS,
      [this](const StepJob& now) {
        implicit_sim::RunStepsFeedback feedback;
        feedback.steps_done = now.done;
        feedback.sim_time = now.sim_time;
        run_steps_server_->publishFeedback(feedback);
      },
      [this] {
        if (!run_steps_server_->isPreemptRequested() && ros::ok()) return false;
        interrupt_.Request();  // the job step in progress stops too; StepOnce clears the request
        return true;
      });
  result.steps_done = job.done;
  result.sim_time = job.sim_time;
  result.success = job.finished && job.success;
  result.message = job.finished ? job.message : "stopped: the node is shutting down";
  publisher_->PublishClock(result.sim_time);
  if (job.cancel) {
    run_steps_server_->setPreempted(result, result.message);
  } else if (result.success) {
    run_steps_server_->setSucceeded(result, result.message);
  } else {
    run_steps_server_->setAborted(result, result.message);
  }
}

}  // namespace implicit_sim
