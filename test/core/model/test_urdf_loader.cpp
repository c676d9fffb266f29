// Scene loading: the shipped scenes load with the scenario's parameters; bad scenes are refused with a message that
// names the link or attribute.
#include "implicit_sim/core/model/urdf_loader.h"

#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "scenario_runner.h"

namespace implicit_sim {
namespace {

using testing_support::ScenePath;

TEST(UrdfLoader, P3SceneHasTheScenarioParameters) {
  const Model m = LoadSceneFromFile(ScenePath("p3_sphere_on_two_spheres.urdf"));
  EXPECT_EQ(m.scene_name, "p3_sphere_on_two_spheres");
  ASSERT_EQ(m.bodies.size(), 3u);
  ASSERT_EQ(m.num_moving(), 1);
  const Body& ball = m.bodies[m.FindBody("ball")];
  EXPECT_DOUBLE_EQ(ball.mass, 1.0);
  EXPECT_TRUE(ball.I_B.isApprox(0.4 * Mat3::Identity()));
  EXPECT_TRUE(ball.f_applied_W.isApprox(Vec3(1.0, 2.6, -9.81)));
  EXPECT_TRUE(m.gravity_W.isZero());
  EXPECT_TRUE(ball.X_WB0.translation().isApprox(Vec3(0, 6.62105263157895, 8.78417110772903)));
  EXPECT_TRUE(m.bodies[m.FindBody("sphere_b")].is_fixed);
  EXPECT_DOUBLE_EQ(m.bodies[m.FindBody("sphere_b")].shapes[0].size[0], 9.0);
  ASSERT_EQ(m.pairs.size(), 2u);
  EXPECT_EQ(m.PairName(0), "ball-sphere_a");
  EXPECT_EQ(m.PairName(1), "ball-sphere_b");
  EXPECT_DOUBLE_EQ(m.pairs[0].friction.mu, 0.2);
  EXPECT_DOUBLE_EQ(m.pairs[1].friction.e_r, 0.3);
}

TEST(UrdfLoader, P1DiscIsACylinderAlongWorldYWithLockedAxes) {
  const Model m = LoadSceneFromFile(ScenePath("p1_ngon10.urdf"));
  const Body& disc = m.bodies[m.FindBody("disc")];
  EXPECT_EQ(disc.shapes[0].type, ShapeType::kPrism);
  EXPECT_EQ(disc.shapes[0].sides, 10);
  const Vec3 axis_W = disc.X_WB0.linear() * disc.shapes[0].X_BS.linear() * Vec3::UnitZ();
  EXPECT_NEAR(std::abs(axis_W.y()), 1.0, 1e-12);
  const Vec3 vertex_W = disc.X_WB0 * (disc.shapes[0].X_BS * Vec3(1.0, 0, 0));  // the prism's vertex on +x
  EXPECT_NEAR(vertex_W.z(), 0.0, 1e-12);                                    // points down, onto the ground
  EXPECT_TRUE(disc.v_WB0.isApprox(Vec3(-3, 0, 0)));
  EXPECT_TRUE(disc.w_WB0.isApprox(Vec3(0, -3, 0)));
  EXPECT_FALSE(disc.locked[0]);
  EXPECT_TRUE(disc.locked[1]);
  EXPECT_TRUE(disc.locked[3]);
  EXPECT_FALSE(disc.locked[4]);
  EXPECT_TRUE(disc.locked[5]);
  EXPECT_DOUBLE_EQ(disc.I_B(1, 1), 0.5);
}

std::string Scene(const std::string& ball_collision, const std::string& extension = "",
                  const std::string& inertial =
                      "<inertial><mass value='1'/><inertia ixx='0.4' iyy='0.4' izz='0.4' ixy='0' ixz='0' iyz='0'/>"
                      "</inertial>",
                  const std::string& joint_type = "floating") {
  return "<robot name='t'>" + extension +
         "<link name='world'/>"
         "<link name='ground'><collision><geometry><box size='1 1 0.01'/></geometry><implicit type='halfspace'/>"
         "</collision></link>"
         "<joint name='g' type='fixed'><parent link='world'/><child link='ground'/></joint>"
         "<link name='ball'>" + inertial + "<collision>" + ball_collision + "</collision></link>"
         "<joint name='b' type='" + joint_type + "'><parent link='world'/><child link='ball'/>"
         "<origin xyz='0 0 1'/></joint></robot>";
}

const char* kSphere = "<geometry><sphere radius='1'/></geometry>";

void ExpectRefused(const std::string& xml, const std::string& must_mention) {
  try {
    LoadSceneFromString(xml);
    ADD_FAILURE() << "accepted a bad scene; expected an error mentioning '" << must_mention << "'";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(must_mention), std::string::npos) << e.what();
  }
}

TEST(UrdfLoader, AcceptsTheMinimalScene) {
  const Model m = LoadSceneFromString(Scene(kSphere));
  EXPECT_EQ(m.pairs.size(), 1u);
  EXPECT_EQ(m.PairName(0), "ball-ground");
}

TEST(UrdfLoader, ComputesInertiaFromTheShapeWhenThereIsNoInertial) {
  const Model m = LoadSceneFromString(
      Scene("<geometry><sphere radius='1'/></geometry><implicit type='ellipsoid' semi_axes='0.3 0.2 0.1' mass='2'/>",
            "", ""));
  const Body& b = m.bodies[m.FindBody("ball")];
  EXPECT_DOUBLE_EQ(b.mass, 2.0);
  EXPECT_NEAR(b.I_B(0, 0), 2.0 * (0.04 + 0.01) / 5.0, 1e-15);
}

TEST(UrdfLoader, RefusesBadScenesNamingWhatIsWrong) {
  ExpectRefused("<robot", "not well-formed");
  ExpectRefused("<notrobot/>", "<robot>");
  ExpectRefused(Scene(kSphere, "", "<inertial><mass value='-1'/><inertia ixx='1' iyy='1' izz='1' ixy='0' ixz='0' "
                                   "iyz='0'/></inertial>"),
                "link 'ball': mass");
  ExpectRefused(Scene(kSphere, "", "<inertial><mass value='1'/><inertia ixx='1' iyy='1' izz='3' ixy='0' ixz='0' "
                                   "iyz='0'/></inertial>"),
                "triangle inequality");
  ExpectRefused(Scene(kSphere + std::string("<implicit type='blob'/>")), "'blob' is unknown");
  ExpectRefused(Scene(kSphere + std::string("<implicit type='superellipsoid' semi_axes='1 1 1' exponent='1.5'/>")),
                "exponent");
  ExpectRefused(Scene(kSphere + std::string("<implicit type='ellipsoid' semi_axes='1 0 1'/>")), "semi_axes");
  ExpectRefused(Scene(kSphere + std::string("<implicit type='sphere' radius='nan'/>")), "radius");
  ExpectRefused(Scene(kSphere, "<implicit_sim><friction mu='-1'/></implicit_sim>"), "'mu'");
  ExpectRefused(Scene(kSphere, "<implicit_sim><friction e_r='-0.01'/></implicit_sim>"), "'e_r'");
  ExpectRefused(Scene(kSphere, "<implicit_sim><friction e_roll='-0.001'/></implicit_sim>"), "'e_roll'");
  ExpectRefused(Scene(kSphere, "<implicit_sim><body link='ball' velocity='1 0 0' locked='x'/></implicit_sim>"),
                "locked axis");
  ExpectRefused(Scene(kSphere, "<implicit_sim><body link='ball' locked='q'/></implicit_sim>"), "'q'");
  ExpectRefused(Scene(kSphere, "<implicit_sim><body link='nobody'/></implicit_sim>"), "<body>");
  ExpectRefused(Scene(kSphere, "<implicit_sim><wind/></implicit_sim>"), "<wind>");
  ExpectRefused(Scene("<geometry><box size='1 2'/></geometry>"),
                "link 'ball' <collision> <geometry> <box> attribute 'size'");
  ExpectRefused(Scene("<geometry><mesh filename='x.stl'/></geometry>"), "link 'ball': collision mesh 'x.stl'");
  ExpectRefused(Scene("<geometry><box size='1 1 1'/></geometry><implicit type='halfspace'/>", "", "", "floating"),
                "link 'ball': its mass properties cannot come from its shapes");
  ExpectRefused(Scene(kSphere, "", std::string("<inertial><mass value='1'/><inertia ixx='1' iyy='1' izz='1' ixy='0' "
                                               "ixz='0' iyz='0'/></inertial>"),
                      "revolute"),
                "joint 'b'");
  ExpectRefused(Scene(kSphere, "", std::string("<inertial><mass value='1'/><inertia ixx='1' iyy='1' izz='1' ixy='0' "
                                               "ixz='0' iyz='0'/></inertial>"),
                      "fixed"),
                "no moving body");
}

TEST(UrdfLoader, RefusesAMissingFile) {
  EXPECT_THROW(LoadSceneFromFile("/nonexistent/scene.urdf"), std::invalid_argument);
}

// A chain of 20,000 links (the audit's S1: recursion in the initial link poses overflowed the stack) loads: every tree
// walk of the loader is iterative and notes what it found, so a chain costs its length. The frames' poses compose.
TEST(UrdfLoader, AChainOfTwentyThousandLinksLoads) {
  constexpr int kLinks = 20000;
  std::string urdf =
      "<robot name='chain'><link name='world'/><link name='l0'><inertial><mass value='0.01'/><inertia ixx='1e-6' "
      "iyy='1e-6' izz='1e-6' ixy='0' ixz='0' iyz='0'/></inertial><collision><geometry><sphere radius='0.001'/>"
      "</geometry></collision></link><joint name='j0' type='floating'><parent link='world'/><child link='l0'/>"
      "<origin xyz='0 0 1'/></joint>";
  for (int i = 1; i < kLinks; ++i) {
    const std::string link = "l" + std::to_string(i), parent = "l" + std::to_string(i - 1);
    urdf += "<link name='" + link + "'/><joint name='j" + std::to_string(i) + "' type='fixed'><parent link='" + parent +
            "'/><child link='" + link + "'/><origin xyz='0 0 0.0001'/></joint>";
  }
  urdf += "</robot>";
  const Model model = LoadSceneFromString(urdf, "chain");
  ASSERT_EQ(model.bodies.size(), 1u);
  ASSERT_EQ(model.frames.size(), static_cast<size_t>(kLinks - 1));
  EXPECT_EQ(model.frames.back().name, "l" + std::to_string(kLinks - 1));
  EXPECT_EQ(model.frames.back().body, 0);
  EXPECT_NEAR(model.frames.back().X_LF.translation().z(), (kLinks - 1) * 1e-4, 1e-9);
}

// The audit's 10^5 free spheres stored every pair (18 GB and rising); a scene past Model::kMaxContactPairs is refused
// before its pairs are formed, with the counts and the limit. 6000 spheres can form 17 997 000 pairs.
TEST(UrdfLoader, AScenePastThePairLimitIsRefusedBeforeItsPairsAreFormed) {
  std::string urdf = "<robot name='many'><link name='world'/>";
  for (int i = 0; i < 6000; ++i) {
    const std::string link = "s" + std::to_string(i);
    urdf += "<link name='" + link + "'><inertial><mass value='1'/><inertia ixx='1e-3' iyy='1e-3' izz='1e-3' ixy='0' "
            "ixz='0' iyz='0'/></inertial><collision><geometry><sphere radius='0.01'/></geometry></collision></link>"
            "<joint name='j" + link + "' type='floating'><parent link='world'/><child link='" + link + "'/><origin xyz='" +
            std::to_string(0.05 * (i % 100)) + " " + std::to_string(0.05 * (i / 100)) + " 1'/></joint>";
  }
  urdf += "</robot>";
  try {
    LoadSceneFromString(urdf, "many");
    ADD_FAILURE() << "loaded";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("6000 shapes can form 17997000 contact pairs, over the limit of 8388608"),
              std::string::npos) << e.what();
  }
}

// A moving chain of `links` revolute links, each with a sphere, above a fixed floor box (the audit's chain with
// collisions: every pair of one robot was listed as excluded, N^2/2 of them, and each pair scanned every joint).
std::string RevoluteChainWithSpheres(int links, const std::string& sim = "") {
  std::string urdf = "<robot name='chain'><link name='world'/><link name='floor'><collision><geometry><box size='9 9 "
                     "0.1'/></geometry></collision></link><joint name='f' type='fixed'><parent link='world'/><child "
                     "link='floor'/><origin xyz='0 0 -1'/></joint>";
  std::string parent = "world";
  for (int i = 0; i < links; ++i) {
    const std::string link = "l" + std::to_string(i);
    urdf += "<link name='" + link + "'><inertial><mass value='0.1'/><inertia ixx='1e-4' iyy='1e-4' izz='1e-4' ixy='0' "
            "ixz='0' iyz='0'/></inertial><collision><geometry><sphere radius='0.01'/></geometry></collision></link>"
            "<joint name='j" + std::to_string(i) + "' type='revolute'><parent link='" + parent + "'/><child link='" +
            link + "'/><origin xyz='0 0 0.05'/><axis xyz='0 1 0'/><limit lower='-1' upper='1' effort='1' "
            "velocity='1'/></joint>";
    parent = link;
  }
  return urdf + sim + "</robot>";
}

// One robot without self-collision is one group: its pairs are never listed, so a 5000-link chain loads with only its
// pairs with the floor, and names are found by hash.
TEST(UrdfLoader, ALongChainWithCollisionsFormsOnlyItsPairsWithOtherBodies) {
  constexpr int kLinks = 5000;
  const Model model = LoadSceneFromString(RevoluteChainWithSpheres(kLinks), "chain");
  ASSERT_EQ(model.bodies.size(), static_cast<size_t>(kLinks + 1));
  EXPECT_EQ(model.pairs.size(), static_cast<size_t>(kLinks));  // each link with the floor
  EXPECT_EQ(model.ContactPairBound(), static_cast<int64_t>(kLinks));
  EXPECT_TRUE(model.excluded_pairs.empty());
  const int first = model.FindBody("l0"), last = model.FindBody("l" + std::to_string(kLinks - 1));
  EXPECT_TRUE(model.Excluded(first, last));
  EXPECT_FALSE(model.Excluded(first, model.FindBody("floor")));
  EXPECT_LT(model.PairIndex(first, last), 0);
  EXPECT_GE(model.PairIndex(last, model.FindBody("floor")), 0);
  for (int b = 0; b < static_cast<int>(model.bodies.size()); ++b) EXPECT_EQ(model.FindBody(model.bodies[b].name), b);
  for (int j = 0; j < static_cast<int>(model.joints.size()); ++j) EXPECT_EQ(model.FindJoint(model.joints[j].name), j);
  EXPECT_EQ(model.FindBody("l" + std::to_string(kLinks)), -1);
  EXPECT_EQ(model.FindJoint("floor"), -1);
}

// With self-collision on, the links not joined form pairs (the bound counts the joined ones too), and a
// <disable_collisions> pair is left out.
TEST(UrdfLoader, ASelfCollidingChainPairsEveryTwoLinksNoJointJoins) {
  constexpr int kLinks = 40;
  const Model model = LoadSceneFromString(
      RevoluteChainWithSpheres(kLinks, "<implicit_sim><self_collide link='l3'/><disable_collisions link1='l0' "
                                       "link2='l9'/></implicit_sim>"),
      "chain");
  const int64_t within = int64_t{kLinks} * (kLinks - 1) / 2;
  EXPECT_EQ(model.pairs.size(), static_cast<size_t>(within - (kLinks - 1) - 1 + kLinks));
  EXPECT_EQ(model.ContactPairBound(), within - 1 + kLinks);
  EXPECT_LT(model.PairIndex(model.FindBody("l0"), model.FindBody("l9")), 0);
  EXPECT_GE(model.PairIndex(model.FindBody("l0"), model.FindBody("l8")), 0);
  EXPECT_LT(model.PairIndex(model.FindBody("l4"), model.FindBody("l5")), 0);  // joined
}

// Past kMaxSceneLinks <link> elements a scene is refused right after the XML parse, with the limit in the message.
TEST(UrdfLoader, MoreLinksThanTheLimitAreRefusedBeforeTheyAreRead) {
  std::string urdf = "<robot name='links'><link name='world'/>";
  for (int i = 0; i < kMaxSceneLinks; ++i) urdf += "<link name='x" + std::to_string(i) + "'/>";
  urdf += "</robot>";
  try {
    LoadSceneFromString(urdf, "links");
    ADD_FAILURE() << "loaded";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "scene 'links': more than 50000 <link> elements (the loader's limit, kMaxSceneLinks)");
  }
}

// A load whose interrupt is due (requested, or past its deadline) throws LoadInterrupted and returns nothing.
TEST(UrdfLoader, ALoadWhoseInterruptIsDueEndsWithLoadInterrupted) {
  const std::string urdf = RevoluteChainWithSpheres(200);
  for (bool by_deadline : {false, true}) {
    StepInterrupt interrupt;
    if (by_deadline) {
      interrupt.SetDeadlineIn(0.0);
    } else {
      interrupt.Request();
    }
    LoaderOptions options;
    options.interrupt = &interrupt;
    try {
      LoadSceneFromString(urdf, "chain", options);
      ADD_FAILURE() << "loaded";
    } catch (const LoadInterrupted& e) {
      EXPECT_STREQ(e.what(), "scene 'chain': loading interrupted");
    }
    interrupt.Clear();
    EXPECT_EQ(LoadSceneFromString(urdf, "chain", options).bodies.size(), 201u);
  }
}

}  // namespace
}  // namespace implicit_sim
