// The scene loader's self-collision rules (internal to the core): which body pairs of one robot form no contact pair.
#pragma once

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
// joints are loaded, before Model::Finalize.
void ExcludeSelfCollisions(const tinyxml2::XMLElement* sim, const urdf::ModelInterface& urdf, Model* model);

}  // namespace loader
}  // namespace implicit_sim
