#include "implicit_sim/ros/live_tuning.h"

#include <stdexcept>

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

LiveTuning::LiveTuning(ros::NodeHandle pnh, const LiveParams& live, const StepperOptions& options,
                       std::function<void()> on_physics_change)
    : live_(live), options_(options), on_physics_change_(std::move(on_physics_change)) {
  server_ = std::make_unique<dynamic_reconfigure::Server<SimNodeConfig>>(server_mutex_, pnh);
  SimNodeConfig config;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    FillConfig(live_, options_, &config);
  }
  server_->updateConfig(config);
  server_->setCallback([this](SimNodeConfig& next, uint32_t) { OnReconfigure(next); });
}

LiveParams LiveTuning::Live() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return live_;
}

void LiveTuning::CopySolverOptions(StepperOptions* options) const {
  std::lock_guard<std::mutex> lock(mutex_);
  options->newton.tolerance = options_.newton.tolerance;
  options->newton.max_iterations = options_.newton.max_iterations;
}

void LiveTuning::OnReconfigure(SimNodeConfig& next) {
  std::lock_guard<std::mutex> lock(mutex_);
  const LiveParams live_before = live_;
  const StepperOptions options_before = options_;
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
    tolerance.set(&options_, next.tolerance);
  } else {
    Refuse(error);
  }
  const OptionRow& max_iterations = SolverRow("max_iterations");
  if (CheckOptionValue(max_iterations, next.max_iterations, "parameter ~max_iterations", &error)) {
    max_iterations.set(&options_, next.max_iterations);
  } else {
    Refuse(error);
  }
  FillConfig(live_, options_, &next);  // what the client sees: the values in force
  const bool physics_changed = live_.drive_stiffness != live_before.drive_stiffness ||
                               live_.drive_damping != live_before.drive_damping ||
                               live_.drag_frequency != live_before.drag_frequency ||
                               options_.newton.tolerance != options_before.newton.tolerance ||
                               options_.newton.max_iterations != options_before.newton.max_iterations;
  if (physics_changed) on_physics_change_();
}

}  // namespace implicit_sim
