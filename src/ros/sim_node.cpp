// The node's core: construction, the physics and publish threads, and stepping with the applied wrenches.
#include "implicit_sim/ros/sim_node.h"  // first: its generated service type Step precedes the core's function Step

#include <chrono>
#include <stdexcept>

#include "implicit_sim/core/model/joints.h"
#include "implicit_sim/core/model/wrench.h"
#include "implicit_sim/ros/conversions.h"

namespace implicit_sim {
namespace {

using WallClock = std::chrono::steady_clock;

}  // namespace

SimNode::SimNode(ros::NodeHandle nh, ros::NodeHandle pnh)
    : nh_(nh),
      pnh_(pnh),
      params_(NodeParams::Read(pnh)),
      model_(LoadNodeScene(nh, params_)),
      options_(params_.options),
      data_(model_),
      diagnostics_(nh, pnh) {
  state_ = initial_state_ = State::Initial(model_);
  paused_ = params_.paused;
  commanded_W_ = Eigen::VectorXd::Zero(model_.nv());
  wrench_W_ = Eigen::VectorXd::Zero(model_.nv());
  joint_efforts_ = Eigen::VectorXd::Zero(model_.joints.size());
  AdvertiseTopics();
  AdvertiseServices();
  PublishStaticTf();
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
    const int v = Model::v_offset(k);
    AddWrenchAtPoint(model_, state_, b, -1, state_.X_WL(model_, b).translation(), commanded_W_.segment<3>(v),
                     commanded_W_.segment<3>(v + 3), &wrench_W_);
  }
  for (const TimedWrench& w : wrenches_) {
    if (t < w.start || (w.end >= 0.0 && t >= w.end)) continue;
    AddWrenchAtPoint(model_, state_, w.body, w.frame_body, w.point, w.force, w.torque, &wrench_W_);
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
  // No forces, but the vector keeps its size: it follows the core's pair layout (Data::LayOut), and a step whose
  // layout is unchanged writes its results into it by index (clearing it made them vanish after ~reset).
  for (ContactResult& contact : data_.contacts) {
    const int pair = contact.pair;
    contact = ContactResult();
    contact.pair = pair;
  }
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
      const std::chrono::duration<double> ahead((sim - pace_sim) / params_.real_time_factor);  // s of wall time
      std::this_thread::sleep_until(pace_wall + std::chrono::duration_cast<WallClock::duration>(ahead));
    }
  }
}

bool SimNode::TakeSnapshot(Snapshot* snapshot) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (shutdown_) return false;
  snapshot->state = state_;
  snapshot->contacts = data_.contacts;
  snapshot->efforts = joint_efforts_;
  snapshot->sim_time = SimTime();
  return true;
}

void SimNode::PublishLoop() {
  PublishMemory memory;
  memory.shapes = ros_conversions::ShapeMarkers(model_);
  memory.on_tf.assign(model_.bodies.size(), 1);  // jointed links leave /tf to robot_state_publisher if asked
  for (const Joint& joint : model_.joints) memory.on_tf[joint.child] = params_.publish_joint_link_tf;
  memory.last_diagnostics = WallClock::now();
  Snapshot snapshot;
  snapshot.state = State::Initial(model_);
  ros::WallRate rate(params_.publish_rate);
  while (TakeSnapshot(&snapshot)) {
    const ros::Time stamp = ros::Time().fromSec(snapshot.sim_time);
    PublishClock(snapshot.sim_time);
    PublishTf(snapshot, stamp, &memory);
    PublishJointStates(snapshot.state, snapshot.efforts, stamp);
    PublishBodyStates(snapshot, stamp);
    PublishContacts(snapshot, stamp);
    PublishMarkers(snapshot, stamp, &memory);
    PublishDiagnostics(&memory);
    rate.sleep();
  }
}

}  // namespace implicit_sim
