// The node's publishing side: /clock, /tf, /tf_static, /joint_states, ~body_states, ~contacts, ~markers,
// ~step_stats, one function per topic (/diagnostics: node_diagnostics.h). The messages are built by ros_conversions.
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

ros::Time Stamp(double sim_time) { return ros::Time().fromSec(sim_time); }

// The effort the core applies for a command: clamped to the URDF effort limit, plus the scene's constant effort (a
// drive's effort comes on top).
double AppliedEffort(const Joint& joint, double commanded) {
  return ClampJointEffort(joint, commanded) + joint.applied_effort;
}

}  // namespace

void SimNode::AdvertiseTopics() {
  clock_pub_ = nh_.advertise<rosgraph_msgs::Clock>("/clock", 10);
  // Latched: a subscriber that connects late (rviz started while paused) gets the last transforms at once, since
  // /tf is never republished with a stamp it already carried (tf2 would warn TF_REPEATED_DATA).
  tf_pub_ = nh_.advertise<tf2_msgs::TFMessage>("/tf", 100, true);
  // The per-state topics are sent when the state changes, and the current one to each new subscriber at once
  // (so a subscriber of a paused simulation is not left waiting). ~markers sends a new subscriber the shapes,
  // frame-locked to their link frames (tf moves them, so they are never sent again), with the current contacts.
  const auto on_connect = [this](void (SimNode::*send)(const Snapshot&, const ros::SingleSubscriberPublisher&)) {
    return [this, send](const ros::SingleSubscriberPublisher& to) { (this->*send)(*Latest(), to); };
  };
  contacts_pub_ = pnh_.advertise<implicit_sim::Contacts>("contacts", 10, on_connect(&SimNode::SendContacts));
  markers_pub_ = pnh_.advertise<visualization_msgs::MarkerArray>("markers", 10, on_connect(&SimNode::SendMarkers));
  stats_pub_ = pnh_.advertise<implicit_sim::StepStats>("step_stats", 100);
  body_states_pub_ =
      pnh_.advertise<implicit_sim::BodyStates>("body_states", 10, on_connect(&SimNode::SendBodyStates));
  joint_states_pub_ =
      nh_.advertise<sensor_msgs::JointState>("joint_states", 10, on_connect(&SimNode::SendJointStates));
}

void SimNode::SendContacts(const Snapshot& snapshot, const ros::SingleSubscriberPublisher& to) {
  to.publish(ContactsMsg(snapshot));
}

void SimNode::SendBodyStates(const Snapshot& snapshot, const ros::SingleSubscriberPublisher& to) {
  to.publish(conv::ToBodyStatesMsg(*snapshot.model, snapshot.state, Stamp(snapshot.sim_time), params_.world_frame));
}

void SimNode::SendJointStates(const Snapshot& snapshot, const ros::SingleSubscriberPublisher& to) {
  const sensor_msgs::JointState msg = JointStatesMsg(snapshot);
  if (!msg.name.empty()) to.publish(msg);
}

// Arrows of the drag springs (ns "drag", ids 0 ... n-1; the ids from n to shown - 1 are deleted).
void SimNode::AppendDragArrows(const Snapshot& snapshot, int shown, double size,
                               visualization_msgs::MarkerArray* msg) const {
  const int n = static_cast<int>(snapshot.drag_arrows.size());
  for (int i = 0; i < std::max(n, shown); ++i) {
    visualization_msgs::Marker m;
    m.header.frame_id = params_.world_frame;
    m.ns = "drag";
    m.id = i;
    m.pose.orientation.w = 1.0;
    if (i >= n) {
      m.action = visualization_msgs::Marker::DELETE;
    } else {
      m.action = visualization_msgs::Marker::ADD;
      m.type = visualization_msgs::Marker::ARROW;
      m.points.resize(2);
      m.points[0] = conv::ToPointMsg(snapshot.drag_arrows[i].first);
      m.points[1] = conv::ToPointMsg(snapshot.drag_arrows[i].second);
      m.scale.x = 0.3 * size, m.scale.y = 0.6 * size, m.scale.z = 0.6 * size;
      m.color.r = 0.2f, m.color.g = 0.6f, m.color.b = 1.0f, m.color.a = 1.0f;
    }
    msg->markers.push_back(m);
  }
}

void SimNode::AnnounceNewWorld(const Snapshot& snapshot, PublishMemory* memory) {
  PublishStaticTf(*snapshot.model);
  if (markers_pub_.getNumSubscribers() > 0) {
    visualization_msgs::MarkerArray msg;
    msg.markers.emplace_back();
    msg.markers.back().action = visualization_msgs::Marker::DELETEALL;
    const visualization_msgs::MarkerArray shapes = conv::ShapeMarkers(*snapshot.model);
    msg.markers.insert(msg.markers.end(), shapes.markers.begin(), shapes.markers.end());
    markers_pub_.publish(msg);
  }
  memory->shown_pairs.clear();
  memory->shown_drag_arrows = 0;
  SetUpDragMarkers(*snapshot.model, snapshot.state);
}

void SimNode::SendMarkers(const Snapshot& snapshot, const ros::SingleSubscriberPublisher& to) {
  visualization_msgs::MarkerArray msg = conv::ShapeMarkers(*snapshot.model);
  const LiveParams live = Live();
  for (const ContactResult& contact : snapshot.contacts) {
    if (!snapshot.stepped || !conv::IsActiveContact(contact, options_.contact_threshold)) continue;
    conv::AppendContactMarkers(contact.pair, contact, true, params_.world_frame, live.force_marker_scale,
                               live.contact_marker_size, &msg);
  }
  to.publish(msg);
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

void SimNode::PublishStaticTf(const Model& model) {
  const std::vector<geometry_msgs::TransformStamped> statics = conv::ToStaticTransforms(model, params_.world_frame);
  if (!statics.empty()) static_broadcaster_.sendTransform(statics);
}

void SimNode::PublishTf(const Snapshot& snapshot, const ros::Time& stamp, PublishMemory* memory) {
  // /tf only when time has moved: tf2 listeners warn about (and drop) a repeated stamp. Late subscribers get the last
  // message from the latched publisher.
  if (snapshot.sim_time <= memory->last_tf_time) return;
  memory->last_tf_time = snapshot.sim_time;
  tf2_msgs::TFMessage msg;
  msg.transforms =
      conv::ToLinkTransforms(*snapshot.model, snapshot.state, memory->on_tf, stamp, params_.world_frame);
  if (!msg.transforms.empty()) tf_pub_.publish(msg);  // one batched /tf message
}

sensor_msgs::JointState SimNode::JointStatesMsg(const Snapshot& snapshot) const {
  const Model& model = *snapshot.model;
  sensor_msgs::JointState msg;
  msg.header.stamp = Stamp(snapshot.sim_time);
  for (int j = 0; j < static_cast<int>(model.joints.size()); ++j) {
    const Joint& joint = model.joints[j];
    if (!joint.has_coordinate()) continue;  // fixed joints are not in JointState
    msg.name.push_back(joint.name);
    msg.position.push_back(JointPosition(model, snapshot.state, j));
    msg.velocity.push_back(JointVelocity(model, snapshot.state, j));
    const double drive = snapshot.stepped ? snapshot.drive_efforts[j] : 0.0;
    msg.effort.push_back(AppliedEffort(joint, snapshot.efforts[j]) + drive);
  }
  return msg;
}

implicit_sim::Contacts SimNode::ContactsMsg(const Snapshot& snapshot) const {
  static const std::vector<ContactResult> kNone;
  return conv::ToContactsMsg(*snapshot.model, snapshot.stepped ? snapshot.contacts : kNone,
                             options_.contact_threshold, Stamp(snapshot.sim_time), params_.world_frame);
}

void SimNode::PublishStateTopics(const Snapshot& snapshot, PublishMemory* memory) {
  PublishTf(snapshot, Stamp(snapshot.sim_time), memory);  // only when time has moved
  if (joint_states_pub_.getNumSubscribers() > 0) {
    const sensor_msgs::JointState msg = JointStatesMsg(snapshot);
    if (!msg.name.empty()) joint_states_pub_.publish(msg);
  }
  if (body_states_pub_.getNumSubscribers() > 0) {
    body_states_pub_.publish(
        conv::ToBodyStatesMsg(*snapshot.model, snapshot.state, Stamp(snapshot.sim_time), params_.world_frame));
  }
  if (contacts_pub_.getNumSubscribers() > 0) contacts_pub_.publish(ContactsMsg(snapshot));
  PublishContactMarkers(snapshot, memory);
}

void SimNode::PublishContactMarkers(const Snapshot& snapshot, PublishMemory* memory) {
  if (markers_pub_.getNumSubscribers() == 0) return;
  const LiveParams live = Live();
  visualization_msgs::MarkerArray msg;
  std::vector<int>& active = memory->active_pairs;
  active.clear();
  for (const ContactResult& contact : snapshot.contacts) {
    if (!snapshot.stepped || !conv::IsActiveContact(contact, options_.contact_threshold)) continue;
    conv::AppendContactMarkers(contact.pair, contact, true, params_.world_frame, live.force_marker_scale,
                               live.contact_marker_size, &msg);
    active.push_back(contact.pair);
  }
  std::sort(active.begin(), active.end());
  for (int pair : memory->shown_pairs) {  // contacts that ended (or left the NCP): delete their markers
    if (std::binary_search(active.begin(), active.end(), pair)) continue;
    conv::AppendContactMarkers(pair, ContactResult(), false, params_.world_frame, live.force_marker_scale,
                               live.contact_marker_size, &msg);
  }
  memory->shown_pairs.swap(active);
  AppendDragArrows(snapshot, memory->shown_drag_arrows, live.contact_marker_size, &msg);
  memory->shown_drag_arrows = static_cast<int>(snapshot.drag_arrows.size());
  if (!msg.markers.empty()) markers_pub_.publish(msg);
}

}  // namespace implicit_sim
