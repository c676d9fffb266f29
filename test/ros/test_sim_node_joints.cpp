// rostest for the node's joint interface on the gripper scene (test/ros/sim_node_joints.test starts it paused):
// /joint_states, ~set_joint_efforts and ~joint_effort_cmd with the validation rules of the wrench commands.
#include <atomic>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <sensor_msgs/JointState.h>
#include <std_srvs/Trigger.h>

#include "implicit_sim/Contacts.h"
#include "implicit_sim/GetBodyState.h"
#include "implicit_sim/SetJointEfforts.h"
#include "implicit_sim/Step.h"
#include "node_test_support.h"

namespace {

using node_test::Call;
using node_test::DiagnosticValue;
using node_test::kNs;
using node_test::Trigger;

void RunSteps(uint32_t n) {
  implicit_sim::Step s;
  s.request.steps = n;
  EXPECT_TRUE(Call(std::string("step"), s).response.success);
}

double BodyZ(const std::string& body) {
  implicit_sim::GetBodyState g;
  g.request.body = body;
  g = Call(std::string("get_body_state"), g);
  EXPECT_TRUE(g.response.success);
  return g.response.state.pose.position.z;
}

// The latest /joint_states message (after the node has published the current state).
sensor_msgs::JointState JointStates() {
  ros::WallDuration(0.1).sleep();
  const auto msg = ros::topic::waitForMessage<sensor_msgs::JointState>("/joint_states", ros::Duration(5));
  EXPECT_TRUE(msg != nullptr);
  return msg ? *msg : sensor_msgs::JointState();
}

double Field(const sensor_msgs::JointState& js, const std::vector<double>& values, const std::string& name) {
  for (size_t i = 0; i < js.name.size(); ++i) {
    if (js.name[i] == name && i < values.size()) return values[i];
  }
  ADD_FAILURE() << "joint '" << name << "' missing from /joint_states";
  return NAN;
}

implicit_sim::SetJointEfforts Efforts(const std::vector<std::string>& names, const std::vector<double>& efforts) {
  implicit_sim::SetJointEfforts s;
  s.request.name = names;
  s.request.effort = efforts;
  return Call(std::string("set_joint_efforts"), s);
}

TEST(SimNodeJoints, JointStatesListEveryMovableJointWithPositionVelocityAndEffort) {
  EXPECT_TRUE(Trigger("reset"));
  const sensor_msgs::JointState js = JointStates();
  EXPECT_EQ(js.name, (std::vector<std::string>{"lift", "left_slide", "right_slide"}));
  ASSERT_EQ(js.position.size(), 3u);
  ASSERT_EQ(js.velocity.size(), 3u);
  ASSERT_EQ(js.effort.size(), 3u);
  for (double q : js.position) EXPECT_NEAR(q, 0.0, 1e-12);
  for (double qd : js.velocity) EXPECT_NEAR(qd, 0.0, 1e-12);
  EXPECT_NEAR(Field(js, js.effort, "lift"), 4.7088, 1e-9);  // the scene's constant efforts
  EXPECT_NEAR(Field(js, js.effort, "left_slide"), 2.0, 1e-12);
}

// The fingers' grip on the ball is published on ~contacts: 2 N normal force from each finger (the scene's efforts),
// and friction carrying the ball's weight while the gripper is held still (lift effort set to hold everything).
TEST(SimNodeJoints, TheGripIsPublishedAsTwoContactsWithTheFingerForces) {
  EXPECT_TRUE(Trigger("reset"));
  ASSERT_TRUE(Efforts({"lift"}, {-4.7088 + 0.4 * 9.81}).response.success);  // lift = total weight 3.924 N: at rest
  RunSteps(50);
  ros::WallDuration(0.1).sleep();
  const auto contacts = ros::topic::waitForMessage<implicit_sim::Contacts>(kNs + "contacts", ros::Duration(5));
  ASSERT_TRUE(contacts != nullptr);
  int fingers = 0;
  double friction = 0.0;
  for (const auto& c : contacts->contacts) {
    const bool finger = c.link1 == "ball" || c.link2 == "ball";
    if (!finger) continue;
    ++fingers;
    EXPECT_NEAR(c.normal_force, 2.0, 1e-6);
    friction += std::hypot(std::hypot(c.friction_force.x, c.friction_force.y), c.friction_force.z);
  }
  EXPECT_EQ(fingers, 2);
  EXPECT_NEAR(friction, 0.1 * 9.81, 1e-6);  // the two contacts carry the ball's weight
  EXPECT_TRUE(Trigger("reset"));
}

TEST(SimNodeJoints, BadEffortRequestsAreRefusedNamingTheProblemAndChangeNothing) {
  EXPECT_TRUE(Trigger("reset"));
  const std::vector<std::pair<std::vector<std::string>, std::vector<double>>> bad = {
      {{"elbow"}, {1.0}},                      // no such joint
      {{"ball_joint"}, {1.0}},                 // floating: no coordinate
      {{"lift", "left_slide"}, {1.0}},         // lengths differ
      {{"lift"}, {NAN}},
      {{"lift"}, {INFINITY}},
      {{"lift"}, {1e300}},
      {{"left_slide", "lift"}, {1.0, NAN}},    // all or nothing: the first is not applied either
  };
  for (const auto& [names, efforts] : bad) {
    const auto res = Efforts(names, efforts).response;
    EXPECT_FALSE(res.success) << res.message;
    EXPECT_FALSE(res.message.empty());
  }
  EXPECT_NE(Efforts({"elbow"}, {1.0}).response.message.find("'elbow'"), std::string::npos);
  const sensor_msgs::JointState js = JointStates();
  EXPECT_NEAR(Field(js, js.effort, "left_slide"), 2.0, 1e-12);  // unchanged
}

TEST(SimNodeJoints, ACommandedEffortMovesTheJointAndIsClampedToTheUrdfLimit) {
  EXPECT_TRUE(Trigger("reset"));
  // lift: the scene pushes with 4.7088 N; commanding -4.7088 N more leaves only gravity: the gripper falls with the
  // ball (g for 0.2 s: 0.196 m).
  ASSERT_TRUE(Efforts({"lift"}, {-4.7088}).response.success);
  const double palm0 = BodyZ("palm");
  RunSteps(200);
  const double fall = palm0 - BodyZ("palm");
  EXPECT_NEAR(fall, 0.5 * 9.81 * 0.2 * 0.2, 0.01);
  // A command beyond the URDF limit (20 N) is clamped: /joint_states reports the applied effort.
  ASSERT_TRUE(Efforts({"lift"}, {1e6}).response.success);
  const sensor_msgs::JointState js = JointStates();
  EXPECT_NEAR(Field(js, js.effort, "lift"), 20.0 + 4.7088, 1e-9);
  EXPECT_NEAR(Field(js, js.position, "lift"), BodyZ("palm") - 0.56, 1e-9);
  EXPECT_TRUE(Trigger("reset"));
  const sensor_msgs::JointState after_reset = JointStates();
  EXPECT_NEAR(Field(after_reset, after_reset.effort, "lift"), 4.7088, 1e-9);  // reset clears commands
}

TEST(SimNodeJoints, BadJointEffortMessagesAreDroppedAndCountedAndAGoodOneActs) {
  ros::NodeHandle nh;
  ros::Publisher pub = nh.advertise<sensor_msgs::JointState>(kNs + "joint_effort_cmd", 1000);
  EXPECT_TRUE(Trigger("reset"));
  for (int i = 0; i < 30 && pub.getNumSubscribers() == 0; ++i) ros::Duration(0.1).sleep();
  const long dropped_before = DiagnosticValue("dropped_joint_effort_commands");
  const long received_before = DiagnosticValue("received_joint_effort_commands");
  const double bad[] = {NAN, INFINITY, -INFINITY, 1e300, -1e300};
  const int sent = 1000;
  for (int i = 0; i < sent; ++i) {
    sensor_msgs::JointState cmd;
    cmd.name = {i % 3 == 0 ? "nowhere" : "lift"};
    cmd.effort = {bad[i % 5]};
    if (i % 7 == 0) cmd.effort.clear();  // no effort for the name
    pub.publish(cmd);
    if (i % 10 == 9) ros::WallDuration(0.002).sleep();
  }
  ros::WallDuration(0.5).sleep();
  const long dropped = DiagnosticValue("dropped_joint_effort_commands") - dropped_before;
  const long received = DiagnosticValue("received_joint_effort_commands") - received_before;
  std::printf("[ INFO ] bad joint effort commands: %d sent, %ld received, %ld dropped\n", sent, received, dropped);
  EXPECT_EQ(dropped, received);
  EXPECT_GE(received, sent / 4);
  const sensor_msgs::JointState unchanged = JointStates();
  EXPECT_NEAR(Field(unchanged, unchanged.effort, "lift"), 4.7088, 1e-9);
  // A good message: open the fingers (efforts away from the ball) and the ball drops out of the grip.
  sensor_msgs::JointState open;
  open.name = {"left_slide", "right_slide"};
  open.effort = {-4.0, 4.0};
  pub.publish(open);
  ros::WallDuration(0.5).sleep();
  const double ball0 = BodyZ("ball");
  RunSteps(300);
  EXPECT_LT(BodyZ("ball"), ball0 - 0.2);  // falls (with the fingers gone: 0.44 m in 0.3 s)
  EXPECT_TRUE(Trigger("reset"));
}

}  // namespace

int main(int argc, char** argv) { return node_test::RunAllTests(argc, argv, "test_sim_node_joints"); }
