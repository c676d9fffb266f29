// The RATTLE steps whose first root created energy (issue 32's defect), captured from the random drops and the pile
// of bench/energy_drops.py (--dump-dir) into bench/corpus/rattle/: each replays as recorded, its energy guard rejects
// the first root (energy_fallbacks), and the root the step ends on does not create energy by an independent balance
// of kinetic and gravitational energy (doc/method.md, "The energy guard").
#include <dirent.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "implicit_sim/core/io/step_case.h"
#include "implicit_sim/core/step/time_stepper.h"

namespace implicit_sim {
namespace {

std::vector<std::string> RattleCases() {
  const std::string dir = std::string(IMPLICIT_SIM_SOURCE_DIR) + "/bench/corpus/rattle/";
  std::vector<std::string> paths;
  if (DIR* d = ::opendir(dir.c_str())) {
    while (const dirent* entry = ::readdir(d)) {
      const std::string name = entry->d_name;
      if (name.size() > 5 && name.compare(name.size() - 5, 5, ".case") == 0) paths.push_back(dir + name);
    }
    ::closedir(d);
  }
  std::sort(paths.begin(), paths.end());
  return paths;
}

// Kinetic plus gravitational energy (J).
double MechanicalEnergy(const Model& model, const State& state) {
  double potential = 0.0;
  for (int slot = 0; slot < model.num_moving(); ++slot) {
    const Vec3 p_WB = state.q.segment<3>(Model::q_offset(slot));
    potential -= model.bodies[model.moving_bodies[slot]].mass * model.gravity_W.dot(p_WB);
  }
  return KineticEnergy(model, state) + potential;
}

double LargestAngularSpeed(const Model& model, const State& state) {
  double largest = 0.0;
  for (int slot = 0; slot < model.num_moving(); ++slot) largest = std::max(largest, state.w_WB(slot).norm());
  return largest;
}

TEST(RattleCases, EachRejectedRootIsReplacedByOneThatCreatesNoEnergy) {
  const std::vector<std::string> paths = RattleCases();
  ASSERT_GE(paths.size(), 5u) << "bench/corpus/rattle/ holds the captured steps";
  for (const std::string& path : paths) {
    SCOPED_TRACE(path);
    const StepCase step_case = ReadStepCase(path);
    ASSERT_EQ(step_case.options.scheme, StepperOptions::Scheme::kRattle);
    const Model model = LoadStepCaseModel(step_case);
    State end;
    const StepReport report = ReplayStepCase(model, step_case, &end);
    EXPECT_EQ(report.converged, step_case.recorded.converged);
    EXPECT_EQ(report.iterations, step_case.recorded.iterations);
    EXPECT_TRUE(report.converged);
    EXPECT_GE(report.energy_fallbacks, 1);  // the first root was rejected
    EXPECT_GE(report.factorizations, report.iterations);  // Newton alone here: a factorization per iteration at least
    const State& start = step_case.inputs.state;
    const double kinetic0 = KineticEnergy(model, start), kinetic1 = KineticEnergy(model, end);
    const double rise = MechanicalEnergy(model, end) - MechanicalEnergy(model, start);
    const double gravity_work = (MechanicalEnergy(model, start) - kinetic0) - (MechanicalEnergy(model, end) - kinetic1);
    double weight = 0.0;
    for (int body : model.moving_bodies) weight += model.bodies[body].mass * model.gravity_W.norm();
    // The guard's allowance: 1 % of the energy in motion, plus h |w| where the paper's step took it (first order).
    const double first_order = report.paper_fallbacks > 0 || report.damping_steps > 0
                                   ? step_case.options.h * std::max(LargestAngularSpeed(model, start),
                                                                    LargestAngularSpeed(model, end))
                                   : 0.0;
    const double allowance =
        (0.01 + first_order) * (std::max(kinetic0, kinetic1) + std::abs(gravity_work)) + 1e-8 * weight;
    EXPECT_LE(rise, allowance) << "kinetic " << kinetic0 << " -> " << kinetic1 << " J";
  }
}

}  // namespace
}  // namespace implicit_sim
