// Scenes as URDF: a root link `world`, moving bodies on `floating` joints, static bodies on `fixed` joints.
// The implicit shapes and the simulation parameters live in extension elements that stock URDF tools ignore:
//   inside <collision>:   <implicit type="..." .../>    (optional for stock sphere, box and cylinder geometry)
//   under <robot>:        <implicit_sim gravity="0 0 -9.81">
//                           <friction mu=".." e_t=".." e_o=".." e_r=".."/>                   default of every pair
//                           <friction link1=".." link2=".." mu=".." .../>                     one pair
//                           <body link=".." velocity="vx vy vz" angular_velocity="wx wy wz"
//                                 force="fx fy fz" torque="tx ty tz" locked="y rx rz"/>
//                         </implicit_sim>
// doc/scenes.md documents every element and attribute with units and allowed ranges.
#pragma once

#include <string>

#include "implicit_sim/core/model/model.h"

namespace implicit_sim {

// Throws std::invalid_argument naming the link, joint or attribute and the allowed range. Never returns a partial
// model.
Model LoadSceneFromString(const std::string& urdf_xml, const std::string& scene_name = "scene");
Model LoadSceneFromFile(const std::string& path);

}  // namespace implicit_sim
