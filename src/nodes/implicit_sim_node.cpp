// implicit_sim_node: the simulator as a ROS node (see README.md for topics, services and parameters).
#include <ros/ros.h>

#include "implicit_sim/ros/sim_node.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "implicit_sim");
  try {
    implicit_sim::SimNode node(ros::NodeHandle(), ros::NodeHandle("~"));
    node.Run();
  } catch (const std::exception& e) {
    ROS_FATAL("implicit_sim_node: %s", e.what());
    return 1;
  }
  return 0;
}
