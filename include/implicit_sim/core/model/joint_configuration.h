// Setting a robot's configuration by joint positions (the node's ~set_joint_positions): the bodies below the named
// joints are placed where the joints put them, with every joint equality exactly satisfied, and left at rest.
#pragma once

#include <map>
#include <string>

#include "implicit_sim/core/model/model.h"
#include "implicit_sim/core/model/state.h"

namespace implicit_sim {

// The child's pose that holds `joint` exactly at position q (rad or m; fixed joints: 0) with its parent at X_WP:
// joint origins coincide (x_C = x_P, plus q along the axis for a prismatic joint) and the child's joint frame is the
// parent's turned by q - offset about the axis (revolute, continuous), so that JointPosition returns q (revolute
// angles modulo 2 pi).
Pose ChildPoseAtPosition(const Joint& joint, const Pose& X_WP, double q);

// Sets the joints named in `positions` (model joint index -> rad or m) in *state: every body in the subtree of a named
// joint is re-placed from its parent through each joint below it, at the requested position for a named joint, at
// c q_leader + offset for a mimic follower of a re-placed leader, and at its current position for the others (so
// their drift is removed too); those bodies get zero velocity. Other bodies keep their state. Returns false and
// changes nothing, with a message naming the joint and the allowed range in *error, for a joint index out of range, a
// fixed joint, a mimic follower (set its leader), a value that is not finite or beyond a limit by more than
// kJointLimitRoundOff.
bool SetJointPositions(const Model& model, const std::map<int, double>& positions, State* state, std::string* error);

}  // namespace implicit_sim
