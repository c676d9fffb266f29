// The ROS node over the core: steps on its own thread, publishes /clock, /tf, /tf_static, ~contacts, ~markers,
// ~step_stats, ~body_states and /diagnostics, and serves a gazebo_ros-like control API. doc/ros_node.md documents the
// contract (topics, services, parameters).
#pragma once

#include <condition_variable>
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
#include <tf2_ros/transform_broadcaster.h>

#include "implicit_sim/ApplyBodyWrench.h"
#include "implicit_sim/BodyWrench.h"
#include "implicit_sim/GetBodyState.h"
#include "implicit_sim/SetBodyState.h"
#include "implicit_sim/SetJointEfforts.h"
#include "implicit_sim/Step.h"
#include "implicit_sim/core/model/model.h"
#include "implicit_sim/core/step/time_stepper.h"

namespace implicit_sim {

// The largest command the node accepts: |force| (N), |torque| (N m) and |joint effort| (N m or N). Larger commands
// are refused; they only drive a step into divergence.
constexpr double kMaxCommand = 1e9;

// Node parameters (private namespace ~), validated at startup.
struct NodeParams {
  std::string scene;              // scene file path, or a name resolved as <scenes_dir>/<name>.urdf; "" -> robot_description
  std::string scenes_dir;         // where scene names are looked up
  double time_step = 0.01;        // s, (0, 1]
  double tolerance = 1e-12;       // Newton tolerance on the scaled residual, (0, 0.1]
  int max_iterations = 100;       // [1, 100000]
  std::string solver = "newton";  // newton or ipopt
  double publish_rate = 30.0;     // Hz, (0, 1000]: /tf, ~body_states, ~contacts, ~markers
  double real_time_factor = 1.0;  // [0, 1000]; 0 = as fast as possible
  bool paused = false;
  // What a refused step (initial overlap, divergence, no finite solution) does after the state is restored: "pause"
  // the simulation, or "reset" the bodies to their initial state and run on (pausing instead if the initial state
  // itself is refused).
  std::string on_fault = "pause";
  std::string world_frame = "world";
  double force_marker_scale = 0.05;  // m/N, (0, 100]: length of a contact force arrow per newton
  double contact_marker_size = 0.05;  // m, (0, 100]: diameter of a contact point (arrows scale with it)
  // Whether /tf carries the links that hang on joints (world -> link, like every other body). Set false to leave them
  // to robot_state_publisher fed by /joint_states (it publishes parent -> child along the URDF tree).
  bool publish_joint_link_tf = true;
  // Reads and validates; throws std::invalid_argument naming the parameter and its range.
  static NodeParams Read(const ros::NodeHandle& pnh);
};

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

  double SimTime() const { return time_offset_ + state_.t; }
  void StepLocked();                 // one step with the active wrenches; mutex held
  void ResetLocked();                // bodies back to the initial state, warm start and wrenches cleared; mutex held
  void ComputeWrenchesLocked();      // fills wrench_W_ for the step starting now
  void PhysicsLoop();
  void PublishLoop();
  void PublishClock(double sim_time);
  void PublishStepStats(const StepReport& report, double sim_time, uint64_t step, double rtf);
  void UpdateDiagnostics(diagnostic_updater::DiagnosticStatusWrapper& status);
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
  // Joints (sim_node_joints.cpp): ~joint_effort_cmd, ~set_joint_efforts and /joint_states.
  bool SetJointEffortsLocked(const std::vector<std::string>& names, const std::vector<double>& efforts,
                             std::string* error);  // all or nothing
  void OnJointEffortCommand(const sensor_msgs::JointState::ConstPtr& msg);
  bool OnSetJointEfforts(implicit_sim::SetJointEfforts::Request& req, implicit_sim::SetJointEfforts::Response& res);
  void PublishJointStates(const State& snapshot, const Eigen::VectorXd& efforts, const ros::Time& stamp);

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
  bool paused_ = false, shutdown_ = false, restart_pacing_ = true;
  uint64_t step_count_ = 0;
  StepReport last_report_;
  std::vector<TimedWrench> wrenches_;
  Eigen::VectorXd commanded_W_;   // ~wrench_cmd, per moving slot: force, torque at the link origin (world)
  Eigen::VectorXd wrench_W_;      // the wrench vector handed to the core (at the centre of mass)
  Eigen::VectorXd joint_efforts_;  // per model joint: the commanded effort (N m or N; fixed joints 0)
  long received_joint_commands_ = 0, dropped_joint_commands_ = 0;
  long diag_steps_ = 0, diag_nonconverged_ = 0, diag_failed_ = 0, dropped_commands_ = 0, received_commands_ = 0;
  long faults_[5] = {0, 0, 0, 0, 0};  // refused or non-converged steps since startup, by StepFault
  bool at_initial_state_ = true;      // no step taken since startup or the last reset
  double rtf_ = 0.0;
  std::string last_failure_;

  std::mutex clock_mutex_;
  double last_clock_ = -1.0;

  ros::Publisher clock_pub_, contacts_pub_, markers_pub_, stats_pub_, body_states_pub_, joint_states_pub_;
  std::vector<ros::ServiceServer> services_;
  ros::Subscriber wrench_sub_, joint_effort_sub_;
  tf2_ros::TransformBroadcaster tf_broadcaster_;
  tf2_ros::StaticTransformBroadcaster static_broadcaster_;
  diagnostic_updater::Updater diagnostics_;
  std::thread physics_thread_, publish_thread_;
};

}  // namespace implicit_sim
