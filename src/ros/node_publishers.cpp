// The node's publishing side: /clock, /tf, /tf_static, /joint_states, ~body_states, ~contacts, ~markers,
// ~step_stats and /diagnostics, one function per topic. The messages are built by ros_conversions.
#include "implicit_sim/ros/sim_node.h"  // first: its generated service type Step precedes the core's function Step

#include <algorithm>
#include <string>

#include <rosgraph_msgs/Clock.h>
#include <tf2_msgs/TFMessage.h>

#include "implicit_sim/BodyStates.h"
#include "implicit_sim/Contacts.h"
#include "implicit_sim/StepStats.h"
#include "implicit_sim/core/model/joints.h"
#include "implicit_sim/ros/conversions.h"

namespace implicit_sim {
namespace conv = ros_conversions;
namespace {

// The effort the core applies for a command: clamped to the URDF effort limit, plus the scene's constant effort.
double AppliedEffort(const Joint& joint, double commanded) {
  return ClampJointEffort(joint, commanded) + joint.applied_effort;
}

// Contact results exist once a step has run.
bool HaveContacts(const State& snapshot) { return snapshot.t > 0.0; }

}  // namespace

void SimNode::AdvertiseTopics() {
  clock_pub_ = nh_.advertise<rosgraph_msgs::Clock>("/clock", 10);
  // Latched: a subscriber that connects late (rviz started while paused) gets the last transforms at once, since
  // /tf is never republished with a stamp it already carried (tf2 would warn TF_REPEATED_DATA).
  tf_pub_ = nh_.advertise<tf2_msgs::TFMessage>("/tf", 100, true);
  contacts_pub_ = pnh_.advertise<implicit_sim::Contacts>("contacts", 10);
  markers_pub_ = pnh_.advertise<visualization_msgs::MarkerArray>("markers", 10);
  stats_pub_ = pnh_.advertise<implicit_sim::StepStats>("step_stats", 100);
  body_states_pub_ = pnh_.advertise<implicit_sim::BodyStates>("body_states", 10);
  joint_states_pub_ = nh_.advertise<sensor_msgs::JointState>("joint_states", 10);
}

void SimNode::PublishClock(double sim_time) {
  std::lock_guard<std::mutex> lock(clock_mutex_);
  last_clock_ = std::max(last_clock_, sim_time);  // /clock never goes backwards; the same time again is allowed
  rosgraph_msgs::Clock msg;
  msg.clock.fromSec(last_clock_);
  clock_pub_.publish(msg);
}

void SimNode::PublishStepStats(const StepReport& report, double sim_time, uint64_t step, double rtf) {
  if (stats_pub_.getNumSubscribers() == 0) return;
  stats_pub_.publish(conv::ToStepStatsMsg(report, sim_time, step, rtf, params_.world_frame));
}

void SimNode::PublishStaticTf() {
  const std::vector<geometry_msgs::TransformStamped> statics = conv::ToStaticTransforms(model_, params_.world_frame);
  if (!statics.empty()) static_broadcaster_.sendTransform(statics);
}

void SimNode::PublishTf(const Snapshot& snapshot, const ros::Time& stamp, PublishMemory* memory) {
  // /tf only when time has moved: tf2 listeners warn about (and drop) a repeated stamp. Late subscribers get the last
  // message from the latched publisher.
  if (snapshot.sim_time <= memory->last_tf_time) return;
  memory->last_tf_time = snapshot.sim_time;
  tf2_msgs::TFMessage msg;
  msg.transforms = conv::ToLinkTransforms(model_, snapshot.state, memory->on_tf, stamp, params_.world_frame);
  if (!msg.transforms.empty()) tf_pub_.publish(msg);  // one batched /tf message
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

void SimNode::PublishBodyStates(const Snapshot& snapshot, const ros::Time& stamp) {
  if (body_states_pub_.getNumSubscribers() == 0) return;
  body_states_pub_.publish(conv::ToBodyStatesMsg(model_, snapshot.state, stamp, params_.world_frame));
}

void SimNode::PublishContacts(const Snapshot& snapshot, const ros::Time& stamp) {
  if (contacts_pub_.getNumSubscribers() == 0) return;
  static const std::vector<ContactResult> kNone;
  const std::vector<ContactResult>& contacts = HaveContacts(snapshot.state) ? snapshot.contacts : kNone;
  contacts_pub_.publish(conv::ToContactsMsg(model_, contacts, options_.contact_threshold, stamp, params_.world_frame));
}

void SimNode::PublishMarkers(const Snapshot& snapshot, const ros::Time& stamp, PublishMemory* memory) {
  if (markers_pub_.getNumSubscribers() == 0) return;
  visualization_msgs::MarkerArray msg = memory->shapes;
  for (auto& m : msg.markers) m.header.stamp = stamp;
  std::vector<int>& active = memory->active_pairs;
  active.clear();
  for (const ContactResult& contact : snapshot.contacts) {
    if (!HaveContacts(snapshot.state) || !conv::IsActiveContact(contact, options_.contact_threshold)) continue;
    conv::AppendContactMarkers(contact.pair, contact, true, params_.world_frame, params_.force_marker_scale,
                               params_.contact_marker_size, &msg);
    active.push_back(contact.pair);
  }
  std::sort(active.begin(), active.end());
  for (int pair : memory->shown_pairs) {  // contacts that ended (or left the NCP): delete their markers
    if (std::binary_search(active.begin(), active.end(), pair)) continue;
    conv::AppendContactMarkers(pair, ContactResult(), false, params_.world_frame, params_.force_marker_scale,
                               params_.contact_marker_size, &msg);
  }
  memory->shown_pairs.swap(active);
  markers_pub_.publish(msg);
}

void SimNode::UpdateDiagnostics(diagnostic_updater::DiagnosticStatusWrapper& status) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (diag_failed_ > 0) {
    const std::string what = paused_ ? "simulation paused: " : "bodies reset: ";
    status.summary(diagnostic_msgs::DiagnosticStatus::ERROR, "step refused, " + what + last_failure_);
  } else if (diag_nonconverged_ > 0) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN, "some steps did not converge");
  } else {
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, paused_ ? "paused" : "running");
  }
  status.add("sim_time_s", SimTime());
  status.add("steps_since_last_report", diag_steps_);
  status.add("nonconverged_steps_since_last_report", diag_nonconverged_);
  status.add("failed_steps_since_last_report", diag_failed_);
  status.add("received_wrench_commands", received_commands_);
  status.add("dropped_wrench_commands", dropped_commands_);
  status.add("received_joint_effort_commands", received_joint_commands_);
  status.add("dropped_joint_effort_commands", dropped_joint_commands_);
  for (StepFault fault : {StepFault::kNotConverged, StepFault::kNoFiniteSolution, StepFault::kInitialOverlap,
                          StepFault::kDiverged, StepFault::kCrossing}) {
    status.add(std::string("faults_") + StepFaultName(fault), faults_[static_cast<int>(fault)]);
  }
  status.add("real_time_factor", rtf_);
  status.add("last_iterations", last_report_.iterations);
  status.add("last_residual", last_report_.residual);
  diag_steps_ = diag_nonconverged_ = diag_failed_ = 0;
}

}  // namespace implicit_sim
