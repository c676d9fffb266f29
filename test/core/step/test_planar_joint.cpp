// The planar joint (URDF type 'planar', model/joints.h): the child's joint origin stays in the plane through the
// parent's with normal `axis`, and the child turns about that normal only. Against closed forms: a box pushed across
// a tilted plane by gravity and a constant force and spun by a constant torque slides and turns exactly as a body with
// three degrees of freedom does, in both schemes; and the loader's and the configuration's refusals.
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "implicit_sim/core/model/joint_configuration.h"
#include "implicit_sim/core/model/joints.h"
#include "implicit_sim/core/model/urdf_loader.h"
#include "implicit_sim/core/step/time_stepper.h"

namespace implicit_sim {
namespace {

// A 2 kg box (inertia diag(0.1, 0.2, 0.3) kg m^2 about its centre, which sits 0.1 m along x from its link frame) on a
// planar joint whose normal is z, 1 m above the world origin; the constant force `force` and torque `torque` (world
// frame, N and N m) act on it, and gravity is `gravity` (m/s^2).
std::string BoxOnPlane(const std::string& gravity, const std::string& force, const std::string& torque,
                       const std::string& joint_extra = "", const std::string& sim_extra = "") {
  return "<robot name='plane'><implicit_sim gravity='" + gravity + "'><body link='box' force='" + force +
         "' torque='" + torque + "'/>" + sim_extra +
         "</implicit_sim><link name='world'/><link name='box'><inertial><origin xyz='0.1 0 0'/><mass value='2'/>"
         "<inertia ixx='0.1' iyy='0.2' izz='0.3' ixy='0' ixz='0' iyz='0'/></inertial><collision><origin "
         "xyz='0.1 0 0'/><geometry><box size='0.2 0.1 0.05'/></geometry></collision></link><joint name='glide' "
         "type='planar'><parent link='world'/><child link='box'/><origin xyz='0 0 1'/><axis xyz='0 0 1'/>" +
         joint_extra + "</joint></robot>";
}

TEST(PlanarJoint, ABoxSlidesAndTurnsInItsPlaneAsThreeDegreesOfFreedomDo) {
  // In the plane: gravity's x part 3 m/s^2 and the force's y part 1 N (0.5 m/s^2 on 2 kg); the torque's z part
  // 0.6 N m turns it at 2 rad/s^2 about the centre's vertical (the joint lets it turn about any vertical; with the
  // centre 0.1 m off the link origin, the centre's acceleration is unaffected). Everything out of the plane (the
  // gravity's z, the force's z, the torque's x and y) is carried by the joint.
  const Model model =
      LoadSceneFromString(BoxOnPlane("3 0 -9.81", "0 1 40", "5 -7 0.6"), "plane");
  ASSERT_EQ(model.joints.size(), 1u);
  EXPECT_EQ(model.joints[0].type, JointType::kPlanar);
  EXPECT_STREQ(JointTypeName(model.joints[0].type), "planar");
  EXPECT_FALSE(model.joints[0].has_coordinate());
  for (const StepperOptions::Scheme scheme : {StepperOptions::Scheme::kRattle, StepperOptions::Scheme::kPaper}) {
    SCOPED_TRACE(scheme == StepperOptions::Scheme::kRattle ? "rattle" : "paper");
    Data data(model);
    State state = State::Initial(model);
    StepperOptions options;
    options.scheme = scheme;
    options.h = 0.01;
    for (int i = 0; i < 50; ++i) ASSERT_TRUE(Step(model, options, &state, &data).converged) << "step " << i;
    const double t = 0.5;  // s
    const Vec3 v = state.v_WB(0), w = state.w_WB(0);
    EXPECT_NEAR(v.x(), 3.0 * t, 1e-9);
    EXPECT_NEAR(v.y(), 0.5 * t, 1e-9);
    EXPECT_NEAR(v.z(), 0.0, 1e-9);
    EXPECT_NEAR(w.z(), 2.0 * t, 1e-9);
    EXPECT_NEAR(w.x(), 0.0, 1e-9);
    EXPECT_NEAR(w.y(), 0.0, 1e-9);
    EXPECT_NEAR(state.X_WB(model, 0).translation().z(), 1.0, 1e-9);  // the centre stays in the plane
    double drift_m = 0.0, drift_rad = 0.0;
    JointDrift(model, state, &drift_m, &drift_rad);
    EXPECT_LT(drift_m, 1e-9);
    EXPECT_LT(drift_rad, 1e-9);
    // The turn about z: 1/2 alpha t^2 = 0.25 rad, to the schemes' order (h t alpha / 2 = 5e-3 rad for the first).
    const Mat3 R = state.X_WB(model, 0).linear();
    EXPECT_NEAR(std::atan2(R(1, 0), R(0, 0)), 0.25, 6e-3);
    EXPECT_NEAR(R(2, 2), 1.0, 1e-12);
  }
}

std::string ZeroAxis(std::string urdf) {
  return urdf.replace(urdf.find("<axis xyz='0 0 1'/>"), 19, "<axis xyz='0 0 0'/>");
}

TEST(PlanarJoint, TheLoaderAndTheConfigurationRefuseWhatAPlanarJointDoesNotHave) {
  const std::string gravity = "0 0 -9.81", none = "0 0 0";
  const std::pair<std::string, const char*> refused[] = {
      {BoxOnPlane(gravity, none, none, "", "<joint name='glide' position='0.1'/>"),
       "the joint must be revolute, continuous or prismatic"},
      {ZeroAxis(BoxOnPlane(gravity, none, none)), "must be a non-zero vector"}};
  for (const auto& [urdf, expected] : refused) {
    try {
      LoadSceneFromString(urdf, "plane");
      ADD_FAILURE() << "accepted " << urdf;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
  }
  // <dynamics> on a planar joint is ignored with one note.
  std::vector<std::string> warnings;
  LoaderOptions options;
  options.warnings = &warnings;
  const Model damped =
      LoadSceneFromString(BoxOnPlane(gravity, none, none, "<dynamics damping='0.5' friction='1'/>"), "plane", options);
  EXPECT_EQ(damped.joints[0].damping, 0.0);
  EXPECT_EQ(damped.joints[0].friction, 0.0);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("<dynamics> of planar joints is ignored"), std::string::npos) << warnings[0];
  // No position to set; a joint below it keeps its place on it when a joint above moves (the next test's robot).
  State state = State::Initial(damped);
  std::string error;
  EXPECT_FALSE(SetJointPositions(damped, {{0, 0.3}}, &state, &error));
  EXPECT_EQ(error, "joint 'glide' is planar: it has no position to set");
}

TEST(PlanarJoint, SettingTheJointAboveCarriesThePlanarChildAlong) {
  const Model model = LoadSceneFromString(
      "<robot name='r'><link name='world'/><link name='arm'><inertial><mass value='1'/><inertia ixx='0.01' iyy='0.01' "
      "izz='0.01' ixy='0' ixz='0' iyz='0'/></inertial></link><joint name='swing' type='continuous'><parent "
      "link='world'/><child link='arm'/><origin xyz='0 0 1'/><axis xyz='0 0 1'/></joint><link name='puck'><inertial>"
      "<mass value='0.5'/><inertia ixx='0.001' iyy='0.001' izz='0.001' ixy='0' ixz='0' iyz='0'/></inertial></link>"
      "<joint name='glide' type='planar'><parent link='arm'/><child link='puck'/><origin xyz='0.5 0 0'/><axis "
      "xyz='0 0 1'/></joint></robot>",
      "r");
  State state = State::Initial(model);
  const int puck = model.FindBody("puck"), arm = model.FindBody("arm");
  // Move the puck within its plane first (0.1 m along the arm's y), then turn the arm by 90 degrees.
  const int slot = model.velocity_slot[puck];
  state.q[Model::q_offset(slot) + 1] += 0.1;
  const Pose X_AP_before = state.X_WB(model, arm).inverse() * state.X_WB(model, puck);
  std::string error;
  ASSERT_TRUE(SetJointPositions(model, {{model.FindJoint("swing"), 0.5 * M_PI}}, &state, &error)) << error;
  const Pose X_AP_after = state.X_WB(model, arm).inverse() * state.X_WB(model, puck);
  EXPECT_LT((X_AP_after.matrix() - X_AP_before.matrix()).norm(), 1e-12);
  EXPECT_LT((state.X_WB(model, puck).translation() - Vec3(-0.1, 0.5, 1.0)).norm(), 1e-12)
      << state.X_WB(model, puck).translation().transpose();
}

}  // namespace
}  // namespace implicit_sim
