// The force-torque sensor (<implicit_sim><sensor type='force_torque' joint=...>, step/sensors.h) against closed forms:
// a hanging chain's joints carry the weight below them, an arm resting on its joint limit or held by an effort reads
// the moment of its weight (and nothing where the ground carries it), and a swinging pendulum's pivot the centripetal
// and tangential reaction m (a_cm - g).
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "implicit_sim/core/io/scene_edit.h"
#include "implicit_sim/core/model/joints.h"
#include "implicit_sim/core/model/urdf_loader.h"
#include "implicit_sim/core/step/sensors.h"
#include "implicit_sim/core/step/time_stepper.h"

namespace implicit_sim {
namespace {

constexpr double kFtGravity = 9.81;  // m/s^2

// A link of mass m (kg) whose centre of mass sits at `com` (link frame) with a small sphere there.
std::string FtArmLink(const std::string& name, double mass, const std::string& com) {
  return "<link name='" + name + "'><inertial><origin xyz='" + com + "'/><mass value='" + std::to_string(mass) +
         "'/><inertia ixx='0.001' iyy='0.001' izz='0.001' ixy='0' ixz='0' iyz='0'/></inertial><collision><origin "
         "xyz='" + com + "'/><geometry><sphere radius='0.02'/></geometry></collision></link>";
}

std::string FtJoint(const std::string& name, const std::string& type, const std::string& parent,
                    const std::string& child, const std::string& xyz, const std::string& extra = "") {
  return "<joint name='" + name + "' type='" + type + "'><parent link='" + parent + "'/><child link='" + child +
         "'/><origin xyz='" + xyz + "'/><axis xyz='0 1 0'/>" + extra + "</joint>";
}

// Two links hanging from a pivot at z = 2 m: 'upper' (2 kg, centre 0.5 m below its joint), 'lower' (1 kg, 0.3 m
// below its joint, which is 1 m below the pivot), with force-torque sensors on both joints.
std::string HangingChain() {
  return "<robot name='chain'><implicit_sim><sensor name='ft_top' type='force_torque' joint='top' rate='100'/>"
         "<sensor name='ft_elbow' type='force_torque' joint='elbow'/></implicit_sim><link name='world'/>" +
         FtArmLink("upper", 2.0, "0 0 -0.5") + FtArmLink("lower", 1.0, "0 0 -0.3") +
         FtJoint("top", "continuous", "world", "upper", "0 0 2") +
         FtJoint("elbow", "continuous", "upper", "lower", "0 0 -1") + "</robot>";
}

// A 1 kg arm along x (centre 0.5 m out) on a pivot about y at z = 1 m (revolute with joint_extra's limit, else
// continuous): gravity turns it towards +q.
std::string HorizontalArm(const std::string& joint_extra, const std::string& sim_extra,
                          const std::string& sensor = "<sensor name='ft' type='force_torque' joint='pivot'/>") {
  return "<robot name='arm'><implicit_sim>" + sensor + sim_extra + "</implicit_sim><link name='world'/>" +
         FtArmLink("arm", 1.0, "0.5 0 0") +
         FtJoint("pivot", joint_extra.empty() ? "continuous" : "revolute", "world", "arm", "0 0 1", joint_extra) +
         "</robot>";
}

ForceTorqueReading StepAndRead(const Model& model, int sensor, int steps, const Eigen::VectorXd* wrench_W = nullptr,
                               const Eigen::VectorXd* efforts = nullptr) {
  Data data(model);
  State state = State::Initial(model), before = state;
  StepperOptions options;  // the defaults: RATTLE
  for (int i = 0; i < steps; ++i) {
    before = state;
    EXPECT_TRUE(Step(model, options, &state, &data, wrench_W).converged) << "step " << i;
  }
  std::vector<char> subtree;
  return ReadForceTorque(model, model.sensors[sensor], before, state, options.h, options.scheme, data.contacts,
                         wrench_W, efforts, &subtree);
}

TEST(ForceTorqueSensor, EachJointOfAHangingChainCarriesTheWeightBelowIt) {
  const Model model = LoadSceneFromString(HangingChain(), "chain");
  ASSERT_EQ(model.sensors.size(), 2u);
  EXPECT_EQ(model.sensors[0].link, "upper");
  EXPECT_EQ(model.sensors[0].joint, model.FindJoint("top"));
  EXPECT_EQ(model.sensors[0].rate_hz, 100.0);
  const ForceTorqueReading top = StepAndRead(model, 0, 50);
  const ForceTorqueReading elbow = StepAndRead(model, 1, 50);
  EXPECT_LT((top.force_L - Vec3(0, 0, 3.0 * kFtGravity)).norm(), 1e-8) << top.force_L.transpose();
  EXPECT_LT((elbow.force_L - Vec3(0, 0, 1.0 * kFtGravity)).norm(), 1e-8) << elbow.force_L.transpose();
  EXPECT_LT(top.torque_L.norm(), 1e-8) << top.torque_L.transpose();  // every weight hangs straight below
  EXPECT_LT(elbow.torque_L.norm(), 1e-8) << elbow.torque_L.transpose();
}

TEST(ForceTorqueSensor, AnArmOnItsLimitOrHeldByAnEffortReadsTheMomentOfItsWeight) {
  // The joint's moment on the arm about the pivot: -(0.5 x) x (-m g z).
  const Vec3 weight_moment(0, -0.5 * kFtGravity, 0);
  {
    SCOPED_TRACE("on the upper limit 0");
    const Model model = LoadSceneFromString(
        HorizontalArm("<limit lower='-1' upper='0' effort='100' velocity='1'/>", ""), "arm");
    const ForceTorqueReading reading = StepAndRead(model, 0, 50);
    EXPECT_LT((reading.force_L - Vec3(0, 0, kFtGravity)).norm(), 1e-8) << reading.force_L.transpose();
    EXPECT_LT((reading.torque_L - weight_moment).norm(), 1e-8) << reading.torque_L.transpose();
  }
  {
    SCOPED_TRACE("the scene's constant effort");
    const Model model = LoadSceneFromString(
        HorizontalArm("", "<joint name='pivot' position='0' velocity='0' effort='-4.905'/>"), "arm");
    const ForceTorqueReading reading = StepAndRead(model, 0, 50);
    EXPECT_LT((reading.force_L - Vec3(0, 0, kFtGravity)).norm(), 1e-8) << reading.force_L.transpose();
    EXPECT_LT((reading.torque_L - weight_moment).norm(), 1e-8) << reading.torque_L.transpose();
  }
  {
    SCOPED_TRACE("resting on the ground under its centre of mass: the contact carries the weight, the joint nothing");
    std::string urdf = HorizontalArm("", "");
    urdf.replace(urdf.find("</robot>"), 8,
                 "<link name='ground'><collision><geometry><box size='4 4 0.001'/></geometry><implicit "
                 "type='halfspace'/></collision></link>" + FtJoint("ground_joint", "fixed", "world", "ground",
                                                                  "0 0 0.98") + "</robot>");
    const Model model = LoadSceneFromString(urdf, "arm_on_ground");
    const ForceTorqueReading reading = StepAndRead(model, 0, 50);
    EXPECT_LT(reading.force_L.norm(), 1e-8) << reading.force_L.transpose();
    EXPECT_LT(reading.torque_L.norm(), 1e-8) << reading.torque_L.transpose();
  }
  {
    SCOPED_TRACE("a commanded effort, passed to the step as an external wrench");
    const Model model = LoadSceneFromString(HorizontalArm("", ""), "arm");
    Eigen::VectorXd efforts = Eigen::VectorXd::Constant(1, -0.5 * kFtGravity);
    Eigen::VectorXd wrench_W = Eigen::VectorXd::Zero(model.nv());
    AddJointEffortWrench(model, State::Initial(model), efforts, &wrench_W);  // the arm does not move: one wrench
    const ForceTorqueReading with = StepAndRead(model, 0, 50, &wrench_W, &efforts);
    EXPECT_LT((with.force_L - Vec3(0, 0, kFtGravity)).norm(), 1e-8) << with.force_L.transpose();
    EXPECT_LT((with.torque_L - weight_moment).norm(), 1e-8) << with.torque_L.transpose();
    // Without the efforts the commanded part is left out: the constraint alone carries the weight's force.
    const ForceTorqueReading without = StepAndRead(model, 0, 50, &wrench_W, nullptr);
    EXPECT_LT((without.force_L - Vec3(0, 0, kFtGravity)).norm(), 1e-8);
    EXPECT_LT(without.torque_L.norm(), 1e-8) << without.torque_L.transpose();
  }
}

TEST(ForceTorqueSensor, ASwingingPendulumsPivotReadsItsCentripetalAndTangentialReaction) {
  // The arm of HorizontalArm released from q = 0 (horizontal) swings down without limits. About the pivot its
  // inertia is I = 0.001 + m L^2; at angle q below the horizontal, q'' = m g L cos q / I and q'^2 = 2 m g L sin q / I.
  // The pivot's force on the arm is m (a_cm - g), a_cm = -L q'^2 e_r + L q'' e_t (e_r: from the pivot to the centre),
  // compared at the middle of each step (the reading is the step's average). Bars for h = 1e-3 s, measured: RATTLE
  // 6.9e-6 of the weight and 2.4e-5 N m about the axis (each a quarter at h / 2: second order), the paper's step
  // 9.3e-3 (half at h / 2: first order) and 1e-13 N m.
  const Model model = LoadSceneFromString(HorizontalArm("", ""), "arm");
  const double m = 1.0, L = 0.5, I = 0.001 + m * L * L;
  for (const auto& [scheme, force_bar, moment_bar] :
       {std::make_tuple(StepperOptions::Scheme::kRattle, 2e-5, 1e-4),
        std::make_tuple(StepperOptions::Scheme::kPaper, 1.2e-2, 1e-11)}) {
    SCOPED_TRACE(scheme == StepperOptions::Scheme::kRattle ? "rattle" : "paper");
    Data data(model);
    State state = State::Initial(model), before = state;
    StepperOptions options;
    options.h = 1e-3;
    options.scheme = scheme;
    std::vector<char> subtree;
    double worst_force = 0.0, worst_axis_moment = 0.0;
    for (int i = 0; i < 400; ++i) {  // 0.4 s: about 60 degrees
      before = state;
      ASSERT_TRUE(Step(model, options, &state, &data).converged) << "step " << i;
      const ForceTorqueReading reading = ReadForceTorque(model, model.sensors[0], before, state, options.h, scheme,
                                                         data.contacts, nullptr, nullptr, &subtree);
      const double q = 0.5 * (JointPosition(model, before, 0) + JointPosition(model, state, 0));
      const double q_dot2 = 2.0 * m * kFtGravity * L * std::sin(q) / I, q_ddot = m * kFtGravity * L * std::cos(q) / I;
      const Vec3 e_r(std::cos(q), 0, -std::sin(q)), e_t(-std::sin(q), 0, -std::cos(q));  // world frame
      const Vec3 force_W = m * (-L * q_dot2 * e_r + L * q_ddot * e_t) - m * Vec3(0, 0, -kFtGravity);
      const Mat3 R_WL = before.X_WL(model, model.FindBody("arm")).linear();
      worst_force = std::max(worst_force, (R_WL * reading.force_L - force_W).norm() / (m * kFtGravity));
      worst_axis_moment = std::max(worst_axis_moment, std::abs(reading.torque_L.y()));
    }
    EXPECT_LT(worst_force, force_bar);          // of the weight, over the swing
    EXPECT_LT(worst_axis_moment, moment_bar);  // N m: a free hinge carries no moment about its axis
    EXPECT_GT(JointPosition(model, state, 0), 0.8);
  }
}

TEST(ForceTorqueSensor, BadDeclarationsAreRefusedNamingTheSensor) {
  const std::pair<const char*, const char*> cases[] = {
      {"<sensor name='s' type='force_torque' joint='wrist'/>", "attribute 'joint' = 'wrist' must name a revolute"},
      {"<sensor name='s' type='force_torque' joint='pivot' link='arm'/>", "takes attribute 'joint', not 'link'"},
      {"<sensor name='s' type='force_torque'/>", "attribute 'joint' = '' must name"},
      {"<sensor name='s' type='imu' link='arm' joint='pivot'/>", "attribute 'joint' is only for a force_torque"},
      {"<sensor name='s' type='force_torque' joint='pivot' rate='2000'/>", "attribute 'rate' = 2000 is out of range"}};
  for (const auto& [sensor, expected] : cases) {
    try {
      LoadSceneFromString(HorizontalArm("", "", sensor), "arm");
      ADD_FAILURE() << "accepted " << sensor;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
  }
}

TEST(ForceTorqueSensor, ASpawnedCopyPrefixesItsJointAndDeletingTheLinkDropsIt) {
  const std::string scene = HorizontalArm("", "");
  SceneAddition addition;
  addition.urdf = scene;
  addition.prefix = "b_";
  addition.X_WO.translation() = Vec3(3, 0, 0);
  std::vector<std::string> added;
  const std::string both = AddToScene(scene, addition, &added);
  const Model model = LoadSceneFromString(both, "both");
  ASSERT_EQ(model.sensors.size(), 2u);
  EXPECT_EQ(model.sensors[1].name, "b_ft");
  EXPECT_EQ(model.sensors[1].joint, model.FindJoint("b_pivot"));
  EXPECT_EQ(model.sensors[1].link, "b_arm");
  std::vector<std::string> removed;
  const Model one = LoadSceneFromString(RemoveFromScene(both, {"b_arm"}, &removed), "one");
  ASSERT_EQ(one.sensors.size(), 1u);
  EXPECT_EQ(one.sensors[0].name, "ft");
}

}  // namespace
}  // namespace implicit_sim
