// Helpers shared by the node's rostests (test_sim_node.cpp, test_sim_node_joints.cpp): service calls, the node's
// /diagnostics values, and a main that spins while the tests run.
#pragma once

#include <string>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <std_srvs/Trigger.h>

namespace node_test {

const std::string kNs = "/implicit_sim/";

// Calls the node's service `name` (waiting up to 10 s for it); a failed call is a test failure.
template <typename Srv>
Srv Call(const std::string& name, Srv srv = Srv()) {
  EXPECT_TRUE(ros::service::waitForService(kNs + name, ros::Duration(10)));
  EXPECT_TRUE(ros::service::call(kNs + name, srv)) << name;
  return srv;
}

inline bool Trigger(const std::string& name) { return Call<std_srvs::Trigger>(name).response.success; }

// The latest value of `key` in the node's /diagnostics status (published every second), as an integer; -1 if absent.
inline long DiagnosticValue(const std::string& key) {
  ros::WallDuration(1.1).sleep();  // a report that covers everything before this call
  const auto diagnostics =
      ros::topic::waitForMessage<diagnostic_msgs::DiagnosticArray>("/diagnostics", ros::Duration(5));
  if (!diagnostics || diagnostics->status.empty()) return -1;
  for (const auto& kv : diagnostics->status[0].values) {
    if (kv.key == key) return std::stol(kv.value);
  }
  return -1;
}

// gtest main for a rostest: ROS initialized as `node_name`, callbacks spun on two threads.
inline int RunAllTests(int argc, char** argv, const char* node_name) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, node_name);
  ros::AsyncSpinner spinner(2);
  spinner.start();
  const int result = RUN_ALL_TESTS();
  ros::shutdown();
  return result;
}

}  // namespace node_test
