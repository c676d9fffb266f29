// ~follow_trajectory (implicit_sim/FollowTrajectory, doc/ros_node.md#following-a-trajectory): a trajectory of
// ~joint_trajectory that the caller waits for, with path and goal tolerances, feedback (desired, actual, error) and a
// result code, as control_msgs/FollowJointTrajectory. The action thread looks at the world between two steps, every
// kPollPeriodS of wall time: tolerances are checked at those moments, in simulation time.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include "implicit_sim/core/model/joints.h"
#include "implicit_sim/ros/sim_node.h"

namespace implicit_sim {
namespace {

using Result = implicit_sim::FollowTrajectoryResult;
constexpr double kPollPeriodS = 0.02;  // wall time between two looks (and feedback messages)

// Tolerances by joint name: {position, velocity} (0: unchecked). False with *error for a negative or non-finite value
// or a joint the trajectory does not move (*code INVALID_JOINTS).
bool ReadTolerances(const std::vector<implicit_sim::JointTolerance>& list, const std::vector<std::string>& joints,
                    const char* what, std::map<std::string, std::pair<double, double>>* out, int* code,
                    std::string* error) {
  for (const implicit_sim::JointTolerance& t : list) {
    if (std::find(joints.begin(), joints.end(), t.name) == joints.end()) {
      *code = Result::INVALID_JOINTS;
      *error = std::string(what) + ": joint '" + t.name + "' is not in the trajectory";
      return false;
    }
    if (!(t.position >= 0.0 && t.velocity >= 0.0 && std::isfinite(t.position) && std::isfinite(t.velocity))) {
      *code = Result::INVALID_GOAL;
      *error = std::string(what) + " of joint '" + t.name + "': position and velocity must be finite and >= 0";
      return false;
    }
    (*out)[t.name] = {t.position, t.velocity};
  }
  return true;
}

// Whether |error| is within the tolerance of each joint (a tolerance of 0 is not checked); *joint names the first
// that is not.
bool Within(const std::vector<std::string>& names, const implicit_sim::FollowTrajectoryFeedback& feedback,
            const std::map<std::string, std::pair<double, double>>& tolerances, std::string* joint) {
  for (size_t i = 0; i < names.size(); ++i) {
    const auto it = tolerances.find(names[i]);
    if (it == tolerances.end()) continue;
    const auto [position, velocity] = it->second;
    if ((position > 0.0 && std::abs(feedback.error.positions[i]) > position) ||
        (velocity > 0.0 && std::abs(feedback.error.velocities[i]) > velocity)) {
      *joint = names[i] + " (position error " + std::to_string(feedback.error.positions[i]) + ", velocity error " +
               std::to_string(feedback.error.velocities[i]) + ")";
      return false;
    }
  }
  return true;
}

}  // namespace

void SimNode::OnFollowTrajectoryGoal(const implicit_sim::FollowTrajectoryGoalConstPtr& goal) {
  Result result;
  const auto finish = [&](int code, const std::string& text) {
    result.error_code = code;
    result.error_string = text;
    if (code == Result::SUCCESSFUL) {
      follow_trajectory_server_->setSucceeded(result, text);
    } else {
      follow_trajectory_server_->setAborted(result, text);
    }
  };
  const std::vector<std::string>& names = goal->trajectory.joint_names;
  std::map<std::string, std::pair<double, double>> path, at_goal;
  int code = Result::SUCCESSFUL;
  std::string error;
  const double goal_time = goal->goal_time_tolerance.toSec();
  if (!ReadTolerances(goal->path_tolerance, names, "path_tolerance", &path, &code, &error) ||
      !ReadTolerances(goal->goal_tolerance, names, "goal_tolerance", &at_goal, &code, &error)) {
    return finish(code, error);
  }
  if (!(goal_time >= 0.0)) return finish(Result::INVALID_GOAL, "goal_time_tolerance must be >= 0");
  uint64_t id = 0;
  double end_time = 0.0;  // s of simulation time: the last point
  bool started = false;
  const bool ran = mailbox_.RunBetweenSteps([&] {
    started = StartTrajectory(Context(), goal->trajectory, world_.get(), &error, &id);
    if (!started) return;
    JournalUnreplayable("~follow_trajectory");
    const Trajectory& trajectory = world_->trajectories.back();
    end_time = trajectory.start + trajectory.times.back();
  });
  if (!ran) return finish(Result::INTERRUPTED, "the node is shutting down");
  if (!started) return finish(Result::INVALID_GOAL, error);

  const size_t n = names.size();
  implicit_sim::FollowTrajectoryFeedback feedback;
  feedback.joint_names = names;
  for (auto* point : {&feedback.desired, &feedback.actual, &feedback.error}) {
    point->positions.assign(n, 0.0);
    point->velocities.assign(n, 0.0);
  }
  const std::vector<double>& last = goal->trajectory.points.back().positions;
  while (true) {
    std::this_thread::sleep_for(std::chrono::duration<double>(kPollPeriodS));
    if (follow_trajectory_server_->isPreemptRequested() || !ros::ok()) {
      mailbox_.RunBetweenSteps([&] { StopTrajectory(id, world_.get()); });
      result.error_code = Result::SUCCESSFUL;
      result.error_string = "cancelled: the joints hold where they are";
      follow_trajectory_server_->setPreempted(result, result.error_string);
      return;
    }
    int verdict = 1;  // 1: go on; otherwise a result code
    std::string text;
    const bool looked = mailbox_.RunBetweenSteps([&] {
      const Model& model = *world_->model;
      const double now = SimTime();
      const Trajectory* running = nullptr;
      for (const Trajectory& t : world_->trajectories) {
        if (t.id == id) running = &t;
      }
      for (size_t i = 0; i < n; ++i) {
        const int j = model.FindJoint(names[i]);
        const bool taken_over = running && running->joints[i] < 0;
        if (j < 0 || taken_over || (!running && now < end_time)) {
          verdict = Result::INTERRUPTED;
          text = j < 0 ? "joint '" + names[i] + "' left the world"
                       : taken_over ? "a later command took joint '" + names[i] + "' over"
                                    : "the trajectory ended early (~reset or a world edit)";
          return;
        }
        double p = last[i], v = 0.0;
        if (running) TrajectoryTargetAt(*running, i, model.joints[j], now, &p, &v);
        feedback.desired.positions[i] = p;
        feedback.desired.velocities[i] = v;
        feedback.actual.positions[i] = JointPosition(model, world_->state, j);
        feedback.actual.velocities[i] = JointVelocity(model, world_->state, j);
        feedback.error.positions[i] = JointDrivePositionError(model.joints[j], p, feedback.actual.positions[i]);
        feedback.error.velocities[i] = v - feedback.actual.velocities[i];
      }
      feedback.header.stamp = ros::Time().fromSec(now);
      std::string joint;
      if (now < end_time) {
        if (!Within(names, feedback, path, &joint)) {
          StopTrajectory(id, world_.get());
          verdict = Result::PATH_TOLERANCE_VIOLATED;
          text = "path tolerance violated at t = " + std::to_string(now) + " s by " + joint;
        }
      } else if (Within(names, feedback, at_goal, &joint)) {
        verdict = Result::SUCCESSFUL;
        text = "reached the last point at t = " + std::to_string(now) + " s";
      } else if (now > end_time + goal_time) {
        verdict = Result::GOAL_TOLERANCE_VIOLATED;
        text = "goal tolerance not reached " + std::to_string(goal_time) + " s after the last point: " + joint;
      }
    });
    if (!looked) return finish(Result::INTERRUPTED, "the node is shutting down");
    follow_trajectory_server_->publishFeedback(feedback);
    if (verdict != 1) return finish(verdict, text);
  }
}

}  // namespace implicit_sim
