// Health checks of a step (StepFault in step_report.h): bodies that overlap where a cold step would start, and
// velocities beyond any physical motion.
#pragma once

#include <string>

#include "implicit_sim/core/model/model.h"
#include "implicit_sim/core/model/state.h"
#include "implicit_sim/core/step/data.h"

namespace implicit_sim {

// True if two bodies of `state` overlap by more than `tolerance` (m); *detail then names the pair and the depth.
// Candidates come from the broad phase (bounding spheres), the depth from the closest points and a separating-plane
// bound. Uses the broad phase and its workspace in *data.
bool FindInitialOverlap(const Model& model, const State& state, double tolerance, Data* data, std::string* detail);

// True if a moving body is faster than max_speed (m/s) or spins faster than max_angular_speed (rad/s).
bool FindDivergence(const Model& model, const State& state, double max_speed, double max_angular_speed,
                    std::string* detail);

}  // namespace implicit_sim
