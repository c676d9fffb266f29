// The node's joint interface: effort commands (topic ~joint_effort_cmd, service ~set_joint_efforts) and
// /joint_states. Efforts enter the step as the wrench of AddJointEffortWrench (core joints.h).
#include "implicit_sim/ros/sim_node.h"  // first: its generated service type Step precedes the core's function Step

#include <cmath>
#include <string>
#include <vector>

#include "implicit_sim/core/model/joints.h"
#include "implicit_sim/core/base/format.h"

namespace implicit_sim {
namespace {

// The effort the core applies for a command: clamped to the URDF effort limit, plus the scene's constant effort.
double AppliedEffort(const Joint& joint, double commanded) {
  return ClampJointEffort(joint, commanded) + joint.applied_effort;
}

}  // namespace

bool SimNode::SetJointEffortsLocked(const std::vector<std::string>& names, const std::vector<double>& efforts,
                                    std::string* error) {
  if (names.size() != efforts.size()) {
    *error = "name and effort must have the same length (" + std::to_string(names.size()) + " names, " +
             std::to_string(efforts.size()) + " efforts)";
    return false;
  }
  std::vector<int> joints(names.size());
  for (size_t i = 0; i < names.size(); ++i) {
    joints[i] = model_.FindJoint(names[i]);
    if (joints[i] < 0 || !model_.joints[joints[i]].has_coordinate()) {
      *error = "no revolute, continuous or prismatic joint '" + names[i] + "' in the scene";
      return false;
    }
    if (!std::isfinite(efforts[i]) || std::abs(efforts[i]) > kMaxCommand) {
      *error = "effort of joint '" + names[i] + "' = " + FormatNumber(efforts[i]) +
               " must be finite with |effort| <= 1e9 (N m or N)";
      return false;
    }
  }
  for (size_t i = 0; i < names.size(); ++i) joint_efforts_[joints[i]] = efforts[i];
  return true;
}

void SimNode::OnJointEffortCommand(const sensor_msgs::JointState::ConstPtr& msg) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++received_joint_commands_;
  std::string error;
  if (!SetJointEffortsLocked(msg->name, msg->effort, &error)) {
    ++dropped_joint_commands_;
    ROS_WARN_THROTTLE(1.0, "implicit_sim: dropped ~joint_effort_cmd: %s (%ld dropped so far)", error.c_str(),
                      dropped_joint_commands_);
  }
}

bool SimNode::OnSetJointEfforts(implicit_sim::SetJointEfforts::Request& req,
                                implicit_sim::SetJointEfforts::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  std::string error;
  res.success = SetJointEffortsLocked(req.name, req.effort, &error);
  res.message = res.success ? "set the effort of " + std::to_string(req.name.size()) + " joints" : error;
  return true;
}

void SimNode::PublishJointStates(const State& snapshot, const Eigen::VectorXd& efforts, const ros::Time& stamp) {
  if (joint_states_pub_.getNumSubscribers() == 0) return;
  sensor_msgs::JointState msg;
  msg.header.stamp = stamp;
  for (int j = 0; j < static_cast<int>(model_.joints.size()); ++j) {
    const Joint& joint = model_.joints[j];
    if (!joint.has_coordinate()) continue;  // fixed joints are not in JointState
    msg.name.push_back(joint.name);
    msg.position.push_back(JointPosition(model_, snapshot, j));
    msg.velocity.push_back(JointVelocity(model_, snapshot, j));
    msg.effort.push_back(AppliedEffort(joint, efforts[j]));
  }
  if (!msg.name.empty()) joint_states_pub_.publish(msg);
}

}  // namespace implicit_sim
