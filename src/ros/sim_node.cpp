// The node's core: construction, the physics, publish and diagnostics threads, and stepping with the applied wrenches.
// The physics thread holds mutex_ for a whole step and then saves the result as the latest snapshot; the publish
// thread reads only that snapshot (under latest_mutex_), so /clock and /tf keep their rates however long a step takes.
#include "implicit_sim/ros/sim_node.h"  // first: its generated service type Step precedes the core's function Step

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <stdexcept>

#include "implicit_sim/core/model/joints.h"
#include "implicit_sim/core/model/wrench.h"
#include "implicit_sim/ros/conversions.h"

namespace implicit_sim {
namespace {

using WallClock = std::chrono::steady_clock;

// How long shutdown waits for a step in progress (a step of a large pile can take seconds) before the node exits
// without it; roslaunch escalates SIGINT to SIGTERM only after 15 s.
constexpr double kShutdownGraceS = 2.0;

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
  SaveLatestLocked();
  AdvertiseTopics();
  AdvertiseServices();
  PublishStaticTf();
  diagnostics_.setHardwareID("implicit_sim " + model_.scene_name);
  diagnostics_.add("solver", this, &SimNode::UpdateDiagnostics);
  ROS_INFO("implicit_sim: scene '%s', %d moving bodies, %zu contact pairs, h = %g s, %s", model_.scene_name.c_str(),
           model_.num_moving(), model_.pairs.size(), options_.h, paused_ ? "paused" : "running");
}

SimNode::~SimNode() { StopThreads(std::numeric_limits<double>::infinity()); }

void SimNode::Run() {
  ros::AsyncSpinner spinner(2);
  spinner.start();
  PublishClock(SimTime());
  StartThread(&physics_thread_, &SimNode::PhysicsLoop);
  StartThread(&publish_thread_, &SimNode::PublishLoop);
  StartThread(&diagnostics_thread_, &SimNode::DiagnosticsLoop);
  ros::waitForShutdown();
  if (!StopThreads(kShutdownGraceS)) {
    // The core's step cannot be interrupted: exit without it (nothing is lost; ROS is already shut down).
    std::fprintf(stderr, "implicit_sim: a step was still running %g s after shutdown; exiting without it\n",
                 kShutdownGraceS);
    std::fflush(nullptr);
    std::_Exit(0);
  }
}

void SimNode::StartThread(std::thread* thread, void (SimNode::*loop)()) {
  {
    std::lock_guard<std::mutex> lock(stop_mutex_);
    ++threads_started_;
  }
  *thread = std::thread([this, loop] {
    (this->*loop)();
    std::lock_guard<std::mutex> lock(stop_mutex_);
    ++threads_ended_;
    stop_cv_.notify_all();
  });
}

bool SimNode::StopThreads(double grace_s) {
  {
    std::unique_lock<std::mutex> lock(stop_mutex_);
    stopping_ = true;
    wake_.notify_all();
    stop_cv_.notify_all();
    const auto all_ended = [this] { return threads_ended_ == threads_started_; };
    if (std::isinf(grace_s)) {
      stop_cv_.wait(lock, all_ended);
    } else if (!stop_cv_.wait_for(lock, std::chrono::duration<double>(grace_s), all_ended)) {
      return false;
    }
  }
  for (std::thread* t : {&publish_thread_, &diagnostics_thread_, &physics_thread_}) {
    if (t->joinable()) t->join();
  }
  return true;
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
    SaveLatestLocked();
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
  SaveLatestLocked();
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
  SaveLatestLocked();
}

void SimNode::SaveLatestLocked() {
  auto snapshot = std::make_shared<Snapshot>();
  snapshot->state = state_;
  snapshot->contacts = data_.contacts;
  snapshot->efforts = joint_efforts_;
  snapshot->sim_time = SimTime();
  std::lock_guard<std::mutex> lock(latest_mutex_);
  latest_ = std::move(snapshot);
}

std::shared_ptr<const SimNode::Snapshot> SimNode::Latest() const {
  std::lock_guard<std::mutex> lock(latest_mutex_);
  return latest_;
}

void SimNode::PhysicsLoop() {
  WallClock::time_point pace_wall;
  double pace_sim = 0.0, rtf_sim = 0.0;
  WallClock::time_point rtf_wall = WallClock::now();
  while (true) {
    std::unique_lock<std::mutex> lock(mutex_);
    // A bounded wait: stopping_ is set without mutex_, so a notification can come between the check and the wait.
    while (!wake_.wait_for(lock, std::chrono::milliseconds(100), [this] { return stopping_ || !paused_; })) {
    }
    if (stopping_) return;
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

// /clock, /tf and the topics at ~publish_rate (wall time) from the latest completed step; never waits for a step.
void SimNode::PublishLoop() {
  PublishMemory memory;
  memory.shapes = ros_conversions::ShapeMarkers(model_);
  memory.on_tf.assign(model_.bodies.size(), 1);  // jointed links leave /tf to robot_state_publisher if asked
  for (const Joint& joint : model_.joints) memory.on_tf[joint.child] = params_.publish_joint_link_tf;
  const auto period =
      std::chrono::duration_cast<WallClock::duration>(std::chrono::duration<double>(1.0 / params_.publish_rate));
  WallClock::time_point next = WallClock::now();
  while (!stopping_) {
    const std::shared_ptr<const Snapshot> latest = Latest();
    const Snapshot& snapshot = *latest;
    const ros::Time stamp = ros::Time().fromSec(snapshot.sim_time);
    PublishClock(snapshot.sim_time);  // every cycle, even when time has not moved (the same time again is allowed)
    PublishTf(snapshot, stamp, &memory);  // only when time has moved
    PublishJointStates(snapshot.state, snapshot.efforts, stamp);
    PublishBodyStates(snapshot, stamp);
    PublishContacts(snapshot, stamp);
    PublishMarkers(snapshot, stamp, &memory);
    next += period;
    const WallClock::time_point now = WallClock::now();
    if (next < now) next = now;  // a late cycle is not made up with a burst
    std::unique_lock<std::mutex> lock(stop_mutex_);
    stop_cv_.wait_until(lock, next, [this] { return stopping_.load(); });
  }
}

// /diagnostics once a second, on its own thread: UpdateDiagnostics takes mutex_ and so waits out a step in progress.
void SimNode::DiagnosticsLoop() {
  std::unique_lock<std::mutex> lock(stop_mutex_);
  while (!stop_cv_.wait_for(lock, std::chrono::seconds(1), [this] { return stopping_.load(); })) {
    lock.unlock();
    diagnostics_.force_update();
    lock.lock();
  }
}

}  // namespace implicit_sim
