// Joint drives of the World: ~joint_command (implicit_sim/JointCommand: targets and gains per joint) and
// ~joint_trajectory (trajectory_msgs/JointTrajectory, interpolated in simulation time with the ~drive_stiffness and
// ~drive_damping gains). Both set Data::joint_drives, the core's implicit PD drives (core/model/joints.h JointDrive);
// a message is applied whole or refused whole (the node warns and counts it in /diagnostics).
#include "implicit_sim/ros/world_commands.h"

#include <algorithm>
#include <atomic>
#include <cmath>

#include "implicit_sim/core/base/format.h"
#include "implicit_sim/core/model/joints.h"

namespace implicit_sim {
namespace {

// Value i of an optional array: `fallback` when it is empty.
double Entry(const std::vector<double>& values, size_t i, double fallback) {
  return values.empty() ? fallback : values[i];
}

bool SameLengthOrEmpty(const std::vector<double>& values, size_t n, const char* what, std::string* error) {
  if (values.empty() || values.size() == n) return true;
  *error = std::string(what) + " must be empty or as long as name (" + std::to_string(n) + "), got " +
           std::to_string(values.size());
  return false;
}

// The joint indices of `names` (revolute, continuous or prismatic joints of the model); false naming the first other.
bool FindDrivenJoints(const Model& model, const std::vector<std::string>& names, std::vector<int>* joints,
                      std::string* error) {
  joints->resize(names.size());
  for (size_t i = 0; i < names.size(); ++i) {
    (*joints)[i] = model.FindJoint(names[i]);
    if ((*joints)[i] < 0 || !model.joints[(*joints)[i]].has_coordinate()) {
      *error = "no revolute, continuous or prismatic joint '" + names[i] + "' in the scene";
      return false;
    }
  }
  return true;
}

// Cubic Hermite interpolation on [0, T] from (p0, v0) to (p1, v1) at s in [0, T]: position and rate.
void Hermite(double p0, double v0, double p1, double v1, double T, double s, double* p, double* v) {
  const double u = s / T, u2 = u * u, u3 = u2 * u;
  *p = (2 * u3 - 3 * u2 + 1) * p0 + (u3 - 2 * u2 + u) * T * v0 + (-2 * u3 + 3 * u2) * p1 + (u3 - u2) * T * v1;
  *v = ((6 * u2 - 6 * u) * p0 + (3 * u2 - 4 * u + 1) * T * v0 + (-6 * u2 + 6 * u) * p1 + (3 * u2 - 2 * u) * T * v1) / T;
}

// Ends the following of `joint` by every trajectory (a later command took it over).
void StopTrajectoryOf(int joint, World* world) {
  for (Trajectory& trajectory : world->trajectories) {
    for (int& j : trajectory.joints) {
      if (j == joint) j = -1;
    }
  }
}

}  // namespace

bool SetJointDrives(const CommandContext& context, const implicit_sim::JointCommand& msg, World* world,
                    std::string* error) {
  const Model& model = *world->model;
  const size_t n = msg.name.size();
  std::vector<int> joints;
  if (!SameLengthOrEmpty(msg.position, n, "position", error) ||
      !SameLengthOrEmpty(msg.velocity, n, "velocity", error) ||
      !SameLengthOrEmpty(msg.stiffness, n, "stiffness", error) ||
      !SameLengthOrEmpty(msg.damping, n, "damping", error) || !FindDrivenJoints(model, msg.name, &joints, error)) {
    return false;
  }
  const LiveParams& live = context.live;
  std::vector<JointDrive> drives(n);
  for (size_t i = 0; i < n; ++i) {
    JointDrive& d = drives[i];
    d.position_target = Entry(msg.position, i, 0.0);
    d.velocity_target = Entry(msg.velocity, i, 0.0);
    d.stiffness = msg.position.empty() ? 0.0 : Entry(msg.stiffness, i, live.drive_stiffness);
    d.damping = Entry(msg.damping, i, live.drive_damping);
    d.gravity_compensation = context.drive_gravity_compensation;
    if (!CheckJointDrive(model.joints[joints[i]], d, error)) return false;
  }
  for (size_t i = 0; i < n; ++i) {
    world->data->joint_drives[joints[i]] = drives[i];
    StopTrajectoryOf(joints[i], world);
  }
  return true;
}

bool StartTrajectory(const CommandContext& context, const trajectory_msgs::JointTrajectory& msg, World* world,
                     std::string* error) {
  return StartTrajectory(context, msg, world, error, nullptr);
}

bool StartTrajectory(const CommandContext& context, const trajectory_msgs::JointTrajectory& msg, World* world,
                     std::string* error, uint64_t* id) {
  static std::atomic<uint64_t> last_id{0};
  const Model& model = *world->model;
  Trajectory trajectory;
  if (!FindDrivenJoints(model, msg.joint_names, &trajectory.joints, error)) return false;
  const size_t n = msg.joint_names.size();
  const LiveParams& live = context.live;
  trajectory.stiffness = live.drive_stiffness;
  trajectory.damping = live.drive_damping;
  trajectory.gravity_compensation = context.drive_gravity_compensation;
  if (n == 0 || msg.points.empty()) {
    *error = "a trajectory needs joint_names and points";
    return false;
  }
  if (trajectory.stiffness == 0.0 && trajectory.damping == 0.0) {
    *error = "~drive_stiffness and ~drive_damping are both 0: set the trajectory's gains first (dynamic_reconfigure)";
    return false;
  }
  // Stamp 0: start now (the JointTrajectory convention); otherwise at the stamp's simulation time.
  trajectory.start = msg.header.stamp.isZero() ? context.sim_time : msg.header.stamp.toSec();
  double last = -1.0;
  for (size_t k = 0; k < msg.points.size(); ++k) {
    const trajectory_msgs::JointTrajectoryPoint& point = msg.points[k];
    const double t = point.time_from_start.toSec();
    if (!std::isfinite(t) || t <= last || (k == 0 && t < 0.0)) {
      *error = "point " + std::to_string(k) + ": time_from_start must be >= 0 and increase strictly";
      return false;
    }
    last = t;
    if (point.positions.size() != n || !SameLengthOrEmpty(point.velocities, n, "velocities", error)) {
      if (error->empty()) *error = "point " + std::to_string(k) + ": positions must be as long as joint_names";
      return false;
    }
    for (size_t i = 0; i < n; ++i) {
      const JointDrive d{point.positions[i], Entry(point.velocities, i, 0.0), trajectory.stiffness,
                         trajectory.damping};
      if (!CheckJointDrive(model.joints[trajectory.joints[i]], d, error)) {
        *error = "point " + std::to_string(k) + ": " + *error;
        return false;
      }
    }
    trajectory.times.push_back(t);
    trajectory.positions.push_back(point.positions);
    trajectory.velocities.push_back(point.velocities.empty() ? std::vector<double>(n, 0.0) : point.velocities);
  }
  // The joints start from where they are: the segment before the first point begins at the current positions.
  for (int j : trajectory.joints) {
    trajectory.from.push_back(JointPosition(model, world->state, j));
    StopTrajectoryOf(j, world);
  }
  trajectory.id = ++last_id;
  if (id) *id = trajectory.id;
  world->trajectories.push_back(std::move(trajectory));
  return true;
}

void TrajectoryTargetAt(const Trajectory& trajectory, size_t i, const Joint& joint, double t, double* p, double* v) {
  const double s = t - trajectory.start;  // s since the trajectory's start
  const auto& times = trajectory.times;
  const size_t k = std::upper_bound(times.begin(), times.end(), s) - times.begin();  // next point index
  if (s < 0.0) {  // not started: hold where it began
    *p = trajectory.from[i], *v = 0.0;
  } else if (k == times.size()) {  // done: hold the last point
    *p = trajectory.positions.back()[i], *v = 0.0;
  } else {
    const double t0 = k == 0 ? 0.0 : times[k - 1];
    const double p0 = k == 0 ? trajectory.from[i] : trajectory.positions[k - 1][i];
    const double v0 = k == 0 ? 0.0 : trajectory.velocities[k - 1][i];
    Hermite(p0, v0, trajectory.positions[k][i], trajectory.velocities[k][i], times[k] - t0, s - t0, p, v);
  }
  if (joint.limited) *p = std::clamp(*p, joint.lower, joint.upper);  // a cubic may overshoot between points
}

void StopTrajectory(uint64_t id, World* world) {
  for (auto it = world->trajectories.begin(); it != world->trajectories.end(); ++it) {
    if (it->id != id) continue;
    for (int j : it->joints) {
      if (j < 0) continue;
      world->data->joint_drives[j] = JointDrive{JointPosition(*world->model, world->state, j), 0.0, it->stiffness,
                                                it->damping, it->gravity_compensation};
    }
    world->trajectories.erase(it);
    return;
  }
}

void UpdateTrajectoryDrives(double t_end, World* world) {
  World& w = *world;
  for (const Trajectory& trajectory : w.trajectories) {
    for (size_t i = 0; i < trajectory.joints.size(); ++i) {
      const int j = trajectory.joints[i];
      if (j < 0) continue;
      double p, v;
      TrajectoryTargetAt(trajectory, i, w.model->joints[j], t_end, &p, &v);
      w.data->joint_drives[j] =
          JointDrive{p, v, trajectory.stiffness, trajectory.damping, trajectory.gravity_compensation};
    }
  }
  // Finished trajectories keep holding their last point (the drives stay as set) but are no longer evaluated.
  w.trajectories.erase(std::remove_if(w.trajectories.begin(), w.trajectories.end(),
                                      [t_end](const Trajectory& trajectory) {
                                        return t_end - trajectory.start > trajectory.times.back();
                                      }),
                       w.trajectories.end());
}

}  // namespace implicit_sim
