// The node's /diagnostics: counters written by the physics thread (steps, faults, pause) and by the command topics
// (received and dropped commands), read once a second by the diagnostics thread. It has a lock of its own and never
// waits for a step, so /diagnostics keeps coming while a long step runs (doc/ros_node.md, "Diagnostics").
#pragma once

#include <array>
#include <mutex>
#include <string>

#include <diagnostic_updater/diagnostic_updater.h>
#include <ros/ros.h>

#include "implicit_sim/core/step/step_report.h"

namespace implicit_sim {

// The command topics whose messages are counted (received, dropped when refused).
enum class CommandTopic { kWrench, kJointEffort, kJointDrive, kCount };

class NodeDiagnostics {
 public:
  NodeDiagnostics(ros::NodeHandle nh, ros::NodeHandle pnh, const std::string& hardware_id, bool paused);
  // A step the physics thread took (or refused: report.advanced false, with `failure` its reason); `paused` and the
  // simulation time (s) and real-time factor after it.
  void CountStep(const StepReport& report, const std::string& failure, bool paused, double sim_time, double rtf);
  // A refusal that pauses the simulation until ~unpause or ~reset (a refused step, a replay that cannot go on).
  void HoldFault(const std::string& failure);
  // ~pause (paused) and ~unpause (running, the held fault cleared); ~reset clears the held fault only.
  void SetPaused(bool paused);
  void ClearFault();
  // A message of a command topic, accepted or refused with `error`; a refusal is warned about (at most once a second,
  // with the count of drops so far). `topic` names the topic in the warning.
  void CountCommand(CommandTopic kind, const char* topic, bool accepted, const std::string& error);
  // Publishes /diagnostics now (the diagnostics thread calls it once a second).
  void Publish() { updater_.force_update(); }

 private:
  void Update(diagnostic_updater::DiagnosticStatusWrapper& status);
  struct Counters {
    long steps = 0, nonconverged = 0, failed = 0;  // since the last report
    std::array<long, static_cast<int>(CommandTopic::kCount)> received{}, dropped{};
    std::array<long, kNumStepFaults> faults{};  // refused or non-converged steps since startup, by StepFault
    bool paused = false;
    bool fault_holds = false;  // a refusal paused the simulation; cleared by ~unpause, ~reset
    std::string last_failure;
    double sim_time = 0.0, rtf = 0.0, last_residual = 0.0;
    long last_iterations = 0;
  };
  std::mutex mutex_;
  Counters counters_;  // guarded by mutex_
  diagnostic_updater::Updater updater_;
};

}  // namespace implicit_sim
