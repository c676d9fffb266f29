// The node's publishing side (doc/ros_node.md): /clock, /tf, /tf_static, /joint_states, ~body_states, ~contacts,
// ~markers and ~step_stats, one function per topic, from snapshots only: the physics thread stores a snapshot after
// every change (Store), the publish thread sends what changed (Cycle) and the read-only services read the latest
// (Latest). It never touches the world, so nothing here waits for a step. Its locks: the snapshot's and /clock's.
#pragma once

#include <functional>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <ros/ros.h>
#include <sensor_msgs/JointState.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <visualization_msgs/MarkerArray.h>

#include "implicit_sim/Contacts.h"
#include "implicit_sim/core/model/model.h"
#include "implicit_sim/core/model/state.h"
#include "implicit_sim/core/step/contact_result.h"
#include "implicit_sim/core/step/step_report.h"
#include "implicit_sim/ros/node_params.h"

namespace implicit_sim {

// The world as the physics thread last saved it; `version` grows with every snapshot.
struct NodeSnapshot {
  std::shared_ptr<const Model> model;
  State state;
  std::vector<ContactResult> contacts;
  Eigen::VectorXd efforts;            // per model joint: the commanded effort (N m or N)
  std::vector<double> drive_efforts;  // per model joint: the drive's effort over the last step (N m or N)
  double sim_time = 0.0;              // s
  uint64_t version = 0;
  bool stepped = false;  // a step has run since startup or the last reset (contact results exist)
  std::vector<std::pair<Vec3, Vec3>> drag_arrows;  // per mouse drag: the grabbed point and the target (m, world)
};

class NodePublisher {
 public:
  // live: the live parameters (rates, marker sizes), read every cycle. The publish thread calls on_new_world when a
  // snapshot of a new model arrives, and on_cycle at the end of every cycle (the interactive markers follow them).
  using SnapshotHook = std::function<void(const NodeSnapshot&)>;
  NodePublisher(ros::NodeHandle nh, ros::NodeHandle pnh, const NodeParams& params, std::function<LiveParams()> live,
                SnapshotHook on_new_world, SnapshotHook on_cycle);
  void Store(std::shared_ptr<const NodeSnapshot> snapshot);  // physics thread
  std::shared_ptr<const NodeSnapshot> Latest() const;        // any thread
  // The publish thread's cycle: /clock every cycle, the per-state topics when the snapshot changed.
  void Cycle();
  // /clock now (never backwards), or at most ~clock_rate per s of simulation time and 1000 per s of wall time.
  void PublishClock(double sim_time);
  void PublishClockThrottled(double sim_time, bool force);
  // ~step_stats, throttled like /clock; steps that did not converge or advance always (physics thread).
  void PublishStepStats(const StepReport& report, double sim_time, uint64_t step, double rtf);
  void PublishStaticTf(const Model& model);

 private:
  // What the publish thread keeps from one cycle to the next (touched by it only).
  struct Memory {
    std::shared_ptr<const Model> model;          // the model the shapes below belong to
    std::vector<char> on_tf;                     // per body, then per frame link: whether /tf carries the link
    std::vector<int> shown_pairs, active_pairs;  // pairs with contact markers: last published, current
    double last_tf_time = -1.0;                  // s, simulation time of the last /tf
    uint64_t last_version = 0;                   // snapshot version last published
    int shown_drag_arrows = 0;                   // drag arrows last published (ids 0 ... n-1)
  };
  void PublishTf(const NodeSnapshot& snapshot);
  void PublishStateTopics(const NodeSnapshot& snapshot);  // after a change of the state
  void AnnounceNewWorld(const NodeSnapshot& snapshot);    // static tf, shapes
  void PublishContactMarkers(const NodeSnapshot& snapshot);
  sensor_msgs::JointState JointStatesMsg(const NodeSnapshot& snapshot) const;
  implicit_sim::Contacts ContactsMsg(const NodeSnapshot& snapshot) const;
  // The current message of a per-state topic to one new subscriber.
  void SendContacts(const ros::SingleSubscriberPublisher& to) const;
  void SendBodyStates(const ros::SingleSubscriberPublisher& to) const;
  void SendJointStates(const ros::SingleSubscriberPublisher& to) const;
  void SendMarkers(const ros::SingleSubscriberPublisher& to) const;
  void AppendDragArrows(const NodeSnapshot& snapshot, int shown, double size,
                        visualization_msgs::MarkerArray* msg) const;

  const NodeParams params_;
  // With publish_joint_link_tf false: the links of robot_description when the node started, which
  // robot_state_publisher (it reads the parameter once) publishes. Links added later are published here.
  std::set<std::string> described_links_;
  double last_stats_time_ = -1e300, last_stats_wall_ = -1e300;  // s: the last ~step_stats (physics thread only)
  const std::function<LiveParams()> live_;
  const SnapshotHook on_new_world_, on_cycle_;
  Memory memory_;  // publish thread
  mutable std::mutex latest_mutex_;
  std::shared_ptr<const NodeSnapshot> latest_;  // guarded by latest_mutex_
  std::mutex clock_mutex_;
  double last_clock_ = -1.0;       // s of sim time, the latest /clock
  double last_clock_wall_ = -1.0;  // s of wall time (steady clock) of the latest throttled /clock
  ros::Publisher clock_pub_, tf_pub_, contacts_pub_, markers_pub_, stats_pub_, body_states_pub_, joint_states_pub_;
  tf2_ros::StaticTransformBroadcaster static_broadcaster_;
};

}  // namespace implicit_sim
