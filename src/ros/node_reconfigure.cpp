// Live tuning through dynamic_reconfigure (cfg/SimNode.cfg): the live parameters (LiveParams) and the solver's
// tolerance and iteration limit. A value that is NaN, Inf, out of its range or (max_iterations) not an integer is
// refused with a warning naming it and its range, and the previous value is kept (and sent back to the client).
#include "implicit_sim/ros/sim_node.h"  // first: its generated service type Step precedes the core's function Step

#include <stdexcept>

#include "implicit_sim/core/step/options.h"

namespace implicit_sim {
namespace {

// The options-table row of a solver parameter (tolerance, max_iterations).
const OptionRow& SolverRow(const std::string& ros_param) {
  for (const OptionRow& row : OptionTable()) {
    if (ros_param == row.ros_param) return row;
  }
  throw std::logic_error("no options row for ~" + ros_param);
}

// The field of the generated config that holds the live parameter `name`.
double* ConfigField(SimNodeConfig* config, const std::string& name) {
  if (name == "real_time_factor") return &config->real_time_factor;
  if (name == "publish_rate") return &config->publish_rate;
  if (name == "clock_rate") return &config->clock_rate;
  if (name == "force_marker_scale") return &config->force_marker_scale;
  if (name == "contact_marker_size") return &config->contact_marker_size;
  if (name == "drive_stiffness") return &config->drive_stiffness;
  if (name == "drive_damping") return &config->drive_damping;
  if (name == "drag_frequency") return &config->drag_frequency;
  throw std::logic_error("cfg/SimNode.cfg has no parameter " + name);
}

// Writes the values in force into a config.
void FillConfig(const LiveParams& live, const StepperOptions& options, SimNodeConfig* config) {
  for (const LiveParamRange& range : LiveParamRanges()) *ConfigField(config, range.name) = live.*range.field;
  config->tolerance = options.newton.tolerance;
  config->max_iterations = options.newton.max_iterations;
}

void Refuse(const std::string& error) {
  ROS_WARN("implicit_sim: dynamic_reconfigure: %s; the previous value is kept", error.c_str());
}

}  // namespace

LiveParams SimNode::Live() const {
  std::lock_guard<std::mutex> lock(live_mutex_);
  return live_;
}

void SimNode::SetUpReconfigure() {
  reconfigure_ = std::make_unique<dynamic_reconfigure::Server<SimNodeConfig>>(reconfigure_mutex_, pnh_);
  SimNodeConfig config;
  {
    std::lock_guard<std::mutex> lock(live_mutex_);
    FillConfig(live_, live_options_, &config);
  }
  reconfigure_->updateConfig(config);
  reconfigure_->setCallback([this](SimNodeConfig& next, uint32_t) { OnReconfigure(next); });
}

void SimNode::OnReconfigure(SimNodeConfig& next) {
  std::lock_guard<std::mutex> lock(live_mutex_);
  const LiveParams live_before = live_;
  const StepperOptions options_before = live_options_;
  for (const LiveParamRange& range : LiveParamRanges()) {
    const double value = *ConfigField(&next, range.name);
    if (value == live_.*range.field) continue;
    const std::string error = CheckLiveParam(range, value);
    if (error.empty()) {
      live_.*range.field = value;
    } else {
      Refuse(error);
    }
  }
  std::string error;
  const OptionRow& tolerance = SolverRow("tolerance");
  if (CheckOptionValue(tolerance, next.tolerance, "parameter ~tolerance", &error)) {
    tolerance.set(&live_options_, next.tolerance);
  } else {
    Refuse(error);
  }
  const OptionRow& max_iterations = SolverRow("max_iterations");
  if (CheckOptionValue(max_iterations, next.max_iterations, "parameter ~max_iterations", &error)) {
    max_iterations.set(&live_options_, next.max_iterations);
  } else {
    Refuse(error);
  }
  FillConfig(live_, live_options_, &next);  // what the client sees: the values in force
  const bool physics_changed = live_.drive_stiffness != live_before.drive_stiffness ||
                               live_.drive_damping != live_before.drive_damping ||
                               live_.drag_frequency != live_before.drag_frequency ||
                               live_options_.newton.tolerance != options_before.newton.tolerance ||
                               live_options_.newton.max_iterations != options_before.newton.max_iterations;
  if (physics_changed) PostBetweenSteps([this] { JournalUnreplayable("~set_parameters"); });
}

}  // namespace implicit_sim
