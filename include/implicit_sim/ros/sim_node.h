// The ROS node over the core: publishes /clock, /tf, /tf_static, ~contacts, ~markers, ~step_stats, ~body_states,
// /joint_states and /diagnostics, and serves a gazebo_ros-like control API. doc/ros_node.md documents the contract.
//
// Threads. The physics thread alone owns the world (model, state, data, commands) and steps it. Everything else talks
// to it through a mailbox: a service posts a command and waits for the physics thread to run it between two steps
// (so it answers within one step, never after a whole ~step job), a command topic posts without waiting, and the
// publish and diagnostics threads read only the snapshot the physics thread saves after every change. No lock is
// ever held across a step. Parts with locks of their own: NodePublisher (node_publisher.h: the topics, from
// snapshots) and NodeDiagnostics (node_diagnostics.h: the counters of /diagnostics). By concern: sim_node.cpp
// (threads, mailbox, stepping), node_jobs.cpp (the ~step service and the ~run_steps action), node_services.cpp
// (services, and the command topics' one path: SubscribeCommand, ApplyCommand), node_world.cpp, node_drives.cpp,
// node_drag.cpp, node_reconfigure.cpp, node_journal.cpp.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <functional>
#include <set>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <actionlib/server/simple_action_server.h>
#include <dynamic_reconfigure/server.h>
#include <Eigen/Core>
#include <interactive_markers/interactive_marker_server.h>
#include <ros/ros.h>
#include <sensor_msgs/JointState.h>
#include <std_srvs/Trigger.h>
#include <trajectory_msgs/JointTrajectory.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <visualization_msgs/MarkerArray.h>

#include "implicit_sim/ApplyBodyWrench.h"
#include "implicit_sim/Delete.h"
#include "implicit_sim/LoadScene.h"
#include "implicit_sim/Spawn.h"
#include "implicit_sim/BodyWrench.h"
#include "implicit_sim/Contacts.h"
#include "implicit_sim/GetBodyState.h"
#include "implicit_sim/JointCommand.h"
#include "implicit_sim/RunStepsAction.h"
#include "implicit_sim/SetBodyState.h"
#include "implicit_sim/SetJointEfforts.h"
#include "implicit_sim/SimNodeConfig.h"
#include "implicit_sim/Step.h"
#include "implicit_sim/core/model/model.h"
#include "implicit_sim/core/model/urdf_loader.h"
#include "implicit_sim/core/step/time_stepper.h"
#include "implicit_sim/ros/input_journal.h"
#include "implicit_sim/ros/node_diagnostics.h"
#include "implicit_sim/ros/node_publisher.h"
#include "implicit_sim/ros/world.h"
#include "implicit_sim/ros/node_params.h"

namespace implicit_sim {

// The largest command the node accepts: |force| (N), |torque| (N m) and |joint effort| (N m or N). Larger commands
// are refused; they only drive a step into divergence.
constexpr double kMaxCommand = 1e9;

// A service's answer when the node stops before the physics thread ran the request.
template <typename Response>
bool ShuttingDownAnswer(Response& res) {
  res.success = false;
  res.message = "refused: the node is shutting down";
  return true;
}

class SimNode {
 public:
  // Loads the scene and sets up publishers and services; throws std::invalid_argument for a bad parameter or scene.
  SimNode(ros::NodeHandle nh, ros::NodeHandle pnh);
  ~SimNode();
  // Starts the physics, publishing and diagnostics threads and blocks until ROS shuts down.
  void Run();

 private:
  // A ~step or ~run_steps request: steps run by the physics thread while paused. Guarded by mailbox_mutex_.
  struct StepJob {
    bool active = false, cancel = false, finished = false, success = false;
    uint64_t requested = 0, done = 0;
    double sim_time = 0.0;  // s, after the last step done
    std::string message;
  };
  // A command topic: its name (for warnings), its journal kind, its /diagnostics counter and what applies a message
  // on the physics thread (false with *error when the message is refused). One each, defined in node_services.cpp.
  template <typename Message>
  struct CommandInput {
    const char* topic;
    JournalInput journal;
    CommandTopic counter;
    bool (SimNode::*apply)(const Message& msg, std::string* error);
  };
  static const CommandInput<implicit_sim::BodyWrench> kWrenchInput;
  static const CommandInput<sensor_msgs::JointState> kJointEffortInput;
  static const CommandInput<implicit_sim::JointCommand> kJointCommandInput;
  static const CommandInput<trajectory_msgs::JointTrajectory> kJointTrajectoryInput;
  struct Command {
    std::function<void()> run;
    bool done = false;
  };

  // node_world.cpp: the open world (its worlds are read, built and edited by world.h).
  void ReplaceWorld(std::unique_ptr<World> next);       // physics thread
  void PublishRobotDescription(const std::string& urdf) const;
  bool OnSpawn(implicit_sim::Spawn::Request& req, implicit_sim::Spawn::Response& res);
  bool OnDelete(implicit_sim::Delete::Request& req, implicit_sim::Delete::Response& res);
  bool OnLoadScene(implicit_sim::LoadScene::Request& req, implicit_sim::LoadScene::Response& res);
  // sim_node.cpp: the mailbox and the physics thread.
  // Runs fn on the physics thread between two steps and waits for it; false (fn not run) when the node is stopping.
  bool RunBetweenSteps(std::function<void()> fn);
  // Queues fn for the physics thread without waiting (command topics).
  void PostBetweenSteps(std::function<void()> fn);
  double SimTime() const { return time_offset_ + world_->state.t; }
  void PhysicsLoop();
  void RunCommands();
  bool JobRunnableLocked() const { return job_.active && !job_.cancel; }
  void StepOnce(double rtf);             // one step with the active wrenches
  void ResetWorld();                     // bodies back to the initial state, warm start and wrenches cleared
  void ComputeWrenches();                // fills wrench_W for the step starting now
  void SaveSnapshot();                   // the current state as the latest snapshot (NodePublisher::Store)
  void PublishLoop();
  void DiagnosticsLoop();
  // Sets stopping_, wakes every thread and joins them once all have ended within grace_s (s); false,
  // nothing joined, when one is still inside a step by then.
  bool StopThreads(double grace_s);
  void StartThread(std::thread* thread, void (SimNode::*loop)());
  // node_jobs.cpp: ~step and ~run_steps.
  bool StartJob(uint64_t steps, uint64_t max_steps, std::string* refusal);  // on the physics thread
  void RunJobStep();                                                        // on the physics thread
  void FinishJobLocked(bool success, const std::string& message);
  bool OnStep(implicit_sim::Step::Request& req, implicit_sim::Step::Response& res);
  void OnRunStepsGoal(const implicit_sim::RunStepsGoalConstPtr& goal);
  // node_reconfigure.cpp: live tuning.
  LiveParams Live() const;
  void SetUpReconfigure();
  void OnReconfigure(SimNodeConfig& next);
  // node_drives.cpp: joint drives.
  bool ApplyJointCommand(const implicit_sim::JointCommand& msg, std::string* error);          // physics thread
  bool StartTrajectory(const trajectory_msgs::JointTrajectory& msg, std::string* error);      // physics thread
  void StopTrajectoryOf(int joint);
  void UpdateTrajectoryDrives();  // the trajectories' targets for the step starting now
  // node_drag.cpp: interactive markers that push bodies.
  void SetUpDragMarkers(const Model& model, const State& state);
  void OnDrag(const visualization_msgs::InteractiveMarkerFeedbackConstPtr& feedback);
  void AddDragWrenches();  // physics thread, into wrench_W
  void UpdateDragMarkers(const NodeSnapshot& snapshot);  // publish thread
  // node_services.cpp: services and command topics (run on the physics thread through the mailbox).
  void AdvertiseServices();
  int FindBodyOrFail(const std::string& name, bool must_move, std::string* error) const;
  bool OnPause(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res);
  bool OnUnpause(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res);
  bool OnReset(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res);
  bool OnClearWrenches(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res);
  bool OnGetBodyState(implicit_sim::GetBodyState::Request& req, implicit_sim::GetBodyState::Response& res);
  bool OnSetBodyState(implicit_sim::SetBodyState::Request& req, implicit_sim::SetBodyState::Response& res);
  bool OnApplyWrench(implicit_sim::ApplyBodyWrench::Request& req, implicit_sim::ApplyBodyWrench::Response& res);
  bool ApplyWrenchCommand(const implicit_sim::BodyWrench& msg, std::string* error);  // physics thread
  bool ApplyJointEfforts(const sensor_msgs::JointState& msg, std::string* error);    // physics thread
  // Subscribes to a command topic: each message is posted to the physics thread, journaled and applied (ApplyCommand).
  template <typename Message>
  ros::Subscriber SubscribeCommand(const std::string& name, uint32_t queue, const CommandInput<Message>& input) {
    return pnh_.subscribe<Message>(
        name, queue, boost::function<void(const typename Message::ConstPtr&)>([this, &input](const auto& msg) {
          PostBetweenSteps([this, &input, msg] {
            Journal(input.journal, *msg);
            ApplyCommand(*msg, input);
          });
        }));
  }
  // A command topic's message on the physics thread (received or replayed): applied and counted in /diagnostics.
  template <typename Message>
  void ApplyCommand(const Message& msg, const CommandInput<Message>& input) {
    std::string error;
    const bool accepted = (this->*input.apply)(msg, &error);
    diagnostics_->CountCommand(input.counter, input.topic, accepted, error);
  }
  // The input journal (physics thread): record a command topic's message, or mark an input it cannot replay.
  template <typename Message>
  void Journal(JournalInput kind, const Message& msg) {
    if (journal_) journal_->Write(step_count_, kind, msg);
  }
  void JournalUnreplayable(const char* input) {
    if (journal_) journal_->WriteUnreplayable(step_count_, input);
  }
  void OpenJournals();  // node_journal.cpp; throws std::invalid_argument for a file it cannot create or read
  // Applies the replayed journal's inputs for the step about to start; false (with the reason) at an input it cannot
  // replay.
  bool ReplayJournalInputs(std::string* refusal);
  bool ApplyJournalRecord(const JournalRecord& record, std::string* refusal);
  void RefuseReplayStep(const std::string& refusal);
  void WaitForPace(std::chrono::steady_clock::time_point until);  // physics thread, between paced steps
  bool SetJointEfforts(const std::vector<std::string>& names, const std::vector<double>& efforts,
                       std::string* error);  // all or nothing; physics thread
  bool OnSetJointEfforts(implicit_sim::SetJointEfforts::Request& req, implicit_sim::SetJointEfforts::Response& res);

  ros::NodeHandle nh_, pnh_;
  NodeParams params_;
  StepperOptions options_;  // physics thread

  // Owned by the physics thread (and the constructor, before it starts).
  std::unique_ptr<World> world_;
  double time_offset_ = 0.0;      // simulation time = time_offset_ + state.t (reset keeps time monotonic)
  bool paused_ = false, restart_pacing_ = true;
  uint64_t step_count_ = 0;
  std::unique_ptr<InputJournalWriter> journal_;  // ~input_journal
  std::unique_ptr<InputJournalReader> replay_;   // ~replay_journal
  uint64_t snapshot_version_ = 0;
  bool stepped_ = false;          // a step has run since startup or the last reset
  double rtf_ = 0.0;

  // The mailbox: commands for the physics thread, and the step job.
  std::mutex mailbox_mutex_;
  std::condition_variable mailbox_cv_;  // wakes the physics thread and the waiters of commands and jobs
  std::vector<std::shared_ptr<Command>> commands_;
  StepJob job_;

  // The live parameters and the solver options they change (tolerance, max_iterations), set by dynamic_reconfigure;
  // the physics thread copies live_options_ into options_ before each step.
  mutable std::mutex live_mutex_;
  LiveParams live_;
  StepperOptions live_options_;
  boost::recursive_mutex reconfigure_mutex_;
  std::unique_ptr<dynamic_reconfigure::Server<SimNodeConfig>> reconfigure_;

  std::unique_ptr<NodeDiagnostics> diagnostics_;  // /diagnostics: its own lock, read by the diagnostics thread

  std::unique_ptr<interactive_markers::InteractiveMarkerServer> drag_server_;
  std::mutex drag_mutex_;
  std::set<std::string> dragged_;  // bodies being dragged (their marker is the user's); guarded by drag_mutex_

  double next_drag_update_ = 0.0;  // publish thread: s of wall time, the next pose update of the interactive markers
  uint64_t drag_version_ = 0;      // publish thread: the snapshot version the interactive markers show

  std::unique_ptr<NodePublisher> publisher_;  // the topics, from snapshots; its own locks

  // Every thread ends: the physics thread after the step in progress, the others at once.
  std::atomic<bool> stopping_{false};
  std::mutex stop_mutex_;
  std::condition_variable stop_cv_;    // wakes the publish and diagnostics threads' waits, and StopThreads
  int threads_started_ = 0, threads_ended_ = 0;  // guarded by stop_mutex_

  std::vector<ros::ServiceServer> services_;
  ros::Subscriber wrench_sub_, joint_effort_sub_, joint_command_sub_, joint_trajectory_sub_;
  std::unique_ptr<actionlib::SimpleActionServer<implicit_sim::RunStepsAction>> run_steps_server_;
  std::thread physics_thread_, publish_thread_, diagnostics_thread_;
};

}  // namespace implicit_sim
