// A planar body (Body::locked: the out-of-plane velocities) on a flat ground. Two things left its dense Newton matrix
// singular at every step of P1 (503 Levenberg-Marquardt fallbacks in the disc's 500 steps, 4 406 on the 100-gon):
// the closest points along its line contact, which no row determines (now the minimum-norm direction of
// semismooth_newton.h), and the friction components whose rates read only locked velocities, along o (out of the
// plane) and the torsion about n, whose fractions were free while the disc stuck and could take a share of the
// friction ellipsoid from the in-plane direction (now s = 0, rows/friction_rows.h).
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "implicit_sim/core/model/urdf_loader.h"
#include "implicit_sim/core/ncp/fischer_burmeister.h"
#include "implicit_sim/core/step/rows/friction_rows.h"
#include "implicit_sim/core/step/time_stepper.h"
#include "scenario_runner.h"

namespace implicit_sim {
namespace {

// Which components count as locked, on the P1 disc (y, rx, rz locked) touching the ground below its centre.
TEST(LockedFriction, AComponentIsLockedWhenItsRateReadsOnlyLockedVelocities) {
  const Model model = LoadSceneFromFile(testing_support::ScenePath("p1_disc_rolling.urdf"));
  const StepLayout layout(model);
  BodyEnd disc, ground;
  disc.col = 0;  // the disc's velocities; the ground is fixed (col -1)
  const Vec3 r(0, 0, -1), zero = Vec3::Zero();  // lever from the disc's centre to the contact (m)
  const auto along = [&](const Vec3& u) {
    return FrictionComponentLocked(layout, disc, u, r.cross(u), ground, u, zero);
  };
  EXPECT_FALSE(along(Vec3::UnitX()));                               // t: in the plane
  EXPECT_TRUE(along(Vec3::UnitY()));                                // o: out of the plane
  EXPECT_TRUE(along(Vec3(1e-12, 1.0, 0.0)));                        // o of a normal off z by rounding
  EXPECT_FALSE(along(Vec3(0.0, std::cos(0.1), std::sin(0.1))));     // o of a tilted ground
  EXPECT_TRUE(FrictionComponentLocked(layout, disc, zero, Vec3::UnitZ(), ground, zero, zero));   // torsion about n
  EXPECT_FALSE(FrictionComponentLocked(layout, disc, zero, Vec3::UnitY(), ground, zero, zero));  // rolling about y
}

// A locked component's slip row is s_k = 0 with the same Jacobian entries (1 on its diagonal, 0 on sigma); the others
// keep rate_k + s_k slip, and the ellipsoid row still reads every fraction.
TEST(LockedFriction, ALockedComponentsRowIsItsFraction) {
  FrictionRows rows;
  rows.first_row = 0;
  rows.count = 3;
  rows.sigma = 3;
  const double rate[3] = {0.3, 0.2, 0.1}, fraction[3] = {0.4, 0.5, 0.6};
  for (int k = 0; k < 3; ++k) {
    rows.rate[k] = rate[k];
    rows.s[k] = fraction[k];
  }
  rows.slip = rows.sigma_value = 0.7;
  rows.zeta = 1.0 - 0.16 - 0.25 - 0.36;
  rows.locked[1] = true;
  rows.projected = false;
  NcpEvalMode mode;
  mode.regularization = 1e-9;
  Eigen::VectorXd Phi = Eigen::VectorXd::Zero(4);
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(4, 4);
  const std::vector<char> no_locked_velocities;
  const auto no_rate_gradient = [](int, int, double) {};
  AddFrictionRows(rows, RowWriter(mode, &Phi, &J, nullptr, no_locked_velocities), RateGradient(no_rate_gradient));
  EXPECT_EQ(Phi[1], 0.5);
  EXPECT_EQ(J.row(1), Eigen::RowVector4d(0, 1, 0, 0));
  EXPECT_DOUBLE_EQ(Phi[0], 0.3 + 0.4 * 0.7);
  EXPECT_DOUBLE_EQ(J(0, 0), 0.7 + 1e-9);
  EXPECT_DOUBLE_EQ(J(0, 3), 0.4);
  EXPECT_DOUBLE_EQ(J(3, 1), -2.0 * FischerBurmeister(0.7, rows.zeta, 0.0, false).db * 0.5);
}

TEST(LockedFriction, PlanarContactsNeedNoLeastSquaresAndHoldZeroOutOfPlane) {
  for (const char* scene : {"p1_disc_rolling.urdf", "p1_ngon10.urdf"}) {
    for (const StepperOptions::Scheme scheme : {StepperOptions::Scheme::kPaper, StepperOptions::Scheme::kRattle}) {
      SCOPED_TRACE(std::string(scene) + (scheme == StepperOptions::Scheme::kPaper ? ", paper" : ", rattle"));
      const Model model = LoadSceneFromFile(testing_support::ScenePath(scene));
      StepperOptions options;
      options.scheme = scheme;
      Data data(model);
      State state = State::Initial(model);
      for (int i = 0; i < 100; ++i) ASSERT_TRUE(Step(model, options, &state, &data).converged) << "step " << i;
      // The disc never needs the LM direction; the 10-gon at a few vertex impacts, where the minimum-norm direction
      // does not decrease the merit (4 with the paper's scheme, 8 with RATTLE's two stages; 366 before, paper).
      EXPECT_LE(data.lm_fallbacks(), std::string(scene) == "p1_disc_rolling.urdf" ? 0 : 10);
      ASSERT_FALSE(data.layout.blocks().empty());
      for (const PairBlock& blk : data.layout.blocks()) {
        EXPECT_LE(std::abs(data.z[blk.offset + pair_index::kSo]), 1e-15);
        EXPECT_LE(std::abs(data.z[blk.offset + pair_index::kSr]), 1e-15);
      }
    }
  }
}

// The in-plane friction keeps the whole Coulomb limit: a planar box pushed along the ground by 0.95 mu m g stays put,
// by 1.2 mu m g it accelerates at (F - mu m g) / m, with either scheme.
TEST(LockedFriction, APlanarBoxSticksBelowAndSlidesAboveTheCoulombLimit) {
  const std::string urdf = R"(<?xml version="1.0"?>
<robot name="planar_box">
  <implicit_sim gravity="0 0 -9.81">
    <friction mu="0.5" e_t="1" e_o="1" e_r="0.1"/>
    <body link="box" locked="y rx rz"/>
  </implicit_sim>
  <link name="world"/>
  <link name="ground">
    <collision><geometry><box size="4 4 0.001"/></geometry><implicit type="halfspace"/></collision>
  </link>
  <joint name="ground_joint" type="fixed"><parent link="world"/><child link="ground"/></joint>
  <link name="box">
    <inertial><mass value="2"/><inertia ixx="0.0133" ixy="0" ixz="0" iyy="0.0133" iyz="0" izz="0.0133"/></inertial>
    <collision><geometry><box size="0.2 0.2 0.2"/></geometry></collision>
  </link>
  <joint name="box_joint" type="floating"><parent link="world"/><child link="box"/><origin xyz="0 0 0.1"/></joint>
</robot>)";
  const Model model = LoadSceneFromString(urdf, "planar_box");
  const double m = 2.0, mu = 0.5, g = 9.81, h = 0.01;
  const int steps = 50;
  for (const StepperOptions::Scheme scheme : {StepperOptions::Scheme::kPaper, StepperOptions::Scheme::kRattle}) {
    for (const double share : {0.95, 1.2}) {
      SCOPED_TRACE("F = " + std::to_string(share) + " mu m g, scheme " + std::to_string(static_cast<int>(scheme)));
      StepperOptions options;
      options.scheme = scheme;
      options.h = h;
      Data data(model);
      State state = State::Initial(model);
      Eigen::VectorXd wrench = Eigen::VectorXd::Zero(model.nv());
      wrench[0] = share * mu * m * g;  // N along x, at the centre of mass
      for (int i = 0; i < steps; ++i) ASSERT_TRUE(Step(model, options, &state, &data, &wrench).converged);
      const double expected_v = share > 1.0 ? (share - 1.0) * mu * g * steps * h : 0.0;  // m/s
      EXPECT_NEAR(state.v[0], expected_v, 1e-6 * (1.0 + expected_v));
      if (share < 1.0) EXPECT_LT(std::abs(state.q[0]), 1e-9);
      EXPECT_EQ(data.lm_fallbacks(), 0);
    }
  }
}

}  // namespace
}  // namespace implicit_sim
