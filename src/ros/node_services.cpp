// The node's services and command topics: pause, unpause, reset, body state, wrenches (~apply_body_wrench,
// ~wrench_cmd, ~clear_body_wrenches), joint efforts (~set_joint_efforts, ~joint_effort_cmd) and drives
// (~joint_command, ~joint_trajectory); what each does to the world is in world_commands.h. Each runs on the physics
// thread between two steps (the command topics without waiting); ~get_body_state reads the latest snapshot. The
// command topics' messages take one path, received or replayed from a journal: journaled, applied, counted.
#include "implicit_sim/ros/sim_node.h"

#include "implicit_sim/core/step/step_health.h"  // first: its generated service type Step precedes the core's function Step

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "implicit_sim/core/base/format.h"
#include "implicit_sim/ros/conversions.h"

namespace implicit_sim {
namespace conv = ros_conversions;
const SimNode::CommandInput<implicit_sim::BodyWrench> SimNode::kWrenchInput{
    "~wrench_cmd", JournalInput::kWrenchCommand, CommandTopic::kWrench, &SetWrenchCommand, false};
const SimNode::CommandInput<sensor_msgs::JointState> SimNode::kJointEffortInput{
    "~joint_effort_cmd", JournalInput::kJointEffortCommand, CommandTopic::kJointEffort, &SetJointEffortCommand, true};
const SimNode::CommandInput<implicit_sim::JointCommand> SimNode::kJointCommandInput{
    "~joint_command", JournalInput::kJointCommand, CommandTopic::kJointDrive, &SetJointDrives, true};
const SimNode::CommandInput<trajectory_msgs::JointTrajectory> SimNode::kJointTrajectoryInput{
    "~joint_trajectory", JournalInput::kJointTrajectory, CommandTopic::kJointDrive, &StartTrajectory, false};

template <typename Message>
ros::Subscriber SimNode::SubscribeCommand(const std::string& name, uint32_t queue, const CommandInput<Message>& input) {
  return pnh_.subscribe<Message>(
      name, queue, boost::function<void(const typename Message::ConstPtr&)>([this, &input](const auto& msg) {
        mailbox_.Post([this, &input, msg] {
          journal_->Record(step_count_, input.journal, *msg);
          ApplyCommand(*msg, input);
        });
      }));
}

template <typename Message>
void SimNode::ApplyCommand(const Message& msg, const CommandInput<Message>& input) {
  std::string error;
  const bool accepted = input.apply(Context(), msg, world_.get(), &error);
  if (accepted && input.save_snapshot) SaveSnapshot();
  diagnostics_->CountCommand(input.counter, input.topic, accepted, error);
}

bool SimNode::ApplyJournalRecord(const JournalRecord& record, std::string* refusal) {
  switch (record.kind) {
    case JournalInput::kWrenchCommand:
      ApplyCommand(record.Decode<implicit_sim::BodyWrench>(), kWrenchInput);
      return true;
    case JournalInput::kJointCommand:
      ApplyCommand(record.Decode<implicit_sim::JointCommand>(), kJointCommandInput);
      return true;
    case JournalInput::kJointEffortCommand:
      ApplyCommand(record.Decode<sensor_msgs::JointState>(), kJointEffortInput);
      return true;
    case JournalInput::kJointTrajectory:
      ApplyCommand(record.Decode<trajectory_msgs::JointTrajectory>(), kJointTrajectoryInput);
      return true;
    case JournalInput::kUnreplayable:
      break;
  }
  *refusal = "the journal's input " + record.Text() + " before step " + std::to_string(record.step) +
             " cannot be replayed";
  return false;
}

void SimNode::AdvertiseServices() {
  services_.push_back(pnh_.advertiseService("pause", &SimNode::OnPause, this));
  services_.push_back(pnh_.advertiseService("unpause", &SimNode::OnUnpause, this));
  services_.push_back(pnh_.advertiseService("reset", &SimNode::OnReset, this));
  services_.push_back(pnh_.advertiseService("clear_body_wrenches", &SimNode::OnClearWrenches, this));
  services_.push_back(pnh_.advertiseService("step", &SimNode::OnStep, this));
  services_.push_back(pnh_.advertiseService("get_body_state", &SimNode::OnGetBodyState, this));
  services_.push_back(pnh_.advertiseService("set_body_state", &SimNode::OnSetBodyState, this));
  services_.push_back(pnh_.advertiseService("apply_body_wrench", &SimNode::OnApplyWrench, this));
  wrench_sub_ = SubscribeCommand("wrench_cmd", 100, kWrenchInput);
  services_.push_back(pnh_.advertiseService("set_joint_efforts", &SimNode::OnSetJointEfforts, this));
  services_.push_back(pnh_.advertiseService("spawn", &SimNode::OnSpawn, this));
  services_.push_back(pnh_.advertiseService("delete", &SimNode::OnDelete, this));
  services_.push_back(pnh_.advertiseService("load_scene", &SimNode::OnLoadScene, this));
  services_.push_back(pnh_.advertiseService("set_joint_positions", &SimNode::OnSetJointPositions, this));
  joint_effort_sub_ = SubscribeCommand("joint_effort_cmd", 100, kJointEffortInput);
  joint_command_sub_ = SubscribeCommand("joint_command", 100, kJointCommandInput);
  joint_trajectory_sub_ = SubscribeCommand("joint_trajectory", 10, kJointTrajectoryInput);
  run_steps_server_ = std::make_unique<actionlib::SimpleActionServer<implicit_sim::RunStepsAction>>(
      pnh_, "run_steps", [this](const implicit_sim::RunStepsGoalConstPtr& goal) { OnRunStepsGoal(goal); }, false);
  follow_trajectory_server_ = std::make_unique<actionlib::SimpleActionServer<implicit_sim::FollowTrajectoryAction>>(
      pnh_, "follow_trajectory",
      [this](const implicit_sim::FollowTrajectoryGoalConstPtr& goal) { OnFollowTrajectoryGoal(goal); }, false);
}

bool SimNode::OnPause(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
  return mailbox_.RunBetweenSteps([&] {
           paused_ = true;
           diagnostics_->SetPaused(true);
           res.success = true;
           res.message = "paused at t = " + FormatNumber(SimTime()) + " s";
         }) || ShuttingDownAnswer(res);
}

bool SimNode::OnUnpause(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
  return mailbox_.RunBetweenSteps([&] {
           if (mailbox_.JobActive()) {
             res.success = false;
             res.message = "refused: a ~step or ~run_steps job is running";
             return;
           }
           paused_ = false;
           restart_pacing_ = true;
           diagnostics_->SetPaused(false);
           res.success = true;
           res.message = "running from t = " + FormatNumber(SimTime()) + " s";
         }) || ShuttingDownAnswer(res);
}

bool SimNode::OnReset(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
  return mailbox_.RunBetweenSteps([&] {
           ResetWorld();
           JournalUnreplayable("~reset");
           diagnostics_->ClearFault();
           res.success = true;
           res.message = "bodies back to their initial state at t = " + FormatNumber(SimTime()) + " s";
         }) || ShuttingDownAnswer(res);
}

bool SimNode::OnClearWrenches(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
  return mailbox_.RunBetweenSteps([&] {
           const size_t n = world_->wrenches.size();
           world_->wrenches.clear();
           world_->commanded_W.setZero();
           JournalUnreplayable("~clear_body_wrenches");
           res.success = true;
           res.message = "cleared " + std::to_string(n) + " timed wrenches and all wrench commands";
         }) || ShuttingDownAnswer(res);
}

bool SimNode::OnGetBodyState(implicit_sim::GetBodyState::Request& req, implicit_sim::GetBodyState::Response& res) {
  const std::shared_ptr<const NodeSnapshot> snapshot = publisher_->Latest();  // never waits for a step
  const Model& model = *snapshot->model;
  const int b = model.FindBody(req.body);
  res.success = b >= 0;
  res.message = b >= 0 ? "t = " + FormatNumber(snapshot->sim_time) + " s" : "unknown body '" + req.body + "'";
  if (b >= 0) res.state = conv::ToBodyStateMsg(model, snapshot->state, b);
  return true;
}

bool SimNode::OnSetBodyState(implicit_sim::SetBodyState::Request& req, implicit_sim::SetBodyState::Response& res) {
  return mailbox_.RunBetweenSteps([&] {
           std::string error;
           const Model& model = *world_->model;
           const int b = FindBodyOrFail(model, req.state.name, true, &error);
           State next = world_->state;
           res.success = b >= 0 && conv::SetBodyStateFromMsg(model, b, req.state, &next, &error);
           std::string overlap;
           Data check(model);
           if (res.success && !req.allow_overlap &&
               FindInitialOverlap(model, next, options_.overlap_tolerance, &check, &overlap)) {
             res.success = false;
             error = "refused: " + overlap + " (more than the overlap tolerance " +
                     FormatNumber(options_.overlap_tolerance) + " m; allow_overlap accepts it)";
           }
           if (res.success) {
             world_->state = next;
             JournalUnreplayable("~set_body_state");
             ClearWarmStart(world_->data.get());  // the next step starts cold from the new configuration
             SaveSnapshot();
           }
           res.message = res.success ? "set '" + req.state.name + "'" : error;
         }) || ShuttingDownAnswer(res);
}

bool SimNode::OnApplyWrench(implicit_sim::ApplyBodyWrench::Request& req,
                            implicit_sim::ApplyBodyWrench::Response& res) {
  return mailbox_.RunBetweenSteps([&] {
           std::string error;
           res.success = AddTimedWrench(Context(), req, world_.get(), &error);
           if (!res.success) {
             res.message = error;
             return;
           }
           JournalUnreplayable("~apply_body_wrench");
           res.success = true;
           res.message = "wrench on '" + req.body + "' from t = " + FormatNumber(world_->wrenches.back().start) + " s";
         }) || ShuttingDownAnswer(res);
}

bool SimNode::OnSetJointEfforts(implicit_sim::SetJointEfforts::Request& req,
                                implicit_sim::SetJointEfforts::Response& res) {
  return mailbox_.RunBetweenSteps([&] {
           std::string error;
           res.success = SetJointEfforts(req.name, req.effort, world_.get(), &error);
           if (res.success) {
             JournalUnreplayable("~set_joint_efforts");
             SaveSnapshot();  // /joint_states shows the new efforts
           }
           res.message = res.success ? "set the effort of " + std::to_string(req.name.size()) + " joints" : error;
         }) || ShuttingDownAnswer(res);
}

}  // namespace implicit_sim
