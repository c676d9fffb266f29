// The second-order RATTLE step (StepperOptions::Scheme::kRattle; doc/method.md, "The second-order step") on smooth
// motion: a rocking ellipsoid, a tumbling one, the convergence order, a drop, a pendulum. Energy of smooth motion
// oscillates about its true value (bounded both ways); impacts only dissipate.
#include <algorithm>
#include <cmath>
#include <cstdio>

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
  SupportPoint(egg.shapes[0], egg.X_WB0, -Vec3::UnitZ(), &lowest);
  egg.X_WB0.translation() = Vec3(0, 0, lift - lowest.z());
  m.bodies.push_back(egg);
  return test_models::Finish(m, FrictionParams{1.0, 1.0, 1.0, 0.01});
}

double Energy(const Model& model, const State& s) { return KineticEnergy(model, s) + 9.81 * s.q[2]; }

struct RockingRun {
  double drift = 0.0, peak_to_peak = 0.0, max_penetration = 0.0, max_gain = 0.0;
  int nonconverged = 0, damping_steps = 0;
  State end;
};

// Energy drift and peak-to-peak of a run, relative to the rocking energy of its start (above the resting energy).
RockingRun Rock(const StepperOptions& options, double duration, double lift = 0.0) {
  const Model model = RockingEllipsoid(lift);
  const double rest = 9.81 * 0.06, E0 = Energy(model, State::Initial(model));
  double E_min = E0, E_max = E0, E = E0;
  RockingRun out;
  const auto stats = RunScene(model, options, duration, [&](const Model&, const State& s, const Data&,
                                                            const StepReport& report) {
    out.damping_steps += report.damping_steps;
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

// The bars (README, "Smooth motion"): drift at 10 s within 5e-3 / 1e-5 of the rocking energy, peak-to-peak within
// 2e-2 / 3e-4, no penetration. Measured -2.45e-3 / -4.86e-6 and 1.40e-2 / 1.39e-4, as an independent statement of
// the same step in Python predicts (-2.5e-3, 1.4e-2; -4.9e-6, 1.4e-4; doc/method.md). The paper's step keeps none of
// it at h = 0.01 and 0.9 % at h = 0.001 (test_time_stepper.cpp).
TEST(RattleEnergy, RockingEllipsoidKeepsItsEnergyToSecondOrder) {
  const double drift_bar[2] = {5e-3, 1e-5}, peak_bar[2] = {2e-2, 3e-4};
  const double hs[2] = {0.01, 0.001};
  for (int i = 0; i < 2; ++i) {
    const RockingRun r = Rock(RattleOptions(hs[i]), 10.0);
    std::printf("[ rattle ] rocking ellipsoid h = %g: drift %.3g, peak-to-peak %.3g of the rocking energy, "
                "penetration %.2g m\n", hs[i], r.drift, r.peak_to_peak, r.max_penetration);
    EXPECT_EQ(r.nonconverged, 0);
    EXPECT_EQ(r.damping_steps, 0);  // smooth rocking is resolved: never damped as a motion of period 2 h
    EXPECT_LE(std::abs(r.drift), drift_bar[i]) << "h = " << hs[i];
    EXPECT_LE(r.peak_to_peak, peak_bar[i]) << "h = " << hs[i];
    EXPECT_GT(r.peak_to_peak, 0.01 * peak_bar[i]) << "h = " << hs[i];  // it oscillates, as a symplectic step does
    EXPECT_LE(r.max_penetration, 1e-8);
    EXPECT_GE(r.end.q[2], 0.0);  // independent check: the centre stays above the ground
  }
}

// Independent check of non-penetration on the rocking run: the ellipsoid's lowest point (support function, closed
// form) never goes below the ground plane by more than 1e-8 m.
TEST(RattleEnergy, RockingEllipsoidNeverPenetratesByItsSupportPoint) {
  const Model model = RockingEllipsoid();
  double lowest_z = 1.0;
  RunScene(model, RattleOptions(0.01), 3.0, [&](const Model& m, const State& s, const Data&, const StepReport&) {
    Vec3 lowest;
    SupportPoint(m.bodies[1].shapes[0], s.X_WB(m, 1), -Vec3::UnitZ(), &lowest);
    lowest_z = std::min(lowest_z, lowest.z());
  });
  EXPECT_GE(lowest_z, -1e-8);
  EXPECT_LE(lowest_z, 1e-6);  // it stays in contact
}

// A torque-free tumbling ellipsoid near its unstable intermediate axis: the variational rotation row conserves the
// angular momentum and (Moser-Veselov) the kinetic energy to round-off; the paper's step loses 7 % at h = 0.01.
TEST(RattleEnergy, TumblingEllipsoidConservesEnergyAndMomentum) {
  Model m;
  m.gravity_W = Vec3::Zero();
  m.bodies.push_back(test_models::MovingBody("egg", MakeEllipsoid(Vec3(0.3, 0.2, 0.1)), 1.0, Pose::Identity()));
  m.bodies.back().w_WB0 = Vec3(0.1, 3.0, 0.2);
  const Model model = test_models::Finish(m);
  const Mat3 I_B = model.bodies[0].I_B;
  auto momentum = [&](const State& s) {
    const Mat3 R = s.X_WB(model, 0).linear();
    return Vec3(R * I_B * R.transpose() * s.w_WB(0));
  };
  for (double h : {0.01, 0.001}) {
    const State initial = State::Initial(model);
    const double E0 = KineticEnergy(model, initial);
    const Vec3 L0 = momentum(initial);
    double dE = 0.0, dL = 0.0, w_y_min = 10.0;
    RunScene(model, RattleOptions(h), 10.0, [&](const Model& mm, const State& s, const Data&, const StepReport& r) {
      ASSERT_TRUE(r.converged);
      dE = std::max(dE, std::abs(KineticEnergy(mm, s) / E0 - 1.0));
      dL = std::max(dL, (momentum(s) - L0).norm() / L0.norm());
      w_y_min = std::min(w_y_min, s.X_WB(mm, 0).linear().col(1).dot(s.w_WB(0)));
    });
    std::printf("[ rattle ] tumbling ellipsoid h = %g: |dE/E| %.2g, |dL|/|L| %.2g\n", h, dE, dL);
    EXPECT_LE(dE, 1e-12) << "h = " << h;
    EXPECT_LE(dL, 1e-12) << "h = " << h;
    EXPECT_LT(w_y_min, 0.0) << "h = " << h;  // it flips about the intermediate axis (the motion is not trivial)
  }
}

// The order of the step on the rocking ellipsoid over 2 s: the end state's error against a run at h / 32 halves by
// 4 when h halves. (The paper's step is first order, but at these steps it damps the rocking away within the 2 s, so
// its errors are not yet in the asymptotic range.)
double RockingError(const StepperOptions& options, const State& reference) {
  const State end = Rock(options, 2.0).end;
  return (end.q - reference.q).norm() + 0.1 * (end.v - reference.v).norm();
}

TEST(RattleEnergy, SecondOrderOnTheRockingEllipsoid) {
  const double h = 0.004;
  const State reference = Rock(RattleOptions(h / 32), 2.0).end;
  const double e1 = RockingError(RattleOptions(h), reference), e2 = RockingError(RattleOptions(h / 2), reference);
  const double order = std::log2(e1 / e2);
  std::printf("[ rattle ] order on the rocking ellipsoid: %.3f (errors %.3g, %.3g)\n", order, e1, e2);
  EXPECT_NEAR(order, 2.0, 0.1);
}

// Dropped 5 cm: the landing dissipates (restitution 0), and energy never rises above its start; no penetration.
TEST(RattleEnergy, DroppedEllipsoidNeverGainsEnergyAndNeverPenetrates) {
  for (double h : {0.01, 0.001}) {
    const Model model = RockingEllipsoid(0.05);
    const double E0 = Energy(model, State::Initial(model));
    double max_gain = -1.0, lowest_z = 1.0;
    const auto stats = RunScene(model, RattleOptions(h), 3.0,
                                [&](const Model& m, const State& s, const Data&, const StepReport&) {
      max_gain = std::max(max_gain, Energy(m, s) - E0);
      Vec3 lowest;
      SupportPoint(m.bodies[1].shapes[0], s.X_WB(m, 1), -Vec3::UnitZ(), &lowest);
      lowest_z = std::min(lowest_z, lowest.z());
    });
    std::printf("[ rattle ] dropped ellipsoid h = %g: largest energy gain %.3g J, lowest point %.3g m\n", h, max_gain,
                lowest_z);
    EXPECT_EQ(stats.nonconverged, 0);
    EXPECT_LE(max_gain, 1e-9) << "h = " << h;
    EXPECT_GE(lowest_z, -1e-8) << "h = " << h;
    EXPECT_LE(stats.max_solver_penetration, 1e-8);
  }
}

// A cylinder landing on its flat end rings there: its one contact point jumps between the rim's sides, the tilt rate
// flips sign every step, and a second-order step keeps that energy (measured: 0.02 rad/s after 2 s at h = 0.005,
// against round-off under the paper's step). Two reversals in a row make the island take the paper's step, which
// damps the ringing to rest and then holds the cylinder there without a Newton iteration. Independent checks: the
// cylinder ends upright at its resting height, and its rim never goes below the ground.
TEST(RattleEnergy, RingingOnAFlatFaceIsDampedToRestAndHeldWithoutIterations) {
  Model m;
  m.bodies.push_back(test_models::FixedBody("ground", MakeHalfSpace()));
  Pose X_WB = Pose::Identity();
  X_WB.linear() = Eigen::AngleAxisd(0.05, Vec3(1, 1, 0).normalized()).toRotationMatrix();
  X_WB.translation() = Vec3(0, 0, 0.08);
  Body can = test_models::MovingBody("can", MakeCylinder(0.04, 0.03), 0.3, X_WB);
  can.w_WB0 = Vec3(0.5, -0.3, 2.0);
  m.bodies.push_back(can);
  const Model model = test_models::Finish(m, FrictionParams{0.5, 1.0, 1.0, 0.01});
  const double h = 0.005;
  int damping_steps = 0, iterations_at_rest = 0, steps = 0;
  double lowest_z = 1.0;
  State end;
  const auto stats = RunScene(model, RattleOptions(h), 2.0, [&](const Model& mm, const State& s, const Data&,
                                                               const StepReport& report) {
    end = s;
    damping_steps += report.damping_steps;
    if (++steps > 350) iterations_at_rest += report.iterations;  // the last 50 steps
    for (double sign : {-1.0, 1.0}) {  // the rims' lowest points (closed form for a cylinder)
      const Pose X = s.X_WB(mm, 1);
      const Vec3 axis = X.linear().col(2);
      const Vec3 down = -Vec3::UnitZ() - axis * axis.dot(-Vec3::UnitZ());
      const Vec3 across = down.norm() > 1e-12 ? Vec3(0.04 * down.normalized()) : Vec3::Zero();
      const Vec3 rim = X.translation() + sign * 0.03 * axis + across;
      lowest_z = std::min(lowest_z, rim.z());
    }
  });
  std::printf("[ rattle ] cylinder on its end: %d damping steps, end speed %.3g m/s, %.3g rad/s, %d iterations in "
              "the last 50 steps\n", damping_steps, end.v_WB(0).norm(), end.w_WB(0).norm(), iterations_at_rest);
  EXPECT_EQ(stats.nonconverged, 0);
  EXPECT_GT(damping_steps, 0);
  EXPECT_LE(end.v_WB(0).norm(), 1e-9);
  EXPECT_LE(end.w_WB(0).norm(), 1e-8);
  EXPECT_EQ(iterations_at_rest, 0);
  EXPECT_NEAR(std::abs(end.X_WB(model, 1).linear()(2, 2)), 1.0, 1e-9);  // on an end face
  EXPECT_NEAR(end.q[2], 0.03, 1e-8);                                      // at its resting height
  EXPECT_GE(lowest_z, -1e-8);
}

}  // namespace
}  // namespace implicit_sim
