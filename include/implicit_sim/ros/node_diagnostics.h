// The node's /diagnostics: counters written by the physics thread (steps, faults, pause) and by the command topics
// (received and dropped commands), read once a second by the diagnostics thread. It has a lock of its own and never
// waits for a step, so /diagnostics keeps coming while a long step runs (doc/ros_node.md, "Diagnostics").
#pragma once

#include <array>
#include <chrono>
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
  // min_real_time_fraction (~min_real_time_fraction, [0, 1]): the status is WARN while the real-time factor of the
  // last second is below this fraction of the requested ~real_time_factor, or a step has run longer than a second
  // (0: never).
  NodeDiagnostics(ros::NodeHandle nh, ros::NodeHandle pnh, const std::string& hardware_id, bool paused,
                  double min_real_time_fraction);
  // The physics thread starts a step (a step that runs long is reported while it runs).
  void BeginStep();
  // A step the physics thread took (or refused: report.advanced false, with `failure` its reason); `paused`, the
  // simulation time (s) and real-time factor after it, the real-time factor it paces to (0: not paced, as a ~step
  // job or real_time_factor 0) and the largest penetration at its end (m, 0 when none).
  void CountStep(const StepReport& report, const std::string& failure, bool paused, double sim_time, double rtf,
                 double requested_rtf, double penetration);
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
    double sim_time = 0.0, rtf = 0.0, last_residual = 0.0, requested_rtf = 0.0;
    long last_iterations = 0;
    // Since the last report: the slowest step (s), the most Newton iterations in one step, the ladder's rungs, the
    // largest penetration (m).
    double slowest_step_s = 0.0, max_penetration = 0.0;
    long max_iterations = 0, cold_restarts = 0, proximal_solves = 0, smoothed_solves = 0, ipopt_solves = 0,
         substeps = 0;
    bool in_step = false;
    std::chrono::steady_clock::time_point step_start;
  };
  // The WARN of a slow simulation ("" when it keeps pace); reads counters_ (mutex_ held).
  std::string SlowStatus() const;
  const double min_real_time_fraction_;
  std::mutex mutex_;
  Counters counters_;  // guarded by mutex_
  diagnostic_updater::Updater updater_;
};

}  // namespace implicit_sim
