// A link with several <collision> elements is one rigid body, the union of its convex shapes: its mass properties from
// the union (closed forms with parallel axes), one contact pair per shape pair, and a dumbbell resting on both its
// spheres with the weight shared exactly and no shape below the floor (checked from the poses alone).
// Also the loader's tolerance of what stock URDF tools accept (vendor attributes, axes of fixed joints, revolute
// ranges of 2 pi and more, drive targets within round-off of a limit).
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "implicit_sim/core/model/joints.h"
#include "implicit_sim/core/model/urdf_loader.h"
#include "implicit_sim/core/step/step_health.h"
#include "scenario_runner.h"

namespace implicit_sim {
namespace {

constexpr double kBellRadius = 0.05;        // sphere radius (m)
constexpr double kBellArm = 0.2;       // sphere centres at x = +-kBellArm in the link frame (m)
constexpr double kBarRadius = 0.01;     // bar radius (m)
constexpr double kBarHalf = 0.15;  // bar half length along x (m)

// A dumbbell link without <inertial>: two spheres and a bar along x, its centre `height` m above a floor.
std::string DumbbellScene(double height, const std::string& extra = "") {
  const std::string sphere = "<geometry><sphere radius='" + std::to_string(kBellRadius) + "'/></geometry>";
  return "<robot name='dumbbell'><link name='world'/>"
         "<link name='floor'><collision><geometry><box size='1 1 1'/></geometry><implicit type='halfspace'/>"
         "</collision></link><joint name='f' type='fixed'><parent link='world'/><child link='floor'/></joint>"
         "<link name='bell'>"
         "<collision><origin xyz='-" + std::to_string(kBellArm) + " 0 0'/>" + sphere + "</collision>"
         "<collision><origin xyz='" + std::to_string(kBellArm) + " 0 0'/>" + sphere + "</collision>"
         "<collision><origin rpy='0 1.5707963267948966 0'/><geometry><cylinder radius='" + std::to_string(kBarRadius) +
         "' length='" + std::to_string(2 * kBarHalf) + "'/></geometry></collision></link>"
         "<joint name='b' type='floating'><parent link='world'/><child link='bell'/>"
         "<origin xyz='0 0 " + std::to_string(height) + "'/></joint>" + extra + "</robot>";
}

TEST(LinkUnions, SeveralCollisionsMakeOneBodyWithItsUnionsMassAndAPairPerShape) {
  std::vector<std::string> notes;
  LoaderOptions options;
  options.warnings = &notes;
  const Model model = LoadSceneFromString(DumbbellScene(0.5), "dumbbell", options);
  const int bell = model.FindBody("bell");
  ASSERT_GE(bell, 0);
  const Body& body = model.bodies[bell];
  ASSERT_EQ(body.shapes.size(), 3u);
  // Closed forms at 1000 kg/m^3: spheres 2/5 m r^2 plus m d^2 off-axis; the bar m (3 r^2 + L^2) / 12 across it.
  const double rho = 1000.0, pi = std::acos(-1.0);
  const double m_s = rho * 4.0 / 3.0 * pi * kBellRadius * kBellRadius * kBellRadius, m_b = rho * pi * kBarRadius * kBarRadius * 2.0 * kBarHalf;
  const double L = 2.0 * kBarHalf;
  const double Ixx = 2.0 * (0.4 * m_s * kBellRadius * kBellRadius) + 0.5 * m_b * kBarRadius * kBarRadius;
  const double Iyy = 2.0 * (0.4 * m_s * kBellRadius * kBellRadius + m_s * kBellArm * kBellArm) + m_b * (3.0 * kBarRadius * kBarRadius + L * L) / 12.0;
  EXPECT_NEAR(body.mass, 2.0 * m_s + m_b, 1e-12);
  EXPECT_NEAR(body.I_B(0, 0), Ixx, 1e-12);
  EXPECT_NEAR(body.I_B(1, 1), Iyy, 1e-12);
  EXPECT_NEAR(body.I_B(2, 2), Iyy, 1e-12);
  EXPECT_NEAR(body.I_B(0, 1), 0.0, 1e-15);
  EXPECT_NEAR(body.X_BL.translation().norm(), 0.0, 1e-15);  // symmetric: the centre of mass at the link origin
  ASSERT_EQ(model.pairs.size(), 3u);  // each shape with the floor, none between the body's own shapes
  std::vector<std::string> names;
  for (int p = 0; p < 3; ++p) names.push_back(model.PairName(p));
  EXPECT_EQ(names, (std::vector<std::string>{"bell#0-floor", "bell#1-floor", "bell#2-floor"}));
  EXPECT_EQ(model.PairIndex(bell, model.FindBody("floor")), 0);
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("'bell'"), std::string::npos) << notes[0];
  EXPECT_NE(notes[0].find("1000 kg/m^3"), std::string::npos) << notes[0];
}

TEST(LinkUnions, ADumbbellRestsOnBothSpheresCarryingHalfItsWeightEach) {
  const Model model = LoadSceneFromString(DumbbellScene(kBellRadius + 0.02), "dumbbell");
  const int bell = model.FindBody("bell");
  const double weight = model.bodies[bell].mass * 9.81;  // N
  double lowest = 1.0;  // the lowest point of any shape over every step end (m), from the poses alone
  double force[3] = {0, 0, 0}, speed = 0.0;  // at the last step end: N, m/s and rad/s
  const auto stats = testing_support::RunScene(model, 0.01, 1.0,
                                               [&](const Model& m, const State& s, const Data& d, const StepReport&) {
    for (int p = 0; p < 3; ++p) force[p] = d.contacts[p].normal_force;
    speed = s.v.norm();
    const Pose X_WB = s.X_WB(m, bell);
    for (const ConvexShape& shape : m.bodies[bell].shapes) {
      const Vec3 c = X_WB * shape.X_BS.translation();
      const double below = shape.type == ShapeType::kSphere
                               ? c.z() - kBellRadius
                               : c.z() - std::hypot(kBarRadius, kBarHalf * std::abs((X_WB.linear() * shape.X_BS.linear() *
                                                                                 Vec3::UnitZ()).z()));
      lowest = std::min(lowest, below);
    }
  });
  EXPECT_EQ(stats.nonconverged, 0);
  EXPECT_GE(lowest, -1e-9);
  EXPECT_NEAR(force[0], weight / 2.0, 1e-6 * weight);
  EXPECT_NEAR(force[1], weight / 2.0, 1e-6 * weight);
  EXPECT_NEAR(force[2], 0.0, 1e-9 * weight);  // the bar stays 4 cm above the floor
  EXPECT_LT(speed, 1e-9);
}

// One joint of `type` between the world and a 0.1 m ball with an <inertial>, with the given joint children.
std::string JointScene(const std::string& type, const std::string& joint_children, const std::string& extra = "") {
  return "<robot name='j'><link name='world'/>"
         "<link name='ball'><inertial><mass value='1'/><inertia ixx='0.004' iyy='0.004' izz='0.004' ixy='0' "
         "ixz='0' iyz='0'/></inertial><collision><geometry><sphere radius='0.1'/></geometry></collision></link>"
         "<joint name='b' type='" + type + "'><parent link='world'/><child link='ball'/><origin xyz='0 0 1'/>" +
         joint_children + "</joint>" + extra + "</robot>";
}

TEST(VendorTolerance, AttributesOfOtherToolsAreNotedOnceAndIgnored) {
  std::vector<std::string> notes;
  LoaderOptions options;
  options.warnings = &notes;
  const std::string extra =
      "<link name='ball2'><inertial><mass value='1'/><inertia ixx='0.004' iyy='0.004' izz='0.004' ixy='0' ixz='0' "
      "iyz='0'/></inertial></link><joint name='c' type='revolute'><parent link='ball'/><child link='ball2'/>"
      "<axis xyz='0 0 1'/><limit lower='-1' upper='1' effort='10' velocity='1' k_velocity='2'/>"
      "<dynamics D='1' K='7000' damping='0.5'/></joint>";
  const Model model = LoadSceneFromString(
      JointScene("revolute", "<axis xyz='0 0 1'/><limit lower='-1' upper='1' effort='10' velocity='1'/>"
                             "<dynamics D='1' K='7000' damping='0.003' mu_coulomb='0'/>",
                 extra),
      "j", options);
  EXPECT_DOUBLE_EQ(model.joints[model.FindJoint("b")].damping, 0.003);
  EXPECT_DOUBLE_EQ(model.joints[model.FindJoint("c")].damping, 0.5);
  std::vector<std::string> named;  // one note per element and attribute name, however often it occurs
  for (const std::string& note : notes) {
    for (const char* a : {"'D' of <dynamics>", "'K' of <dynamics>", "'mu_coulomb' of <dynamics>",
                          "'k_velocity' of <limit>"}) {
      if (note.find(a) != std::string::npos) named.push_back(a);
    }
  }
  EXPECT_EQ(named, (std::vector<std::string>{"'D' of <dynamics>", "'K' of <dynamics>", "'mu_coulomb' of <dynamics>",
                                             "'k_velocity' of <limit>"}));
  EXPECT_EQ(notes.size(), 4u);
}

TEST(VendorTolerance, TheAxisOfAFixedJointIsIgnoredAsUrdfdomIgnoresIt) {
  const std::string fixed_with_zero_axis =
      "<robot name='f'><link name='world'/><link name='base'><collision><geometry><box size='1 1 0.1'/></geometry>"
      "</collision></link><joint name='w' type='fixed'><parent link='world'/><child link='base'/>"
      "<axis xyz='0 0 0'/></joint><link name='ball'><inertial><mass value='1'/><inertia ixx='0.004' iyy='0.004' "
      "izz='0.004' ixy='0' ixz='0' iyz='0'/></inertial><collision><geometry><sphere radius='0.1'/></geometry>"
      "</collision></link><joint name='b' type='floating'><parent link='world'/><child link='ball'/>"
      "<origin xyz='0 0 1'/></joint></robot>";
  EXPECT_NO_THROW(LoadSceneFromString(fixed_with_zero_axis, "f"));
}

TEST(VendorTolerance, ARevoluteRangeOfTwoPiOrMoreTurnsFreelyFromWhereItStarts) {
  // UR5's +-2 pi joints: no limit rows, the limits kept for start positions; a start at 4 rad is taken as given and a
  // constant effort spins the joint past pi as a continuous joint would (theta = theta0 + tau t^2 / (2 I)).
  std::vector<std::string> notes;
  LoaderOptions options;
  options.warnings = &notes;
  const double tau = 0.01, I = 0.004;  // N m, kg m^2 about z
  const Model model = LoadSceneFromString(
      JointScene("revolute", "<axis xyz='0 0 1'/><limit lower='-6.283185307179586' upper='6.283185307179586' "
                             "effort='10' velocity='3.15'/>",
                 "<implicit_sim gravity='0 0 0'><joint name='b' position='4' effort='" + std::to_string(tau) +
                     "'/></implicit_sim>"),
      "j", options);
  const Joint& joint = model.joints[model.FindJoint("b")];
  EXPECT_FALSE(joint.limited);
  EXPECT_DOUBLE_EQ(joint.upper, 2.0 * std::acos(-1.0));
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("joint 'b'"), std::string::npos) << notes[0];
  const double T = 4.0;  // s: the joint turns by tau T^2 / (2 I) = 20 rad
  double q = 0.0, qd = 0.0;  // at the end (rad, rad/s)
  const auto stats = testing_support::RunScene(model, 0.01, T,
                                               [&](const Model& m, const State& s, const Data&, const StepReport&) {
    q = JointPosition(m, s, 0);
    qd = JointVelocity(m, s, 0);
  });
  EXPECT_EQ(stats.nonconverged, 0);
  const double alpha = tau / I, turned = 4.0 + alpha * T * T / 2.0;  // rad/s^2, rad
  // A first-order step lags the exact angle by at most alpha h T / 2 (0.05 of 24 rad here).
  EXPECT_NEAR(std::remainder(q - turned, 2.0 * std::acos(-1.0)), 0.0, alpha * 0.01 * T / 2.0);
  EXPECT_NEAR(qd, tau * T / I, 1e-9);
}

TEST(VendorTolerance, ADriveTargetWithinRoundOffOfALimitIsOnIt) {
  const Model model = LoadSceneFromString(
      JointScene("prismatic", "<axis xyz='0 0 1'/><limit lower='0' upper='0.04' effort='20' velocity='0.2'/>"), "j");
  const Joint& finger = model.joints[0];
  JointDrive drive;
  drive.stiffness = 100.0;
  std::string error;
  for (double target : {-1.1e-16, 0.04 + 1e-13}) {
    drive.position_target = target;
    EXPECT_TRUE(CheckJointDrive(finger, drive, &error)) << error;
  }
  drive.position_target = -1e-9;
  EXPECT_FALSE(CheckJointDrive(finger, drive, &error));
  EXPECT_NE(error.find("outside the joint limits"), std::string::npos) << error;
}

}  // namespace
}  // namespace implicit_sim

namespace implicit_sim {
namespace {

// A two-link arm on a base welded to the world whose forearm folds back onto the base at the start pose (into it by
// 0.5 - elbow_z m when the elbow is lower than 0.5 m), with `sim` inside <implicit_sim>.
std::string FoldedArm(const std::string& sim, const std::string& elbow_z = "0.5") {
  const std::string inertial =
      "<inertial><mass value='1'/><inertia ixx='0.01' iyy='0.01' izz='0.01' ixy='0' ixz='0' iyz='0'/></inertial>";
  return "<robot name='arm'><link name='world'/><link name='base'><collision><geometry><box size='0.2 0.2 0.2'/>"
         "</geometry></collision></link><joint name='weld' type='fixed'><parent link='world'/><child link='base'/>"
         "</joint><link name='upper'>" + inertial +
         "<collision><origin xyz='0 0 0.25'/><geometry><box size='0.05 0.05 0.5'/></geometry></collision></link>"
         "<joint name='shoulder' type='revolute'><parent link='base'/><child link='upper'/><origin xyz='0 0 0.1'/>"
         "<axis xyz='0 1 0'/><limit lower='-3' upper='3' effort='10' velocity='1'/></joint>"
         "<link name='fore'>" + inertial +
         "<collision><origin xyz='0 0 0.25'/><geometry><box size='0.05 0.05 0.5'/></geometry></collision></link>"
         "<joint name='elbow' type='revolute'><parent link='upper'/><child link='fore'/><origin xyz='0 0 " + elbow_z + "' "
         "rpy='0 3.14159 0'/><axis xyz='0 1 0'/><limit lower='-3' upper='3' effort='10' velocity='1'/></joint>"
         "<link name='ball'>" + inertial + "<collision><geometry><sphere radius='0.05'/></geometry></collision></link>"
         "<joint name='ball_joint' type='floating'><parent link='world'/><child link='ball'/>"
         "<origin xyz='1 0 0.5'/></joint><implicit_sim>" + sim + "</implicit_sim></robot>";
}

TEST(SelfCollision, OneRobotsLinksMeetOnlyWhenAskedAndNeverAcrossADisabledPair) {
  const auto pair = [](const Model& m, const char* a, const char* b) { return m.PairIndex(m.FindBody(a), m.FindBody(b)); };
  const Model plain = LoadSceneFromString(FoldedArm(""), "arm");
  EXPECT_LT(pair(plain, "base", "fore"), 0);  // off by default, as Gazebo: the folded forearm in the base is fine
  EXPECT_GE(pair(plain, "ball", "fore"), 0);  // a free body is no part of the robot
  EXPECT_GE(pair(plain, "ball", "base"), 0);
  const Model self = LoadSceneFromString(FoldedArm("<self_collide link='fore'/>"), "arm");
  EXPECT_GE(pair(self, "base", "fore"), 0);
  EXPECT_LT(pair(self, "base", "upper"), 0);  // joined: never
  const Model srdf = LoadSceneFromString(
      FoldedArm("<self_collide link='base'/><disable_collisions link1='fore' link2='base' reason='Never'/>"), "arm");
  EXPECT_LT(pair(srdf, "base", "fore"), 0);
  EXPECT_GE(pair(srdf, "ball", "fore"), 0);
  for (const std::string& bad : {std::string("<disable_collisions link1='fore' link2='hand'/>"),
                                 std::string("<self_collide link='hand'/>")}) {
    try {
      LoadSceneFromString(FoldedArm(bad), "arm");
      ADD_FAILURE() << "accepted " << bad;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("must name a link of the scene"), std::string::npos) << e.what();
    }
  }
}

// Self-collision off: links that no joint joins but overlap at the start pose are named in one note, not refused.
TEST(SelfCollision, OverlapsOfARobotWithoutSelfCollisionAreNotedInOneLine) {
  const auto notes_of = [](const std::string& sim, const std::string& elbow_z) {
    std::vector<std::string> notes;
    LoaderOptions options;
    options.warnings = &notes;
    LoadSceneFromString(FoldedArm(sim, elbow_z), "arm", options);
    std::vector<std::string> overlaps;
    for (const std::string& note : notes) {
      if (note.find("overlap at their robot's start pose") != std::string::npos) overlaps.push_back(note);
    }
    return overlaps;
  };
  // The forearm reaches 0.05 m into the base (lifting it out is shorter than sliding it out sideways, 0.125 m). The
  // upper arm and the forearm fill the same space, but the elbow joins them.
  const std::vector<std::string> folded = notes_of("", "0.45");
  ASSERT_EQ(folded.size(), 1u);
  EXPECT_NE(folded[0].find("1 pairs of links"), std::string::npos) << folded[0];
  EXPECT_NE(folded[0].find("'base'-'fore' (0.05 m)"), std::string::npos) << folded[0];
  EXPECT_EQ(folded[0].find("'upper'"), std::string::npos) << folded[0];
  EXPECT_TRUE(notes_of("", "0.5").empty());  // resting on the base, 1e-7 m deep by the 3.14159 rad fold: no note
  EXPECT_TRUE(notes_of("<disable_collisions link1='fore' link2='base' reason='Default'/>", "0.45").empty());
  // Self-collision on: the pair collides, and the stepper's overlap check refuses such a start; no note.
  const std::vector<std::string> self = notes_of("<self_collide link='base'/>", "0.45");
  EXPECT_TRUE(self.empty());
  const Model model = LoadSceneFromString(FoldedArm("<self_collide link='base'/>", "0.45"), "arm");
  Data data(model);
  std::string detail;
  EXPECT_TRUE(FindInitialOverlap(model, State::Initial(model), 1e-6, &data, &detail));
  EXPECT_NE(detail.find("base"), std::string::npos) << detail;
}

}  // namespace
}  // namespace implicit_sim
