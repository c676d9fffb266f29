// The energy guard's balance (step/energy_guard.h) against closed forms, and the rules that keep a pair of RATTLE's
// stage 1 on its start frame (problems/rattle_position.h): only where the geometry fixes the closest points.
#include <gtest/gtest.h>

#include "implicit_sim/core/step/energy_guard.h"
#include "step/step_problems_fixture.h"
#include "test_models.h"

namespace implicit_sim {
namespace {

using test_models::MakePose;

Model BodyOnGround(const ConvexShape& shape, double height) {
  Model m;
  m.bodies.push_back(test_models::FixedBody("ground", MakeHalfSpace()));
  m.bodies.push_back(test_models::MovingBody("part", shape, 2.0, MakePose(Vec3(0, 0, height))));
  return test_models::Finish(m);
}

// One free body (a sphere far above the ground, no pair in the layout) stepped by paper eq. 2 with the velocities v1
// = v0 + h g: the kinetic energy rises by the work of gravity less m h^2 |g|^2 / 2 (backward Euler's loss).
TEST(EnergyGuard, AFreeFallStepLosesExactlyBackwardEulersShare) {
  const Model model = BodyOnGround(MakeSphere(0.1), 10.0);
  testing_support::StepProblems problems(model);
  Eigen::VectorXd unused;
  std::vector<int> new_blocks;
  problems.layout.SetActivePairs({}, nullptr, &unused, &new_blocks);
  State start = State::Initial(model);
  start.v << 0.3, -0.2, 1.5, 2.0, -1.0, 0.5;  // m/s, rad/s
  const double h = 0.01, m = 2.0, g = 9.81;
  problems.kinematics.BeginStep(start, h, nullptr);
  Eigen::VectorXd z = Eigen::VectorXd::Zero(problems.layout.size());
  z.head<6>() = start.v;
  z[2] -= h * g;  // v1 = v0 + h g; the sphere's spin stays (no torque on a sphere)
  const EnergyBalance balance = StepEnergyBalance(problems.kinematics, z, z);
  EXPECT_NEAR(balance.excess(), -0.5 * m * h * h * g * g, 1e-12);
  EXPECT_NEAR(balance.external_work, -m * g * h * z[2], 1e-12);
  EXPECT_TRUE(balance.holds());
  // One per cent more kinetic energy than the step can supply is beyond the allowance.
  Eigen::VectorXd faster = z;
  faster.head<3>() *= 1.1;
  const EnergyBalance created = StepEnergyBalance(problems.kinematics, z, faster);
  EXPECT_GT(created.excess(), created.allowance);
  EXPECT_FALSE(created.holds());
}

// The start frame of a closed pair at a given closest point of the part, with the given inequalities of the part
// active (multiplier 1) and the ground's one.
bool KeepsStartFrame(const Model& model, const Vec3& p_W, const std::vector<int>& active) {
  testing_support::StepProblems problems(model, true);
  const State start = State::Initial(model);
  problems.kinematics.BeginStep(start, 0.01, nullptr);
  const PairBlock& blk = problems.layout.blocks().at(0);
  Eigen::VectorXd z = Eigen::VectorXd::Zero(problems.layout.size());
  z.segment<3>(blk.offset + pair_index::kN) = Vec3::UnitZ();
  z[blk.offset + pair_index::kD] = 0.0;
  z[blk.normal_force()] = 1.0;
  const bool part_first = problems.layout.bodies()[blk.body1] == 1;
  z.segment<3>(blk.offset + (part_first ? pair_index::kA1 : pair_index::kA2)) = p_W;
  z.segment<3>(blk.offset + (part_first ? pair_index::kA2 : pair_index::kA1)) = Vec3(p_W.x(), p_W.y(), 0.0);
  const int part_multipliers = part_first ? blk.offset + pair_index::kAlpha : blk.beta();
  const int ground_multipliers = part_first ? blk.beta() : blk.offset + pair_index::kAlpha;
  for (int k : active) z[part_multipliers + k] = 1.0;
  z[ground_multipliers] = 1.0;
  problems.position.SetStartFrames(z, std::vector<char>(1, 1));
  return problems.position.uses_start_frame(0);
}

// The index of the box face whose outward normal (shape frame) is `normal`.
int Face(const ConvexShape& box, const Vec3& normal) {
  for (size_t k = 0; k < box.inequalities.size(); ++k) {
    if ((box.inequalities[k].X_SP.linear() * box.inequalities[k].normal - normal).norm() < 1e-12) return k;
  }
  return -1;
}

TEST(RattleStartFrames, KeptWhereTheGeometryFixesTheClosestPoints) {
  // An ellipsoid touching at its lowest point: curved both ways.
  EXPECT_TRUE(KeepsStartFrame(BodyOnGround(MakeEllipsoid(Vec3(0.2, 0.1, 0.06)), 0.06), Vec3(0, 0, 0), {0}));
  // A box on a vertex (three faces active): one point.
  const ConvexShape box = MakeBox(Vec3(0.1, 0.07, 0.05));
  const int bottom = Face(box, -Vec3::UnitZ()), front = Face(box, Vec3::UnitX()), side = Face(box, Vec3::UnitY());
  ASSERT_GE(bottom, 0);
  ASSERT_GE(front, 0);
  ASSERT_GE(side, 0);
  EXPECT_TRUE(KeepsStartFrame(BodyOnGround(box, 0.05), Vec3(0.1, 0.07, 0), {bottom, front, side}));
  // A superellipsoid's nearly flat middle (p = 8: zero curvature at the centre of its face): strictly convex, so its
  // closest point is unique (its drift limit is then a share of the bounding radius, not of the radius of curvature).
  EXPECT_TRUE(KeepsStartFrame(BodyOnGround(MakeSuperellipsoid(Vec3(0.05, 0.04, 0.02), 8), 0.02), Vec3(0, 0, 0), {0}));
}

TEST(RattleStartFrames, EndFrameWhereThePartTouchesAlongALineOrAPatch) {
  const ConvexShape box = MakeBox(Vec3(0.1, 0.07, 0.05));
  const int bottom = Face(box, -Vec3::UnitZ()), front = Face(box, Vec3::UnitX());
  EXPECT_FALSE(KeepsStartFrame(BodyOnGround(box, 0.05), Vec3(0.02, 0.01, 0), {bottom}));         // flat on a face
  EXPECT_FALSE(KeepsStartFrame(BodyOnGround(box, 0.05), Vec3(0.1, 0.01, 0), {bottom, front}));   // on an edge
  // A cylinder on its side (the infinite cylinder's inequality active, no cap).
  const ConvexShape cylinder = MakeCylinder(0.04, 0.03);
  int side = -1;
  for (size_t k = 0; k < cylinder.inequalities.size(); ++k) {
    if (cylinder.inequalities[k].kind == Inequality::Kind::kInfiniteCylinder) side = k;
  }
  ASSERT_GE(side, 0);
  Model lying = BodyOnGround(cylinder, 0.04);
  lying.bodies[1].X_WB0.linear() = test_models::Rot(M_PI / 2, Vec3::UnitX());
  EXPECT_FALSE(KeepsStartFrame(lying, Vec3(0, 0.01, 0), {side}));
}

}  // namespace
}  // namespace implicit_sim
