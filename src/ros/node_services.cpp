// The node's services and command topics: pause, unpause, reset, body state, wrenches (~apply_body_wrench,
// ~wrench_cmd, ~clear_body_wrenches) and joint efforts (~set_joint_efforts, ~joint_effort_cmd; they enter the step
// as the wrench of AddJointEffortWrench, core joints.h). Each runs on the physics thread between two steps
// (RunBetweenSteps; the command topics PostBetweenSteps without waiting); ~get_body_state reads the latest snapshot.
#include "implicit_sim/ros/sim_node.h"  // first: its generated service type Step precedes the core's function Step

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "implicit_sim/core/base/format.h"
#include "implicit_sim/ros/conversions.h"

namespace implicit_sim {
namespace conv = ros_conversions;
namespace {

// Sets *error when a commanded force (N) or torque (N m) is non-finite or larger than kMaxCommand.
bool CheckWrenchValues(const Vec3& force, const Vec3& torque, std::string* error) {
  if (!force.allFinite() || !torque.allFinite()) {
    *error = "wrench must be finite";
  } else if (force.norm() > kMaxCommand || torque.norm() > kMaxCommand) {
    *error = "wrench too large: |force| and |torque| must be <= 1e9 (N, N m)";
  } else {
    return true;
  }
  return false;
}

}  // namespace

const SimNode::CommandInput<implicit_sim::BodyWrench> SimNode::kWrenchInput{
    "~wrench_cmd", JournalInput::kWrenchCommand, CommandTopic::kWrench, &SimNode::ApplyWrenchCommand};
const SimNode::CommandInput<sensor_msgs::JointState> SimNode::kJointEffortInput{
    "~joint_effort_cmd", JournalInput::kJointEffortCommand, CommandTopic::kJointEffort, &SimNode::ApplyJointEfforts};
const SimNode::CommandInput<implicit_sim::JointCommand> SimNode::kJointCommandInput{
    "~joint_command", JournalInput::kJointCommand, CommandTopic::kJointDrive, &SimNode::ApplyJointCommand};
const SimNode::CommandInput<trajectory_msgs::JointTrajectory> SimNode::kJointTrajectoryInput{
    "~joint_trajectory", JournalInput::kJointTrajectory, CommandTopic::kJointDrive, &SimNode::StartTrajectory};

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
  joint_effort_sub_ = SubscribeCommand("joint_effort_cmd", 100, kJointEffortInput);
  joint_command_sub_ = SubscribeCommand("joint_command", 100, kJointCommandInput);
  joint_trajectory_sub_ = SubscribeCommand("joint_trajectory", 10, kJointTrajectoryInput);
  run_steps_server_ = std::make_unique<actionlib::SimpleActionServer<implicit_sim::RunStepsAction>>(
      pnh_, "run_steps", [this](const implicit_sim::RunStepsGoalConstPtr& goal) { OnRunStepsGoal(goal); }, false);
}

int SimNode::FindBodyOrFail(const std::string& name, bool must_move, std::string* error) const {
  const Model& model = *world_->model;
  const int b = model.FindBody(name);
  if (b < 0) {
    *error = "unknown body '" + name + "'";
  } else if (must_move && model.bodies[b].is_fixed) {
    *error = "body '" + name + "' is fixed";
    return -1;
  }
  return b;
}

bool SimNode::OnPause(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
  return RunBetweenSteps([&] {
           paused_ = true;
           diagnostics_->SetPaused(true);
           res.success = true;
           res.message = "paused at t = " + FormatNumber(SimTime()) + " s";
         }) || ShuttingDownAnswer(res);
}

bool SimNode::OnUnpause(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
  return RunBetweenSteps([&] {
           std::lock_guard<std::mutex> lock(mailbox_mutex_);
           if (job_.active) {
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
  return RunBetweenSteps([&] {
           ResetWorld();
           JournalUnreplayable("~reset");
           diagnostics_->ClearFault();
           res.success = true;
           res.message = "bodies back to their initial state at t = " + FormatNumber(SimTime()) + " s";
         }) || ShuttingDownAnswer(res);
}

bool SimNode::OnClearWrenches(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
  return RunBetweenSteps([&] {
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
  return RunBetweenSteps([&] {
           std::string error;
           const int b = FindBodyOrFail(req.state.name, true, &error);
           res.success =
               b >= 0 && conv::SetBodyStateFromMsg(*world_->model, b, req.state, &world_->state, &error);
           if (res.success) {
             JournalUnreplayable("~set_body_state");
             ClearWarmStart(world_->data.get());  // the next step starts cold from the new configuration
             SaveSnapshot();
           }
           res.message = res.success ? "set '" + req.state.name + "'" : error;
         }) || ShuttingDownAnswer(res);
}

bool SimNode::OnApplyWrench(implicit_sim::ApplyBodyWrench::Request& req,
                            implicit_sim::ApplyBodyWrench::Response& res) {
  return RunBetweenSteps([&] {
           std::string error;
           res.success = false;
           const int b = FindBodyOrFail(req.body, true, &error);
           int frame_body = -1;
           if (!req.reference_frame.empty() && req.reference_frame != params_.world_frame) {
             frame_body = world_->model->FindBody(req.reference_frame);
             if (frame_body < 0) error = "unknown reference_frame '" + req.reference_frame + "'";
           }
           TimedWrench w{b, frame_body, conv::ToVec3(req.reference_point), conv::ToVec3(req.wrench.force),
                         conv::ToVec3(req.wrench.torque), std::max(req.start_time, SimTime()), -1.0};
           if (error.empty() &&
               (!w.point.allFinite() || !std::isfinite(req.start_time) || !std::isfinite(req.duration))) {
             error = "reference_point, start_time and duration must be finite";
           }
           if (error.empty()) CheckWrenchValues(w.force, w.torque, &error);  // sets error when refused
           if (error.empty() && req.duration == 0.0) error = "duration must be > 0 s, or < 0 for until cleared";
           if (!error.empty()) {
             res.message = error;
             return;
           }
           if (req.duration > 0.0) w.end = w.start + req.duration;
           world_->wrenches.push_back(w);
           JournalUnreplayable("~apply_body_wrench");
           res.success = true;
           res.message = "wrench on '" + req.body + "' from t = " + FormatNumber(w.start) + " s";
         }) || ShuttingDownAnswer(res);
}

bool SimNode::ApplyWrenchCommand(const implicit_sim::BodyWrench& msg, std::string* error) {
  const Vec3 f = conv::ToVec3(msg.wrench.force), tau = conv::ToVec3(msg.wrench.torque);
  const int b = FindBodyOrFail(msg.body, true, error);
  if (b < 0 || !CheckWrenchValues(f, tau, error)) return false;
  const int v = Model::v_offset(world_->model->velocity_slot[b]);
  world_->commanded_W.segment<3>(v) = f;
  world_->commanded_W.segment<3>(v + 3) = tau;
  return true;
}

bool SimNode::SetJointEfforts(const std::vector<std::string>& names, const std::vector<double>& efforts,
                              std::string* error) {
  const Model& model = *world_->model;
  if (names.size() != efforts.size()) {
    *error = "name and effort must have the same length (" + std::to_string(names.size()) + " names, " +
             std::to_string(efforts.size()) + " efforts)";
    return false;
  }
  std::vector<int> joints(names.size());
  for (size_t i = 0; i < names.size(); ++i) {
    joints[i] = model.FindJoint(names[i]);
    if (joints[i] < 0 || !model.joints[joints[i]].has_coordinate()) {
      *error = "no revolute, continuous or prismatic joint '" + names[i] + "' in the scene";
      return false;
    }
    if (!std::isfinite(efforts[i]) || std::abs(efforts[i]) > kMaxCommand) {
      *error = "effort of joint '" + names[i] + "' = " + FormatNumber(efforts[i]) +
               " must be finite with |effort| <= 1e9 (N m or N)";
      return false;
    }
  }
  for (size_t i = 0; i < names.size(); ++i) world_->joint_efforts[joints[i]] = efforts[i];
  SaveSnapshot();  // /joint_states shows the new efforts
  return true;
}

bool SimNode::ApplyJointEfforts(const sensor_msgs::JointState& msg, std::string* error) {
  return SetJointEfforts(msg.name, msg.effort, error);
}

bool SimNode::OnSetJointEfforts(implicit_sim::SetJointEfforts::Request& req,
                                implicit_sim::SetJointEfforts::Response& res) {
  return RunBetweenSteps([&] {
           std::string error;
           res.success = SetJointEfforts(req.name, req.effort, &error);
           if (res.success) JournalUnreplayable("~set_joint_efforts");
           res.message = res.success ? "set the effort of " + std::to_string(req.name.size()) + " joints" : error;
         }) || ShuttingDownAnswer(res);
}

}  // namespace implicit_sim
