// Watches the ROS master (~on_master_loss, doc/ros_node.md "Master loss"): once a second it asks the master for its
// pid. A master that does not answer, or answers with another pid (it was restarted and knows nothing of this node),
// is logged as an ERROR once. Then "exit" asks the node to shut down (exit status 1), and "reregister" waits for a
// master and registers the node's publications, subscriptions and services with it again.
#pragma once

#include <functional>
#include <string>
#include <vector>

namespace implicit_sim {

class MasterWatch {
 public:
  enum class Policy { kExit, kReregister };
  // service_names: the node's services (roscpp lists topics, not services). Asks the master for its pid at once: build
  // it after the node has registered.
  MasterWatch(Policy policy, std::function<std::vector<std::string>()> service_names);
  // One check (the diagnostics thread, every second); false when the node must exit.
  bool Check();
  bool exit_requested() const { return exit_requested_; }

 private:
  // Registers every publication, subscription and service of this node with the master; false if one call failed.
  bool Reregister();

  Policy policy_;
  std::function<std::vector<std::string>()> service_names_;
  int known_pid_ = -1;  // the master this node is registered with
  bool lost_ = false;
  bool exit_requested_ = false;
};

}  // namespace implicit_sim
