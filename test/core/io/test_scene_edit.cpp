// Scene editing (io/scene_edit.h): spawned scenes and robots load with the composed poses, the rigid-motion twist and
// renamed <implicit_sim> entries; removing links takes their subtrees and entries; the robot description has no free
// bodies; an add followed by a remove restores the model; bad inputs are refused naming the problem.
#include "implicit_sim/core/io/scene_edit.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <tinyxml2.h>
#include <urdf_parser/urdf_parser.h>

#include "implicit_sim/core/model/joints.h"
#include "implicit_sim/core/model/urdf_loader.h"
#include "io/scene_xml.h"
#include "scenario_runner.h"
#include "test_models.h"

namespace implicit_sim {
namespace {

using testing_support::ScenePath;

std::string ReadScene(const std::string& file) {
  std::ifstream in(ScenePath(file));
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

Pose MakePose(double angle, const Vec3& axis, const Vec3& p) {
  Pose X = Pose::Identity();
  X.linear() = Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
  X.translation() = p;
  return X;
}

const Body& BodyNamed(const Model& m, const std::string& name) {
  const int b = m.FindBody(name);
  if (b < 0) throw std::runtime_error("no body '" + name + "'");
  return m.bodies[b];
}

std::vector<std::string> BodyNames(const Model& m) {
  std::vector<std::string> names;
  for (const Body& b : m.bodies) names.push_back(b.name);
  return names;
}

const ContactPair& PairOf(const Model& m, const std::string& a, const std::string& b) {
  const int pair = m.PairIndex(m.FindBody(a), m.FindBody(b));
  if (pair < 0) throw std::runtime_error("no pair " + a + "-" + b);
  return m.pairs[pair];
}

void ExpectPoseNear(const Pose& actual, const Pose& expected, double tol, const std::string& what) {
  EXPECT_LE((actual.translation() - expected.translation()).norm(), tol) << what;
  EXPECT_LE((actual.linear() - expected.linear()).norm(), tol) << what;
}

// The call throws std::invalid_argument whose message contains every one of `parts`.
void ExpectRefused(const std::function<void()>& call, const std::vector<std::string>& parts) {
  try {
    call();
    ADD_FAILURE() << "not refused; expected a message with '" << parts.front() << "'";
  } catch (const std::invalid_argument& e) {
    for (const std::string& part : parts) EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
  }
}

// A scene addition with a static pedestal, a free puck (centre of mass off its link origin, its own twist, a force),
// a pendulum on a revolute joint to world, a friction pair, a joint entry, and a default friction and gravity that
// the scene's replace.
const char kToyScene[] = R"(<?xml version="1.0"?>
<robot name="toy">
  <implicit_sim gravity="0 0 -1">
    <friction mu="0.9" e_r="0.7"/>
    <friction link1="puck" link2="pedestal" mu="0.25"/>
    <body link="puck" velocity="1 -0.5 0.25" angular_velocity="0.3 0 2" force="0 0 -3"/>
    <joint name="hinge" position="0.2" velocity="0.5" effort="0.1"/>
  </implicit_sim>
  <link name="world"/>
  <link name="pedestal">
    <collision><geometry><box size="0.2 0.2 0.2"/></geometry></collision>
  </link>
  <joint name="pedestal_joint" type="fixed">
    <parent link="world"/><child link="pedestal"/><origin xyz="0.3 0 0.1" rpy="0 0 0.5"/>
  </joint>
  <link name="puck">
    <inertial><origin xyz="0.01 0.02 0"/><mass value="0.5"/>
      <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.0015"/></inertial>
    <collision><geometry><cylinder radius="0.05" length="0.02"/></geometry></collision>
  </link>
  <joint name="puck_joint" type="floating">
    <parent link="world"/><child link="puck"/><origin xyz="0 0.2 0.5" rpy="0.1 0.2 0.3"/>
  </joint>
  <link name="bob">
    <inertial><origin xyz="0 0 -0.5"/><mass value="1"/>
      <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.001"/></inertial>
    <collision><origin xyz="0 0 -0.5"/><geometry><sphere radius="0.05"/></geometry></collision>
  </link>
  <joint name="hinge" type="revolute">
    <parent link="world"/><child link="bob"/><origin xyz="0 -0.5 1"/><axis xyz="0 1 0"/>
    <limit lower="-1" upper="1" effort="10" velocity="10"/>
  </joint>
</robot>
)";

// A robot (root `base`, not `world`): a post carrying a 2-link arm, as in arm_push.urdf.
const char kArm[] = R"(<?xml version="1.0"?>
<robot name="arm">
  <implicit_sim><joint name="shoulder" effort="1.0"/></implicit_sim>
  <link name="base">
    <inertial><origin xyz="0 0 0.025"/><mass value="2"/>
      <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.001"/></inertial>
    <collision><origin xyz="0 0 0.025"/><geometry><box size="0.05 0.05 0.05"/></geometry></collision>
  </link>
  <link name="upper_arm">
    <inertial><origin xyz="0.2 0 0"/><mass value="0.2"/>
      <inertia ixx="0.00005" ixy="0" ixz="0" iyy="0.0027" iyz="0" izz="0.0027"/></inertial>
    <collision><origin xyz="0.2 0 0"/><geometry><box size="0.4 0.04 0.04"/></geometry></collision>
  </link>
  <joint name="shoulder" type="continuous">
    <parent link="base"/><child link="upper_arm"/><origin xyz="0 0 0.1"/><axis xyz="0 0 1"/>
    <limit effort="5" velocity="10"/>
  </joint>
  <link name="forearm">
    <inertial><origin xyz="0.15 0 0"/><mass value="0.15"/>
      <inertia ixx="0.00004" ixy="0" ixz="0" iyy="0.0012" iyz="0" izz="0.0012"/></inertial>
    <collision><origin xyz="0.15 0 0"/><geometry><box size="0.3 0.04 0.04"/></geometry></collision>
  </link>
  <joint name="elbow" type="revolute">
    <parent link="upper_arm"/><child link="forearm"/><origin xyz="0.4 0 0" rpy="0 0.3 0"/><axis xyz="0 0 1"/>
    <limit lower="-0.3" upper="0.3" effort="5" velocity="10"/>
  </joint>
</robot>
)";

// kArm as a scene of its own: the reference the spawned copies are compared with (root welded at the identity).
std::string ArmAsScene(const std::string& joint_type) {
  std::string text = kArm;
  text.replace(text.find("  <link name=\"base\">"), 0,
               "  <link name=\"world\"/>\n  <joint name=\"base_joint\" type=\"" + joint_type +
                   "\"><parent link=\"world\"/><child link=\"base\"/></joint>\n");
  return text;
}

// The world velocity of the point p of a body moving rigidly with O.
Vec3 RigidVelocity(const SceneAddition& a, const Vec3& p) {
  return a.v_WO + a.w_WO.cross(p - a.X_WO.translation());
}

TEST(SceneEdit, SpawnsTheP3SceneTwiceWithComposedPosesAndTwists) {
  const std::string p3 = ReadScene("p3_sphere_on_two_spheres.urdf");
  const Model alone = LoadSceneFromString(p3);
  SceneAddition first;
  first.urdf = p3;
  first.prefix = "a/";
  first.X_WO = MakePose(0.7, Vec3(1, 2, 3), Vec3(1, -2, 0.5));
  first.v_WO = Vec3(0.5, -1, 2);
  first.w_WO = Vec3(0.1, 0.2, -0.3);
  SceneAddition second = first;
  second.prefix = "b_";
  second.X_WO = MakePose(-2.5, Vec3(-1, 0.5, 0.2), Vec3(-3, 4, 20));
  second.v_WO = Vec3::Zero();
  second.w_WO = Vec3(0, 0, 1.5);
  std::vector<std::string> added_first, added_second;
  const std::string once = AddToScene(ReadScene("cube_drop.urdf"), first, &added_first);
  const std::string twice = AddToScene(once, second, &added_second);
  EXPECT_EQ(added_first, (std::vector<std::string>{"a/ball", "a/sphere_a", "a/sphere_b"}));
  EXPECT_EQ(added_second, (std::vector<std::string>{"b_ball", "b_sphere_a", "b_sphere_b"}));
  const Model m = LoadSceneFromString(twice);
  EXPECT_EQ(BodyNames(m), (std::vector<std::string>{"ground", "cube", "a/ball", "a/sphere_a", "a/sphere_b",
                                                     "b_ball", "b_sphere_a", "b_sphere_b"}));
  EXPECT_EQ(m.num_moving(), 3);
  EXPECT_EQ(m.gravity_W, Vec3(0, 0, -9.81));  // the scene's gravity, not P3's zero
  for (const SceneAddition* a : {&first, &second}) {
    for (const Body& original : alone.bodies) {
      const Body& b = BodyNamed(m, a->prefix + original.name);
      ExpectPoseNear(b.X_WB0, a->X_WO * original.X_WB0, 1e-12, b.name);
      EXPECT_EQ(b.is_fixed, original.is_fixed) << b.name;
      EXPECT_EQ(b.mass, original.mass) << b.name;
    }
    const Body& ball = BodyNamed(m, a->prefix + "ball");
    EXPECT_LE((ball.v_WB0 - RigidVelocity(*a, ball.X_WB0.translation())).norm(), 1e-12);
    EXPECT_LE((ball.w_WB0 - a->w_WO).norm(), 1e-15);
    EXPECT_EQ(ball.f_applied_W, Vec3(1.0, 2.6, -9.81));  // world-frame loads stay as written
    // The addition's default friction (mu 0.2) is ignored: the scene's (mu 0.5, e_r 0.01 m) applies.
    EXPECT_EQ(PairOf(m, a->prefix + "ball", a->prefix + "sphere_a").friction.mu, 0.5);
    EXPECT_EQ(PairOf(m, a->prefix + "ball", "ground").friction.e_r, 0.01);
  }
  EXPECT_EQ(AddToScene(ReadScene("cube_drop.urdf"), first, nullptr), once);  // deterministic
  SceneAddition shifted = first;
  shifted.X_WO = MakePose(0.0, Vec3::UnitZ(), Vec3(1, 2, 3));
  const std::string text = AddToScene(ReadScene("cube_drop.urdf"), shifted, nullptr);
  EXPECT_NE(text.find("<origin xyz=\"1 13.4 3\" rpy=\"0 0 0\"/>"), std::string::npos) << text;  // no "-0"
}

TEST(SceneEdit, SpawnRenamesFrictionPairsAndJointEntriesAndRotatesTheOwnTwist) {
  const Model alone = LoadSceneFromString(kToyScene);
  SceneAddition a;
  a.urdf = kToyScene;
  a.prefix = "toy_1/";
  a.X_WO = MakePose(1.1, Vec3(0.3, -0.4, 1), Vec3(0.7, 0.1, 0.05));
  a.v_WO = Vec3(-0.2, 0.4, 0.1);
  a.w_WO = Vec3(0.5, -0.1, 0.8);
  const Model m = LoadSceneFromString(AddToScene(ReadScene("cube_drop.urdf"), a, nullptr));
  const Mat3 R_WO = a.X_WO.linear();
  for (const char* name : {"pedestal", "puck", "bob"}) {
    ExpectPoseNear(BodyNamed(m, a.prefix + name).X_WB0, a.X_WO * BodyNamed(alone, name).X_WB0, 1e-12, name);
  }
  const Body& puck = BodyNamed(m, "toy_1/puck");
  const Body& puck_alone = BodyNamed(alone, "puck");
  const Vec3 p_puck = puck.X_WB0.translation();  // the centre of mass, 0.01 0.02 0 off the link origin
  EXPECT_LE((puck.v_WB0 - (R_WO * puck_alone.v_WB0 + RigidVelocity(a, p_puck))).norm(), 1e-12);
  EXPECT_LE((puck.w_WB0 - (R_WO * Vec3(0.3, 0, 2) + a.w_WO)).norm(), 1e-12);
  EXPECT_EQ(puck.f_applied_W, Vec3(0, 0, -3));
  // The pair keeps its mu; the rest comes from the scene's default (e_r 0.01 m), not the addition's (0.7 m).
  const FrictionParams& pair = PairOf(m, "toy_1/puck", "toy_1/pedestal").friction;
  EXPECT_EQ(pair.mu, 0.25);
  EXPECT_EQ(pair.e_r, 0.01);
  EXPECT_EQ(PairOf(m, "toy_1/puck", "ground").friction.mu, 0.5);
  EXPECT_EQ(PairOf(m, "toy_1/bob", "cube").friction.e_r, 0.01);
  ASSERT_GE(m.FindJoint("toy_1/hinge"), 0);
  const Joint& hinge = m.joints[m.FindJoint("toy_1/hinge")];
  EXPECT_EQ(hinge.initial_position, 0.2);
  EXPECT_EQ(hinge.initial_velocity, 0.5);
  EXPECT_EQ(hinge.applied_effort, 0.1);
  EXPECT_EQ(m.FindJoint("hinge"), -1);
  // A jointed body takes its twist from the joint (not from the spawn twist): the original's, rotated.
  const Body& bob = BodyNamed(m, "toy_1/bob");
  EXPECT_LE((bob.w_WB0 - R_WO * BodyNamed(alone, "bob").w_WB0).norm(), 1e-12);
  EXPECT_LE((bob.v_WB0 - R_WO * BodyNamed(alone, "bob").v_WB0).norm(), 1e-12);
  EXPECT_GT(bob.w_WB0.norm(), 0.49);
}

TEST(SceneEdit, SpawnsARobotWeldedAndFloating) {
  const Model welded_alone = LoadSceneFromString(ArmAsScene("fixed"));
  const Model floating_alone = LoadSceneFromString(ArmAsScene("floating"));
  SceneAddition welded;
  welded.urdf = kArm;
  welded.prefix = "r1/";
  welded.X_WO = MakePose(0.4, Vec3(0, 0, 1), Vec3(1, 1, 0));
  welded.v_WO = Vec3(3, 0, 0);  // no free body: ignored
  SceneAddition floating = welded;
  floating.prefix = "r2/";
  floating.floating_root = true;
  floating.X_WO = MakePose(-0.9, Vec3(1, 1, 0), Vec3(-1, 0.5, 0.3));
  floating.v_WO = Vec3(0.1, 0.2, -0.3);
  floating.w_WO = Vec3(0.4, -0.5, 0.6);
  std::vector<std::string> added;
  const std::string text =
      AddToScene(AddToScene(ReadScene("cube_drop.urdf"), welded, &added), floating, nullptr);
  EXPECT_EQ(added, (std::vector<std::string>{"r1/base", "r1/upper_arm", "r1/forearm"}));
  const Model m = LoadSceneFromString(text);
  EXPECT_TRUE(BodyNamed(m, "r1/base").is_fixed);
  EXPECT_FALSE(BodyNamed(m, "r2/base").is_fixed);
  for (const char* name : {"base", "upper_arm", "forearm"}) {
    ExpectPoseNear(BodyNamed(m, std::string("r1/") + name).X_WB0,
                   welded.X_WO * BodyNamed(welded_alone, name).X_WB0, 1e-12, name);
    const Body& b = BodyNamed(m, std::string("r2/") + name);
    ExpectPoseNear(b.X_WB0, floating.X_WO * BodyNamed(floating_alone, name).X_WB0, 1e-12, name);
    // The whole robot moves rigidly with O: the root by the spawn twist, its links through their joints.
    EXPECT_LE((b.v_WB0 - RigidVelocity(floating, b.X_WB0.translation())).norm(), 1e-12) << name;
    EXPECT_LE((b.w_WB0 - floating.w_WO).norm(), 1e-12) << name;
  }
  EXPECT_TRUE(BodyNamed(m, "r1/upper_arm").v_WB0.isZero(0.0));
  for (const char* prefix : {"r1/", "r2/"}) {
    const int shoulder = m.FindJoint(std::string(prefix) + "shoulder");
    ASSERT_GE(shoulder, 0) << prefix;
    EXPECT_EQ(m.joints[shoulder].applied_effort, 1.0);
    EXPECT_GE(m.FindJoint(std::string(prefix) + "elbow"), 0);
  }
  tinyxml2::XMLDocument doc;
  ASSERT_EQ(doc.Parse(text.c_str()), tinyxml2::XML_SUCCESS);
  std::map<std::string, std::string> attach_types;
  for (auto* j = doc.RootElement()->FirstChildElement("joint"); j; j = j->NextSiblingElement("joint")) {
    if (std::string(j->FirstChildElement("parent")->Attribute("link")) == "world") {
      attach_types[j->Attribute("name")] = j->Attribute("type");
    }
  }
  EXPECT_EQ(attach_types["r1/base_joint"], "fixed");
  EXPECT_EQ(attach_types["r2/base_joint"], "floating");
}

// ~spawn's start options: joint positions by the addition's own names (an existing <implicit_sim><joint> entry keeps
// its effort and gains the position), self-collision on request, and an SRDF's <disable_collisions> renamed.
TEST(SceneEdit, SpawnTakesJointPositionsSelfCollideAndAnSrdf) {
  SceneAddition arm;
  arm.urdf = kArm;
  arm.prefix = "r1/";
  arm.X_WO = MakePose(0.0, Vec3(0, 0, 1), Vec3(0, 0, 1));
  arm.joint_positions = {{"shoulder", 1.25}, {"elbow", -0.2}};
  const Model plain = LoadSceneFromString(AddToScene(ReadScene("cube_drop.urdf"), arm, nullptr));
  State state = State::Initial(plain);
  EXPECT_NEAR(JointPosition(plain, state, plain.FindJoint("r1/shoulder")), 1.25, 1e-12);
  EXPECT_NEAR(JointPosition(plain, state, plain.FindJoint("r1/elbow")), -0.2, 1e-12);
  EXPECT_EQ(plain.joints[plain.FindJoint("r1/shoulder")].applied_effort, 1.0);
  const int base = plain.FindBody("r1/base"), upper = plain.FindBody("r1/upper_arm");
  const int fore = plain.FindBody("r1/forearm");
  auto excluded = [](const Model& m, int a, int b) { return m.Excluded(a, b); };
  EXPECT_TRUE(excluded(plain, base, fore));  // self-collision off by default: the whole robot
  SceneAddition colliding = arm;
  colliding.self_collide = true;
  const Model self = LoadSceneFromString(AddToScene(ReadScene("cube_drop.urdf"), colliding, nullptr));
  EXPECT_FALSE(excluded(self, base, fore));
  colliding.srdf = "<robot name='arm'><group name='g'/><disable_collisions link1='base' link2='forearm' "
                   "reason='Never'/></robot>";
  const Model semantic = LoadSceneFromString(AddToScene(ReadScene("cube_drop.urdf"), colliding, nullptr));
  EXPECT_TRUE(excluded(semantic, base, fore));
  EXPECT_FALSE(excluded(semantic, upper, semantic.FindBody("cube")));
  auto refusal = [&](SceneAddition a) {
    try {
      AddToScene(ReadScene("cube_drop.urdf"), a, nullptr);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  SceneAddition bad = arm;
  bad.joint_positions = {{"wrist", 0.1}};
  EXPECT_EQ(refusal(bad), "AddToScene: joint_positions: 'wrist' is not a joint of the addition");
  bad.joint_positions = {{"elbow", std::nan("")}};
  EXPECT_EQ(refusal(bad), "AddToScene: joint_positions['elbow'] must be finite");
  bad = arm;
  bad.srdf = "<robot><disable_collisions link1='base' link2='hand'/></robot>";
  EXPECT_EQ(refusal(bad), "AddToScene: SRDF <disable_collisions link2='hand'>: not a link of the addition");
  bad.srdf = "<srdf/>";
  EXPECT_EQ(refusal(bad), "AddToScene: the SRDF is not an XML document with a root element <robot>");
  bad = arm;
  bad.joint_positions = {{"elbow", 0.5}};  // beyond its limit of 0.3: the loader's message
  const std::string beyond = AddToScene(ReadScene("cube_drop.urdf"), bad, nullptr);
  try {
    LoadSceneFromString(beyond);
    ADD_FAILURE() << "a start position beyond the limit was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("r1/elbow"), std::string::npos) << e.what();
  }
}

// ~load_scene's and robot_description_semantic's path: start positions and an SRDF on a whole scene.
TEST(SceneEdit, WithStartEntriesSetsAScenesJointPositionsAndSrdfPairs) {
  const std::string scene = ArmAsScene("fixed");
  EXPECT_EQ(WithStartEntries(scene, {}, ""), scene);
  const std::string srdf = "<robot name='arm'><disable_collisions link1='base' link2='forearm' reason='Never'/></robot>";
  std::string text = WithStartEntries(scene, {{"elbow", 0.25}}, srdf);
  text.replace(text.find("<implicit_sim>"), 14, "<implicit_sim><self_collide link='base'/>");
  const Model m = LoadSceneFromString(text);
  EXPECT_NEAR(JointPosition(m, State::Initial(m), m.FindJoint("elbow")), 0.25, 1e-12);
  EXPECT_EQ(m.joints[m.FindJoint("shoulder")].applied_effort, 1.0);  // the scene's own entry is kept
  const int base = m.FindBody("base"), fore = m.FindBody("forearm");
  EXPECT_TRUE(m.Excluded(base, fore));
  try {
    WithStartEntries(scene, {{"knee", 0.1}}, "");
    ADD_FAILURE() << "an unknown joint was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "WithStartEntries: joint_positions: 'knee' is not a joint of the scene");
  }
}

TEST(SceneEdit, RefusesANameClashNamingTheLinkOrJoint) {
  const std::string p3 = ReadScene("p3_sphere_on_two_spheres.urdf");
  SceneAddition a;
  a.urdf = p3;
  ExpectRefused([&] { AddToScene(p3, a, nullptr); }, {"link 'ball' already exists in the scene"});
  a.urdf = kArm;
  a.prefix = "arm_";
  const std::string scene = ReadScene("cube_drop.urdf");
  const std::string with_arm = AddToScene(scene, a, nullptr);
  ExpectRefused([&] { AddToScene(with_arm, a, nullptr); }, {"link 'arm_base' already exists"});
  // Only the joint clashes: a scene whose link names differ but which has a joint 'arm_shoulder'.
  std::string joint_clash = scene;
  joint_clash.replace(joint_clash.find("name=\"cube_joint\""), 17, "name=\"arm_shoulder\"");
  ExpectRefused([&] { AddToScene(joint_clash, a, nullptr); }, {"joint 'arm_shoulder' already exists"});
}

void AppendAttributeValues(const tinyxml2::XMLElement* e, std::string* out) {
  for (const tinyxml2::XMLAttribute* a = e->FirstAttribute(); a; a = a->Next()) *out += std::string(a->Value()) + " ";
  for (auto* child = e->FirstChildElement(); child; child = child->NextSiblingElement()) {
    AppendAttributeValues(child, out);
  }
}

// Every attribute value of every element of `text`, space-separated (names, references, numbers).
std::string AttributeValues(const std::string& text) {
  tinyxml2::XMLDocument doc;
  if (doc.Parse(text.c_str()) != tinyxml2::XML_SUCCESS) throw std::runtime_error("not XML");
  std::string out;
  AppendAttributeValues(doc.RootElement(), &out);
  return out;
}

TEST(SceneEdit, RemovesASubtreeWithItsJointsAndEntries) {
  std::string gripper = ReadScene("gripper_lift.urdf");
  gripper.replace(gripper.find("  </implicit_sim>"), 0,
                  "    <friction link1=\"left_finger\" link2=\"ball\" mu=\"0.7\"/>\n"
                  "    <friction link1=\"ball\" link2=\"right_finger\" mu=\"0.6\"/>\n");
  ASSERT_EQ(PairOf(LoadSceneFromString(gripper), "left_finger", "ball").friction.mu, 0.7);
  std::vector<std::string> removed;
  const std::string without_palm = RemoveFromScene(gripper, {"palm"}, &removed);
  EXPECT_EQ(removed, (std::vector<std::string>{"palm", "left_finger", "right_finger"}));
  const std::string values = " " + AttributeValues(without_palm);  // (the file's comment still mentions them)
  for (const char* gone : {"palm", "left_finger", "right_finger", "lift", "left_slide", "right_slide"}) {
    EXPECT_EQ(values.find(std::string(" ") + gone + " "), std::string::npos) << gone;
  }
  EXPECT_NE(values.find(" ball "), std::string::npos);
  const Model m = LoadSceneFromString(without_palm);
  EXPECT_EQ(BodyNames(m), std::vector<std::string>{"ball"});
  EXPECT_TRUE(m.joints.empty());
  EXPECT_EQ(m.pairs.size(), 0u);

  const Model one_finger = LoadSceneFromString(RemoveFromScene(gripper, {"left_finger"}, &removed));
  EXPECT_EQ(removed, std::vector<std::string>{"left_finger"});
  EXPECT_EQ(BodyNames(one_finger), (std::vector<std::string>{"palm", "right_finger", "ball"}));
  EXPECT_EQ(one_finger.FindJoint("left_slide"), -1);
  EXPECT_EQ(one_finger.joints[one_finger.FindJoint("right_slide")].applied_effort, -2.0);
  EXPECT_EQ(PairOf(one_finger, "ball", "right_finger").friction.mu, 0.6);
}

TEST(SceneEdit, RemoveRefusesAnUnknownLinkAndWorld) {
  const std::string gripper = ReadScene("gripper_lift.urdf");
  ExpectRefused([&] { RemoveFromScene(gripper, {"palm", "thumb"}, nullptr); }, {"link 'thumb'", "not in the scene"});
  ExpectRefused([&] { RemoveFromScene(gripper, {"world"}, nullptr); }, {"link 'world'"});
}

std::vector<std::string> UrdfdomLinks(const std::string& text) {
  const urdf::ModelInterfaceSharedPtr model = urdf::parseURDF(text);
  if (!model) throw std::runtime_error("urdfdom could not parse the robot description");
  std::vector<urdf::LinkSharedPtr> links;
  model->getLinks(links);
  std::vector<std::string> names;
  for (const auto& l : links) names.push_back(l->name);
  return names;  // ordered by name
}

TEST(SceneEdit, RobotDescriptionHasNoFreeBodiesAndNoExtension) {
  const std::string arm = RobotDescriptionOf(ReadScene("arm_push.urdf"));
  EXPECT_EQ(UrdfdomLinks(arm), (std::vector<std::string>{"floor", "forearm", "upper_arm", "world"}));
  EXPECT_EQ(arm.find("implicit_sim"), std::string::npos);
  EXPECT_EQ(arm.find("egg"), std::string::npos);
  EXPECT_NE(arm.find("<implicit type=\"halfspace\"/>"), std::string::npos);  // what urdfdom ignores may stay

  const std::string gripper = RobotDescriptionOf(ReadScene("gripper_lift.urdf"));
  EXPECT_EQ(UrdfdomLinks(gripper), (std::vector<std::string>{"left_finger", "palm", "right_finger", "world"}));

  EXPECT_EQ(UrdfdomLinks(RobotDescriptionOf(ReadScene("p3_sphere_on_two_spheres.urdf"))),
            (std::vector<std::string>{"sphere_a", "sphere_b", "world"}));
  // A planar joint's subtree goes too (robot_state_publisher's KDL would make the joint fixed).
  EXPECT_EQ(UrdfdomLinks(RobotDescriptionOf(test_models::kPlanarJointRobotUrdf)),
            (std::vector<std::string>{"arm", "world"}));
  // A floating robot goes whole; only `world` remains, still a URDF urdfdom reads.
  SceneAddition a;
  a.urdf = kArm;
  a.floating_root = true;
  std::string only_world = ReadScene("p2_sphere_spinning.urdf");
  only_world = RemoveFromScene(only_world, {"ground"}, nullptr);
  const std::string description = RobotDescriptionOf(AddToScene(only_world, a, nullptr));
  EXPECT_EQ(UrdfdomLinks(description), std::vector<std::string>{"world"});
}

void ExpectSameModel(const Model& a, const Model& b) {
  ASSERT_EQ(BodyNames(a), BodyNames(b));
  for (size_t i = 0; i < a.bodies.size(); ++i) {
    EXPECT_TRUE(a.bodies[i].X_WB0.isApprox(b.bodies[i].X_WB0, 0.0)) << a.bodies[i].name;
    EXPECT_EQ(a.bodies[i].mass, b.bodies[i].mass) << a.bodies[i].name;
    EXPECT_EQ(a.bodies[i].v_WB0, b.bodies[i].v_WB0) << a.bodies[i].name;
  }
  ASSERT_EQ(a.pairs.size(), b.pairs.size());
  for (size_t k = 0; k < a.pairs.size(); ++k) {
    EXPECT_EQ(a.PairName(k), b.PairName(k));
    EXPECT_EQ(a.pairs[k].friction.mu, b.pairs[k].friction.mu) << a.PairName(k);
    EXPECT_EQ(a.pairs[k].friction.e_r, b.pairs[k].friction.e_r) << a.PairName(k);
  }
  ASSERT_EQ(a.joints.size(), b.joints.size());
  for (size_t k = 0; k < a.joints.size(); ++k) EXPECT_EQ(a.joints[k].name, b.joints[k].name);
  EXPECT_EQ(a.gravity_W, b.gravity_W);
}

TEST(SceneEdit, AddThenRemoveRestoresTheModel) {
  std::string original = ReadScene("arm_push.urdf");
  original.replace(original.find("  </implicit_sim>"), 0, "    <friction link1=\"egg\" link2=\"floor\" mu=\"0.8\"/>\n");
  SceneAddition toy;
  toy.urdf = kToyScene;
  toy.prefix = "t/";
  toy.X_WO = MakePose(0.3, Vec3(0, 0, 1), Vec3(2, 0, 0));
  toy.v_WO = Vec3(1, 0, 0);
  SceneAddition robot;
  robot.urdf = kArm;
  robot.prefix = "r/";
  robot.floating_root = true;
  std::vector<std::string> toy_links, robot_links, removed;
  const std::string added = AddToScene(AddToScene(original, toy, &toy_links), robot, &robot_links);
  ASSERT_EQ(LoadSceneFromString(added).bodies.size(), 4u + 3u + 3u);
  const std::string restored = RemoveFromScene(RemoveFromScene(added, toy_links, nullptr), {"r/base"}, &removed);
  EXPECT_EQ(removed, robot_links);
  ExpectSameModel(LoadSceneFromString(restored), LoadSceneFromString(original));
  EXPECT_EQ(PairOf(LoadSceneFromString(restored), "egg", "floor").friction.mu, 0.8);
}

TEST(SceneEdit, ResolvesRelativeMeshNamesAndMergesMaterials) {
  const std::string scene = R"(<robot name="s"><material name="grey"><color rgba="0.5 0.5 0.5 1"/></material>
    <link name="world"/></robot>)";
  const std::string addition = R"(<robot name="a">
    <material name="grey"><color rgba="0.5 0.5 0.5 1"/></material>
    <material name="red"><color rgba="1 0 0 1"/></material>
    <link name="body">
      <visual><geometry><mesh filename="meshes/body.dae"/></geometry><material name="grey"/></visual>
      <visual><geometry><mesh filename="../shared/./arm.stl"/></geometry><material name="red"/></visual>
      <visual><geometry><mesh filename="package://pkg/m.dae"/></geometry></visual>
      <visual><geometry><mesh filename="/abs/m.dae"/></geometry></visual>
    </link>
    <link name="tip"/>
    <joint name="tip_joint" type="fixed"><parent link="body"/><child link="tip"/>
      <mimic joint="tip_joint"/></joint>
  </robot>)";
  SceneAddition a;
  a.urdf = addition;
  a.base_dir = "/opt/models/toy";
  a.prefix = "p_";
  const std::string once = AddToScene(scene, a, nullptr);
  // A different 'red' in the scene: the addition's is renamed with the prefix, with its references.
  const std::string scene_red = R"(<robot name="s"><material name="red"><color rgba="0.9 0 0 1"/></material>
    <link name="world"/></robot>)";
  const std::string renamed = AddToScene(scene_red, a, nullptr);
  for (const std::string& text : {once, renamed}) ASSERT_NO_THROW(UrdfdomLinks(text)) << text;
  tinyxml2::XMLDocument doc;
  ASSERT_EQ(doc.Parse(once.c_str()), tinyxml2::XML_SUCCESS);
  const tinyxml2::XMLElement* robot = doc.RootElement();
  std::vector<std::string> materials, meshes;
  for (auto* m = robot->FirstChildElement("material"); m; m = m->NextSiblingElement("material")) {
    materials.push_back(m->Attribute("name"));
  }
  const tinyxml2::XMLElement* body = robot->FirstChildElement("link")->NextSiblingElement("link");
  ASSERT_STREQ(body->Attribute("name"), "p_body");
  for (auto* v = body->FirstChildElement("visual"); v; v = v->NextSiblingElement("visual")) {
    meshes.push_back(v->FirstChildElement("geometry")->FirstChildElement("mesh")->Attribute("filename"));
  }
  EXPECT_EQ(materials, (std::vector<std::string>{"grey", "red"}));  // the identical 'grey' once
  EXPECT_EQ(meshes, (std::vector<std::string>{"/opt/models/toy/meshes/body.dae", "/opt/models/shared/arm.stl",
                                              "package://pkg/m.dae", "/abs/m.dae"}));
  EXPECT_NE(once.find("<mimic joint=\"p_tip_joint\"/>"), std::string::npos);
  EXPECT_NE(renamed.find("<material name=\"p_red\">"), std::string::npos);
  EXPECT_NE(renamed.find("<material name=\"p_red\"/>"), std::string::npos);
  a.prefix = "";
  ExpectRefused([&] { AddToScene(scene_red, a, nullptr); }, {"material 'red'"});
}

TEST(SceneEdit, RpyRoundTripIsExactAtAndNearGimbalLock) {
  for (const Vec3& rpy : {Vec3(0.3, -1.2, 2.9), Vec3(-3.0, M_PI / 2, 0.7), Vec3(1.0, -M_PI / 2, -0.4),
                          Vec3(0.2, M_PI / 2 - 1e-9, 0.1), Vec3(0, 0, M_PI)}) {
    const Mat3 R = scene_xml::RotationOfRpy(rpy);
    EXPECT_LE((scene_xml::RotationOfRpy(scene_xml::RpyOf(R)) - R).norm(), 1e-14) << rpy.transpose();
  }
  // A spawn at gimbal lock composes exactly too.
  const std::string cube = ReadScene("cube_drop.urdf");
  SceneAddition a;
  a.urdf = cube;
  a.prefix = "g_";
  a.X_WO = Pose::Identity();
  a.X_WO.linear() = scene_xml::RotationOfRpy(Vec3(0.4, M_PI / 2, -1.3));
  const Model m = LoadSceneFromString(AddToScene(cube, a, nullptr));
  ExpectPoseNear(BodyNamed(m, "g_cube").X_WB0, a.X_WO * BodyNamed(LoadSceneFromString(cube), "cube").X_WB0, 1e-12,
                 "g_cube");
}

TEST(SceneEdit, RefusesBadInputsNamingTheProblem) {
  const std::string scene = ReadScene("cube_drop.urdf");
  SceneAddition a;
  a.urdf = ReadScene("p3_sphere_on_two_spheres.urdf");
  ExpectRefused([&] { AddToScene("<robot name='x'><link", a, nullptr); }, {"the scene", "not well-formed XML"});
  SceneAddition not_xml = a;
  not_xml.urdf = "<robot name='a'><link name='b'></robot>";
  ExpectRefused([&] { AddToScene(scene, not_xml, nullptr); }, {"the addition", "not well-formed XML"});
  not_xml.urdf = "<model/>";
  ExpectRefused([&] { AddToScene(scene, not_xml, nullptr); }, {"the addition", "no <robot> element"});
  SceneAddition nan_pose = a;
  nan_pose.X_WO.translation().x() = std::nan("");
  ExpectRefused([&] { AddToScene(scene, nan_pose, nullptr); }, {"X_WO must be finite"});
  SceneAddition skewed = a;
  skewed.X_WO.linear()(0, 0) = 2.0;
  ExpectRefused([&] { AddToScene(scene, skewed, nullptr); }, {"X_WO is not a rotation"});
  SceneAddition nan_twist = a;
  nan_twist.w_WO.y() = INFINITY;
  ExpectRefused([&] { AddToScene(scene, nan_twist, nullptr); }, {"w_WO must be finite"});
  SceneAddition bad_prefix = a;
  bad_prefix.prefix = "left hand";
  ExpectRefused([&] { AddToScene(scene, bad_prefix, nullptr); }, {"prefix 'left hand'", "character ' '", "A-Z"});
  SceneAddition relative_dir = a;
  relative_dir.base_dir = "models/toy";
  ExpectRefused([&] { AddToScene(scene, relative_dir, nullptr); }, {"base_dir 'models/toy'", "absolute"});
  SceneAddition quaternion = a;
  quaternion.prefix = "q_";
  const std::string origin_b = "<origin xyz=\"0 11.4 0\"/>";
  quaternion.urdf.replace(quaternion.urdf.find(origin_b), origin_b.size(),
                          "<origin xyz=\"0 11.4 0\" quat_xyzw=\"0 0 0 1\"/>");
  ExpectRefused([&] { AddToScene(scene, quaternion, nullptr); }, {"joint 'sphere_b_joint'", "quat_xyzw"});
  SceneAddition bad_number = a;
  bad_number.prefix = "n_";
  bad_number.urdf.replace(bad_number.urdf.find("0 11.4 0"), 8, "0 nan 0");
  ExpectRefused([&] { AddToScene(scene, bad_number, nullptr); }, {"joint 'sphere_b_joint'", "'nan'"});
  SceneAddition empty = a;
  empty.urdf = "<robot name='e'><link name='world'/></robot>";
  ExpectRefused([&] { AddToScene(scene, empty, nullptr); }, {"no link besides 'world'"});
  empty.urdf = "<robot name='e'/>";
  ExpectRefused([&] { AddToScene(scene, empty, nullptr); }, {"no link besides 'world'"});
  SceneAddition two_roots = a;
  two_roots.urdf = "<robot name='t'><link name='a'/><link name='b'/></robot>";
  ExpectRefused([&] { AddToScene(scene, two_roots, nullptr); }, {"exactly one root link", "'a', 'b'"});
  SceneAddition dangling = a;
  dangling.urdf = "<robot name='d'><link name='a'/><joint name='j' type='fixed'><parent link='a'/>"
                  "<child link='b'/></joint></robot>";
  ExpectRefused([&] { AddToScene(scene, dangling, nullptr); }, {"joint 'j'", "link 'b' is not defined"});
  SceneAddition locked = a;
  locked.prefix = "l_";
  locked.urdf.replace(locked.urdf.find("force="), 0, "locked=\"z\" ");
  locked.v_WO = Vec3(0, 0, 1);
  ExpectRefused([&] { AddToScene(scene, locked, nullptr); }, {"link 'ball'", "locked axis 'z'"});
  ExpectRefused([&] { RemoveFromScene("<robot", {"a"}, nullptr); }, {"not well-formed XML"});
  ExpectRefused([&] { RobotDescriptionOf("<robot name='r'><link/></robot>"); }, {"a <link> has no attribute 'name'"});
}

}  // namespace
}  // namespace implicit_sim
