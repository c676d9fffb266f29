// The node's core: construction, the physics, publish and diagnostics threads, and stepping with the commanded
// wrenches. Only the physics thread touches world_; the others post commands to it (mailbox_) or read the snapshot it
// saves (NodePublisher::Latest), so no lock is held across a step.
#include "implicit_sim/ros/sim_node.h"  // first: its generated service type Step precedes the core's function Step

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <algorithm>
#include <limits>
#include <stdexcept>

#include "implicit_sim/core/step/time_stepper.h"

namespace implicit_sim {
namespace {

using WallClock = std::chrono::steady_clock;

// How long shutdown waits for the step in progress to stop (it is interrupted between two factorizations, so this is
// a safety net) before the node exits without it; roslaunch escalates SIGINT to SIGTERM only after 15 s.
constexpr double kShutdownGraceS = 2.0;
// At real time, a simulation that fell behind by more than this (s of wall time; a slow step) goes on at the real-time
// pace from where it is instead of catching up in a burst faster than real time.
constexpr double kMaxPaceLagS = 0.1;

}  // namespace

SimNode::SimNode(ros::NodeHandle nh, ros::NodeHandle pnh, StepInterrupt* stop)
    : nh_(nh), pnh_(pnh), params_(NodeParams::Read(pnh)), options_(params_.options), stop_(stop ? stop : &own_stop_) {
  world_ = BuildWorld(params_, ReadNodeScene(nh, params_), stop_);
  journal_ = std::make_unique<NodeJournal>(params_.input_journal, params_.replay_journal);
  PublishRobotDescription(world_->urdf);
  const Model& model = *world_->model;
  paused_ = params_.paused;
  live_ = std::make_unique<LiveTuning>(pnh, params_.live, params_.options, [this] {
    mailbox_.Post([this] { JournalUnreplayable("~set_parameters"); });
  });
  diagnostics_ = std::make_unique<NodeDiagnostics>(nh, pnh, "implicit_sim " + model.scene_name, paused_,
                                                   params_.min_real_time_fraction);
  drag_markers_ = std::make_unique<DragMarkers>(pnh, params_.world_frame, params_.interactive_markers,
                                                [this](const DragMarkers::Feedback& f) { OnDragFeedback(f); });
  publisher_ = std::make_unique<NodePublisher>(
      nh, pnh, params_, [this] { return live_->Live(); },
      [this](const NodeSnapshot& snapshot) { drag_markers_->SetUp(*snapshot.model, snapshot.state); },
      [this](const NodeSnapshot& snapshot) { drag_markers_->Follow(snapshot); });
  sensors_ = std::make_unique<NodeSensors>(pnh, params_.world_frame, params_.options.contact_threshold);
  sensors_->SetWorld(model, SimTime());
  SaveSnapshot();
  AdvertiseServices();
  publisher_->PublishStaticTf(model);
  drag_markers_->SetUp(model, world_->state);
  ROS_INFO("implicit_sim: scene '%s', %d moving bodies, %zu contact pairs, h = %g s, %s", model.scene_name.c_str(),
           model.num_moving(), model.pairs.size(), options_.h, paused_ ? "paused" : "running");
}

SimNode::~SimNode() {
  if (run_steps_server_) run_steps_server_->shutdown();
  if (follow_trajectory_server_) follow_trajectory_server_->shutdown();
  StopThreads(std::numeric_limits<double>::infinity());
  drag_markers_.reset();
}

void SimNode::Run() {
  ros::AsyncSpinner spinner(4);  // services wait for the physics thread: several may wait at once
  spinner.start();
  publisher_->PublishClock(SimTime());
  mailbox_.SetStepCutter(kCutStepAfter, [this] { CutStepForCommand(); });
  master_watch_ = std::make_unique<MasterWatch>(
      params_.exit_on_master_loss ? MasterWatch::Policy::kExit : MasterWatch::Policy::kReregister, [this] {
        std::vector<std::string> names;
        for (const ros::ServiceServer& service : services_) names.push_back(service.getService());
        for (const char* own : {"get_loggers", "set_logger_level", "set_parameters"}) {
          names.push_back(ros::names::resolve("~" + std::string(own)));
        }
        return names;
      });
  StartThread(&physics_thread_, &SimNode::PhysicsLoop);
  StartThread(&publish_thread_, &SimNode::PublishLoop);
  StartThread(&diagnostics_thread_, &SimNode::DiagnosticsLoop);
  run_steps_server_->start();
  follow_trajectory_server_->start();
  ros::waitForShutdown();
  if (!StopThreads(kShutdownGraceS)) {
    // The step did not stop in time (a single factorization or Ipopt iteration that long): exit without it (nothing is
    // lost; ROS is already shut down).
    std::fprintf(stderr, "implicit_sim: a step was still running %g s after shutdown; exiting without it\n",
                 kShutdownGraceS);
    std::fflush(nullptr);
    std::_Exit(0);
  }
  run_steps_server_->shutdown();
  follow_trajectory_server_->shutdown();
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
  stopping_ = true;
  stop_->Request();       // a scene loading on a service thread stops between two links
  interrupt_.Request();  // the step in progress stops between two factorizations
  mailbox_.Stop();
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

CommandContext SimNode::Context() const {
  return CommandContext{SimTime(), live_->Live(), params_.world_frame, params_.drive_gravity_compensation};
}

void SimNode::CutStepForCommand() {
  std::lock_guard<std::mutex> lock(cut_mutex_);
  if (!step_running_ || !step_cuttable_ || step_cut_) return;
  step_cut_ = true;
  interrupt_.Request();  // the step stops between two factorizations and is undone
}

bool SimNode::StepOnce(double rtf, bool paced) {
  live_->CopySolverOptions(&options_);
  std::string replay_refusal;
  if (journal_->replaying() &&
      !journal_->Replay(
          step_count_, [this](const JournalRecord& r, std::string* refusal) { return ApplyJournalRecord(r, refusal); },
          &replay_refusal)) {
    RefuseReplayStep(replay_refusal);
    return true;
  }
  ComputeStepWrench(Context(), options_.h, world_.get());
  World& w = *world_;
  StepReport report;
  w.data->interrupt = &interrupt_;
  state_before_ = w.state;
  diagnostics_->BeginStep();
  {
    std::lock_guard<std::mutex> lock(cut_mutex_);
    step_running_ = true;
    step_cuttable_ = !redoing_cut_step_;
  }
  try {
    report = Step(*w.model, options_, &w.state, w.data.get(), &w.wrench_W);
  } catch (const std::exception& e) {
    report.advanced = false;
    report.fault = StepFault::kNoFiniteSolution;
    report.fault_detail = e.what();
  }
  bool cut = false;
  {
    std::lock_guard<std::mutex> lock(cut_mutex_);
    step_running_ = false;
    cut = step_cut_;
    step_cut_ = false;
    // A cut requested after the step's last check: the request must not stop the next step.
    if (cut && report.fault != StepFault::kInterrupted && !stopping_) interrupt_.Clear();
  }
  if (report.fault == StepFault::kInterrupted) {  // undone: no step, no fault (a command, a cancelled job, shutdown)
    if (!stopping_) interrupt_.Clear();
    redoing_cut_step_ = cut;
    return false;
  }
  redoing_cut_step_ = false;
  ++step_count_;
  std::string failure;
  if (report.advanced) {
    stepped_ = true;
    const bool rattle = options_.scheme == StepperOptions::Scheme::kRattle && report.paper_fallbacks == 0;
    sensors_->Sample(*w.model, state_before_, w.state, options_.h,
                     rattle ? StepperOptions::Scheme::kRattle : StepperOptions::Scheme::kPaper, w.data->contacts,
                     w.wrench_W, w.joint_efforts, SimTime());
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
  double penetration = 0.0;  // m
  for (const ContactResult& contact : w.data->contacts) penetration = std::max(penetration, -contact.gap);
  diagnostics_->CountStep(report, failure, paused_, SimTime(), rtf, paced ? live_->Live().real_time_factor : 0.0,
                          penetration);
  if (!report.advanced) mailbox_.FailJob(SimTime(), failure);
  SaveSnapshot();
  publisher_->PublishClockThrottled(SimTime(), !report.advanced);
  publisher_->PublishStepStats(report, SimTime(), step_count_, rtf);
  return true;
}

// The replay cannot go on: pause (and end a ~step or ~run_steps job) before the step, which is not taken.
void SimNode::RefuseReplayStep(const std::string& refusal) {
  paused_ = true;
  ROS_ERROR("implicit_sim: replay stops: %s; the simulation is paused", refusal.c_str());
  diagnostics_->HoldFault(refusal);
  mailbox_.FailJob(SimTime(), refusal);
}

void SimNode::ResetWorld() {
  time_offset_ = SimTime();  // simulation time keeps increasing; bodies return to their initial state
  ResetWorldState(world_.get());
  restart_pacing_ = true;
  stepped_ = false;
  SaveSnapshot();
}

void SimNode::OnDragFeedback(const DragMarkers::Feedback& feedback) {
  mailbox_.Post([this, feedback] {
    const DragEvent event = ApplyDragFeedback(*feedback, world_.get());
    if (event == DragEvent::kGrab) JournalUnreplayable("~drag");
    if (event == DragEvent::kGrab || event == DragEvent::kRelease) {
      drag_markers_->SetDragged(feedback->marker_name, event == DragEvent::kGrab);
    }
  });
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
    const PhysicsMailbox::Work work = mailbox_.WaitForWork(!paused_);
    if (work == PhysicsMailbox::Work::kStop) return;
    if (work == PhysicsMailbox::Work::kJobStep) {
      if (StepOnce(0.0, false)) mailbox_.CountJobStep(SimTime());  // a refused step ends the job itself
      continue;
    }
    if (paused_) continue;
    if (restart_pacing_) {
      pace_wall = rtf_wall = WallClock::now();
      pace_sim = rtf_sim = SimTime();
      restart_pacing_ = false;
    }
    StepOnce(rtf_, true);
    const double sim = SimTime();
    const auto now = WallClock::now();
    const double window = std::chrono::duration<double>(now - rtf_wall).count();
    if (window >= 1.0) {  // real-time factor over the last second
      rtf_ = (sim - rtf_sim) / window;
      rtf_sim = sim;
      rtf_wall = now;
    }
    const double real_time_factor = live_->Live().real_time_factor;
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
        // Until the step is due, the commands that arrive run at once: a stream of commands must neither wait for
        // the next step nor make the simulation run ahead of the wall clock. ~pause, ~reset or a new world end the
        // wait: the loop decides what comes next.
        mailbox_.RunUntil(due, [this] { return paused_ || restart_pacing_; });
      }
    }
  }
}

// /clock, /tf and the topics at ~publish_rate (wall time) from the latest snapshot; never waits for a step. The
// per-state topics are sent when the snapshot changed, so a paused simulation sends nothing again but /clock.
void SimNode::PublishLoop() {
  WallClock::time_point next = WallClock::now();
  while (!stopping_) {
    const std::chrono::duration<double> period_s(1.0 / live_->Live().publish_rate);
    const auto period = std::chrono::duration_cast<WallClock::duration>(period_s);
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
    master_watch_->Check();
    lock.lock();
  }
}

}  // namespace implicit_sim
