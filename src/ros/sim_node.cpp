#include "implicit_sim/ros/sim_node.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <stdexcept>

#include <rosgraph_msgs/Clock.h>

#include "implicit_sim/BodyStates.h"
#include "implicit_sim/Contacts.h"
#include "implicit_sim/StepStats.h"
#include "implicit_sim/core/base/format.h"
#include "implicit_sim/core/model/urdf_loader.h"
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

using WallClock = std::chrono::steady_clock;

template <typename T>
T ReadParam(const ros::NodeHandle& pnh, const std::string& name, T fallback) {
  T value = fallback;
  if (pnh.hasParam(name) && !pnh.getParam(name, value)) {
    throw std::invalid_argument("parameter ~" + name + " has the wrong type");
  }
  return value;
}

void CheckRange(const std::string& name, double value, double lo, double hi, bool lo_open, const std::string& unit) {
  const bool ok = std::isfinite(value) && (lo_open ? value > lo : value >= lo) && value <= hi;
  if (!ok) {
    throw std::invalid_argument("parameter ~" + name + " = " + FormatNumber(value) + " is out of range " +
                                (lo_open ? "(" : "[") + FormatNumber(lo) + ", " + FormatNumber(hi) + "] " + unit);
  }
}

Model LoadModel(const ros::NodeHandle& nh, const NodeParams& p) {
  if (!p.scene.empty()) {
    const bool is_path = p.scene.find('/') != std::string::npos ||
                         (p.scene.size() > 5 && p.scene.substr(p.scene.size() - 5) == ".urdf");
    const std::string path = is_path ? p.scene : p.scenes_dir + "/" + p.scene + ".urdf";
    if (!std::ifstream(path)) {
      throw std::invalid_argument("parameter ~scene = '" + p.scene + "': no scene file '" + path + "'");
    }
    return LoadSceneFromFile(path);
  }
  std::string xml;
  if (!nh.getParam("robot_description", xml)) {
    throw std::invalid_argument("no scene: set ~scene (file path or scene name) or the robot_description parameter");
  }
  return LoadSceneFromString(xml, "robot_description");
}

}  // namespace

NodeParams NodeParams::Read(const ros::NodeHandle& pnh) {
  NodeParams p;
  p.scene = ReadParam<std::string>(pnh, "scene", "");
  p.scenes_dir = ReadParam<std::string>(pnh, "scenes_dir", IMPLICIT_SIM_SCENES_DIR);
  p.time_step = ReadParam(pnh, "time_step", p.time_step);
  p.tolerance = ReadParam(pnh, "tolerance", p.tolerance);
  p.max_iterations = ReadParam(pnh, "max_iterations", p.max_iterations);
  p.solver = ReadParam(pnh, "solver", p.solver);
  if (p.solver != "newton" && p.solver != "ipopt") {
    throw std::invalid_argument("parameter ~solver = '" + p.solver + "' must be newton or ipopt");
  }
  p.publish_rate = ReadParam(pnh, "publish_rate", p.publish_rate);
  p.real_time_factor = ReadParam(pnh, "real_time_factor", p.real_time_factor);
  p.paused = ReadParam(pnh, "paused", p.paused);
  p.on_fault = ReadParam(pnh, "on_fault", p.on_fault);
  if (p.on_fault != "pause" && p.on_fault != "reset") {
    throw std::invalid_argument("parameter ~on_fault = '" + p.on_fault + "' must be pause or reset");
  }
  p.world_frame = ReadParam(pnh, "world_frame", p.world_frame);
  p.force_marker_scale = ReadParam(pnh, "force_marker_scale", p.force_marker_scale);
  p.contact_marker_size = ReadParam(pnh, "contact_marker_size", p.contact_marker_size);
  p.publish_joint_link_tf = ReadParam(pnh, "publish_joint_link_tf", p.publish_joint_link_tf);
  CheckRange("time_step", p.time_step, 0.0, 1.0, true, "s");
  CheckRange("tolerance", p.tolerance, 0.0, 0.1, true, "");
  CheckRange("max_iterations", p.max_iterations, 1, 100000, false, "");
  CheckRange("publish_rate", p.publish_rate, 0.0, 1000.0, true, "Hz");
  CheckRange("real_time_factor", p.real_time_factor, 0.0, 1000.0, false, "(0: as fast as possible)");
  CheckRange("force_marker_scale", p.force_marker_scale, 0.0, 100.0, true, "m/N");
  CheckRange("contact_marker_size", p.contact_marker_size, 0.0, 100.0, true, "m");
  if (p.world_frame.empty()) throw std::invalid_argument("parameter ~world_frame must not be empty");
  return p;
}

SimNode::SimNode(ros::NodeHandle nh, ros::NodeHandle pnh)
    : nh_(nh),
      pnh_(pnh),
      params_(NodeParams::Read(pnh)),
      model_(LoadModel(nh, params_)),
      data_(model_),
      diagnostics_(nh, pnh) {
  options_.h = params_.time_step;
  options_.newton.tolerance = params_.tolerance;
  options_.newton.max_iterations = params_.max_iterations;
  options_.solver = params_.solver == "ipopt" ? StepperOptions::Solver::kIpopt : StepperOptions::Solver::kNewton;
  std::string error;
  if (!options_.IsValid(&error)) throw std::invalid_argument(error);
  state_ = initial_state_ = State::Initial(model_);
  paused_ = params_.paused;
  commanded_W_ = Eigen::VectorXd::Zero(6 * model_.num_moving());
  wrench_W_ = Eigen::VectorXd::Zero(6 * model_.num_moving());
  joint_efforts_ = Eigen::VectorXd::Zero(model_.joints.size());

  clock_pub_ = nh_.advertise<rosgraph_msgs::Clock>("/clock", 10);
  contacts_pub_ = pnh_.advertise<implicit_sim::Contacts>("contacts", 10);
  markers_pub_ = pnh_.advertise<visualization_msgs::MarkerArray>("markers", 10);
  stats_pub_ = pnh_.advertise<implicit_sim::StepStats>("step_stats", 100);
  body_states_pub_ = pnh_.advertise<implicit_sim::BodyStates>("body_states", 10);
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
  joint_states_pub_ = nh_.advertise<sensor_msgs::JointState>("joint_states", 10);

  std::vector<geometry_msgs::TransformStamped> statics;
  for (const Body& body : model_.bodies) {
    if (!body.is_fixed) continue;
    geometry_msgs::TransformStamped t;
    t.header.frame_id = params_.world_frame;
    t.child_frame_id = body.name;
    t.transform = conv::ToTransformMsg(body.X_WB0 * body.X_BL);
    statics.push_back(t);
  }
  if (!statics.empty()) static_broadcaster_.sendTransform(statics);
  diagnostics_.setHardwareID("implicit_sim " + model_.scene_name);
  diagnostics_.add("solver", this, &SimNode::UpdateDiagnostics);
  ROS_INFO("implicit_sim: scene '%s', %d moving bodies, %zu contact pairs, h = %g s, %s", model_.scene_name.c_str(),
           model_.num_moving(), model_.pairs.size(), options_.h, paused_ ? "paused" : "running");
}

SimNode::~SimNode() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    shutdown_ = true;
  }
  wake_.notify_all();
  if (physics_thread_.joinable()) physics_thread_.join();
  if (publish_thread_.joinable()) publish_thread_.join();
}

void SimNode::Run() {
  ros::AsyncSpinner spinner(2);
  spinner.start();
  PublishClock(SimTime());
  physics_thread_ = std::thread(&SimNode::PhysicsLoop, this);
  publish_thread_ = std::thread(&SimNode::PublishLoop, this);
  ros::waitForShutdown();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    shutdown_ = true;
  }
  wake_.notify_all();
  physics_thread_.join();
  publish_thread_.join();
}

void SimNode::ComputeWrenchesLocked() {
  wrench_W_.setZero();
  const double t = SimTime() + 1e-9;
  for (int k = 0; k < model_.num_moving(); ++k) {  // ~wrench_cmd: at the link origin, world frame
    const int b = model_.moving_bodies[k];
    const Vec3 arm = conv::LinkPose(model_, state_, b).translation() - state_.X_WB(model_, b).translation();
    const Vec3 f = commanded_W_.segment<3>(6 * k);
    wrench_W_.segment<3>(6 * k) += f;
    wrench_W_.segment<3>(6 * k + 3) += commanded_W_.segment<3>(6 * k + 3) + arm.cross(f);
  }
  for (const TimedWrench& w : wrenches_) {
    if (t < w.start || (w.end >= 0.0 && t >= w.end)) continue;
    const Pose X_WF = w.frame_body < 0 ? Pose::Identity() : conv::LinkPose(model_, state_, w.frame_body);
    const Vec3 f_W = X_WF.linear() * w.force;
    const Vec3 arm = X_WF * w.point - state_.X_WB(model_, w.body).translation();
    const int k = model_.velocity_slot[w.body];
    wrench_W_.segment<3>(6 * k) += f_W;
    wrench_W_.segment<3>(6 * k + 3) += X_WF.linear() * w.torque + arm.cross(f_W);
  }
  if (!model_.joints.empty()) AddJointEffortWrench(model_, state_, joint_efforts_, &wrench_W_);
}

void SimNode::StepLocked() {
  ComputeWrenchesLocked();
  StepReport report;
  try {
    report = Step(model_, options_, &state_, &data_, &wrench_W_);
  } catch (const std::exception& e) {
    report.advanced = false;
    report.fault = StepFault::kNoFiniteSolution;
    report.fault_detail = e.what();
  }
  ++step_count_;
  ++diag_steps_;
  ++faults_[static_cast<int>(report.fault)];
  if (!report.converged) ++diag_nonconverged_;
  last_report_ = report;
  if (report.advanced) {
    at_initial_state_ = false;
    return;
  }
  // Step left the last good state in place (it never publishes NaN): warn once, then pause or reset.
  ++diag_failed_;
  last_failure_ = std::string(StepFaultName(report.fault)) + (report.fault_detail.empty() ? "" : ": ") +
                  report.fault_detail;
  if (params_.on_fault == "reset" && !at_initial_state_) {
    ROS_WARN("implicit_sim: step refused (%s); bodies reset to their initial state", last_failure_.c_str());
    ResetLocked();
  } else {
    paused_ = true;
    ROS_ERROR("implicit_sim: step refused (%s); the simulation is paused", last_failure_.c_str());
  }
}

void SimNode::ResetLocked() {
  time_offset_ = SimTime();  // simulation time keeps increasing; bodies return to their initial state
  state_ = initial_state_;
  ClearWarmStart(&data_);
  data_.contacts.clear();
  wrenches_.clear();
  commanded_W_.setZero();
  joint_efforts_.setZero();
  restart_pacing_ = true;
  at_initial_state_ = true;
}

void SimNode::PhysicsLoop() {
  WallClock::time_point pace_wall;
  double pace_sim = 0.0, rtf_sim = 0.0;
  WallClock::time_point rtf_wall = WallClock::now();
  while (true) {
    std::unique_lock<std::mutex> lock(mutex_);
    wake_.wait(lock, [this] { return shutdown_ || !paused_; });
    if (shutdown_) return;
    if (restart_pacing_) {
      pace_wall = rtf_wall = WallClock::now();
      pace_sim = rtf_sim = SimTime();
      restart_pacing_ = false;
    }
    StepLocked();
    const double sim = SimTime();
    const auto now = WallClock::now();
    const double window = std::chrono::duration<double>(now - rtf_wall).count();
    if (window >= 1.0) {  // real-time factor over the last second
      rtf_ = (sim - rtf_sim) / window;
      rtf_sim = sim;
      rtf_wall = now;
    }
    const StepReport report = last_report_;
    const uint64_t step = step_count_;
    const double rtf = rtf_;
    lock.unlock();
    PublishClock(sim);
    PublishStepStats(report, sim, step, rtf);
    if (params_.real_time_factor > 0.0) {
      std::this_thread::sleep_until(pace_wall + std::chrono::duration_cast<WallClock::duration>(std::chrono::duration<double>(
                                                    (sim - pace_sim) / params_.real_time_factor)));
    }
  }
}

void SimNode::PublishClock(double sim_time) {
  std::lock_guard<std::mutex> lock(clock_mutex_);
  if (sim_time < last_clock_) return;  // /clock never goes backwards
  last_clock_ = sim_time;
  rosgraph_msgs::Clock msg;
  msg.clock.fromSec(sim_time);
  clock_pub_.publish(msg);
}

void SimNode::PublishStepStats(const StepReport& r, double sim_time, uint64_t step, double rtf) {
  if (stats_pub_.getNumSubscribers() == 0) return;
  implicit_sim::StepStats msg;
  msg.header.stamp.fromSec(sim_time);
  msg.header.frame_id = params_.world_frame;
  msg.step = step;
  msg.converged = r.converged;
  msg.advanced = r.advanced;
  msg.status = !r.advanced ? "failed" : r.converged ? "converged" : "not converged";
  msg.iterations = r.iterations;
  msg.residual = r.residual;
  msg.complementarity_error = r.complementarity_error;
  msg.active_contacts = r.active_contacts;
  msg.cold_restarts = r.cold_restarts;
  msg.smoothed_solves = r.smoothed_solves;
  msg.ipopt_solves = r.ipopt_solves;
  msg.substeps = r.substeps;
  msg.wall_time = r.wall_time_s;
  msg.real_time_factor = rtf;
  stats_pub_.publish(msg);
}

void SimNode::PublishLoop() {
  const visualization_msgs::MarkerArray shapes = conv::ShapeMarkers(model_);
  State snapshot = State::Initial(model_);
  std::vector<ContactResult> contacts;
  Eigen::VectorXd efforts;
  std::vector<char> on_tf(model_.bodies.size(), 1);  // jointed links leave /tf to robot_state_publisher if asked
  for (const Joint& joint : model_.joints) on_tf[joint.child] = params_.publish_joint_link_tf;
  std::vector<int> shown_pairs, active_pairs;  // pairs with contact markers: last published, current
  ros::WallRate rate(params_.publish_rate);
  WallClock::time_point last_diagnostics = WallClock::now(), last_tf_wall;
  double last_tf_time = -1.0;
  while (true) {
    double sim;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (shutdown_) return;
      snapshot = state_;
      contacts = data_.contacts;
      efforts = joint_efforts_;
      sim = SimTime();
    }
    const ros::Time stamp = ros::Time().fromSec(sim);
    PublishClock(sim);
    // /tf only when time has moved (tf2 listeners warn about repeated stamps), and every 5 s while paused so that
    // late subscribers get the poses.
    const bool moved = sim != last_tf_time || WallClock::now() - last_tf_wall >= std::chrono::seconds(5);
    if (moved) {
      last_tf_time = sim;
      last_tf_wall = WallClock::now();
    }
    std::vector<geometry_msgs::TransformStamped> transforms;
    for (int b : model_.moving_bodies) {
      if (!on_tf[b]) continue;
      geometry_msgs::TransformStamped t;
      t.header.stamp = stamp;
      t.header.frame_id = params_.world_frame;
      t.child_frame_id = model_.bodies[b].name;
      t.transform = conv::ToTransformMsg(conv::LinkPose(model_, snapshot, b));
      transforms.push_back(t);
    }
    if (moved && !transforms.empty()) tf_broadcaster_.sendTransform(transforms);  // one batched /tf message
    PublishJointStates(snapshot, efforts, stamp);
    if (body_states_pub_.getNumSubscribers() > 0) {
      implicit_sim::BodyStates msg;
      msg.header.stamp = stamp;
      msg.header.frame_id = params_.world_frame;
      for (int b : model_.moving_bodies) msg.bodies.push_back(conv::ToBodyStateMsg(model_, snapshot, b));
      for (int b = 0; b < static_cast<int>(model_.bodies.size()); ++b) {
        if (model_.bodies[b].is_fixed) msg.bodies.push_back(conv::ToBodyStateMsg(model_, snapshot, b));
      }
      body_states_pub_.publish(msg);
    }
    const bool have_contacts = snapshot.t > 0.0;  // no step yet: no contact results
    if (contacts_pub_.getNumSubscribers() > 0) {
      implicit_sim::Contacts msg;
      msg.header.stamp = stamp;
      msg.header.frame_id = params_.world_frame;
      for (const ContactResult& contact : contacts) {
        if (have_contacts && contact.normal_force > options_.contact_threshold) {
          msg.contacts.push_back(conv::ToContactMsg(model_, contact.pair, contact));
        }
      }
      contacts_pub_.publish(msg);
    }
    if (markers_pub_.getNumSubscribers() > 0) {
      visualization_msgs::MarkerArray msg = shapes;
      for (auto& m : msg.markers) m.header.stamp = stamp;
      active_pairs.clear();
      for (const ContactResult& contact : contacts) {
        if (!have_contacts || !(contact.normal_force > options_.contact_threshold)) continue;
        conv::AppendContactMarkers(contact.pair, contact, true, params_.world_frame, params_.force_marker_scale,
                                   params_.contact_marker_size, &msg);
        active_pairs.push_back(contact.pair);
      }
      std::sort(active_pairs.begin(), active_pairs.end());
      for (int pair : shown_pairs) {  // contacts that ended (or left the NCP): delete their markers
        if (std::binary_search(active_pairs.begin(), active_pairs.end(), pair)) continue;
        conv::AppendContactMarkers(pair, ContactResult(), false, params_.world_frame, params_.force_marker_scale,
                                   params_.contact_marker_size, &msg);
      }
      shown_pairs.swap(active_pairs);
      markers_pub_.publish(msg);
    }
    if (WallClock::now() - last_diagnostics >= std::chrono::seconds(1)) {
      diagnostics_.force_update();
      last_diagnostics = WallClock::now();
    }
    rate.sleep();
  }
}

void SimNode::UpdateDiagnostics(diagnostic_updater::DiagnosticStatusWrapper& status) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (diag_failed_ > 0) {
    status.summary(diagnostic_msgs::DiagnosticStatus::ERROR,
                   std::string("step refused, ") + (paused_ ? "simulation paused: " : "bodies reset: ") + last_failure_);
  } else if (diag_nonconverged_ > 0) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN, "some steps did not converge");
  } else {
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, paused_ ? "paused" : "running");
  }
  status.add("sim_time_s", SimTime());
  status.add("steps_since_last_report", diag_steps_);
  status.add("nonconverged_steps_since_last_report", diag_nonconverged_);
  status.add("failed_steps_since_last_report", diag_failed_);
  status.add("received_wrench_commands", received_commands_);
  status.add("dropped_wrench_commands", dropped_commands_);
  status.add("received_joint_effort_commands", received_joint_commands_);
  status.add("dropped_joint_effort_commands", dropped_joint_commands_);
  for (StepFault fault : {StepFault::kNotConverged, StepFault::kNoFiniteSolution, StepFault::kInitialOverlap,
                          StepFault::kDiverged}) {
    status.add(std::string("faults_") + StepFaultName(fault), faults_[static_cast<int>(fault)]);
  }
  status.add("real_time_factor", rtf_);
  status.add("last_iterations", last_report_.iterations);
  status.add("last_residual", last_report_.residual);
  diag_steps_ = diag_nonconverged_ = diag_failed_ = 0;
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
    for (; done < req.steps && !shutdown_; ++done) {
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
  if (res.success) ClearWarmStart(&data_);  // the next step starts cold from the new configuration
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
  const int k = model_.velocity_slot[b];
  commanded_W_.segment<3>(6 * k) = f;
  commanded_W_.segment<3>(6 * k + 3) = tau;
}

}  // namespace implicit_sim
