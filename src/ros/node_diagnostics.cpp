#include "implicit_sim/ros/node_diagnostics.h"

#include <algorithm>

#include "implicit_sim/core/base/format.h"

namespace implicit_sim {
namespace {

// Per command topic: the names of its two /diagnostics keys, "received_<name>_commands" and "dropped_<name>_commands".
constexpr const char* kCommandKeyNames[] = {"wrench", "joint_effort", "drive"};

}  // namespace

NodeDiagnostics::NodeDiagnostics(ros::NodeHandle nh, ros::NodeHandle pnh, const std::string& hardware_id,
                                 bool paused, double min_real_time_fraction)
    : min_real_time_fraction_(min_real_time_fraction), updater_(nh, pnh) {
  counters_.paused = paused;
  updater_.setHardwareID(hardware_id);
  updater_.add("solver", this, &NodeDiagnostics::Update);
}

void NodeDiagnostics::BeginStep() {
  std::lock_guard<std::mutex> lock(mutex_);
  counters_.in_step = true;
  counters_.step_start = std::chrono::steady_clock::now();
}

void NodeDiagnostics::CountStep(const StepReport& report, const std::string& failure, bool paused, double sim_time,
                                double rtf, double requested_rtf, double penetration) {
  std::lock_guard<std::mutex> lock(mutex_);
  Counters& c = counters_;
  ++c.steps;
  c.in_step = false;
  c.requested_rtf = requested_rtf;
  c.slowest_step_s = std::max(c.slowest_step_s, report.wall_time_s);
  c.max_iterations = std::max<long>(c.max_iterations, report.iterations);
  c.max_penetration = std::max(c.max_penetration, penetration);
  c.cold_restarts += report.cold_restarts;
  c.proximal_solves += report.proximal_solves;
  c.smoothed_solves += report.smoothed_solves;
  c.ipopt_solves += report.ipopt_solves;
  c.substeps += report.substeps;
  ++c.faults[static_cast<int>(report.fault)];
  if (!report.converged) ++c.nonconverged;
  if (!report.advanced) {
    ++c.failed;
    c.last_failure = failure;
    c.fault_holds = paused;
  }
  c.paused = paused;
  c.sim_time = sim_time;
  c.rtf = rtf;
  c.last_iterations = report.iterations;
  c.last_residual = report.residual;
}

void NodeDiagnostics::HoldFault(const std::string& failure) {
  std::lock_guard<std::mutex> lock(mutex_);
  counters_.paused = true;
  counters_.fault_holds = true;
  counters_.last_failure = failure;
}

void NodeDiagnostics::SetPaused(bool paused) {
  std::lock_guard<std::mutex> lock(mutex_);
  counters_.paused = paused;
  if (paused) return;
  counters_.fault_holds = false;
  counters_.last_failure.clear();
}

void NodeDiagnostics::ClearFault() {
  std::lock_guard<std::mutex> lock(mutex_);
  counters_.fault_holds = false;
  counters_.last_failure.clear();
}

void NodeDiagnostics::CountCommand(CommandTopic kind, const char* topic, bool accepted, const std::string& error) {
  const int k = static_cast<int>(kind);
  long dropped = 0;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    ++counters_.received[k];
    if (!accepted) dropped = ++counters_.dropped[k];
  }
  if (!accepted) {
    ROS_WARN_THROTTLE(1.0, "implicit_sim: dropped %s: %s (%ld dropped so far)", topic, error.c_str(), dropped);
  }
}

std::string NodeDiagnostics::SlowStatus() const {
  const Counters& c = counters_;
  if (c.paused || !(min_real_time_fraction_ > 0.0)) return "";
  const double running_s =
      c.in_step ? std::chrono::duration<double>(std::chrono::steady_clock::now() - c.step_start).count() : 0.0;
  std::string what;
  if (running_s > 1.0) {
    what = "a step has been running for " + FormatNumber(running_s) + " s";
  } else if (c.requested_rtf > 0.0 && c.steps > 0 && c.rtf < min_real_time_fraction_ * c.requested_rtf) {
    what = "real-time factor " + FormatNumber(c.rtf) + " below " + FormatNumber(min_real_time_fraction_) +
           " of the requested " + FormatNumber(c.requested_rtf);
  } else {
    return "";
  }
  return what + " (last second: slowest step " + FormatNumber(c.slowest_step_s) + " s, up to " +
         std::to_string(c.max_iterations) + " Newton iterations a step; cold restarts " +
         std::to_string(c.cold_restarts) + ", proximal " + std::to_string(c.proximal_solves) + ", continuation " +
         std::to_string(c.smoothed_solves) + ", Ipopt " + std::to_string(c.ipopt_solves) + ", sub-step splits " +
         std::to_string(c.substeps) + "; largest penetration " + FormatNumber(c.max_penetration) + " m)";
}

void NodeDiagnostics::Update(diagnostic_updater::DiagnosticStatusWrapper& status) {
  std::lock_guard<std::mutex> lock(mutex_);
  Counters& c = counters_;
  const std::string slow = SlowStatus();
  if (c.fault_holds) {  // until ~unpause or ~reset: the simulation stays halted by the fault
    status.summary(diagnostic_msgs::DiagnosticStatus::ERROR, "step refused, simulation paused: " + c.last_failure);
  } else if (c.failed > 0) {
    status.summary(diagnostic_msgs::DiagnosticStatus::ERROR, "step refused, bodies reset: " + c.last_failure);
  } else if (c.nonconverged > 0) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN,
                   "some steps did not converge" + (slow.empty() ? "" : "; " + slow));
  } else if (!slow.empty()) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN, slow);
  } else {
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, c.paused ? "paused" : "running");
  }
  status.add("sim_time_s", c.sim_time);
  status.add("steps_since_last_report", c.steps);
  status.add("nonconverged_steps_since_last_report", c.nonconverged);
  status.add("failed_steps_since_last_report", c.failed);
  for (int k = 0; k < static_cast<int>(CommandTopic::kCount); ++k) {
    status.add(std::string("received_") + kCommandKeyNames[k] + "_commands", c.received[k]);
    status.add(std::string("dropped_") + kCommandKeyNames[k] + "_commands", c.dropped[k]);
  }
  for (int f = 1; f < kNumStepFaults; ++f) {  // every fault but kNone and kInterrupted (an undone step: no fault)
    if (static_cast<StepFault>(f) == StepFault::kInterrupted) continue;
    status.add(std::string("faults_") + StepFaultName(static_cast<StepFault>(f)), c.faults[f]);
  }
  status.add("real_time_factor", c.rtf);
  status.add("last_iterations", c.last_iterations);
  status.add("last_residual", c.last_residual);
  status.add("slowest_step_s", c.slowest_step_s);
  status.add("max_iterations_per_step", c.max_iterations);
  status.add("cold_restarts", c.cold_restarts);
  status.add("proximal_solves", c.proximal_solves);
  status.add("smoothed_solves", c.smoothed_solves);
  status.add("ipopt_solves", c.ipopt_solves);
  status.add("substeps", c.substeps);
  status.add("max_penetration_m", c.max_penetration);
  c.steps = c.nonconverged = c.failed = 0;
  c.slowest_step_s = c.max_penetration = 0.0;
  c.max_iterations = c.cold_restarts = c.proximal_solves = c.smoothed_solves = c.ipopt_solves = c.substeps = 0;
}

}  // namespace implicit_sim
