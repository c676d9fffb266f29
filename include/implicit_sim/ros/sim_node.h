// The ROS node over the core: publishes /clock, /tf, /tf_static, ~contacts, ~markers, ~step_stats, ~body_states,
// /joint_states and /diagnostics, and serves a gazebo_ros-like control API. doc/ros_node.md documents the contract.
//
// Threads. The physics thread alone owns the world and steps it; every other thread reaches it through the
// PhysicsMailbox (physics_mailbox.h): a service posts a command and waits for the physics thread to run it between
// two steps (so it answers within one step, never after a whole ~step job), a command topic posts without waiting.
// The parts other threads read have locks of their own and never wait for a step: NodePublisher (the topics, from
// the snapshots the physics thread saves), NodeDiagnostics, LiveTuning (dynamic_reconfigure) and DragMarkers. What
// the commands do to the world is in world_commands.h, how worlds are read and built in world.h. By concern:
// sim_node.cpp (threads, stepping), node_jobs.cpp (~step, ~run_steps), node_services.cpp (services, the command
// topics' one path and the journal's replay), node_world.cpp (~spawn, ~delete, ~load_scene, ~set_joint_positions).
#pragma once

#include <atomic>
#include <condition_variable>
#include <memory>
#include <chrono>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <actionlib/server/simple_action_server.h>
#include <ros/ros.h>
#include <sensor_msgs/JointState.h>
#include <std_srvs/Trigger.h>
#include <trajectory_msgs/JointTrajectory.h>

#include "implicit_sim/core/base/interrupt.h"
#include "implicit_sim/ApplyBodyWrench.h"
#include "implicit_sim/BodyWrench.h"
#include "implicit_sim/Delete.h"
#include "implicit_sim/FollowTrajectoryAction.h"
#include "implicit_sim/GetBodyState.h"
#include "implicit_sim/JointCommand.h"
#include "implicit_sim/LoadScene.h"
#include "implicit_sim/RunStepsAction.h"
#include "implicit_sim/SetBodyState.h"
#include "implicit_sim/SetJointEfforts.h"
#include "implicit_sim/SetJointPositions.h"
#include "implicit_sim/Spawn.h"
#include "implicit_sim/Step.h"
#include "implicit_sim/core/step/options.h"
#include "implicit_sim/ros/drag_markers.h"
#include "implicit_sim/ros/live_tuning.h"
#include "implicit_sim/ros/node_diagnostics.h"
#include "implicit_sim/ros/node_journal.h"
#include "implicit_sim/ros/node_params.h"
#include "implicit_sim/ros/node_publisher.h"
#include "implicit_sim/ros/node_sensors.h"
#include "implicit_sim/ros/master_watch.h"
#include "implicit_sim/ros/physics_mailbox.h"
#include "implicit_sim/ros/world.h"
#include "implicit_sim/ros/world_commands.h"

namespace implicit_sim {

// A service's answer when the node stops before the physics thread ran the request.
template <typename Response>
bool ShuttingDownAnswer(Response& res) {
  res.success = false;
  res.message = "refused: the node is shutting down";
  return true;
}

class SimNode {
 public:
  // Loads the scene and sets up publishers and services; throws std::invalid_argument for a bad parameter or scene,
  // LoadInterrupted when `stop` (main's SIGINT and SIGTERM; null: the node's own) was requested during the load.
  // Every later load (~load_scene, ~spawn, ~delete) watches it too, and shutdown requests it.
  SimNode(ros::NodeHandle nh, ros::NodeHandle pnh, StepInterrupt* stop = nullptr);
  ~SimNode();
  // Starts the physics, publishing and diagnostics threads and blocks until ROS shuts down.
  void Run();
  // Whether the node shut down because it lost the ROS master (~on_master_loss: exit).
  bool exited_on_master_loss() const { return master_watch_ && master_watch_->exit_requested(); }

 private:
  // A command topic: its name (for warnings), its journal kind, its /diagnostics counter, what applies a message to
  // the world (false with *error when it is refused) and whether the change shows in the snapshot (/joint_states).
  // One each, defined in node_services.cpp.
  template <typename Message>
  struct CommandInput {
    const char* topic;
    JournalInput journal;
    CommandTopic counter;
    bool (*apply)(const CommandContext& context, const Message& msg, World* world, std::string* error);
    bool save_snapshot;
  };
  static const CommandInput<implicit_sim::BodyWrench> kWrenchInput;
  static const CommandInput<sensor_msgs::JointState> kJointEffortInput;
  static const CommandInput<implicit_sim::JointCommand> kJointCommandInput;
  static const CommandInput<trajectory_msgs::JointTrajectory> kJointTrajectoryInput;

  // sim_node.cpp: the threads and the step (physics thread).
  double SimTime() const { return time_offset_ + world_->state.t; }
  CommandContext Context() const;
  void PhysicsLoop();
  // One step with the commanded wrenches; false if it was interrupted (interrupt_: a cancelled job, shutdown) and so
  // not taken. rtf: the real-time factor of the last second; paced: the step keeps ~real_time_factor's pace (false for
  // a job's step, which runs as fast as it can).
  bool StepOnce(double rtf, bool paced);
  void ResetWorld();          // bodies back to the initial state, warm start and commands cleared
  void SaveSnapshot();        // the current state as the latest snapshot (NodePublisher::Store)
  void RefuseReplayStep(const std::string& refusal);
  void OnDragFeedback(const DragMarkers::Feedback& feedback);  // posts the drag to the physics thread
  void PublishLoop();
  void DiagnosticsLoop();
  // Stops the mailbox, wakes every thread and joins them once all have ended within grace_s (s); false, nothing
  // joined, when one is still inside a step by then.
  bool StopThreads(double grace_s);
  void StartThread(std::thread* thread, void (SimNode::*loop)());
  // node_world.cpp: the open world (its worlds are read, built and edited by world.h).
  void ReplaceWorld(std::unique_ptr<World> next);  // physics thread
  void PublishRobotDescription(const std::string& urdf) const;
  bool OnSpawn(implicit_sim::Spawn::Request& req, implicit_sim::Spawn::Response& res);
  bool OnDelete(implicit_sim::Delete::Request& req, implicit_sim::Delete::Response& res);
  bool OnLoadScene(implicit_sim::LoadScene::Request& req, implicit_sim::LoadScene::Response& res);
  bool OnSetJointPositions(implicit_sim::SetJointPositions::Request& req,
                           implicit_sim::SetJointPositions::Response& res);
  // node_jobs.cpp: ~step and ~run_steps.
  bool StartJob(uint64_t steps, uint64_t max_steps, std::string* refusal);  // physics thread
  bool OnStep(implicit_sim::Step::Request& req, implicit_sim::Step::Response& res);
  void OnRunStepsGoal(const implicit_sim::RunStepsGoalConstPtr& goal);
  // node_follow_trajectory.cpp: ~follow_trajectory.
  void OnFollowTrajectoryGoal(const implicit_sim::FollowTrajectoryGoalConstPtr& goal);
  // node_services.cpp: services and command topics (applied on the physics thread through the mailbox).
  void AdvertiseServices();
  bool OnPause(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res);
  bool OnUnpause(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res);
  bool OnReset(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res);
  bool OnClearWrenches(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res);
  bool OnGetBodyState(implicit_sim::GetBodyState::Request& req, implicit_sim::GetBodyState::Response& res);
  bool OnSetBodyState(implicit_sim::SetBodyState::Request& req, implicit_sim::SetBodyState::Response& res);
  bool OnApplyWrench(implicit_sim::ApplyBodyWrench::Request& req, implicit_sim::ApplyBodyWrench::Response& res);
  bool OnSetJointEfforts(implicit_sim::SetJointEfforts::Request& req, implicit_sim::SetJointEfforts::Response& res);
  // Subscribes to a command topic: each message is posted to the physics thread, journaled and applied.
  template <typename Message>
  ros::Subscriber SubscribeCommand(const std::string& name, uint32_t queue, const CommandInput<Message>& input);
  // A command topic's message on the physics thread (received or replayed): applied and counted in /diagnostics.
  template <typename Message>
  void ApplyCommand(const Message& msg, const CommandInput<Message>& input);
  bool ApplyJournalRecord(const JournalRecord& record, std::string* refusal);  // a replayed input
  void JournalUnreplayable(const char* input) { journal_->RecordUnreplayable(step_count_, input); }

  ros::NodeHandle nh_, pnh_;
  const NodeParams params_;

  // Owned by the physics thread (and the constructor, before it starts); other threads go through mailbox_.
  StepperOptions options_;
  std::unique_ptr<World> world_;
  double time_offset_ = 0.0;  // simulation time = time_offset_ + state.t (reset keeps time monotonic)
  bool paused_ = false, restart_pacing_ = true;
  uint64_t step_count_ = 0;
  std::unique_ptr<NodeJournal> journal_;  // ~input_journal, ~replay_journal
  uint64_t snapshot_version_ = 0;
  bool stepped_ = false;  // a step has run since startup or the last reset
  double rtf_ = 0.0;

  PhysicsMailbox mailbox_;
  // Parts with locks of their own.
  std::unique_ptr<LiveTuning> live_;
  std::unique_ptr<NodeDiagnostics> diagnostics_;
  std::unique_ptr<DragMarkers> drag_markers_;
  std::unique_ptr<NodePublisher> publisher_;
  std::unique_ptr<NodeSensors> sensors_;  // the physics thread's
  State state_before_;                    // the state at the start of the step in progress (the IMUs' differences)

  // Every thread ends: the physics thread after the step in progress, the others at once.
  std::atomic<bool> stopping_{false};
  // Stops the step in progress (Data::interrupt) when a ~run_steps job is cancelled, at shutdown, and when a service's
  // command has waited kCutStepAfter for it (CutStepForCommand).
  StepInterrupt interrupt_;
  StepInterrupt own_stop_;
  StepInterrupt* stop_;  // main's or own_stop_: requested by SIGINT, SIGTERM and StopThreads; loads watch it
  // A service's command that has waited this long cuts the step in progress: the step is undone, the command runs and
  // the step is redone from its start state, so results are as if the command had come before it. A redone step is
  // not cut again (the simulation always advances); shutdown and a cancelled job still stop it.
  static constexpr std::chrono::milliseconds kCutStepAfter{50};
  void CutStepForCommand();  // any thread
  std::mutex cut_mutex_;
  bool step_running_ = false, step_cuttable_ = false, step_cut_ = false;  // guarded by cut_mutex_
  bool redoing_cut_step_ = false;  // the physics thread's: the next step redoes a cut one
  std::mutex stop_mutex_;
  std::condition_variable stop_cv_;  // wakes the publish and diagnostics threads' waits, and StopThreads
  int threads_started_ = 0, threads_ended_ = 0;  // guarded by stop_mutex_

  std::vector<ros::ServiceServer> services_;
  std::unique_ptr<MasterWatch> master_watch_;  // checked by the diagnostics thread
  ros::Subscriber wrench_sub_, joint_effort_sub_, joint_command_sub_, joint_trajectory_sub_;
  std::unique_ptr<actionlib::SimpleActionServer<implicit_sim::RunStepsAction>> run_steps_server_;
  std::unique_ptr<actionlib::SimpleActionServer<implicit_sim::FollowTrajectoryAction>> follow_trajectory_server_;
  std::thread physics_thread_, publish_thread_, diagnostics_thread_;
};

}  // namespace implicit_sim
