#include "implicit_sim/ros/node_publisher.h"

#include <algorithm>
#include <chrono>
#include <string>

#include <rosgraph_msgs/Clock.h>
#include <tinyxml2.h>
#include <tf2_msgs/TFMessage.h>

#include "implicit_sim/BodyStates.h"
#include "implicit_sim/StepStats.h"
#include "implicit_sim/core/model/joints.h"
#include "implicit_sim/ros/conversions.h"

namespace implicit_sim {
namespace conv = ros_conversions;
namespace {

// /clock from the physics thread: at most ~clock_rate messages per second of simulation time and at most this many
// per second of wall time (as fast as possible, sim time runs hundreds of times faster than the wall).
constexpr double kMaxClockWallRate = 1000.0;  // Hz

ros::Time Stamp(double sim_time) { return ros::Time().fromSec(sim_time); }

double WallSeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// The effort the core applies for a command: clamped to the URDF effort limit, plus the scene's constant effort (a
// drive's effort comes on top).
double AppliedEffort(const Joint& joint, double commanded) {
  return ClampJointEffort(joint, commanded) + joint.applied_effort;
}

// The names of a URDF's links ({} when it does not parse: then the node publishes every link itself).
std::set<std::string> LinkNamesOf(const std::string& urdf) {
  std::set<std::string> names;
  tinyxml2::XMLDocument document;
  if (document.Parse(urdf.c_str(), urdf.size()) != tinyxml2::XML_SUCCESS) return names;
  const tinyxml2::XMLElement* robot = document.FirstChildElement("robot");
  for (auto* link = robot ? robot->FirstChildElement("link") : nullptr; link; link = link->NextSiblingElement("link")) {
    if (link->Attribute("name")) names.insert(link->Attribute("name"));
  }
  return names;
}

}  // namespace

NodePublisher::NodePublisher(ros::NodeHandle nh, ros::NodeHandle pnh, const NodeParams& params,
                             std::function<LiveParams()> live, SnapshotHook on_new_world, SnapshotHook on_cycle)
    : params_(params), live_(std::move(live)), on_new_world_(std::move(on_new_world)), on_cycle_(std::move(on_cycle)) {
  std::string description;
  if (!params_.publish_joint_link_tf && nh.getParam("robot_description", description)) {
    described_links_ = LinkNamesOf(description);
  }
  clock_pub_ = nh.advertise<rosgraph_msgs::Clock>("/clock", 10);
  // Latched: a subscriber that connects late (rviz started while paused) gets the last transforms at once, since
  // /tf is never republished with a stamp it already carried (tf2 would warn TF_REPEATED_DATA).
  tf_pub_ = nh.advertise<tf2_msgs::TFMessage>("/tf", 100, true);
  // The per-state topics are sent when the state changes, and the current one to each new subscriber at once
  // (so a subscriber of a paused simulation is not left waiting). ~markers sends a new subscriber the shapes,
  // frame-locked to their link frames (tf moves them, so they are never sent again), with the current contacts.
  const auto on_connect = [this](void (NodePublisher::*send)(const ros::SingleSubscriberPublisher&) const) {
    return [this, send](const ros::SingleSubscriberPublisher& to) { (this->*send)(to); };
  };
  contacts_pub_ = pnh.advertise<implicit_sim::Contacts>("contacts", 10, on_connect(&NodePublisher::SendContacts));
  markers_pub_ = pnh.advertise<visualization_msgs::MarkerArray>("markers", 10, on_connect(&NodePublisher::SendMarkers));
  stats_pub_ = pnh.advertise<implicit_sim::StepStats>("step_stats", 100);
  body_states_pub_ =
      pnh.advertise<implicit_sim::BodyStates>("body_states", 10, on_connect(&NodePublisher::SendBodyStates));
  joint_states_pub_ =
      nh.advertise<sensor_msgs::JointState>("joint_states", 10, on_connect(&NodePublisher::SendJointStates));
}

void NodePublisher::Store(std::shared_ptr<const NodeSnapshot> snapshot) {
  std::lock_guard<std::mutex> lock(latest_mutex_);
  latest_ = std::move(snapshot);
}

std::shared_ptr<const NodeSnapshot> NodePublisher::Latest() const {
  std::lock_guard<std::mutex> lock(latest_mutex_);
  return latest_;
}

void NodePublisher::Cycle() {
  const std::shared_ptr<const NodeSnapshot> latest = Latest();
  const NodeSnapshot& snapshot = *latest;
  if (memory_.model != snapshot.model) {  // a new world: its shapes and static frames, stale contacts deleted
    if (memory_.model) AnnounceNewWorld(snapshot);
    memory_.model = snapshot.model;
    // Jointed links and frame links: to robot_state_publisher if asked, unless it never heard of them (spawned).
    const Model& model = *snapshot.model;
    const auto ours = [&](const std::string& link) {
      return params_.publish_joint_link_tf || described_links_.count(link) == 0;
    };
    memory_.on_tf.assign(model.bodies.size() + model.frames.size(), 1);
    for (const Joint& joint : model.joints) memory_.on_tf[joint.child] = ours(model.bodies[joint.child].name);
    for (size_t f = 0; f < model.frames.size(); ++f) memory_.on_tf[model.bodies.size() + f] = ours(model.frames[f].name);
  }
  PublishClock(snapshot.sim_time);  // every cycle, even when time has not moved (the same time again is allowed)
  if (snapshot.version != memory_.last_version) {
    memory_.last_version = snapshot.version;
    PublishStateTopics(snapshot);
  }
  on_cycle_(snapshot);
}

// A subscriber that connects before the first snapshot is stored gets the first message with the next change.
void NodePublisher::SendContacts(const ros::SingleSubscriberPublisher& to) const {
  const std::shared_ptr<const NodeSnapshot> snapshot = Latest();
  if (snapshot) to.publish(ContactsMsg(*snapshot));
}

void NodePublisher::SendBodyStates(const ros::SingleSubscriberPublisher& to) const {
  const std::shared_ptr<const NodeSnapshot> snapshot = Latest();
  if (!snapshot) return;
  to.publish(conv::ToBodyStatesMsg(*snapshot->model, snapshot->state, Stamp(snapshot->sim_time), params_.world_frame));
}

void NodePublisher::SendJointStates(const ros::SingleSubscriberPublisher& to) const {
  const std::shared_ptr<const NodeSnapshot> snapshot = Latest();
  if (!snapshot) return;
  const sensor_msgs::JointState msg = JointStatesMsg(*snapshot);
  if (!msg.name.empty()) to.publish(msg);
}

// Arrows of the drag springs (ns "drag", ids 0 ... n-1; the ids from n to shown - 1 are deleted).
void NodePublisher::AppendDragArrows(const NodeSnapshot& snapshot, int shown, double size,
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

void NodePublisher::AnnounceNewWorld(const NodeSnapshot& snapshot) {
  PublishStaticTf(*snapshot.model);
  if (markers_pub_.getNumSubscribers() > 0) {
    visualization_msgs::MarkerArray msg;
    msg.markers.emplace_back();
    msg.markers.back().action = visualization_msgs::Marker::DELETEALL;
    const visualization_msgs::MarkerArray shapes = conv::ShapeMarkers(*snapshot.model);
    msg.markers.insert(msg.markers.end(), shapes.markers.begin(), shapes.markers.end());
    markers_pub_.publish(msg);
  }
  memory_.shown_pairs.clear();
  memory_.shown_drag_arrows = 0;
  on_new_world_(snapshot);
}

void NodePublisher::SendMarkers(const ros::SingleSubscriberPublisher& to) const {
  const std::shared_ptr<const NodeSnapshot> snapshot = Latest();
  if (!snapshot) return;
  visualization_msgs::MarkerArray msg = conv::ShapeMarkers(*snapshot->model);
  const LiveParams live = live_();
  for (const ContactResult& contact : snapshot->contacts) {
    if (!snapshot->stepped || !conv::IsActiveContact(contact, params_.options.contact_threshold)) continue;
    conv::AppendContactMarkers(contact.pair, contact, true, params_.world_frame, live.force_marker_scale,
                               live.contact_marker_size, &msg);
  }
  to.publish(msg);
}

void NodePublisher::PublishClock(double sim_time) {
  std::lock_guard<std::mutex> lock(clock_mutex_);
  last_clock_ = std::max(last_clock_, sim_time);  // /clock never goes backwards; the same time again is allowed
  rosgraph_msgs::Clock msg;
  msg.clock.fromSec(last_clock_);
  clock_pub_.publish(msg);
}

void NodePublisher::PublishClockThrottled(double sim_time, bool force) {
  const double wall = WallSeconds();
  {
    std::lock_guard<std::mutex> lock(clock_mutex_);
    const bool due = sim_time >= last_clock_ + 1.0 / live_().clock_rate - 1e-12 &&
                     wall >= last_clock_wall_ + 1.0 / kMaxClockWallRate;
    if (!force && !due) return;
    last_clock_wall_ = wall;
  }
  PublishClock(sim_time);
}

void NodePublisher::PublishStepStats(const StepReport& report, double sim_time, uint64_t step, double rtf) {
  if (stats_pub_.getNumSubscribers() == 0) return;
  // Throttled like /clock (at most ~clock_rate per second of simulation time and 1000 per second of wall time), so
  // tiny steps as fast as possible do not flood a bag; a step that did not converge or advance always goes out.
  const double wall = WallSeconds();
  const bool due = sim_time >= last_stats_time_ + 1.0 / live_().clock_rate - 1e-12 &&
                   wall >= last_stats_wall_ + 1.0 / kMaxClockWallRate;
  if (!due && report.converged && report.advanced) return;
  last_stats_time_ = sim_time;
  last_stats_wall_ = wall;
  stats_pub_.publish(conv::ToStepStatsMsg(report, sim_time, step, rtf, params_.world_frame));
}

void NodePublisher::PublishStaticTf(const Model& model) {
  const std::vector<geometry_msgs::TransformStamped> statics = conv::ToStaticTransforms(model, params_.world_frame);
  if (!statics.empty()) static_broadcaster_.sendTransform(statics);
}

void NodePublisher::PublishTf(const NodeSnapshot& snapshot) {
  // /tf only when time has moved: tf2 listeners warn about (and drop) a repeated stamp. Late subscribers get the last
  // message from the latched publisher.
  if (snapshot.sim_time <= memory_.last_tf_time) return;
  memory_.last_tf_time = snapshot.sim_time;
  tf2_msgs::TFMessage msg;
  msg.transforms = conv::ToLinkTransforms(*snapshot.model, snapshot.state, memory_.on_tf, Stamp(snapshot.sim_time),
                                          params_.world_frame);
  if (!msg.transforms.empty()) tf_pub_.publish(msg);  // one batched /tf message
}

sensor_msgs::JointState NodePublisher::JointStatesMsg(const NodeSnapshot& snapshot) const {
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

implicit_sim::Contacts NodePublisher::ContactsMsg(const NodeSnapshot& snapshot) const {
  static const std::vector<ContactResult> kNone;
  return conv::ToContactsMsg(*snapshot.model, snapshot.stepped ? snapshot.contacts : kNone,
                             params_.options.contact_threshold, Stamp(snapshot.sim_time), params_.world_frame);
}

void NodePublisher::PublishStateTopics(const NodeSnapshot& snapshot) {
  PublishTf(snapshot);  // only when time has moved
  if (joint_states_pub_.getNumSubscribers() > 0) {
    const sensor_msgs::JointState msg = JointStatesMsg(snapshot);
    if (!msg.name.empty()) joint_states_pub_.publish(msg);
  }
  if (body_states_pub_.getNumSubscribers() > 0) {
    body_states_pub_.publish(
        conv::ToBodyStatesMsg(*snapshot.model, snapshot.state, Stamp(snapshot.sim_time), params_.world_frame));
  }
  if (contacts_pub_.getNumSubscribers() > 0) contacts_pub_.publish(ContactsMsg(snapshot));
  PublishContactMarkers(snapshot);
}

void NodePublisher::PublishContactMarkers(const NodeSnapshot& snapshot) {
  if (markers_pub_.getNumSubscribers() == 0) return;
  const LiveParams live = live_();
  visualization_msgs::MarkerArray msg;
  std::vector<int>& active = memory_.active_pairs;
  active.clear();
  for (const ContactResult& contact : snapshot.contacts) {
    if (!snapshot.stepped || !conv::IsActiveContact(contact, params_.options.contact_threshold)) continue;
    conv::AppendContactMarkers(contact.pair, contact, true, params_.world_frame, live.force_marker_scale,
                               live.contact_marker_size, &msg);
    active.push_back(contact.pair);
  }
  std::sort(active.begin(), active.end());
  for (int pair : memory_.shown_pairs) {  // contacts that ended (or left the NCP): delete their markers
    if (std::binary_search(active.begin(), active.end(), pair)) continue;
    conv::AppendContactMarkers(pair, ContactResult(), false, params_.world_frame, live.force_marker_scale,
                               live.contact_marker_size, &msg);
  }
  memory_.shown_pairs.swap(active);
  AppendDragArrows(snapshot, memory_.shown_drag_arrows, live.contact_marker_size, &msg);
  memory_.shown_drag_arrows = static_cast<int>(snapshot.drag_arrows.size());
  if (!msg.markers.empty()) markers_pub_.publish(msg);
}

}  // namespace implicit_sim
