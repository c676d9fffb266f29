// AddWrenchAtPoint against closed forms: a force at a point off the centre of mass gives the torque r x f, a force
// and a point given in a rotated link frame are turned into the world, and a link frame offset from the centre of
// mass (Body::X_BL) moves the point of application.
#include "implicit_sim/core/model/wrench.h"

#include <cmath>
#include <stdexcept>

#include <gtest/gtest.h>

#include "test_models.h"

namespace implicit_sim {
namespace {

using test_models::MakePose;
using test_models::Rot;

constexpr double kTol = 1e-12;

// A fixed "ground" (turned half a turn about x, 1 m down), a moving "turned" body at (1, 0, 0) turned a quarter turn
// about z (slot 0) and a moving "upright" body at (0, 0, 2) (slot 1). X_BL of "turned" is given.
Model ThreeBodies(const Pose& X_BL_turned = Pose::Identity()) {
  Model m;
  m.gravity_W = Vec3::Zero();
  m.bodies.push_back(
      test_models::FixedBody("ground", MakeHalfSpace(), MakePose(Vec3(0, 0, -1), Rot(kPi, Vec3::UnitX()))));
  m.bodies.push_back(test_models::MovingBody("turned", MakeSphere(0.1), 1.0,
                                             MakePose(Vec3(1, 0, 0), Rot(0.5 * kPi, Vec3::UnitZ()))));
  m.bodies.back().X_BL = X_BL_turned;
  m.bodies.push_back(test_models::MovingBody("upright", MakeSphere(0.1), 1.0, MakePose(Vec3(0, 0, 2))));
  return test_models::Finish(m);
}

struct Wrench {
  Vec3 f_W, tau_W;
};

Wrench Slot(const Eigen::VectorXd& wrench_W, int slot) {
  return {wrench_W.segment<3>(Model::v_offset(slot)), wrench_W.segment<3>(Model::v_offset(slot) + 3)};
}

TEST(Wrench, WorldForceAtAnOffsetPointGivesTheLeverArmTorque) {
  const Model model = ThreeBodies();
  const State state = State::Initial(model);
  Eigen::VectorXd wrench_W = Eigen::VectorXd::Ones(model.nv());  // the wrench is added to what is there
  // At p_WP = (0, 2, 2) on "upright" (centre of mass (0, 0, 2)): r = (0, 2, 0), f = (0, 0, 3): r x f = (6, 0, 0).
  AddWrenchAtPoint(model, state, model.FindBody("upright"), -1, Vec3(0, 2, 2), Vec3(0, 0, 3), Vec3(0.5, 0, 0),
                   &wrench_W);
  const Wrench upright = Slot(wrench_W, 1);
  EXPECT_TRUE(upright.f_W.isApprox(Vec3(1, 1, 4), kTol)) << upright.f_W.transpose();
  EXPECT_TRUE(upright.tau_W.isApprox(Vec3(1 + 0.5 + 6, 1, 1), kTol)) << upright.tau_W.transpose();
  EXPECT_TRUE(wrench_W.head<6>().isApprox(Eigen::VectorXd::Ones(6), kTol));  // the other body: untouched
}

TEST(Wrench, ForcePointAndTorqueInARotatedLinkFrameAreTurnedIntoTheWorld) {
  const Model model = ThreeBodies();
  const State state = State::Initial(model);
  Eigen::VectorXd wrench_W = Eigen::VectorXd::Zero(model.nv());
  const int turned = model.FindBody("turned");
  // R_WL turns x into y: f_L = (1, 0, 0) -> f_W = (0, 1, 0); p_LP = (2, 0, 1) -> r = (0, 2, 1); tau_L = (1, 0, 0) ->
  // (0, 1, 0). r x f_W = (-1, 0, 0).
  AddWrenchAtPoint(model, state, turned, turned, Vec3(2, 0, 1), Vec3(1, 0, 0), Vec3(1, 0, 0), &wrench_W);
  const Wrench w = Slot(wrench_W, 0);
  EXPECT_TRUE(w.f_W.isApprox(Vec3(0, 1, 0), kTol)) << w.f_W.transpose();
  EXPECT_NEAR((w.tau_W - Vec3(-1, 1, 0)).norm(), 0.0, kTol) << w.tau_W.transpose();
  EXPECT_TRUE(wrench_W.tail<6>().isZero());
}

TEST(Wrench, ALinkFrameOffsetFromTheCentreOfMassMovesThePointOfApplication) {
  // L sits 0.5 m along x of B and is turned a quarter turn about x of B: p_WL = (1, 0, 0) + R_WB (0.5, 0, 0) =
  // (1, 0.5, 0), and f_L = (0, 2, 0) -> R_WB R_BL f_L = R_WB (0, 0, 2) = (0, 0, 2).
  const Model model = ThreeBodies(MakePose(Vec3(0.5, 0, 0), Rot(0.5 * kPi, Vec3::UnitX())));
  const State state = State::Initial(model);
  Eigen::VectorXd wrench_W = Eigen::VectorXd::Zero(model.nv());
  const int turned = model.FindBody("turned");
  EXPECT_TRUE(state.X_WL(model, turned).translation().isApprox(Vec3(1, 0.5, 0), kTol));
  AddWrenchAtPoint(model, state, turned, turned, Vec3::Zero(), Vec3(0, 2, 0), Vec3::Zero(), &wrench_W);
  const Wrench w = Slot(wrench_W, 0);
  EXPECT_TRUE(w.f_W.isApprox(Vec3(0, 0, 2), kTol)) << w.f_W.transpose();
  // r = (0, 0.5, 0), f = (0, 0, 2): r x f = (1, 0, 0).
  EXPECT_NEAR((w.tau_W - Vec3(1, 0, 0)).norm(), 0.0, kTol) << w.tau_W.transpose();
}

TEST(Wrench, AnotherBodysFrameExpressesTheWrench) {
  const Model model = ThreeBodies();
  const State state = State::Initial(model);
  Eigen::VectorXd wrench_W = Eigen::VectorXd::Zero(model.nv());
  // The ground's frame is turned half a turn about x, 1 m down: p_FP = (0, 0, 1) -> p_WP = (0, 0, -2) and
  // f_F = (0, 1, 0) -> (0, -1, 0). On "upright" (centre (0, 0, 2)): r = (0, 0, -4), r x f = (-4, 0, 0).
  AddWrenchAtPoint(model, state, model.FindBody("upright"), model.FindBody("ground"), Vec3(0, 0, 1), Vec3(0, 1, 0),
                   Vec3::Zero(), &wrench_W);
  const Wrench w = Slot(wrench_W, 1);
  EXPECT_TRUE(w.f_W.isApprox(Vec3(0, -1, 0), kTol)) << w.f_W.transpose();
  EXPECT_NEAR((w.tau_W - Vec3(-4, 0, 0)).norm(), 0.0, kTol) << w.tau_W.transpose();
}

TEST(Wrench, RefusesAFixedBodyAnUnknownFrameAndAWrongSize) {
  const Model model = ThreeBodies();
  const State state = State::Initial(model);
  Eigen::VectorXd wrench_W = Eigen::VectorXd::Zero(model.nv());
  const Vec3 zero = Vec3::Zero();
  EXPECT_THROW(AddWrenchAtPoint(model, state, model.FindBody("ground"), -1, zero, zero, zero, &wrench_W),
               std::invalid_argument);
  EXPECT_THROW(AddWrenchAtPoint(model, state, 1, 7, zero, zero, zero, &wrench_W), std::invalid_argument);
  Eigen::VectorXd short_W = Eigen::VectorXd::Zero(6);
  EXPECT_THROW(AddWrenchAtPoint(model, state, 1, -1, zero, zero, zero, &short_W), std::invalid_argument);
}

}  // namespace
}  // namespace implicit_sim
