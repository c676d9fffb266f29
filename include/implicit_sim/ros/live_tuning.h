// Live tuning through dynamic_reconfigure (cfg/SimNode.cfg): the live parameters (LiveParams) and the solver's
// tolerance and iteration limit. A value that is NaN, Inf, out of its range or (max_iterations) not an integer is
// refused with a warning naming it and its range, and the previous value is kept (and sent back to the client).
// Its own lock: any thread reads it.
#pragma once

#include <functional>
#include <memory>
#include <mutex>

#include <dynamic_reconfigure/server.h>
#include <ros/ros.h>

#include "implicit_sim/SimNodeConfig.h"
#include "implicit_sim/core/step/options.h"
#include "implicit_sim/ros/node_params.h"

namespace implicit_sim {

class LiveTuning {
 public:
  // Serves ~set_parameters from the start values. on_physics_change runs (on the reconfigure thread) after an
  // accepted change of a value that changes the physics (drive gains, drag frequency, solver tolerance or limit).
  LiveTuning(ros::NodeHandle pnh, const LiveParams& live, const StepperOptions& options,
             std::function<void()> on_physics_change);

  LiveParams Live() const;
  // Copies the solver options in force (tolerance, max_iterations) into *options.
  void CopySolverOptions(StepperOptions* options) const;

 private:
  void OnReconfigure(SimNodeConfig& next);

  mutable std::mutex mutex_;
  LiveParams live_;
  StepperOptions options_;
  const std::function<void()> on_physics_change_;
  boost::recursive_mutex server_mutex_;
  std::unique_ptr<dynamic_reconfigure::Server<SimNodeConfig>> server_;
};

}  // namespace implicit_sim
