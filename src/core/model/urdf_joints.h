// The scene loader's joint part (internal to the core): checks of <joint> elements before urdfdom parses them, the
// joint starts of <implicit_sim><joint>, the initial link poses along the joint tree, and Model::joints.
#pragma once

#include <map>
#include <string>

#include <tinyxml2.h>
#include <urdf_model/model.h>

#include "implicit_sim/core/model/model.h"

namespace implicit_sim {
namespace loader {

// Refuses an unsupported type or a malformed <axis>, <limit> or <dynamics> (naming the joint and attribute), so that
// urdfdom never refuses one with a message that names nothing.
void CheckJointElement(const tinyxml2::XMLElement* joint, const std::string& where);

// Initial joint position (rad or m) and velocity (rad/s or m/s) and a constant effort, from
// <implicit_sim><joint name position velocity effort/>.
struct JointStart {
  double position = 0.0;
  double velocity = 0.0;
  double effort = 0.0;  // constant applied effort, N m or N
};
using JointStarts = std::map<std::string, JointStart>;
JointStarts ReadJointStarts(const tinyxml2::XMLElement* sim, const urdf::ModelInterface& urdf);

// Whether a chain of fixed joints welds the link to 'world' (then it is a fixed body).
bool IsWeldedToWorld(const urdf::Link& link);
// The initial pose of the link frame in the world: the joint origins and initial joint motions from 'world' down.
Pose InitialLinkPose(const urdf::Link& link, const JointStarts& starts);

// Fills model->joints, parents before children, with every revolute, continuous and prismatic joint and every fixed
// joint whose child moves, and gives each jointed child its initial velocity from its parent's and the joint's.
// The bodies must be loaded (poses, body settings) and model->joints must be empty; call before Model::Finalize.
void BuildJoints(const urdf::ModelInterface& urdf, const JointStarts& starts, Model* model);

}  // namespace loader
}  // namespace implicit_sim
