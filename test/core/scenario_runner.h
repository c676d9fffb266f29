// Runs a scene from scenes/ headless for the scenario tests and hands every step end to a callback.
#pragma once

#include <cmath>
#include <functional>
#include <string>

#include "implicit_sim/core/state.h"
#include "implicit_sim/core/time_stepper.h"
#include "implicit_sim/core/urdf_loader.h"

namespace implicit_sim {
namespace testing_support {

inline std::string ScenePath(const std::string& file) {
  return std::string(IMPLICIT_SIM_SOURCE_DIR) + "/scenes/" + file;
}

struct RunStats {
  int steps = 0;
  int nonconverged = 0;
  double max_solver_penetration = 0.0;  // max over steps and pairs of -gap (m), as the solver reports it
  double ke0 = 0.0, ke_final = 0.0;
};

using StepCallback = std::function<void(const Model&, const State&, const Data&, const StepReport&)>;

inline RunStats RunScene(const Model& model, double h, double duration, const StepCallback& on_step = nullptr) {
  StepperOptions options;
  options.h = h;
  Data data(model);
  State state = State::Initial(model);
  RunStats stats;
  stats.ke0 = KineticEnergy(model, state);
  const long steps = std::lround(duration / h);
  for (long i = 0; i < steps; ++i) {
    const StepReport report = Step(model, options, &state, &data);
    ++stats.steps;
    if (!report.converged) ++stats.nonconverged;
    for (const ContactResult& c : data.contacts) {
      stats.max_solver_penetration = std::max(stats.max_solver_penetration, -c.gap);
    }
    if (on_step) on_step(model, state, data, report);
  }
  stats.ke_final = KineticEnergy(model, state);
  return stats;
}

}  // namespace testing_support
}  // namespace implicit_sim
