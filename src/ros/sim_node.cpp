// The node's core: construction, the mailbox, the physics, publish and diagnostics threads, and stepping with the
// applied wrenches. Only the physics thread touches world_; the others post commands to it (RunBetweenSteps,
// PostBetweenSteps) or read the snapshot it saves (Latest), so no lock is held across a step.
#include "implicit_sim/ros/sim_node.h"  // first: its generated service type Step precedes the core's function Step

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <algorithm>
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
// At real time, a simulation that fell behind by more than this (s of wall time; a slow step) goes on at the real-time
// pace from where it is instead of catching up in a burst faster than real time.
constexpr double kMaxPaceLagS = 0.1;

}  // namespace

SimNode::SimNode(ros::NodeHandle nh, ros::NodeHandle pnh)
    : nh_(nh),
      pnh_(pnh),
      params_(NodeParams::Read(pnh)),
      options_(params_.options),
      live_(params_.live),
      live_options_(params_.options) {
  world_ = BuildWorld(params_, ReadNodeScene(nh, params_));
  OpenJournals();
  PublishRobotDescription(world_->urdf);
  const Model& model = *world_->model;
  paused_ = params_.paused;
  diagnostics_ = std::make_unique<NodeDiagnostics>(nh, pnh, "implicit_sim " + model.scene_name, paused_);
  publisher_ = std::make_unique<NodePublisher>(
      nh, pnh, params_, [this] { return Live(); },
      [this](const NodeSnapshot& snapshot) { SetUpDragMarkers(*snapshot.model, snapshot.state); },
      [this](const NodeSnapshot& snapshot) { UpdateDragMarkers(snapshot); });
  SaveSnapshot();
  AdvertiseServices();
  publisher_->PublishStaticTf(model);
  SetUpReconfigure();
  SetUpDragMarkers(model, world_->state);
  ROS_INFO("implicit_sim: scene '%s', %d moving bodies, %zu contact pairs, h = %g s, %s", model.scene_name.c_str(),
           model.num_moving(), model.pairs.size(), options_.h, paused_ ? "paused" : "running");
}

SimNode::~SimNode() {
  if (run_steps_server_) run_steps_server_->shutdown();
  StopThreads(std::numeric_limits<double>::infinity());
  drag_server_.reset();
}

void SimNode::Run() {
  ros::AsyncSpinner spinner(4);  // services wait for the physics thread: several may wait at once
  spinner.start();
  publisher_->PublishClock(SimTime());
  StartThread(&physics_thread_, &SimNode::PhysicsLoop);
  StartThread(&publish_thread_, &SimNode::PublishLoop);
  StartThread(&diagnostics_thread_, &SimNode::DiagnosticsLoop);
  run_steps_server_->start();
  ros::waitForShutdown();
  if (!StopThreads(kShutdownGraceS)) {
    // The core's step cannot be interrupted: exit without it (nothing is lost; ROS is already shut down).
    std::fprintf(stderr, "implicit_sim: a step was still running %g s after shutdown; exiting without it\n",
                 kShutdownGraceS);
    std::fflush(nullptr);
    std::_Exit(0);
  }
  run_steps_server_->shutdown();
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
    std::lock_guard<std::mutex> lock(mailbox_mutex_);  // the waiters of commands and jobs check stopping_ under it
    stopping_ = true;
  }
  mailbox_cv_.notify_all();
  {
    std::unique_lock<std::mutex> lock(stop_mutex_);
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

bool SimNode::RunBetweenSteps(std::function<void()> fn) {
  auto command = std::make_shared<Command>();
  command->run = std::move(fn);
  std::unique_lock<std::mutex> lock(mailbox_mutex_);
  if (stopping_) return false;
  commands_.push_back(command);
  mailbox_cv_.notify_all();
  mailbox_cv_.wait(lock, [&] { return command->done || stopping_; });
  return command->done;
}

void SimNode::PostBetweenSteps(std::function<void()> fn) {
  auto command = std::make_shared<Command>();
  command->run = std::move(fn);
  std::lock_guard<std::mutex> lock(mailbox_mutex_);
  commands_.push_back(command);
  mailbox_cv_.notify_all();
}

void SimNode::RunCommands() {
  std::vector<std::shared_ptr<Command>> commands;
  {
    std::lock_guard<std::mutex> lock(mailbox_mutex_);
    commands.swap(commands_);
  }
  if (commands.empty()) return;
  for (const auto& command : commands) command->run();
  {
    std::lock_guard<std::mutex> lock(mailbox_mutex_);
    for (const auto& command : commands) command->done = true;
  }
  mailbox_cv_.notify_all();
}

void SimNode::ComputeWrenches() {
  UpdateTrajectoryDrives();
  World& w = *world_;
  const Model& model = *w.model;
  w.wrench_W.setZero();
  const double t = SimTime() + 1e-9;
  for (int k = 0; k < model.num_moving(); ++k) {  // ~wrench_cmd: at the link origin, world frame
    const int b = model.moving_bodies[k];
    const int v = Model::v_offset(k);
    AddWrenchAtPoint(model, w.state, b, -1, w.state.X_WL(model, b).translation(), w.commanded_W.segment<3>(v),
                     w.commanded_W.segment<3>(v + 3), &w.wrench_W);
  }
  for (const TimedWrench& tw : w.wrenches) {
    if (t < tw.start || (tw.end >= 0.0 && t >= tw.end)) continue;
    AddWrenchAtPoint(model, w.state, tw.body, tw.frame_body, tw.point, tw.force, tw.torque, &w.wrench_W);
  }
  if (!model.joints.empty()) AddJointEffortWrench(model, w.state, w.joint_efforts, &w.wrench_W);
  AddDragWrenches();
}

void SimNode::StepOnce(double rtf) {
  {
    std::lock_guard<std::mutex> lock(live_mutex_);
    options_.newton.tolerance = live_options_.newton.tolerance;
    options_.newton.max_iterations = live_options_.newton.max_iterations;
  }
  std::string replay_refusal;
  if (replay_ && !ReplayJournalInputs(&replay_refusal)) {
    RefuseReplayStep(replay_refusal);
    return;
  }
  ComputeWrenches();
  World& w = *world_;
  StepReport report;
  try {
    report = Step(*w.model, options_, &w.state, w.data.get(), &w.wrench_W);
  } catch (const std::exception& e) {
    report.advanced = false;
    report.fault = StepFault::kNoFiniteSolution;
    report.fault_detail = e.what();
  }
  ++step_count_;
  std::string failure;
  if (report.advanced) {
    stepped_ = true;
  } else {
    // Step left the last good state in place (it never publishes NaN): warn once, then pause or reset.
    failure = std::string(StepFaultName(report.fault)) + (report.fault_detail.empty() ? "" : ": ") +
              report.fault_detail;
    if (params_.on_fault == OnFault::kReset && stepped_) {
      ROS_WARN("implicit_sim: step refused (%s); bodies reset to their initial state", failure.c_str());
      ResetWorld();
    } else {
      paused_ = true;
      ROS_ERROR("implicit_sim: step refused (%s); the simulation is paused", failure.c_str());
    }
  }
  diagnostics_->CountStep(report, failure, paused_, SimTime(), rtf);
  if (!report.advanced) {
    std::lock_guard<std::mutex> lock(mailbox_mutex_);
    job_.sim_time = SimTime();
    if (job_.active) FinishJobLocked(false, "stopped after " + std::to_string(job_.done) + " steps: " + failure);
  }
  SaveSnapshot();
  publisher_->PublishClockThrottled(SimTime(), !report.advanced);
  publisher_->PublishStepStats(report, SimTime(), step_count_, rtf);
}

// The replay cannot go on: pause (and end a ~step or ~run_steps job) before the step, which is not taken.
void SimNode::RefuseReplayStep(const std::string& refusal) {
  paused_ = true;
  ROS_ERROR("implicit_sim: replay stops: %s; the simulation is paused", refusal.c_str());
  diagnostics_->HoldFault(refusal);
  std::lock_guard<std::mutex> lock(mailbox_mutex_);
  if (job_.active) FinishJobLocked(false, "stopped after " + std::to_string(job_.done) + " steps: " + refusal);
}

void SimNode::ResetWorld() {
  World& w = *world_;
  time_offset_ = SimTime();  // simulation time keeps increasing; bodies return to their initial state
  w.state = w.initial_state;
  ClearWarmStart(w.data.get());
  // No forces, but the vector keeps its size: it follows the core's pair layout (Data::LayOut), and a step whose
  // layout is unchanged writes its results into it by index (clearing it made them vanish after ~reset).
  for (ContactResult& contact : w.data->contacts) {
    const int pair = contact.pair;
    contact = ContactResult();
    contact.pair = pair;
  }
  w.wrenches.clear();
  w.commanded_W.setZero();
  w.joint_efforts.setZero();
  std::fill(w.data->joint_drives.begin(), w.data->joint_drives.end(), JointDrive());
  w.trajectories.clear();
  w.drags.clear();
  restart_pacing_ = true;
  stepped_ = false;
  SaveSnapshot();
}

void SimNode::SaveSnapshot() {
  const World& w = *world_;
  auto snapshot = std::make_shared<NodeSnapshot>();
  snapshot->model = w.model;
  snapshot->state = w.state;
  snapshot->contacts = w.data->contacts;
  snapshot->efforts = w.joint_efforts;
  snapshot->drive_efforts = w.data->joint_drive_effort;
  snapshot->sim_time = SimTime();
  snapshot->version = ++snapshot_version_;
  snapshot->stepped = stepped_;
  for (const DragSpring& drag : w.drags) {
    snapshot->drag_arrows.emplace_back(w.state.X_WL(*w.model, drag.body) * drag.p_LG, drag.target_W);
  }
  publisher_->Store(std::move(snapshot));
}

void SimNode::PhysicsLoop() {
  WallClock::time_point pace_wall, rtf_wall = WallClock::now();
  double pace_sim = 0.0, rtf_sim = 0.0, pace_factor = -1.0;
  while (true) {
    bool run_job = false;
    {
      std::unique_lock<std::mutex> lock(mailbox_mutex_);
      mailbox_cv_.wait(lock, [this] { return stopping_ || !commands_.empty() || !paused_ || JobRunnableLocked(); });
      if (stopping_) return;
      run_job = JobRunnableLocked();
    }
    RunCommands();
    if (run_job) {
      RunJobStep();
      continue;
    }
    if (paused_ || stopping_) continue;
    if (restart_pacing_) {
      pace_wall = rtf_wall = WallClock::now();
      pace_sim = rtf_sim = SimTime();
      restart_pacing_ = false;
    }
    StepOnce(rtf_);
    const double sim = SimTime();
    const auto now = WallClock::now();
    const double window = std::chrono::duration<double>(now - rtf_wall).count();
    if (window >= 1.0) {  // real-time factor over the last second
      rtf_ = (sim - rtf_sim) / window;
      rtf_sim = sim;
      rtf_wall = now;
    }
    const double real_time_factor = Live().real_time_factor;
    if (real_time_factor != pace_factor) {  // a new factor paces from now on
      pace_factor = real_time_factor;
      pace_wall = now;
      pace_sim = sim;
    }
    if (real_time_factor > 0.0) {
      const std::chrono::duration<double> ahead((sim - pace_sim) / real_time_factor);  // s of wall time
      const auto due = pace_wall + std::chrono::duration_cast<WallClock::duration>(ahead);
      if (now - due > std::chrono::duration<double>(kMaxPaceLagS)) {  // fell behind: go on from here, no burst
        pace_wall = now;
        pace_sim = sim;
      } else {
        WaitForPace(due);
      }
    }
  }
}

// Sleeps until `until`, the wall time at which the simulation is due, running the commands that arrive meanwhile:
// a stream of commands must neither wait for the next step nor make the simulation run ahead of the wall clock.
void SimNode::WaitForPace(std::chrono::steady_clock::time_point until) {
  std::unique_lock<std::mutex> lock(mailbox_mutex_);
  while (mailbox_cv_.wait_until(lock, until, [this] { return stopping_ || !commands_.empty(); })) {
    if (stopping_) return;
    lock.unlock();
    RunCommands();
    lock.lock();
    if (paused_ || restart_pacing_) return;  // ~pause, ~reset or a new world: the loop decides what comes next
  }
}

// /clock, /tf and the topics at ~publish_rate (wall time) from the latest snapshot; never waits for a step. The
// per-state topics are sent when the snapshot changed, so a paused simulation sends nothing again but /clock.
void SimNode::PublishLoop() {
  WallClock::time_point next = WallClock::now();
  while (!stopping_) {
    const auto period =
        std::chrono::duration_cast<WallClock::duration>(std::chrono::duration<double>(1.0 / Live().publish_rate));
    publisher_->Cycle();
    next += period;
    const WallClock::time_point now = WallClock::now();
    if (next < now) next = now;  // a late cycle is not made up with a burst
    std::unique_lock<std::mutex> lock(stop_mutex_);
    stop_cv_.wait_until(lock, next, [this] { return stopping_.load(); });
  }
}

// /diagnostics once a second, on its own thread; it reads counters only, so a step in progress never delays it.
void SimNode::DiagnosticsLoop() {
  std::unique_lock<std::mutex> lock(stop_mutex_);
  while (!stop_cv_.wait_for(lock, std::chrono::seconds(1), [this] { return stopping_.load(); })) {
    lock.unlock();
    diagnostics_->Publish();
    lock.lock();
  }
}

}  // namespace implicit_sim
