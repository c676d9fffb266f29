// RATTLE's energy check (doc/method.md, "The second-order step", energy check; FindEnergyGain in time_stepper.cpp):
// a converged two-stage step that gains energy is a spurious solution, rejected and solved again. The case is drop
// 11 of examples/monte_carlo_drop.py --scheme rattle (seed 1): a rounded box tipping onto a face, whose warm-started
// step from t = 0.305 s converged to a stage-1 root with a 703 N impulse at the previous contact point, which spun
// the box up to 510 rad/s (0.29 J to 53 J).
#include <cmath>

#include <gtest/gtest.h>

#include "implicit_sim/core/model/urdf_loader.h"
#include "implicit_sim/core/step/time_stepper.h"

namespace implicit_sim {
namespace {

// examples/monte_carlo_drop.py's scene: a superellipsoid of half extents 0.05 x 0.035 x 0.025 m, exponent 10,
// 0.5 kg, on the ground plane z = 0, mu = 0.5, e_t = e_o = 1, e_r = 0.01 m.
constexpr const char* kPartDropUrdf = R"(<?xml version="1.0"?>
<robot name="part_drop">
  <implicit_sim gravity="0 0 -9.81">
    <friction mu="0.5" e_t="1" e_o="1" e_r="0.01"/>
  </implicit_sim>
  <link name="world"/>
  <link name="ground">
    <collision>
      <geometry><box size="4 4 0.001"/></geometry>
      <implicit type="halfspace"/>
    </collision>
  </link>
  <joint name="ground_joint" type="fixed">
    <parent link="world"/>
    <child link="ground"/>
  </joint>
  <link name="part">
    <collision>
      <geometry><box size="0.1 0.07 0.05"/></geometry>
      <implicit type="superellipsoid" semi_axes="0.05 0.035 0.025" exponent="10.0" mass="0.5"/>
    </collision>
  </link>
  <joint name="part_joint" type="floating">
    <parent link="world"/>
    <child link="part"/>
    <origin xyz="0 0 1"/>
  </joint>
</robot>
)";

// Drop 11's release (draw_drop(11) of the example, seed 1): lowest point 0.1 m above the ground, at rest but spinning.
State ReleaseOfDrop11(const Model& model) {
  State s = State::Initial(model);
  s.q << 0.0, 0.0, 0.15968266330772957, 0.5329758893548291, -0.0020150189810209046, -0.8100008532804656,
      0.2446042901296966;
  s.v << 0.0, 0.0, 0.0, 0.018169508012117353, -1.432937992165854, 1.4542472260941468;
  return s;
}

// Kinetic plus gravitational energy (J).
double MechanicalEnergy(const Model& model, const State& s) { return KineticEnergy(model, s) + 0.5 * 9.81 * s.q[2]; }

TEST(RattleEnergyCheck, RejectsTheSpuriousRootOfTheTippingBox) {
  const Model model = LoadSceneFromString(kPartDropUrdf, "part_drop");
  StepperOptions options;
  options.h = 0.005;
  options.scheme = StepperOptions::Scheme::kRattle;
  State state = ReleaseOfDrop11(model);
  Data data(model);
  for (int k = 0; k < 61; ++k) ASSERT_TRUE(Step(model, options, &state, &data).converged) << "step " << k;
  ASSERT_NEAR(state.t, 0.305, 1e-12);
  const double before = MechanicalEnergy(model, state);
  const StepReport report = Step(model, options, &state, &data);
  const double after = MechanicalEnergy(model, state);
  std::printf("t = 0.305 s -> 0.310 s: energy %.6g J -> %.6g J, |w| %.4g rad/s, %d iterations, %d energy rejections\n",
              before, after, state.w_WB(0).norm(), report.iterations, report.energy_rejections);
  EXPECT_TRUE(report.converged);
  EXPECT_GE(report.energy_rejections, 1);  // the warm-started solve lands on the spurious root
  EXPECT_LT(after - before, 1e-3);         // was +52.7 J
  EXPECT_LT(state.w_WB(0).norm(), 50.0);   // was 510 rad/s
}

// The drop from release to 1 s: no step gains more than a small share of the energy it moves.
TEST(RattleEnergyCheck, TippingBoxNeverGainsEnergy) {
  const Model model = LoadSceneFromString(kPartDropUrdf, "part_drop");
  StepperOptions options;
  options.h = 0.005;
  options.scheme = StepperOptions::Scheme::kRattle;
  State state = ReleaseOfDrop11(model);
  Data data(model);
  const double release = MechanicalEnergy(model, state);
  double highest = release;
  int nonconverged = 0;
  while (state.t < 1.0 - 1e-12) {
    const StepReport report = Step(model, options, &state, &data);
    ASSERT_TRUE(report.advanced);
    nonconverged += !report.converged;
    highest = std::max(highest, MechanicalEnergy(model, state));
  }
  EXPECT_EQ(nonconverged, 0);
  EXPECT_LT(highest - release, 1e-3);
}

}  // namespace
}  // namespace implicit_sim
