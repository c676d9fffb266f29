// The commands the node applies to its World between two steps (on the physics thread, which alone owns the World):
// wrench and joint-effort commands, joint drives and trajectories, mouse drags, a reset, and the wrench handed to the
// core for the next step. Each refusal leaves the World unchanged and says why in *error (doc/ros_node.md).
#pragma once

#include <string>
#include <vector>

#include <sensor_msgs/JointState.h>
#include <trajectory_msgs/JointTrajectory.h>
#include <visualization_msgs/InteractiveMarkerFeedback.h>

#include "implicit_sim/ApplyBodyWrench.h"
#include "implicit_sim/BodyWrench.h"
#include "implicit_sim/JointCommand.h"
#include "implicit_sim/ros/node_params.h"
#include "implicit_sim/ros/world.h"

namespace implicit_sim {

// The largest command the node accepts: |force| (N), |torque| (N m) and |joint effort| (N m or N). Larger commands
// are refused; they only drive a step into divergence.
constexpr double kMaxCommand = 1e9;

// What a command needs besides the World: the simulation time it arrives at (s) and the live parameters in force.
struct CommandContext {
  double sim_time = 0.0;
  LiveParams live;
  std::string world_frame;
  bool drive_gravity_compensation = false;  // ~drive_gravity_compensation
};

// The body named `name`; -1 with *error when there is none or (must_move) it is fixed.
int FindBodyOrFail(const Model& model, const std::string& name, bool must_move, std::string* error);

// ~wrench_cmd: the body's commanded wrench at its link origin, world frame.
bool SetWrenchCommand(const CommandContext& context, const implicit_sim::BodyWrench& msg, World* world,
                      std::string* error);
// ~apply_body_wrench: a timed wrench from max(start_time, now) for `duration` (< 0: until cleared).
bool AddTimedWrench(const CommandContext& context, const implicit_sim::ApplyBodyWrench::Request& req, World* world,
                    std::string* error);
// ~set_joint_efforts and ~joint_effort_cmd: all efforts or none.
bool SetJointEfforts(const std::vector<std::string>& names, const std::vector<double>& efforts, World* world,
                     std::string* error);
bool SetJointEffortCommand(const CommandContext& context, const sensor_msgs::JointState& msg, World* world,
                           std::string* error);

// ~joint_command: targets and gains per joint (world_drives.cpp); stops the trajectories of those joints.
bool SetJointDrives(const CommandContext& context, const implicit_sim::JointCommand& msg, World* world,
                    std::string* error);
// ~joint_trajectory: followed from its stamp (0: now) with the live drive gains.
bool StartTrajectory(const CommandContext& context, const trajectory_msgs::JointTrajectory& msg, World* world,
                     std::string* error);
bool StartTrajectory(const CommandContext& context, const trajectory_msgs::JointTrajectory& msg, World* world,
                     std::string* error, uint64_t* id);  // *id: its Trajectory::id

// The drives the trajectories give for the step ending at t_end (s); finished trajectories are dropped, their drives
// keep holding the last point.
void UpdateTrajectoryDrives(double t_end, World* world);
// The drive targets of joint i of `trajectory` at simulation time t (s): the cubic Hermite curve clamped to the joint's
// limits, the start position before it starts, the last point after it ends.
void TrajectoryTargetAt(const Trajectory& trajectory, size_t i, const Joint& joint, double t, double* p, double* v);
// Ends the trajectory of this id (if it still runs): its joints' drives hold where the joints are, at rest.
void StopTrajectory(uint64_t id, World* world);

// A mouse drag's event applied to the World's drag springs (world_drives.cpp): a grab adds a spring at the clicked
// point, a move pulls it along, a release removes it.
enum class DragEvent { kNone, kGrab, kMove, kRelease };
DragEvent ApplyDragFeedback(const visualization_msgs::InteractiveMarkerFeedback& feedback, World* world);

// The wrench handed to the core for the step from sim_time to sim_time + h (s): the commands, the timed wrenches, the
// joint efforts and the drag springs, after the trajectories set the drives for the step's end.
void ComputeStepWrench(const CommandContext& context, double h, World* world);

// The bodies back at their initial state; warm start, contact forces, wrenches, efforts, drives, trajectories and
// drags cleared (the contact results keep their pair layout).
void ResetWorldState(World* world);

}  // namespace implicit_sim
