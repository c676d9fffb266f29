// XML helpers of the scene editor (scene_edit.cpp): parsing a URDF text into its <robot> element with the tree checks
// the editor relies on, reading and writing <origin> elements with numbers in the classic "C" locale, and printing.
// Internal to the core.
#pragma once

#include <map>
#include <string>
#include <vector>

#include <tinyxml2.h>

#include "implicit_sim/core/base/types.h"

namespace implicit_sim {
namespace scene_xml {

[[noreturn]] void Fail(const std::string& message);  // throws std::invalid_argument

// The <robot> element of `text` parsed into `doc`, after checking that every link and joint has a unique non-empty
// name and every joint a <parent link> and <child link> naming defined links. `what` names the text in errors.
tinyxml2::XMLElement* ParseRobot(const std::string& text, const std::string& what, tinyxml2::XMLDocument* doc);

// The document as text (tinyxml2's indented printing).
std::string Print(const tinyxml2::XMLDocument& doc);
// One element and its children as compact text (to compare two elements).
std::string PrintCompact(const tinyxml2::XMLElement& e);

// The direct children of `robot` with tag `tag`, in document order.
std::vector<tinyxml2::XMLElement*> ChildrenNamed(tinyxml2::XMLElement* robot, const char* tag);
// The link named by `<end link="..."/>` ("parent" or "child") of a joint that ParseRobot checked.
std::string JointLink(const tinyxml2::XMLElement* joint, const char* end);
// The joints of `robot` by the name of their parent link, each list in document order.
std::map<std::string, std::vector<tinyxml2::XMLElement*>> JointsByParent(tinyxml2::XMLElement* robot);

// Attribute `name` of `e` as 3 finite numbers; `fallback` when absent. `where` names the element in errors.
Vec3 ReadVec3(const tinyxml2::XMLElement* e, const char* name, const std::string& where, const Vec3& fallback);
std::string Vec3Text(const Vec3& v);  // "x y z", shortest round-trip numbers, "0" for -0

// The pose given by the <origin xyz rpy> child of `e` (identity without one). Only xyz and rpy are accepted (the loader
// refuses quat_xyzw, which urdfdom would ignore).
Pose ReadOrigin(const tinyxml2::XMLElement* e, const std::string& where);
// Sets the <origin> child of `joint` (created after <child> if absent) to X, as xyz and rpy.
void WriteOrigin(tinyxml2::XMLElement* joint, const Pose& X);

// URDF's roll-pitch-yaw: R = Rz(yaw) Ry(pitch) Rx(roll), rpy = (roll, pitch, yaw); RpyOf is exact to rounding for every
// rotation, gimbal lock included (pitch in [-pi/2, pi/2]).
Mat3 RotationOfRpy(const Vec3& rpy);
Vec3 RpyOf(const Mat3& R);

}  // namespace scene_xml
}  // namespace implicit_sim
