// The ROS node over the core: steps on its own thread, publishes /clock, /tf, /tf_static, ~contacts, ~markers,
// ~step_stats, ~body_states and /diagnostics, and serves a gazebo_ros-like control API. Three threads: physics (steps,
// holding mutex_ for the whole step), publish (/clock, /tf and the topics at ~publish_rate from the latest completed
// step, never taking mutex_, so a slow step never delays them) and diagnostics (once a second). doc/ros_node.md documents the
// contract (topics, services, parameters). By concern: sim_node.cpp (construction, threads, stepping),
// node_params.cpp (parameters), node_services.cpp (services and command topics, joints included) and
// node_publishers.cpp (topics and diagnostics).
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <diagnostic_updater/diagnostic_updater.h>
#include <Eigen/Core>
#include <sensor_msgs/JointState.h>
#include <ros/ros.h>
#include <std_srvs/Trigger.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <visualization_msgs/MarkerArray.h>

#include "implicit_sim/ApplyBodyWrench.h"
#include "implicit_sim/BodyWrench.h"
#include "implicit_sim/GetBodyState.h"
#include "implicit_sim/SetBodyState.h"
#include "implicit_sim/SetJointEfforts.h"
#include "implicit_sim/Step.h"
#include "implicit_sim/core/model/model.h"
#include "implicit_sim/core/step/time_stepper.h"
#include "implicit_sim/ros/node_params.h"

namespace implicit_sim {

// The largest command the node accepts: |force| (N), |torque| (N m) and |joint effort| (N m or N). Larger commands
// are refused; they only drive a step into divergence.
constexpr double kMaxCommand = 1e9;

class SimNode {
 public:
  // Loads the scene and sets up publishers and services; throws std::invalid_argument for a bad parameter or scene.
  SimNode(ros::NodeHandle nh, ros::NodeHandle pnh);
  ~SimNode();
  // Starts the physics and publishing threads and blocks until ROS shuts down.
  void Run();

 private:
  struct TimedWrench {
    int body;            // moving body receiving it
    int frame_body;      // body whose link frame expresses it, -1 for the world frame
    Vec3 point, force, torque;  // in that frame (m, N, N m)
    double start, end;   // simulation time (s); end < 0: until cleared
  };

  // The latest completed state, saved under mutex_ whenever the state changes (every step, reset, set_body_state,
  // joint efforts) and read by the publish thread under latest_mutex_ only.
  struct Snapshot {
    State state;
    std::vector<ContactResult> contacts;
    Eigen::VectorXd efforts;  // per model joint (N m or N)
    double sim_time = 0.0;    // s
  };
  // What the publish thread keeps from one cycle to the next (touched by it only).
  struct PublishMemory {
    visualization_msgs::MarkerArray shapes;  // the shape markers, built once
    std::vector<char> on_tf;                 // per body: whether /tf carries its link
    std::vector<int> shown_pairs, active_pairs;  // pairs with contact markers: last published, current
    double last_tf_time = -1.0;              // s, simulation time of the last /tf
  };

  double SimTime() const { return time_offset_ + state_.t; }
  // sim_node.cpp: stepping and threads.
  void StepLocked();                 // one step with the active wrenches; mutex held
  void ResetLocked();                // bodies back to the initial state, warm start and wrenches cleared; mutex held
  void ComputeWrenchesLocked();      // fills wrench_W_ for the step starting now
  void SaveLatestLocked();           // the current state as the latest snapshot; mutex held
  std::shared_ptr<const Snapshot> Latest() const;
  void PhysicsLoop();
  void PublishLoop();
  void DiagnosticsLoop();
  // Sets stopping_, wakes every thread and joins them once all have ended within grace_s (s); false,
  // nothing joined, when one is still inside a step (or waiting for it) by then.
  bool StopThreads(double grace_s);
  void StartThread(std::thread* thread, void (SimNode::*loop)());
  // node_publishers.cpp: one function per topic.
  void AdvertiseTopics();
  void PublishClock(double sim_time);
  void PublishStepStats(const StepReport& report, double sim_time, uint64_t step, double rtf);
  void PublishStaticTf();
  void PublishTf(const Snapshot& snapshot, const ros::Time& stamp, PublishMemory* memory);
  void PublishBodyStates(const Snapshot& snapshot, const ros::Time& stamp);
  void PublishContacts(const Snapshot& snapshot, const ros::Time& stamp);
  void PublishMarkers(const Snapshot& snapshot, const ros::Time& stamp, PublishMemory* memory);
  void PublishJointStates(const State& snapshot, const Eigen::VectorXd& efforts, const ros::Time& stamp);
  void UpdateDiagnostics(diagnostic_updater::DiagnosticStatusWrapper& status);
  // node_services.cpp: services and command topics.
  void AdvertiseServices();
  int FindBodyOrFail(const std::string& name, bool must_move, std::string* error) const;
  bool OnPause(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res);
  bool OnUnpause(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res);
  bool OnReset(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res);
  bool OnClearWrenches(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res);
  bool OnStep(implicit_sim::Step::Request& req, implicit_sim::Step::Response& res);
  bool OnGetBodyState(implicit_sim::GetBodyState::Request& req, implicit_sim::GetBodyState::Response& res);
  bool OnSetBodyState(implicit_sim::SetBodyState::Request& req, implicit_sim::SetBodyState::Response& res);
  bool OnApplyWrench(implicit_sim::ApplyBodyWrench::Request& req, implicit_sim::ApplyBodyWrench::Response& res);
  void OnWrenchCommand(const implicit_sim::BodyWrench::ConstPtr& msg);
  // Joints: ~joint_effort_cmd and ~set_joint_efforts.
  bool SetJointEffortsLocked(const std::vector<std::string>& names, const std::vector<double>& efforts,
                             std::string* error);  // all or nothing
  void OnJointEffortCommand(const sensor_msgs::JointState::ConstPtr& msg);
  bool OnSetJointEfforts(implicit_sim::SetJointEfforts::Request& req, implicit_sim::SetJointEfforts::Response& res);

  ros::NodeHandle nh_, pnh_;
  NodeParams params_;
  const Model model_;
  StepperOptions options_;

  // Guarded by mutex_.
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  State state_, initial_state_;
  Data data_;
  double time_offset_ = 0.0;      // simulation time = time_offset_ + state_.t (reset keeps time monotonic)
  bool paused_ = false, restart_pacing_ = true;
  uint64_t step_count_ = 0;
  StepReport last_report_;
  std::vector<TimedWrench> wrenches_;
  Eigen::VectorXd commanded_W_;   // ~wrench_cmd, per moving slot (Model::v_offset): f_W (N), tau_W (N m) at the link
                                  // origin
  Eigen::VectorXd wrench_W_;      // the wrench vector handed to the core (at the centre of mass; core/model/wrench.h)
  Eigen::VectorXd joint_efforts_;  // per model joint: the commanded effort (N m or N; fixed joints 0)
  long received_joint_commands_ = 0, dropped_joint_commands_ = 0;
  long diag_steps_ = 0, diag_nonconverged_ = 0, diag_failed_ = 0, dropped_commands_ = 0, received_commands_ = 0;
  long faults_[6] = {0, 0, 0, 0, 0, 0};  // refused or non-converged steps since startup, by StepFault
  bool at_initial_state_ = true;      // no step taken since startup or the last reset
  double rtf_ = 0.0;
  std::string last_failure_;

  std::mutex clock_mutex_;
  double last_clock_ = -1.0;

  mutable std::mutex latest_mutex_;
  std::shared_ptr<const Snapshot> latest_;  // guarded by latest_mutex_

  // Every thread ends: the physics thread after the step in progress (StopThreads does not take mutex_, which a
  // step holds), the others at once.
  std::atomic<bool> stopping_{false};
  std::mutex stop_mutex_;
  std::condition_variable stop_cv_;    // wakes the publish and diagnostics threads' waits, and StopThreads
  int threads_started_ = 0, threads_ended_ = 0;  // guarded by stop_mutex_

  ros::Publisher clock_pub_, tf_pub_, contacts_pub_, markers_pub_, stats_pub_, body_states_pub_, joint_states_pub_;
  std::vector<ros::ServiceServer> services_;
  ros::Subscriber wrench_sub_, joint_effort_sub_;
  tf2_ros::StaticTransformBroadcaster static_broadcaster_;
  diagnostic_updater::Updater diagnostics_;
  std::thread physics_thread_, publish_thread_, diagnostics_thread_;
};

}  // namespace implicit_sim
