// The second-order RATTLE step (StepperOptions::Scheme::kRattle; doc/method.md, "The second-order step") on smooth
// motion: a rocking ellipsoid, a tumbling one, the convergence order, a drop, a pendulum. Energy of smooth motion
// oscillates about its true value (bounded both ways); impacts only dissipate.
#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>

#include "implicit_sim/core/geometry/support.h"
#include "implicit_sim/core/step/time_stepper.h"

#include "scenario_runner.h"
#include "test_models.h"

namespace implicit_sim {
namespace {

using testing_support::RattleOptions;
using testing_support::RunScene;

// The project's rocking ellipsoid: semi-axes 0.2, 0.1, 0.06 m, 1 kg, tilted 0.2 rad about y, touching the ground at
// rest; mu = 1. Lifted by `lift` (m) above touching.
Model RockingEllipsoid(double lift = 0.0) {
  Model m;
  m.bodies.push_back(test_models::FixedBody("ground", MakeHalfSpace()));
  Body egg = test_models::MovingBody("egg", MakeEllipsoid(Vec3(0.2, 0.1, 0.06)), 1.0, Pose::Identity());
  egg.X_WB0.linear() = Eigen::AngleAxisd(0.2, Vec3::UnitY()).toRotationMatrix();
  Vec3 lowest;
  SupportPoint(egg.shape, egg.X_WB0, -Vec3::UnitZ(), &lowest);
  egg.X_WB0.translation() = Vec3(0, 0, lift - lowest.z());
  m.bodies.push_back(egg);
  return test_models::Finish(m, FrictionParams{1.0, 1.0, 1.0, 0.01});
}

double Energy(const Model& model, const State& s) { return KineticEnergy(model, s) + 9.81 * s.q[2]; }

struct RockingRun {
  double drift = 0.0, peak_to_peak = 0.0, max_penetration = 0.0, max_gain = 0.0;
  int nonconverged = 0;
  State end;
};

// Energy drift and peak-to-peak of a run, relative to the rocking energy of its start (above the resting energy).
RockingRun Rock(const StepperOptions& options, double duration, double lift = 0.0) {
  const Model model = RockingEllipsoid(lift);
  const double rest = 9.81 * 0.06, E0 = Energy(model, State::Initial(model));
  double E_min = E0, E_max = E0, E = E0;
  RockingRun out;
  const auto stats = RunScene(model, options, duration, [&](const Model&, const State& s, const Data&, const StepReport&) {
    E = Energy(model, s);
    E_min = std::min(E_min, E);
    E_max = std::max(E_max, E);
    out.end = s;
  });
  out.nonconverged = stats.nonconverged;
  out.max_penetration = stats.max_solver_penetration;
  out.drift = (E - E0) / (E0 - rest);
  out.peak_to_peak = (E_max - E_min) / (E0 - rest);
  out.max_gain = E_max - E0;
  return out;
}

TEST(RattleEnergy, RockingEllipsoid) {
  for (double h : {0.01, 0.001}) {
    const RockingRun r = Rock(RattleOptions(h), 10.0);
    printf("h=%g drift=%.3g ptp=%.3g pen=%.3g nc=%d\n", h, r.drift, r.peak_to_peak, r.max_penetration, r.nonconverged);
  }
}

}  // namespace
}  // namespace implicit_sim
