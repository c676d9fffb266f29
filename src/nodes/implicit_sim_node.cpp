// implicit_sim_node: the simulator as a ROS node (see doc/ros_node.md for topics, services and parameters).
#include <csignal>
#include <iostream>

#include <ros/ros.h>

#include "implicit_sim/ros/sim_node.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "implicit_sim");
  // SIGTERM (systemd, docker stop, kill) shuts down like SIGINT: threads joined, exit code 0.
  std::signal(SIGTERM, [](int) { ros::requestShutdown(); });
  try {
    implicit_sim::SimNode node(ros::NodeHandle(), ros::NodeHandle("~"));
    node.Run();
    if (node.exited_on_master_loss()) return 1;  // ~on_master_loss: exit (the ERROR names the master)
  } catch (const std::exception& e) {
    std::cerr << "implicit_sim_node: " << e.what() << std::endl;  // one line naming the parameter or link
    ROS_FATAL("implicit_sim_node: %s", e.what());                  // and on /rosout
    return 1;
  }
  return 0;
}
