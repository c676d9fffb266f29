#include "implicit_sim/ros/node_diagnostics.h"

namespace implicit_sim {
namespace {

// Per command topic: the names of its two /diagnostics keys, "received_<name>_commands" and "dropped_<name>_commands".
constexpr const char* kCommandKeyNames[] = {"wrench", "joint_effort", "drive"};

}  // namespace

NodeDiagnostics::NodeDiagnostics(ros::NodeHandle nh, ros::NodeHandle pnh, const std::string& hardware_id,
                                 bool paused)
    : updater_(nh, pnh) {
  counters_.paused = paused;
  updater_.setHardwareID(hardware_id);
  updater_.add("solver", this, &NodeDiagnostics::Update);
}

void NodeDiagnostics::CountStep(const StepReport& report, const std::string& failure, bool paused, double sim_time,
                                double rtf) {
  std::lock_guard<std::mutex> lock(mutex_);
  Counters& c = counters_;
  ++c.steps;
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

void NodeDiagnostics::Update(diagnostic_updater::DiagnosticStatusWrapper& status) {
  std::lock_guard<std::mutex> lock(mutex_);
  Counters& c = counters_;
  if (c.fault_holds) {  // until ~unpause or ~reset: the simulation stays halted by the fault
    status.summary(diagnostic_msgs::DiagnosticStatus::ERROR, "step refused, simulation paused: " + c.last_failure);
  } else if (c.failed > 0) {
    status.summary(diagnostic_msgs::DiagnosticStatus::ERROR, "step refused, bodies reset: " + c.last_failure);
  } else if (c.nonconverged > 0) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN, "some steps did not converge");
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
  c.steps = c.nonconverged = c.failed = 0;
}

}  // namespace implicit_sim
