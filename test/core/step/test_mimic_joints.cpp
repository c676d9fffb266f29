// Mimic joints (URDF <mimic joint multiplier offset>): one equality row per follower in the step. A gripper whose
// right finger mimics the left one closes symmetrically under a drive on the left finger alone, the relation holding
// at every step end to the solver tolerance in both schemes; two pendulums of different lengths coupled by a mimic
// swing with the period of the combined pendulum (closed form); bad mimics are refused naming the joint.
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "implicit_sim/core/model/joints.h"
#include "implicit_sim/core/model/urdf_loader.h"
#include "scenario_runner.h"

namespace implicit_sim {
namespace {

const char* kFingerInertial =
    "<inertial><mass value='0.05'/><inertia ixx='1e-5' iyy='1e-5' izz='1e-5' ixy='0' ixz='0' iyz='0'/></inertial>";

// A palm welded to the world and two fingers sliding apart along y; the right one mimics the left one.
std::string MimicGripper(const std::string& mimic_attributes) {
  return std::string("<robot name='gripper'><link name='world'/>"
                     "<link name='palm'><collision><geometry><box size='0.1 0.1 0.02'/></geometry></collision></link>"
                     "<joint name='palm_joint' type='fixed'><parent link='world'/><child link='palm'/>"
                     "<origin xyz='0 0 0.5'/></joint>"
                     "<link name='left'>") + kFingerInertial +
         "<collision><geometry><box size='0.01 0.01 0.05'/></geometry></collision></link>"
         "<joint name='left_joint' type='prismatic'><parent link='palm'/><child link='left'/>"
         "<origin xyz='0 0.02 -0.04'/><axis xyz='0 1 0'/><limit lower='0' upper='0.04' effort='20' velocity='0.2'/>"
         "</joint><link name='right'>" + kFingerInertial +
         "<collision><geometry><box size='0.01 0.01 0.05'/></geometry></collision></link>"
         "<joint name='right_joint' type='prismatic'><parent link='palm'/><child link='right'/>"
         "<origin xyz='0 -0.02 -0.04'/><axis xyz='0 -1 0'/><limit lower='0' upper='0.04' effort='20' velocity='0.2'/>"
         "<mimic joint='left_joint' " + mimic_attributes + "/></joint></robot>";
}

class MimicSchemes : public ::testing::TestWithParam<StepperOptions::Scheme> {};

TEST_P(MimicSchemes, AFingerThatMimicsTheDrivenOneClosesWithIt) {
  const Model model = LoadSceneFromString(MimicGripper(""), "gripper");
  const int left = model.FindJoint("left_joint"), right = model.FindJoint("right_joint");
  ASSERT_EQ(model.joints[right].mimic_leader, left);
  EXPECT_FALSE(model.joints[right].limited);
  StepperOptions options;
  options.h = 0.005;
  options.scheme = GetParam();
  Data data(model);
  data.joint_drives[left] = JointDrive{0.03, 0.0, 200.0, 5.0};
  std::string error;
  ASSERT_TRUE(CheckJointDrive(model.joints[left], data.joint_drives[left], &error)) << error;
  EXPECT_FALSE(CheckJointDrive(model.joints[right], data.joint_drives[left], &error));
  EXPECT_NE(error.find("mimics another joint"), std::string::npos) << error;
  State state = State::Initial(model);
  double worst = 0.0;  // the largest |q_right - q_left| at any step end (m)
  for (int i = 0; i < 400; ++i) {
    const StepReport report = Step(model, options, &state, &data);
    ASSERT_TRUE(report.converged) << "step " << i;
    worst = std::max(worst, std::abs(JointPosition(model, state, right) - JointPosition(model, state, left)));
  }
  EXPECT_LT(worst, 1e-10);
  EXPECT_NEAR(JointPosition(model, state, left), 0.03, 1e-6);  // the drive holds both fingers at its target
  EXPECT_NEAR(JointPosition(model, state, right), 0.03, 1e-6);
}

INSTANTIATE_TEST_SUITE_P(Schemes, MimicSchemes,
                         ::testing::Values(StepperOptions::Scheme::kPaper, StepperOptions::Scheme::kRattle));

// Bobs (spheres r = 0.05 m, 1 kg) at lengths L1 = 1 m and L2 = 0.5 m on hinges about y at the world origin; hinge2
// mimics hinge1 (multiplier 1). Together they swing as one body of pivot inertia I = sum (2/5 m r^2 + m L^2) under
// the torque -(m1 L1 + m2 L2) g sin(theta): period 2 pi sqrt(I / (M g l)) / AGM(1, cos(theta0 / 2)).
TEST(MimicJoints, TwoCoupledPendulumsSwingWithTheCombinedPeriod) {
  // Each bob hangs L below its hinge: its inertial and collision origins at z = -L in the link frame.
  const auto bob = [](const std::string& name, const std::string& length) {
    const std::string down = "<origin xyz='0 0 -" + length + "'/>";
    return "<link name='" + name + "'><inertial>" + down + "<mass value='1'/><inertia ixx='0.001' iyy='0.001' "
           "izz='0.001' ixy='0' ixz='0' iyz='0'/></inertial><collision>" + down +
           "<geometry><sphere radius='0.05'/></geometry></collision></link>";
  };
  const double theta0 = 0.0872665;  // rad (5 deg)
  const std::string urdf =
      "<robot name='pair'><link name='world'/>" + bob("bob1", "1") + bob("bob2", "0.5") +
      "<joint name='hinge1' type='continuous'><parent link='world'/><child link='bob1'/><axis xyz='0 1 0'/></joint>"
      "<joint name='hinge2' type='continuous'><parent link='world'/><child link='bob2'/><axis xyz='0 1 0'/>"
      "<mimic joint='hinge1'/></joint>"
      "<implicit_sim><joint name='hinge1' position='0.0872665'/></implicit_sim></robot>";
  const Model model = LoadSceneFromString(urdf, "pair");
  const int hinge1 = model.FindJoint("hinge1"), hinge2 = model.FindJoint("hinge2");
  ASSERT_EQ(model.joints[hinge2].mimic_leader, hinge1);
  const double g = 9.81, I = 2 * 0.001 + 1.0 * 1.0 + 1.0 * 0.25, Ml = 1.0 * 1.0 + 1.0 * 0.5;  // kg m^2, kg m
  double a = 1.0, b = std::cos(theta0 / 2.0);
  for (int i = 0; i < 30; ++i) {
    const double next = 0.5 * (a + b);
    b = std::sqrt(a * b);
    a = next;
  }
  const double period = 2.0 * std::acos(-1.0) * std::sqrt(I / (Ml * g)) / a;  // s
  StepperOptions options;
  options.h = 0.001;
  Data data(model);
  State state = State::Initial(model);
  EXPECT_NEAR(JointPosition(model, state, hinge2), theta0, 1e-12);  // the follower starts where its leader puts it
  std::vector<double> crossings;  // times at which theta1 crosses 0 downwards (s)
  double previous = JointPosition(model, state, hinge1), worst = 0.0;
  while (state.t < 2.5 * period) {
    ASSERT_TRUE(Step(model, options, &state, &data).converged);
    const double q = JointPosition(model, state, hinge1);
    worst = std::max(worst, std::abs(JointPosition(model, state, hinge2) - q));
    if (previous > 0.0 && q <= 0.0) crossings.push_back(state.t - options.h * q / (q - previous));
    previous = q;
  }
  ASSERT_GE(crossings.size(), 2u);
  EXPECT_NEAR((crossings[1] - crossings[0]) / period, 1.0, 1e-4);
  EXPECT_LT(worst, 1e-10);
  std::printf("[ mimic ] coupled pendulums: period %.7f s, closed form %.7f s; |q2 - q1| <= %.1e rad\n",
              crossings[1] - crossings[0], period, worst);
}

TEST(MimicJoints, BadMimicsAreRefusedNamingTheJoint) {
  const auto refused = [](const std::string& urdf, const std::string& must_mention) {
    try {
      LoadSceneFromString(urdf, "gripper");
      ADD_FAILURE() << "accepted; expected '" << must_mention << "'";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(must_mention), std::string::npos) << e.what();
    }
  };
  std::string missing = MimicGripper("");
  missing.replace(missing.find("mimic joint='left_joint'"), 24, "mimic joint='thumb_joint'");
  refused(missing, "joint 'right_joint' <mimic>: attribute 'joint' = 'thumb_joint' names no joint");
  refused(MimicGripper("offset='0.05'"), "joint 'right_joint' <mimic>: its leader's start puts it at 0.05");
  refused(MimicGripper("multiplier='x'"), "joint 'right_joint' <mimic> attribute 'multiplier'");
  refused(MimicGripper("gain='2'"), "unknown attribute 'gain'");
  std::string self = MimicGripper("");
  self.replace(self.find("mimic joint='left_joint'"), 24, "mimic joint='right_joint'");
  refused(self, "must be another revolute, continuous or prismatic joint that mimics none");
}

}  // namespace
}  // namespace implicit_sim
