// The node's services and command topics: pause, unpause, reset, step, body state, wrenches (~apply_body_wrench,
// ~wrench_cmd, ~clear_body_wrenches) and joint efforts (~set_joint_efforts, ~joint_effort_cmd; they enter the step
// as the wrench of AddJointEffortWrench, core joints.h).
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
void CheckWrenchValues(const Vec3& force, const Vec3& torque, std::string* error) {
  if (!force.allFinite() || !torque.allFinite()) {
    *error = "wrench must be finite";
  } else if (force.norm() > kMaxCommand || torque.norm() > kMaxCommand) {
    *error = "wrench too large: |force| and |torque| must be <= 1e9 (N, N m)";
  }
}

}  // namespace

void SimNode::AdvertiseServices() {
  services_.push_back(pnh_.advertiseService("pause", &SimNode::OnPause, this));
  services_.push_back(pnh_.advertiseService("unpause", &SimNode::OnUnpause, this));
  services_.push_back(pnh_.advertiseService("reset", &SimNode::OnReset, this));
  services_.push_back(pnh_.advertiseService("clear_body_wrenches", &SimNode::OnClearWrenches, this));
  services_.push_back(pnh_.advertiseService("step", &SimNode::OnStep, this));
  services_.push_back(pnh_.advertiseService("get_body_state", &SimNode::OnGetBodyState, this));
  services_.push_back(pnh_.advertiseService("set_body_state", &SimNode::OnSetBodyState, this));
  services_.push_back(pnh_.advertiseService("apply_body_wrench", &SimNode::OnApplyWrench, this));
  wrench_sub_ = pnh_.subscribe("wrench_cmd", 100, &SimNode::OnWrenchCommand, this);
  services_.push_back(pnh_.advertiseService("set_joint_efforts", &SimNode::OnSetJointEfforts, this));
  joint_effort_sub_ = pnh_.subscribe("joint_effort_cmd", 100, &SimNode::OnJointEffortCommand, this);
}

int SimNode::FindBodyOrFail(const std::string& name, bool must_move, std::string* error) const {
  const int b = model_.FindBody(name);
  if (b < 0) {
    *error = "unknown body '" + name + "'";
  } else if (must_move && model_.bodies[b].is_fixed) {
    *error = "body '" + name + "' is fixed";
    return -1;
  }
  return b;
}

bool SimNode::OnPause(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  paused_ = true;
  res.success = true;
  res.message = "paused at t = " + FormatNumber(SimTime()) + " s";
  return true;
}

bool SimNode::OnUnpause(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    paused_ = false;
    restart_pacing_ = true;
    diag_failed_ = 0;
    last_failure_.clear();
    res.success = true;
    res.message = "running from t = " + FormatNumber(SimTime()) + " s";
  }
  wake_.notify_all();
  return true;
}

bool SimNode::OnReset(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  ResetLocked();
  last_failure_.clear();
  res.success = true;
  res.message = "bodies back to their initial state at t = " + FormatNumber(SimTime()) + " s";
  return true;
}

bool SimNode::OnClearWrenches(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  const size_t n = wrenches_.size();
  wrenches_.clear();
  commanded_W_.setZero();
  res.success = true;
  res.message = "cleared " + std::to_string(n) + " timed wrenches and all wrench commands";
  return true;
}

bool SimNode::OnStep(implicit_sim::Step::Request& req, implicit_sim::Step::Response& res) {
  StepReport report;
  uint64_t step;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    res.sim_time = SimTime();
    if (!paused_) {
      res.success = false;
      res.message = "refused: the simulation is running; call ~pause first";
      return true;
    }
    if (req.steps < 1 || req.steps > 1000000) {
      res.success = false;
      res.message = "steps must be in [1, 1000000], got " + std::to_string(req.steps);
      return true;
    }
    uint32_t done = 0;
    for (; done < req.steps && !stopping_; ++done) {
      StepLocked();
      if (!last_report_.advanced) break;
    }
    res.sim_time = SimTime();
    res.success = last_report_.advanced && done == req.steps;
    res.message = res.success ? "ran " + std::to_string(done) + " steps"
                              : "stopped after " + std::to_string(done) + " steps: " + last_failure_;
    report = last_report_;
    step = step_count_;
  }
  PublishClock(res.sim_time);
  PublishStepStats(report, res.sim_time, step, 0.0);
  return true;
}

bool SimNode::OnGetBodyState(implicit_sim::GetBodyState::Request& req, implicit_sim::GetBodyState::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  std::string error;
  const int b = FindBodyOrFail(req.body, false, &error);
  res.success = b >= 0;
  res.message = b >= 0 ? "t = " + FormatNumber(SimTime()) + " s" : error;
  if (b >= 0) res.state = conv::ToBodyStateMsg(model_, state_, b);
  return true;
}

bool SimNode::OnSetBodyState(implicit_sim::SetBodyState::Request& req, implicit_sim::SetBodyState::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  std::string error;
  const int b = FindBodyOrFail(req.state.name, true, &error);
  res.success = b >= 0 && conv::SetBodyStateFromMsg(model_, b, req.state, &state_, &error);
  if (res.success) {
    ClearWarmStart(&data_);  // the next step starts cold from the new configuration
    SaveLatestLocked();
  }
  res.message = res.success ? "set '" + req.state.name + "'" : error;
  return true;
}

bool SimNode::OnApplyWrench(implicit_sim::ApplyBodyWrench::Request& req,
                            implicit_sim::ApplyBodyWrench::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  std::string error;
  res.success = false;
  const int b = FindBodyOrFail(req.body, true, &error);
  int frame_body = -1;
  if (!req.reference_frame.empty() && req.reference_frame != params_.world_frame) {
    frame_body = model_.FindBody(req.reference_frame);
    if (frame_body < 0) error = "unknown reference_frame '" + req.reference_frame + "'";
  }
  TimedWrench w{b, frame_body, conv::ToVec3(req.reference_point), conv::ToVec3(req.wrench.force),
                conv::ToVec3(req.wrench.torque), std::max(req.start_time, SimTime()), -1.0};
  if (error.empty() && (!w.point.allFinite() || !std::isfinite(req.start_time) || !std::isfinite(req.duration))) {
    error = "reference_point, start_time and duration must be finite";
  }
  if (error.empty()) CheckWrenchValues(w.force, w.torque, &error);
  if (error.empty() && req.duration == 0.0) error = "duration must be > 0 s, or < 0 for until cleared";
  if (!error.empty()) {
    res.message = error;
    return true;
  }
  if (req.duration > 0.0) w.end = w.start + req.duration;
  wrenches_.push_back(w);
  res.success = true;
  res.message = "wrench on '" + req.body + "' from t = " + FormatNumber(w.start) + " s";
  return true;
}

void SimNode::OnWrenchCommand(const implicit_sim::BodyWrench::ConstPtr& msg) {
  const Vec3 f = conv::ToVec3(msg->wrench.force), tau = conv::ToVec3(msg->wrench.torque);
  std::lock_guard<std::mutex> lock(mutex_);
  ++received_commands_;
  std::string error;
  const int b = FindBodyOrFail(msg->body, true, &error);
  if (b >= 0) CheckWrenchValues(f, tau, &error);
  if (!error.empty()) {
    ++dropped_commands_;
    ROS_WARN_THROTTLE(1.0, "implicit_sim: dropped ~wrench_cmd: %s (%ld dropped so far)", error.c_str(),
                      dropped_commands_);
    return;
  }
  const int v = Model::v_offset(model_.velocity_slot[b]);
  commanded_W_.segment<3>(v) = f;
  commanded_W_.segment<3>(v + 3) = tau;
}


bool SimNode::SetJointEffortsLocked(const std::vector<std::string>& names, const std::vector<double>& efforts,
                                    std::string* error) {
  if (names.size() != efforts.size()) {
    *error = "name and effort must have the same length (" + std::to_string(names.size()) + " names, " +
             std::to_string(efforts.size()) + " efforts)";
    return false;
  }
  std::vector<int> joints(names.size());
  for (size_t i = 0; i < names.size(); ++i) {
    joints[i] = model_.FindJoint(names[i]);
    if (joints[i] < 0 || !model_.joints[joints[i]].has_coordinate()) {
      *error = "no revolute, continuous or prismatic joint '" + names[i] + "' in the scene";
      return false;
    }
    if (!std::isfinite(efforts[i]) || std::abs(efforts[i]) > kMaxCommand) {
      *error = "effort of joint '" + names[i] + "' = " + FormatNumber(efforts[i]) +
               " must be finite with |effort| <= 1e9 (N m or N)";
      return false;
    }
  }
  for (size_t i = 0; i < names.size(); ++i) joint_efforts_[joints[i]] = efforts[i];
  SaveLatestLocked();  // /joint_states shows the new efforts
  return true;
}

void SimNode::OnJointEffortCommand(const sensor_msgs::JointState::ConstPtr& msg) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++received_joint_commands_;
  std::string error;
  if (!SetJointEffortsLocked(msg->name, msg->effort, &error)) {
    ++dropped_joint_commands_;
    ROS_WARN_THROTTLE(1.0, "implicit_sim: dropped ~joint_effort_cmd: %s (%ld dropped so far)", error.c_str(),
                      dropped_joint_commands_);
  }
}

bool SimNode::OnSetJointEfforts(implicit_sim::SetJointEfforts::Request& req,
                                implicit_sim::SetJointEfforts::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  std::string error;
  res.success = SetJointEffortsLocked(req.name, req.effort, &error);
  res.message = res.success ? "set the effort of " + std::to_string(req.name.size()) + " joints" : error;
  return true;
}

}  // namespace implicit_sim
