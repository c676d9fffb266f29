// Scene editing for an open world: the model is const after loading, so the node (~spawn, ~delete, ~load_scene,
// robot_description) changes the world by editing the scene's URDF text (doc/scenes.md) with these functions and
// loading the result again. All three are pure functions on text: they never touch files, the output depends on the
// inputs only (same input, same bytes), and on an error they throw std::invalid_argument with a message naming the
// link, joint, element or attribute at fault. The output is printed by tinyxml2 (re-indented; comments kept).
//
// Frames: W is the world (the scene's link `world`); O is the addition's frame, the frame its own `world` link (a
// scene addition) or its root link (a robot addition) takes in W. Lengths in m, angles in rad, velocities in m/s and
// rad/s, all in the world frame W unless a name says otherwise.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "implicit_sim/core/base/types.h"

namespace implicit_sim {

// What to add to a scene (~spawn).
struct SceneAddition {
  // The addition's URDF: a scene (root link `world`, bodies on floating or fixed joints to it, jointed robots hanging
  // on it) or a robot (one root link, not `world`).
  std::string urdf;
  // Absolute directory that relative <mesh filename> and <texture filename> values in `urdf` resolve against
  // ("" = leave them as written). Names with a scheme ("package://", "file://") or starting with '/' are kept.
  std::string base_dir;
  // Prepended to every link and joint name of the addition and to the names in its <implicit_sim> entries; characters
  // from [A-Za-z0-9_/-] only ("" = no renaming).
  std::string prefix;
  // Pose of O in W: every origin of a joint whose parent is the addition's `world` (free, static and jointed bodies
  // alike) becomes X_WO * origin; a robot's root is attached at X_WO.
  Pose X_WO = Pose::Identity();
  // Rigid motion of O, world frame: every new free body (a link on a `floating` joint to world) starts with
  //   v_body = R_WO v_own + v_WO + w_WO x (p_body - p_WO),   w_body = R_WO w_own + w_WO,
  // where p_body is the body's centre of mass in W, p_WO the origin of O, and v_own, w_own the addition's own initial
  // twist of that body (its <implicit_sim><body velocity angular_velocity>, zero when absent). Bodies on other joints
  // take their twist from their parent, as the loader does; a welded robot (floating_root = false) gets none.
  Vec3 v_WO = Vec3::Zero();  // m/s, velocity of the origin of O
  Vec3 w_WO = Vec3::Zero();  // rad/s
  // Robot additions only: the root link is welded to `world` at X_WO (false) or put on a floating joint there (true).
  bool floating_root = false;
  // Start positions of the addition's joints (rad or m) by the addition's own joint names (before the prefix): each
  // becomes, or overrides the position of, the addition's <implicit_sim><joint name position>; the loader checks it
  // against the joint's type and limits.
  std::map<std::string, double> joint_positions;
  // true: the addition's robots collide with themselves (an <implicit_sim><self_collide> per robot); default off, as in
  // Gazebo (doc/scenes.md#self-collision).
  bool self_collide = false;
  // An SRDF's text ("" = none): its <disable_collisions link1 link2 reason> elements, renamed with the prefix, join the
  // scene's <implicit_sim>; its other elements (groups, end effectors, virtual joints) do not concern the simulator.
  std::string srdf;
};

// The scene with the addition merged in:
// - the addition's links and joints (renamed with the prefix, also in joint <parent>, <child> and <mimic joint>)
//   appended after the scene's elements, in the addition's order; its `world` link is the scene's `world`;
// - a robot's root attached to `world` by a joint `<prefix><root>_joint` (fixed, or floating with floating_root) at
//   X_WO;
// - the addition's <implicit_sim> entries <friction link1 link2>, <body link> and <joint name> renamed and appended
//   to the scene's <implicit_sim> (created if absent). The addition's DEFAULT friction (<friction> without link1 and
//   link2) and its gravity are ignored: the scene's default friction and gravity apply to the new bodies too.
//   <body force torque locked> stay as written (world axes, like gravity);
// - relative mesh and texture file names made absolute against base_dir;
// - the addition's top-level <material> definitions appended, except one identical to a scene material of the same
//   name (dropped: the scene's is used); a different one of the same name is renamed with the prefix, together with
//   the addition's references to it;
// - joint_positions, self_collide and the SRDF's <disable_collisions> as <implicit_sim> entries of the addition;
// - other top-level elements of the addition (<gazebo>, <transmission>, comments) are not copied.
// *added_links (if not null) receives the new link names in the addition's order.
// Throws std::invalid_argument (the result is not produced) naming the thing when: either text is not a URDF robot
// (not well-formed XML, no <robot>, a link or joint without a name or defined twice, a joint between undefined
// links), the scene has no `world` link, the addition has no link besides `world` or (a robot) not exactly one root
// link, a new link or joint name already exists in the scene, the prefix has a character outside [A-Za-z0-9_/-],
// base_dir is not absolute, X_WO is not finite or not a rotation, the twist is not finite, an origin that is composed
// has an attribute other than xyz and rpy (the loader refuses quat_xyzw) or a bad number, a new free body with a
// locked axis would start moving along it, joint_positions names a joint the addition lacks or a value that is not
// finite, or the SRDF is not an XML <robot> or names a link the addition lacks.
std::string AddToScene(const std::string& scene_urdf, const SceneAddition& addition,
                       std::vector<std::string>* added_links);

// The scene with start positions of its joints (rad or m, by name) and an SRDF's <disable_collisions> pairs ("" =
// none) as <implicit_sim> entries: what ~load_scene takes beside the scene and the node's robot_description_semantic
// parameter gives. Throws std::invalid_argument as AddToScene does, for a joint or link the scene lacks.
std::string WithStartEntries(const std::string& scene_urdf, const std::map<std::string, double>& joint_positions,
                             const std::string& srdf);

// The scene without the named links and everything that hangs on them through joints (their subtrees), without the
// joints to and inside those subtrees, and without the <implicit_sim> entries that name them (<friction> pairs with
// either link removed, <body link>, <joint name> of a removed joint) and <gazebo reference> elements of removed links.
// *removed_links (if not null) receives every removed link, named ones and their subtrees, in the scene's order.
// Throws std::invalid_argument naming it for a link name that is not in the scene or is `world`, and when the scene is
// not a URDF robot. A scene with nothing left to simulate is not an error here (the loader decides).
std::string RemoveFromScene(const std::string& scene_urdf, const std::vector<std::string>& links,
                            std::vector<std::string>* removed_links);

// The scene as robot_state_publisher and rviz's RobotModel should see it: the subtrees on `floating` joints to world
// and on `planar` joints removed (the simulator publishes those bodies' tf itself; robot_state_publisher would treat
// either joint as fixed and publish a wrong static transform) and the <implicit_sim> element dropped. Jointed robots and static links
// stay. The result is a valid URDF (urdfdom parses it) even when only `world` and static links remain. Throws
// std::invalid_argument when the scene is not a URDF robot.
std::string RobotDescriptionOf(const std::string& scene_urdf);

}  // namespace implicit_sim
