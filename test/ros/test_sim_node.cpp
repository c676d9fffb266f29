// rostest for implicit_sim_node on the P3 scene (test/ros/sim_node_p3.test starts it paused, as fast as possible).
// The tests share one node; each one that needs the initial state calls ~reset first.
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <gtest/gtest.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>
#include <std_srvs/Trigger.h>
#include <tf2_msgs/TFMessage.h>
#include <tf2_ros/transform_listener.h>
#include <visualization_msgs/MarkerArray.h>

#include "implicit_sim/ApplyBodyWrench.h"
#include "implicit_sim/BodyStates.h"
#include "implicit_sim/BodyWrench.h"
#include "implicit_sim/Contacts.h"
#include "implicit_sim/GetBodyState.h"
#include "implicit_sim/SetBodyState.h"
#include "implicit_sim/Step.h"
#include "implicit_sim/StepStats.h"
#include "implicit_sim/core/step/time_stepper.h"
#include "implicit_sim/core/model/urdf_loader.h"
#include "node_test_support.h"

namespace {

using node_test::Call;
using node_test::DiagnosticValue;
using node_test::kNs;
using node_test::Trigger;
using StepSrv = struct implicit_sim::Step;  // the service type; the core's Step() function hides the bare name
constexpr double kH = 0.01;

StepSrv RunSteps(uint32_t n) {
  StepSrv s;
  s.request.steps = n;
  return Call(std::string("step"), s);
}

implicit_sim::BodyState Ball() {
  implicit_sim::GetBodyState g;
  g.request.body = "ball";
  g = Call(std::string("get_body_state"), g);
  EXPECT_TRUE(g.response.success);
  return g.response.state;
}

void ExpectSameState(const implicit_sim::BodyState& a, const implicit_sim::BodyState& b) {
  EXPECT_EQ(a.pose.position.x, b.pose.position.x);
  EXPECT_EQ(a.pose.position.y, b.pose.position.y);
  EXPECT_EQ(a.pose.position.z, b.pose.position.z);
  EXPECT_EQ(a.pose.orientation.w, b.pose.orientation.w);
  EXPECT_EQ(a.pose.orientation.x, b.pose.orientation.x);
  EXPECT_EQ(a.twist.linear.x, b.twist.linear.x);
  EXPECT_EQ(a.twist.linear.z, b.twist.linear.z);
  EXPECT_EQ(a.twist.angular.y, b.twist.angular.y);
}

double ClockNow() {
  const auto msg = ros::topic::waitForMessage<rosgraph_msgs::Clock>("/clock", ros::Duration(10));
  EXPECT_TRUE(msg != nullptr);
  return msg ? msg->clock.toSec() : NAN;
}

// The headless core on the same scene file, for "same numbers" comparisons.
implicit_sim::State CoreAfter(int steps) {
  using namespace implicit_sim;
  const Model model = LoadSceneFromFile(std::string(IMPLICIT_SIM_SOURCE_DIR) + "/scenes/p3_sphere_on_two_spheres.urdf");
  Data data(model);
  State state = State::Initial(model);
  StepperOptions options;
  options.h = kH;
  for (int i = 0; i < steps; ++i) implicit_sim::Step(model, options, &state, &data);
  return state;
}

std::string RunCommand(const std::string& command, int* exit_code) {
  std::string output;
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  std::array<char, 512> buffer;
  while (pipe && fgets(buffer.data(), buffer.size(), pipe)) output += buffer.data();
  const int status = pipe ? pclose(pipe) : -1;
  *exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return output;
}

TEST(SimNode, EveryTopicIsAdvertisedWithItsType) {
  ros::topic::waitForMessage<rosgraph_msgs::Clock>("/clock", ros::Duration(10));
  const std::pair<std::string, std::string> expected[] = {
      {"/clock", "rosgraph_msgs/Clock"},
      {"/tf", "tf2_msgs/TFMessage"},
      {"/tf_static", "tf2_msgs/TFMessage"},
      {"/diagnostics", "diagnostic_msgs/DiagnosticArray"},
      {kNs + "contacts", "implicit_sim/Contacts"},
      {kNs + "markers", "visualization_msgs/MarkerArray"},
      {kNs + "step_stats", "implicit_sim/StepStats"},
      {kNs + "body_states", "implicit_sim/BodyStates"}};
  ros::master::V_TopicInfo topics;
  ASSERT_TRUE(ros::master::getTopics(topics));
  for (const auto& [name, type] : expected) {
    bool found = false;
    for (const auto& t : topics) found = found || (t.name == name && t.datatype == type);
    EXPECT_TRUE(found) << name << " [" << type << "] is not advertised";
  }
}

TEST(SimNode, EveryServiceAnswersWithItsType) {
  for (const char* name : {"pause", "unpause", "reset", "clear_body_wrenches"}) {
    std_srvs::Trigger t;
    EXPECT_TRUE(ros::service::waitForService(kNs + name, ros::Duration(10))) << name;
    EXPECT_TRUE(ros::service::call(kNs + name, t)) << name;
  }
  EXPECT_TRUE(Trigger("pause"));
  implicit_sim::ApplyBodyWrench a;
  implicit_sim::SetBodyState s;
  EXPECT_TRUE(ros::service::call(kNs + "apply_body_wrench", a));  // typed calls fail on a type mismatch
  EXPECT_TRUE(ros::service::call(kNs + "set_body_state", s));
  EXPECT_TRUE(ros::service::exists(kNs + "get_body_state", false));
  EXPECT_TRUE(ros::service::exists(kNs + "step", false));
}

TEST(SimNode, TfResolvesWorldToBall) {
  tf2_ros::Buffer buffer;
  tf2_ros::TransformListener listener(buffer);
  std::string error;
  EXPECT_TRUE(buffer.canTransform("world", "ball", ros::Time(0), ros::Duration(10), &error)) << error;
  EXPECT_TRUE(buffer.canTransform("world", "sphere_b", ros::Time(0), ros::Duration(10), &error)) << error;
  const auto t = buffer.lookupTransform("world", "sphere_b", ros::Time(0));
  EXPECT_DOUBLE_EQ(t.transform.translation.y, 11.4);
}

TEST(SimNode, StepAdvancesTheClockByNhAndMatchesTheHeadlessCore) {
  EXPECT_TRUE(Trigger("pause"));
  EXPECT_TRUE(Trigger("reset"));
  const double before = ClockNow();
  const StepSrv s = RunSteps(100);
  ASSERT_TRUE(s.response.success) << s.response.message;
  EXPECT_NEAR(s.response.sim_time - before, 100 * kH, 1e-9);
  ros::Duration(0.2).sleep();
  EXPECT_NEAR(ClockNow() - before, 100 * kH, 1e-9);
  const implicit_sim::State core = CoreAfter(100);
  const implicit_sim::BodyState ball = Ball();
  EXPECT_EQ(ball.pose.position.x, core.q[0]);
  EXPECT_EQ(ball.pose.position.y, core.q[1]);
  EXPECT_EQ(ball.pose.position.z, core.q[2]);
  EXPECT_EQ(ball.twist.linear.x, core.v[0]);
  EXPECT_EQ(ball.twist.linear.z, core.v[2]);
  EXPECT_EQ(ball.twist.angular.y, core.v[4]);
}

TEST(SimNode, ContactsMatchTheReferenceForcesAtTheStart) {
  EXPECT_TRUE(Trigger("reset"));
  ASSERT_TRUE(RunSteps(1).response.success);
  const auto msg = ros::topic::waitForMessage<implicit_sim::Contacts>(kNs + "contacts", ros::Duration(10));
  ASSERT_TRUE(msg != nullptr);
  ASSERT_EQ(msg->contacts.size(), 2u);
  for (const auto& c : msg->contacts) {
    EXPECT_EQ(c.link1, "ball");
    const double reference = c.link2 == "sphere_a" ? 2.641 : 8.767;
    EXPECT_NEAR(c.normal_force, reference, 0.01 * reference) << c.link2;
    EXPECT_NEAR(std::hypot(std::hypot(c.normal.x, c.normal.y), c.normal.z), 1.0, 1e-9);
    EXPECT_GE(c.gap, -1e-8);
  }
  const auto stats = ros::topic::waitForMessage<implicit_sim::StepStats>(kNs + "step_stats", ros::Duration(1));
  (void)stats;  // step_stats is published per step; the next test checks its content
}

TEST(SimNode, StepStatsMarkersBodyStatesAndDiagnosticsArePublished) {
  ros::NodeHandle nh;
  implicit_sim::StepStats::ConstPtr stats;
  ros::Subscriber sub = nh.subscribe<implicit_sim::StepStats>(
      kNs + "step_stats", 10, [&](const implicit_sim::StepStats::ConstPtr& m) { stats = m; });
  ros::Duration(0.5).sleep();
  ASSERT_TRUE(RunSteps(3).response.success);
  for (int i = 0; i < 50 && !stats; ++i) ros::Duration(0.05).sleep();
  ASSERT_TRUE(stats != nullptr);
  EXPECT_TRUE(stats->converged);
  EXPECT_EQ(stats->status, "converged");
  EXPECT_GT(stats->iterations, 0u);
  EXPECT_LE(stats->residual, 1e-10);  // the bar is 1e-12 (1 + |z|_inf); P3's largest unknown is O(10)
  const auto markers = ros::topic::waitForMessage<visualization_msgs::MarkerArray>(kNs + "markers", ros::Duration(10));
  ASSERT_TRUE(markers != nullptr);
  int shapes = 0, contact_points = 0;
  for (const auto& m : markers->markers) {
    shapes += m.ns == "shapes";
    contact_points += m.ns == "contact_points" && m.action == visualization_msgs::Marker::ADD;
  }
  EXPECT_EQ(shapes, 3);
  EXPECT_EQ(contact_points, 2);
  const auto states = ros::topic::waitForMessage<implicit_sim::BodyStates>(kNs + "body_states", ros::Duration(10));
  ASSERT_TRUE(states != nullptr);
  ASSERT_EQ(states->bodies.size(), 3u);
  EXPECT_EQ(states->bodies[0].name, "ball");
  const auto diagnostics =
      ros::topic::waitForMessage<diagnostic_msgs::DiagnosticArray>("/diagnostics", ros::Duration(10));
  ASSERT_TRUE(diagnostics != nullptr);
  ASSERT_FALSE(diagnostics->status.empty());
  EXPECT_EQ(diagnostics->status[0].level, diagnostic_msgs::DiagnosticStatus::OK);
}

TEST(SimNode, ResetRestoresTheInitialStateExactly) {
  EXPECT_TRUE(Trigger("reset"));
  const implicit_sim::BodyState initial = Ball();
  EXPECT_EQ(initial.pose.position.y, 6.62105263157895);
  EXPECT_EQ(initial.pose.position.z, 8.78417110772903);
  ASSERT_TRUE(RunSteps(25).response.success);
  EXPECT_NE(Ball().pose.position.x, initial.pose.position.x);
  const double before = ClockNow();
  EXPECT_TRUE(Trigger("reset"));
  ExpectSameState(Ball(), initial);
  EXPECT_GE(ClockNow(), before);  // simulation time does not jump back
}

TEST(SimNode, BadServiceCallsAreRefusedAndChangeNothing) {
  EXPECT_TRUE(Trigger("reset"));
  ASSERT_TRUE(RunSteps(5).response.success);
  const implicit_sim::BodyState before = Ball();
  implicit_sim::GetBodyState get;
  get.request.body = "nobody";
  EXPECT_FALSE(Call(std::string("get_body_state"), get).response.success);
  EXPECT_FALSE(RunSteps(0).response.success);
  implicit_sim::SetBodyState set;
  set.request.state = before;
  set.request.state.name = "nobody";
  EXPECT_FALSE(Call(std::string("set_body_state"), set).response.success);
  set.request.state.name = "sphere_a";
  EXPECT_FALSE(Call(std::string("set_body_state"), set).response.success);
  set.request.state = before;
  set.request.state.pose.orientation.w = set.request.state.pose.orientation.x = 0.0;
  set.request.state.pose.orientation.y = set.request.state.pose.orientation.z = 0.0;
  EXPECT_FALSE(Call(std::string("set_body_state"), set).response.success);
  set.request.state = before;
  set.request.state.twist.linear.x = NAN;
  EXPECT_FALSE(Call(std::string("set_body_state"), set).response.success);
  // Into sphere_a: refused as ~spawn refuses an overlap, unless allowed.
  get.request.body = "sphere_a";
  set.request.state = before;
  set.request.state.pose.position = Call(std::string("get_body_state"), get).response.state.pose.position;
  const implicit_sim::SetBodyState::Response overlapping = Call(std::string("set_body_state"), set).response;
  EXPECT_FALSE(overlapping.success);
  EXPECT_NE(overlapping.message.find("refused: pair '"), std::string::npos) << overlapping.message;
  EXPECT_NE(overlapping.message.find("overlaps by up to"), std::string::npos) << overlapping.message;
  ExpectSameState(Ball(), before);
  set.request.allow_overlap = true;
  EXPECT_TRUE(Call(std::string("set_body_state"), set).response.success);
  set.request.state = before;
  EXPECT_TRUE(Call(std::string("set_body_state"), set).response.success);
  set.request.allow_overlap = false;
  implicit_sim::ApplyBodyWrench wrench;
  wrench.request.body = "nobody";
  wrench.request.duration = 1.0;
  EXPECT_FALSE(Call(std::string("apply_body_wrench"), wrench).response.success);
  wrench.request.body = "ball";
  wrench.request.wrench.force.x = INFINITY;
  EXPECT_FALSE(Call(std::string("apply_body_wrench"), wrench).response.success);
  wrench.request.wrench.force.x = 1.0;
  wrench.request.duration = 0.0;
  EXPECT_FALSE(Call(std::string("apply_body_wrench"), wrench).response.success);
  wrench.request.duration = 1.0;
  wrench.request.reference_frame = "no_frame";
  EXPECT_FALSE(Call(std::string("apply_body_wrench"), wrench).response.success);
  ExpectSameState(Ball(), before);
}

// A body set to 1e6 m/s: the next step is refused as diverged in that same step, the state stays as it was set
// (finite), the node stays paused, and the fault is counted in /diagnostics.
TEST(SimNode, ADivergingStepIsRefusedCountedAndChangesNothing) {
  EXPECT_TRUE(Trigger("reset"));
  implicit_sim::SetBodyState set;
  set.request.state = Ball();
  set.request.state.twist.linear.x = 1e6;
  ASSERT_TRUE(Call(std::string("set_body_state"), set).response.success);
  const implicit_sim::BodyState before = Ball();
  const StepSrv step = RunSteps(1);
  EXPECT_FALSE(step.response.success);
  EXPECT_NE(step.response.message.find("diverged"), std::string::npos) << step.response.message;
  ExpectSameState(Ball(), before);
  EXPECT_TRUE(std::isfinite(Ball().pose.position.x));
  EXPECT_EQ(DiagnosticValue("faults_diverged"), 1);
  EXPECT_TRUE(Trigger("reset"));
  EXPECT_TRUE(RunSteps(5).response.success);  // a reset recovers
}

TEST(SimNode, StepIsRefusedWhileRunning) {
  EXPECT_TRUE(Trigger("unpause"));
  const StepSrv s = RunSteps(1);
  EXPECT_FALSE(s.response.success);
  EXPECT_NE(s.response.message.find("running"), std::string::npos);
  EXPECT_TRUE(Trigger("pause"));
}

TEST(SimNode, NonFiniteWrenchCommandsAreDroppedAndWrenchesMoveTheBall) {
  ros::NodeHandle nh;
  ros::Publisher pub = nh.advertise<implicit_sim::BodyWrench>(kNs + "wrench_cmd", 10);
  EXPECT_TRUE(Trigger("reset"));
  for (int i = 0; i < 30 && pub.getNumSubscribers() == 0; ++i) ros::Duration(0.1).sleep();
  implicit_sim::BodyWrench cmd;
  cmd.body = "ball";
  cmd.wrench.force.z = NAN;
  pub.publish(cmd);
  ros::Duration(0.3).sleep();
  ASSERT_TRUE(RunSteps(10).response.success);
  const implicit_sim::State core = CoreAfter(10);
  EXPECT_EQ(Ball().pose.position.x, core.q[0]);  // the NaN command was dropped: same numbers as without it
  // A 100 N upward push for 0.05 s lifts the ball off both spheres.
  implicit_sim::ApplyBodyWrench wrench;
  wrench.request.body = "ball";
  wrench.request.wrench.force.z = 100.0;
  wrench.request.duration = 0.05;
  ASSERT_TRUE(Call(std::string("apply_body_wrench"), wrench).response.success);
  ASSERT_TRUE(RunSteps(10).response.success);
  EXPECT_GT(Ball().twist.linear.z, 1.0);
  EXPECT_TRUE(Trigger("clear_body_wrenches"));
}

TEST(SimNode, ABadParameterOrSceneStopsTheNodeAtStartup) {
  int code = 0;
  std::string out = RunCommand(std::string("timeout 30 ") + IMPLICIT_SIM_NODE +
                                   " __name:=bad_param _scene:=p3_sphere_on_two_spheres _time_step:=-1",
                               &code);
  EXPECT_EQ(code, 1) << out;
  EXPECT_NE(out.find("~time_step"), std::string::npos) << out;
  out = RunCommand(std::string("timeout 30 ") + IMPLICIT_SIM_NODE + " __name:=bad_scene _scene:=no_such_scene", &code);
  EXPECT_EQ(code, 1) << out;
  EXPECT_NE(out.find("~scene"), std::string::npos) << out;
  // ~world_frame naming a link (tf would get ball -> ball) and a misspelt parameter stop the node too.
  out = RunCommand(std::string("timeout 30 ") + IMPLICIT_SIM_NODE +
                       " __name:=bad_frame _scene:=p3_sphere_on_two_spheres _world_frame:=ball",
                   &code);
  EXPECT_EQ(code, 1) << out;
  EXPECT_NE(out.find("~world_frame = 'ball' is a link"), std::string::npos) << out;
  out = RunCommand(std::string("timeout 30 ") + IMPLICIT_SIM_NODE +
                       " __name:=bad_name _scene:=p3_sphere_on_two_spheres _publish_rat:=5",
                   &code);
  EXPECT_EQ(code, 1) << out;
  EXPECT_NE(out.find("unknown parameter ~publish_rat"), std::string::npos) << out;
}

// Solver parameters go through the core's options table: an integer parameter given as a non-integer double is
// refused (roscpp would round it), and the Newton tolerance is in (0, 0.1] as for the core and the runner.
TEST(SimNode, SolverParametersAreCheckedAgainstTheOptionsTable) {
  for (const std::string& param : {std::string("_max_iterations:=1.5"), std::string("_tolerance:=0.5")}) {
    int code = 0;
    const std::string out = RunCommand(std::string("timeout 30 ") + IMPLICIT_SIM_NODE +
                                           " __name:=bad_option _scene:=p3_sphere_on_two_spheres " + param,
                                       &code);
    EXPECT_EQ(code, 1) << out;
    EXPECT_NE(out.find("~" + param.substr(1, param.find(':') - 1)), std::string::npos) << out;
  }
}

TEST(SimNode, ReadsTheSceneFromRobotDescriptionWhenNoSceneIsGiven) {
  std::ifstream file(std::string(IMPLICIT_SIM_SOURCE_DIR) + "/scenes/p2_sphere_spinning.urdf");
  std::stringstream xml;
  xml << file.rdbuf();
  ros::param::set("/described/robot_description", xml.str());
  int code = 0;
  // Runs until timeout's SIGINT after 4 s (timeout then exits 124); a missing or bad scene would exit 1 at once.
  const std::string out = RunCommand(std::string("timeout -s INT 4 ") + IMPLICIT_SIM_NODE +
                                         " __ns:=/described __name:=from_description _paused:=true",
                                     &code);
  EXPECT_EQ(code, 124) << out;
  ros::param::del("/described/robot_description");
  const std::string missing = RunCommand(
      std::string("timeout 30 ") + IMPLICIT_SIM_NODE + " __ns:=/described __name:=no_description", &code);
  EXPECT_EQ(code, 1) << missing;
  EXPECT_NE(missing.find("robot_description"), std::string::npos) << missing;
}

TEST(SimNode, ABagRecordedWhileRunningHoldsEveryTopic) {
  EXPECT_TRUE(Trigger("reset"));
  EXPECT_TRUE(Trigger("unpause"));
  const std::string bag = "/tmp/implicit_sim_rostest.bag";
  int code = 0;
  std::string out = RunCommand("rm -f " + bag + "; timeout 60 rosbag record -O " + bag +
                                   " --duration=3 /clock /tf /tf_static " + kNs + "contacts " + kNs + "markers " +
                                   kNs + "body_states " + kNs + "step_stats",
                               &code);
  EXPECT_EQ(code, 0) << out;
  EXPECT_TRUE(Trigger("pause"));
  out = RunCommand("rosbag info " + bag, &code);
  EXPECT_EQ(code, 0) << out;
  for (const std::string topic : {"/clock", "/tf ", "/tf_static", "contacts", "markers", "body_states", "step_stats"}) {
    EXPECT_NE(out.find(topic), std::string::npos) << topic << " missing in\n" << out;
  }
}

// 10,000 bad wrench commands (NaN, +-Inf, +-1e300, unknown and fixed bodies) while the simulation runs: every one is
// dropped and counted, and nothing non-finite reaches the state, /tf, ~body_states or ~markers.
TEST(SimNode, TenThousandBadWrenchCommandsAreDroppedCountedAndHarmless) {
  ros::NodeHandle nh;
  ros::Publisher pub = nh.advertise<implicit_sim::BodyWrench>(kNs + "wrench_cmd", 1000);
  EXPECT_TRUE(Trigger("reset"));
  for (int i = 0; i < 30 && pub.getNumSubscribers() == 0; ++i) ros::Duration(0.1).sleep();
  std::atomic<int> non_finite{0}, messages{0};
  auto finite_states = nh.subscribe<implicit_sim::BodyStates>(
      kNs + "body_states", 10, [&](const implicit_sim::BodyStates::ConstPtr& m) {
        ++messages;
        for (const auto& b : m->bodies) {
          non_finite += !std::isfinite(b.pose.position.x + b.pose.position.y + b.pose.position.z +
                                       b.pose.orientation.w + b.twist.linear.x + b.twist.angular.z);
        }
      });
  auto finite_tf = nh.subscribe<tf2_msgs::TFMessage>("/tf", 10, [&](const tf2_msgs::TFMessage::ConstPtr& m) {
    for (const auto& t : m->transforms) {
      non_finite += !std::isfinite(t.transform.translation.x + t.transform.translation.z + t.transform.rotation.w);
    }
  });
  auto finite_markers = nh.subscribe<visualization_msgs::MarkerArray>(
      kNs + "markers", 10, [&](const visualization_msgs::MarkerArray::ConstPtr& m) {
        for (const auto& marker : m->markers) {
          non_finite += !std::isfinite(marker.pose.position.x + marker.scale.x);
          for (const auto& p : marker.points) non_finite += !std::isfinite(p.x + p.y + p.z);
        }
      });
  const long dropped_before = DiagnosticValue("dropped_wrench_commands");
  const long received_before = DiagnosticValue("received_wrench_commands");
  const double t_before = ClockNow();
  EXPECT_TRUE(Trigger("unpause"));
  const double bad[] = {NAN, INFINITY, -INFINITY, 1e300, -1e300};
  const char* bodies[] = {"ball", "ball", "ball", "nobody", "sphere_a"};
  int sent = 0;
  for (int i = 0; i < 10000; ++i, ++sent) {
    implicit_sim::BodyWrench cmd;
    cmd.body = bodies[i % 5];
    cmd.wrench.force.x = bad[i % 5];
    cmd.wrench.torque.y = (i % 7 == 0) ? 4.9e-324 : bad[(i / 5) % 5];  // a denormal now and then
    pub.publish(cmd);
    if (i % 10 == 9) ros::WallDuration(0.002).sleep();  // 5 kHz
  }
  ros::WallDuration(1.0).sleep();
  EXPECT_TRUE(Trigger("pause"));
  const long dropped = DiagnosticValue("dropped_wrench_commands") - dropped_before;
  const long received = DiagnosticValue("received_wrench_commands") - received_before;
  // Every command that arrived was dropped and counted (the subscriber queue of 100 may lose some on a busy machine).
  EXPECT_EQ(dropped, received);
  EXPECT_GE(received, sent / 4);
  EXPECT_LE(received, sent);
  std::printf("[ INFO ] bad wrench commands: %d sent, %ld received, %ld dropped\n", sent, received, dropped);
  EXPECT_GT(ClockNow(), t_before + 1.0);  // the simulation kept stepping
  EXPECT_GT(messages.load(), 10);
  EXPECT_EQ(non_finite.load(), 0);
  const implicit_sim::BodyState ball = Ball();
  EXPECT_TRUE(std::isfinite(ball.pose.position.x + ball.pose.position.z + ball.twist.linear.x));
  EXPECT_TRUE(Trigger("reset"));
}

// The node binary next to this test's (devel/lib/implicit_sim/).
std::string NodeBinary() {
  char path[4096];
  const ssize_t n = readlink("/proc/self/exe", path, sizeof(path) - 1);
  const std::string self(path, n > 0 ? n : 0);
  return self.substr(0, self.rfind('/')) + "/implicit_sim_node";
}

std::string SignalShutdown() {
  return "/usr/bin/python3 " + std::string(IMPLICIT_SIM_SOURCE_DIR) + "/test/ros/signal_shutdown.py ";
}

// A subscriber that drops what it gets (queue 1).
template <class Message>
ros::Subscriber Ignore(ros::NodeHandle& nh, const std::string& topic) {
  return nh.subscribe<Message>(topic, 1, boost::function<void(const typename Message::ConstPtr&)>(
                                             [](const typename Message::ConstPtr&) {}));
}

// SIGINT and SIGTERM stop a second node instance (running as fast as possible) with exit code 0 (how long it takes is
// recorded; the 2 s target is measured by bench/refusal_bench.py).
TEST(SimNode, SigintAndSigtermShutDownCleanly) {
  for (const char* signal : {"INT", "TERM"}) {
    SCOPED_TRACE(signal);
    const std::string node = std::string("/signal_test_") + signal;
    int code = 0;
    const std::string out = RunCommand(
        SignalShutdown() + signal + " 'contact pairs' " + NodeBinary() + " __name:=" + node.substr(1) +
            " _scene:=p3_sphere_on_two_spheres _scenes_dir:=" + IMPLICIT_SIM_SOURCE_DIR + "/scenes _real_time_factor:=0",
        &code);
    int exit_code = -1, ms = -1;
    ASSERT_EQ(std::sscanf(out.substr(out.rfind("exit=")).c_str(), "exit=%d ms=%d", &exit_code, &ms), 2) << out;
    EXPECT_EQ(exit_code, 0) << out;
    RecordProperty(std::string("shutdown_ms_") + signal, std::to_string(ms));
  }
}

// SIGINT in the middle of a long step (P3 with a tolerance no solve reaches: its first step climbs every rung and
// sub-step, 6-7 s) interrupts the step (Data::interrupt): the node exits 0 within its 2 s grace, without abandoning
// a step still running.
TEST(SimNode, SigintInterruptsALongStep) {
  int code = 0;
  const std::string out = RunCommand(
      SignalShutdown() + "--settle=1 INT 'contact pairs' " + NodeBinary() +
          " __name:=signal_test_long_step _scene:=p3_sphere_on_two_spheres _scenes_dir:=" + IMPLICIT_SIM_SOURCE_DIR +
          "/scenes _real_time_factor:=0 _tolerance:=1e-300",
      &code);
  int exit_code = -1, ms = -1;
  ASSERT_EQ(std::sscanf(out.substr(out.rfind("exit=")).c_str(), "exit=%d ms=%d", &exit_code, &ms), 2) << out;
  EXPECT_EQ(exit_code, 0) << out;
  EXPECT_EQ(out.find("still running"), std::string::npos) << out;
  EXPECT_LT(ms, 2000) << out;
  RecordProperty("long_step_shutdown_ms", std::to_string(ms));
}

// A loopback TCP port that is free now, for a master of a second roslaunch's own.
int FreePort() {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t length = sizeof(address);
  const bool ok = fd >= 0 && bind(fd, reinterpret_cast<sockaddr*>(&address), length) == 0 &&
                  getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length) == 0;
  if (fd >= 0) close(fd);
  return ok ? ntohs(address.sin_port) : -1;
}

bool FileExists(const std::string& path) {
  struct stat info;
  return stat(path.c_str(), &info) == 0;
}

// The message count of `topic` in `rosbag info` output (its line "<topic>   N msgs : type"), or -1.
long BagMessages(const std::string& info, const std::string& topic) {
  std::istringstream lines(info);
  for (std::string line; std::getline(lines, line);) {
    std::istringstream words(line);
    std::string word;
    words >> word;
    if (word == "topics:") words >> word;
    long count = -1;
    if (word == topic && words >> count) return count;
  }
  return -1;
}

// SIGINT and SIGTERM to `roslaunch implicit_sim p3_sphere_on_two_spheres.launch record:=true` (with a master of its
// own: the launch sets /use_sim_time and names its node /implicit_sim) stop it with exit code 0 and leave the bag
// closed: `<bag>` exists, `<bag>.active` does not, and `rosbag info` reads messages on every recorded topic. The
// signal reaches roslaunch only (each node runs in a session of its own), as it would from a supervisor; roslaunch
// then sends SIGINT to the recorder and the node, waits for them (it would escalate to SIGTERM after 15 s), stops
// its master and exits; the recorder renames `<bag>.active` to `<bag>` when it closes the bag on that SIGINT. A
// recorder that dies otherwise (SIGKILL, or a roslaunch killed before its shutdown, which orphans it) leaves
// `<bag>.active`. roslaunch's exit takes about 1.8 s here (its own, rosout's and the master's shutdown), so it is
// printed, not bounded; the node's own shutdown time is measured by bench/refusal_bench.py.
TEST(SimNode, SigintAndSigtermToRoslaunchLeaveTheRecordedBagClosed) {
  const int port = FreePort();
  ASSERT_GT(port, 0);
  char dir_template[] = "/tmp/implicit_sim_launch_bag_XXXXXX";  // not shared with a concurrent run
  ASSERT_NE(mkdtemp(dir_template), nullptr);
  const std::string dir = dir_template;
  int code = 0;
  for (const char* signal : {"INT", "TERM"}) {
    SCOPED_TRACE(signal);
    const std::string bag = dir + "/" + signal + ".bag";
    const std::string out = RunCommand(
        // Line-buffered node output: block-buffered, "Recording to" would reach the log only at exit.
        "ROSCONSOLE_STDOUT_LINE_BUFFERED=1 ROS_MASTER_URI=http://localhost:" + std::to_string(port) + " " +
            SignalShutdown() + "--settle=3 " + signal +
            " 'Recording to' roslaunch implicit_sim p3_sphere_on_two_spheres.launch record:=true bag:=" + bag,
        &code);
    int exit_code = -1, ms = -1;
    ASSERT_NE(out.rfind("exit="), std::string::npos) << out;
    ASSERT_EQ(std::sscanf(out.substr(out.rfind("exit=")).c_str(), "exit=%d ms=%d", &exit_code, &ms), 2) << out;
    EXPECT_EQ(exit_code, 0) << out;
    EXPECT_NE(out.find("Recording to"), std::string::npos) << out;
    EXPECT_EQ(out.find("escalating"), std::string::npos) << out;  // every node stopped on roslaunch's first SIGINT
    EXPECT_TRUE(FileExists(bag)) << out;
    EXPECT_FALSE(FileExists(bag + ".active")) << out;
    const std::string info = RunCommand("rosbag info " + bag, &code);
    EXPECT_EQ(code, 0) << info;
    std::string counts;
    for (const std::string topic : {"/clock", "/tf", "/tf_static", "/implicit_sim/contacts", "/implicit_sim/markers",
                                    "/implicit_sim/body_states", "/implicit_sim/step_stats"}) {
      const long messages = BagMessages(info, topic);
      EXPECT_GT(messages, 0) << topic << " in\n" << info;
      counts += " " + topic + " " + std::to_string(messages);
    }
    std::printf("[ INFO ] SIG%s to roslaunch: exit %d after %d ms; bag:%s\n", signal, exit_code, ms, counts.c_str());
  }
  if (!HasFailure()) RunCommand("rm -rf " + dir, &code);
}

// 50 subscribe / unsubscribe cycles on every topic, plus one subscriber whose queue is never spun, while the
// simulation runs: it keeps stepping and the node's resident memory grows by less than 5 MB.
TEST(SimNode, SubscriberChurnAndAStalledSubscriberLeaveStepsAndMemoryAlone) {
  auto node_rss_kb = []() {
    int code = 0;
    const std::string out = RunCommand(
        "pid=$(pgrep -f 'implicit_sim_node.*__name:=implicit_sim' | head -1); grep VmRSS /proc/$pid/status", &code);
    long kb = -1;
    const size_t at = out.find("VmRSS:");
    if (at != std::string::npos) kb = std::stol(out.substr(at + 6));
    return kb;
  };
  ros::NodeHandle nh;
  ros::CallbackQueue never_spun;
  ros::NodeHandle stalled_nh;
  stalled_nh.setCallbackQueue(&never_spun);
  ros::Subscriber stalled = Ignore<implicit_sim::BodyStates>(stalled_nh, kNs + "body_states");
  EXPECT_TRUE(Trigger("reset"));
  EXPECT_TRUE(Trigger("unpause"));
  ros::WallDuration(1.0).sleep();
  const long rss_before = node_rss_kb();
  const double t_before = ClockNow();
  for (int cycle = 0; cycle < 50; ++cycle) {
    std::vector<ros::Subscriber> subscribers;
    subscribers.push_back(Ignore<implicit_sim::Contacts>(nh, kNs + "contacts"));
    subscribers.push_back(Ignore<visualization_msgs::MarkerArray>(nh, kNs + "markers"));
    subscribers.push_back(Ignore<implicit_sim::StepStats>(nh, kNs + "step_stats"));
    subscribers.push_back(Ignore<implicit_sim::BodyStates>(nh, kNs + "body_states"));
    subscribers.push_back(Ignore<tf2_msgs::TFMessage>(nh, "/tf"));
    subscribers.push_back(Ignore<rosgraph_msgs::Clock>(nh, "/clock"));
    ros::WallDuration(0.05).sleep();
  }
  ros::WallDuration(1.0).sleep();
  const long rss_after = node_rss_kb();
  const double t_after = ClockNow();
  EXPECT_TRUE(Trigger("pause"));
  ASSERT_GT(rss_before, 0);
  ASSERT_GT(rss_after, 0);
  std::printf("[ INFO ] node RSS %ld kB -> %ld kB over 50 subscriber cycles; sim time %.2f -> %.2f s\n", rss_before,
              rss_after, t_before, t_after);
  EXPECT_LT(rss_after - rss_before, 5 * 1024);
  EXPECT_GT(t_after, t_before + 1.0);  // still stepping
  EXPECT_TRUE(Trigger("reset"));
}

}  // namespace

int main(int argc, char** argv) { return node_test::RunAllTests(argc, argv, "test_sim_node"); }
