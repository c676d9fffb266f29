// The scene loader's self-collision rules (internal to the core): which body pairs of one robot form no contact pair.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include <tinyxml2.h>
#include <urdf_model/model.h>

#include "implicit_sim/core/model/model.h"

namespace implicit_sim {
namespace loader {

// Fills model->excluded_pairs (sorted, unique) and model->self_collision_group. A robot is a set of bodies joined by
// joints other than `floating` ones and those to `world` (frame links count as their nearest body ancestor). As in
// Gazebo, a robot's bodies do not collide with each other (one group) unless <implicit_sim><self_collide link="L"/>
// names one of its links; every <implicit_sim><disable_collisions link1 link2 [reason]/> (an SRDF's element, copied)
// removes that pair. Throws std::invalid_argument naming the element for a link that is not in the scene. Call after
// the bodies and joints are loaded, before Model::Finalize.
void ExcludeSelfCollisions(const tinyxml2::XMLElement* sim, const urdf::ModelInterface& urdf, Model* model);

// One line naming the pairs of bodies of one self-collision group, neither disabled nor joined, whose shapes overlap
// by more than 1e-6 m at the bodies' start poses, with the depth bound of each; empty when there are none. Call after
// Model::Finalize.
std::string SelfOverlapNote(const Model& model);

}  // namespace loader
}  // namespace implicit_sim
