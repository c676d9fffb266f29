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

// Fills model->excluded_pairs (sorted, unique). A robot is a set of bodies joined by joints other than `floating`
// ones and those to `world` (frame links count as their nearest body ancestor). As in Gazebo, a robot's bodies do not
// collide with each other unless <implicit_sim><self_collide link="L"/> names one of its links; every
// <implicit_sim><disable_collisions link1 link2 [reason]/> (an SRDF's element, copied) removes that pair too.
// Throws std::invalid_argument naming the element for a link that is not in the scene. Call after the bodies and
// joints are loaded, before Model::Finalize. Returns the pairs left out only because their robot does not
// self-collide (none an SRDF names), sorted.
std::vector<std::pair<int, int>> ExcludeSelfCollisions(const tinyxml2::XMLElement* sim, const urdf::ModelInterface& urdf, Model* model);

// One line naming the pairs of `not_self_colliding` (from ExcludeSelfCollisions) that no joint joins and whose shapes
// overlap by more than 1e-6 m at the bodies' start poses, with the depth bound of each; empty when there are none.
// Call after Model::Finalize.
std::string SelfOverlapNote(const Model& model, const std::vector<std::pair<int, int>>& not_self_colliding);

}  // namespace loader
}  // namespace implicit_sim
