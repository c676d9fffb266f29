// implicit_sim_node: the simulator as a ROS node (see doc/ros_node.md for topics, services and parameters).
#include <csignal>
#include <iostream>

#include <ros/ros.h>

#include "implicit_sim/ros/sim_node.h"

namespace {

// Requested by SIGINT and SIGTERM: a scene loading (at startup or for a service) stops between two links.
implicit_sim::StepInterrupt g_stop;

// SIGINT (Ctrl-C, roslaunch) and SIGTERM (systemd, docker stop, kill) shut down alike: threads joined, exit code 0.
// Both only store flags, as roscpp's own SIGINT handler does.
extern "C" void OnStopSignal(int) {
  g_stop.Request();
  ros::requestShutdown();
}

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "implicit_sim", ros::init_options::NoSigintHandler);
  std::signal(SIGINT, OnStopSignal);
  std::signal(SIGTERM, OnStopSignal);
  try {
    implicit_sim::SimNode node(ros::NodeHandle(), ros::NodeHandle("~"), &g_stop);
    node.Run();
    if (node.exited_on_master_loss()) return 1;  // ~on_master_loss: exit (the ERROR names the master)
  } catch (const implicit_sim::LoadInterrupted& e) {
    std::cerr << "implicit_sim_node: " << e.what() << " (shutdown requested)" << std::endl;
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "implicit_sim_node: " << e.what() << std::endl;  // one line naming the parameter or link
    ROS_FATAL("implicit_sim_node: %s", e.what());                  // and on /rosout
    return 1;
  }
  return 0;
}
