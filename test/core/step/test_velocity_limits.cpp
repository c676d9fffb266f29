// Joint velocity limits as a bound (Joint::velocity_limited, doc/scenes.md#velocity-limits): the URDF
// <limit velocity> caps the joint rate by two complementarity rows when the scene or LoaderOptions asks for it. Against
// closed forms: a slider pushed along its rail by a constant effort accelerates exactly as without the bound until
// it reaches it, then moves at the bound (its position gaining h v_max a step), in both schemes; a pendulum falling
// from the horizontal never turns faster than its bound and leaves it when gravity slows it; the default leaves the
// rate unbounded; and the loader's refusals.
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "implicit_sim/core/io/scene_edit.h"
#include "implicit_sim/core/model/joints.h"
#include "implicit_sim/core/model/urdf_loader.h"
#include "implicit_sim/core/step/time_stepper.h"

namespace implicit_sim {
namespace {

constexpr double kRailBound = 0.505;  // m/s, reached at 0.2525 s, inside a step of 0.01 s
constexpr double kRailAccel = 2.0;    // m/s^2: the rail's effort of 4 N on the 2 kg slider

// A 2 kg slider on a horizontal prismatic rail along x, pushed by a constant effort; `entry` adds attributes to the
// rail's <implicit_sim><joint>.
std::string PushedRail(const std::string& entry, const std::string& velocity = "0.505") {
  return "<robot name='rail'><implicit_sim gravity='0 0 -9.81'><joint name='rail' effort='4' " + entry +
         "/></implicit_sim><link name='world'/><link name='slider'><inertial><mass value='2'/><inertia ixx='0.01' "
         "iyy='0.01' izz='0.01' ixy='0' ixz='0' iyz='0'/></inertial><collision><geometry><box size='0.1 0.1 0.1'/>"
         "</geometry></collision></link><joint name='rail' type='prismatic'><parent link='world'/><child "
         "link='slider'/><origin xyz='0 0 1'/><axis xyz='1 0 0'/><limit lower='-10' upper='10' effort='10' "
         "velocity='" + velocity + "'/></joint></robot>";
}

const StepperOptions::Scheme kBoundedSchemes[] = {StepperOptions::Scheme::kRattle, StepperOptions::Scheme::kPaper};
const char* BoundedSchemeName(StepperOptions::Scheme scheme) {
  return scheme == StepperOptions::Scheme::kRattle ? "rattle" : "paper";
}

TEST(VelocityLimits, ASliderPushedAlongItsRailReachesItsBoundAndStaysOnIt) {
  const Model bounded = LoadSceneFromString(PushedRail("enforce_velocity_limit='true'"), "rail");
  const Model free = LoadSceneFromString(PushedRail(""), "rail");
  ASSERT_TRUE(bounded.joints[0].velocity_limited);
  EXPECT_EQ(bounded.joints[0].velocity_limit, kRailBound);
  EXPECT_FALSE(free.joints[0].velocity_limited);  // off by default
  for (const StepperOptions::Scheme scheme : kBoundedSchemes) {
    SCOPED_TRACE(BoundedSchemeName(scheme));
    StepperOptions options;
    options.scheme = scheme;
    options.h = 0.01;
    Data data_bounded(bounded), data_free(free);
    State s_bounded = State::Initial(bounded), s_free = State::Initial(free);
    for (int i = 1; i <= 50; ++i) {
      const double x_before = JointPosition(bounded, s_bounded, 0);
      ASSERT_TRUE(Step(bounded, options, &s_bounded, &data_bounded).converged) << "step " << i;
      ASSERT_TRUE(Step(free, options, &s_free, &data_free).converged) << "step " << i;
      const double t = i * options.h, v = JointVelocity(bounded, s_bounded, 0), x = JointPosition(bounded, s_bounded, 0);
      EXPECT_LE(std::abs(v), kRailBound + 1e-12) << "t = " << t;
      EXPECT_NEAR(JointVelocity(free, s_free, 0), kRailAccel * t, 1e-9) << "t = " << t;  // unbounded: a t
      if (t < 0.25 - 1e-9) {  // below the bound the rows are slack: the same motion as without them
        EXPECT_NEAR(v, kRailAccel * t, 1e-9) << "t = " << t;
        EXPECT_NEAR(x, JointPosition(free, s_free, 0), 1e-12) << "t = " << t;
      } else if (t > 0.26 + 1e-9) {  // on the bound: v_max, and h v_max a step
        EXPECT_NEAR(v, kRailBound, 1e-9) << "t = " << t;
        EXPECT_NEAR(x - x_before, options.h * kRailBound, 1e-9) << "t = " << t;
      }
    }
    EXPECT_GT(JointVelocity(free, s_free, 0), 0.99);  // 1 m/s without the bound
    double drift_m = 1.0, drift_rad = 1.0;
    JointDrift(bounded, s_bounded, &drift_m, &drift_rad);
    EXPECT_LT(drift_m, 1e-9);
    EXPECT_LT(drift_rad, 1e-9);
  }
}

// A 1 kg point-like bob on a massless-looking 0.5 m rod (a sphere of radius 0.05 m at the end of a revolute joint)
// released horizontal: unbounded it would pass the bottom at sqrt(2 g l) / l = 8.86 rad/s; bounded at 3 rad/s it turns
// at 3 rad/s from about a fifth of the way down, and is slowed below the bound by gravity past the bottom.
TEST(VelocityLimits, APendulumNeverTurnsFasterThanItsBound) {
  const std::string urdf =
      "<robot name='p'><implicit_sim gravity='0 0 -9.81'><joint name='pivot' enforce_velocity_limit='true'/>"
      "</implicit_sim><link name='world'/><link name='bob'><inertial><origin xyz='0.5 0 0'/><mass value='1'/>"
      "<inertia ixx='1e-3' iyy='1e-3' izz='1e-3' ixy='0' ixz='0' iyz='0'/></inertial><collision><origin "
      "xyz='0.5 0 0'/><geometry><sphere radius='0.05'/></geometry></collision></link><joint name='pivot' "
      "type='continuous'><parent link='world'/><child link='bob'/><origin xyz='0 0 1'/><axis xyz='0 1 0'/><limit "
      "effort='0' velocity='3'/></joint></robot>";
  const Model model = LoadSceneFromString(urdf, "p");
  for (const StepperOptions::Scheme scheme : kBoundedSchemes) {
    SCOPED_TRACE(BoundedSchemeName(scheme));
    StepperOptions options;
    options.scheme = scheme;
    options.h = 0.005;
    Data data(model);
    State state = State::Initial(model);
    double fastest = 0.0, slowest_after_bottom = 10.0;
    bool past_bottom = false;
    for (int i = 0; i < 200; ++i) {
      ASSERT_TRUE(Step(model, options, &state, &data).converged) << "step " << i;
      const double rate = JointVelocity(model, state, 0), q = JointPosition(model, state, 0);
      fastest = std::max(fastest, std::abs(rate));
      past_bottom = past_bottom || q > 0.5 * M_PI + 0.3;  // +y axis: the bob swings down through +q
      if (past_bottom) slowest_after_bottom = std::min(slowest_after_bottom, std::abs(rate));
    }
    EXPECT_NEAR(fastest, 3.0, 1e-9);  // reached, never exceeded
    EXPECT_TRUE(past_bottom);
    EXPECT_LT(slowest_after_bottom, 2.9);  // gravity takes it off the bound on the way up
    double drift_m = 1.0, drift_rad = 1.0;
    JointDrift(model, state, &drift_m, &drift_rad);
    EXPECT_LT(drift_m, 1e-9);
    EXPECT_LT(drift_rad, 1e-9);
  }
}

TEST(VelocityLimits, TheLoaderDefaultAndEachJointsEntry) {
  LoaderOptions enforce;
  enforce.enforce_velocity_limits = true;
  EXPECT_TRUE(LoadSceneFromString(PushedRail(""), "rail", enforce).joints[0].velocity_limited);
  EXPECT_FALSE(LoadSceneFromString(PushedRail("enforce_velocity_limit='false'"), "rail", enforce).joints[0].velocity_limited);
  // A joint without a <limit velocity> > 0 has nothing to bound: the default passes over it.
  EXPECT_FALSE(LoadSceneFromString(PushedRail("", "0"), "rail", enforce).joints[0].velocity_limited);
}

// ~spawn's core (io/scene_edit.h): the addition's <implicit_sim><joint enforce_velocity_limit> keeps its meaning under
// the prefix.
TEST(VelocityLimits, AJointsEntryTravelsWithASpawnedRobot) {
  SceneAddition addition;
  addition.urdf = PushedRail("enforce_velocity_limit='true'");
  addition.prefix = "r/";
  const Model model = LoadSceneFromString(
      AddToScene("<robot name='w'><link name='world'/></robot>", addition, nullptr), "w");
  const int rail = model.FindJoint("r/rail");
  ASSERT_GE(rail, 0);
  EXPECT_TRUE(model.joints[rail].velocity_limited);
}

TEST(VelocityLimits, TheLoaderRefusesWhatItCannotBound) {
  const std::pair<std::string, std::string> refused[] = {
      {PushedRail("enforce_velocity_limit='yes'"),
       "<implicit_sim><joint name='rail'> attribute 'enforce_velocity_limit' = 'yes' must be 'true' or 'false'"},
      {PushedRail("enforce_velocity_limit='true'", "0"),
       "<implicit_sim><joint name='rail'> attribute 'enforce_velocity_limit': the joint has no <limit velocity> > 0 "
       "to enforce"},
      {PushedRail("enforce_velocity_limit='true' velocity='0.7'"),
       "<implicit_sim><joint name='rail'>: start velocity 0.7 is outside its velocity limit [-0.505, 0.505]"},
      {PushedRail("enforce_velocity_limit='true'", "-1"), "<limit> attribute 'velocity' must be >= 0 (0: none)"}};
  for (const auto& [urdf, message] : refused) {
    try {
      LoadSceneFromString(urdf, "rail");
      ADD_FAILURE() << "loaded: " << message;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace implicit_sim
