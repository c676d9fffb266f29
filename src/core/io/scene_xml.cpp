#include "scene_xml.h"

#include <cmath>
#include <locale>
#include <set>
#include <sstream>
#include <stdexcept>

#include "implicit_sim/core/base/format.h"

namespace implicit_sim {
namespace scene_xml {

using tinyxml2::XMLElement;

void Fail(const std::string& message) { throw std::invalid_argument(message); }

namespace {

std::string NameOf(const XMLElement* e) {
  const char* name = e->Attribute("name");
  return name ? name : "";
}

// Unique non-empty link names; returns them.
std::set<std::string> CheckLinks(XMLElement* robot, const std::string& what) {
  std::set<std::string> links;
  for (XMLElement* link : ChildrenNamed(robot, "link")) {
    const std::string name = NameOf(link);
    if (name.empty()) Fail(what + " is not a URDF robot: a <link> has no attribute 'name'");
    if (!links.insert(name).second) Fail(what + ": link '" + name + "' is defined more than once");
  }
  return links;
}

// Unique non-empty joint names, each joint between defined links.
void CheckJoints(XMLElement* robot, const std::set<std::string>& links, const std::string& what) {
  std::set<std::string> joints;
  for (XMLElement* joint : ChildrenNamed(robot, "joint")) {
    const std::string name = NameOf(joint);
    if (name.empty()) Fail(what + " is not a URDF robot: a <joint> has no attribute 'name'");
    if (!joints.insert(name).second) Fail(what + ": joint '" + name + "' is defined more than once");
    for (const char* end : {"parent", "child"}) {
      const XMLElement* e = joint->FirstChildElement(end);
      const char* link = e ? e->Attribute("link") : nullptr;
      if (!link) Fail(what + ": joint '" + name + "' has no <" + end + " link=\"...\"/>");
      if (!links.count(link)) Fail(what + ": joint '" + name + "': <" + end + "> link '" + link + "' is not defined");
    }
  }
}

}  // namespace

XMLElement* ParseRobot(const std::string& text, const std::string& what, tinyxml2::XMLDocument* doc) {
  if (doc->Parse(text.c_str(), text.size()) != tinyxml2::XML_SUCCESS) {
    Fail(what + " is not a URDF robot: not well-formed XML (" + doc->ErrorStr() + ")");
  }
  XMLElement* robot = doc->FirstChildElement("robot");
  if (!robot) Fail(what + " is not a URDF robot: no <robot> element");
  CheckJoints(robot, CheckLinks(robot, what), what);
  return robot;
}

std::string Print(const tinyxml2::XMLDocument& doc) {
  tinyxml2::XMLPrinter printer;
  doc.Print(&printer);
  return printer.CStr();
}

std::string PrintCompact(const XMLElement& e) {
  tinyxml2::XMLPrinter printer(nullptr, /*compact=*/true);
  e.Accept(&printer);
  return printer.CStr();
}

std::vector<XMLElement*> ChildrenNamed(XMLElement* robot, const char* tag) {
  std::vector<XMLElement*> out;
  for (XMLElement* e = robot->FirstChildElement(tag); e; e = e->NextSiblingElement(tag)) out.push_back(e);
  return out;
}

std::string JointLink(const XMLElement* joint, const char* end) {
  return joint->FirstChildElement(end)->Attribute("link");
}

std::map<std::string, std::vector<XMLElement*>> JointsByParent(XMLElement* robot) {
  std::map<std::string, std::vector<XMLElement*>> by_parent;
  for (XMLElement* joint : ChildrenNamed(robot, "joint")) by_parent[JointLink(joint, "parent")].push_back(joint);
  return by_parent;
}

Vec3 ReadVec3(const XMLElement* e, const char* name, const std::string& where, const Vec3& fallback) {
  const char* text = e ? e->Attribute(name) : nullptr;
  if (!text) return fallback;
  const std::string what = where + " attribute '" + name + "'";
  std::istringstream in(text);
  in.imbue(std::locale::classic());
  std::vector<double> values;
  std::string token;
  while (in >> token) {
    std::istringstream number(token);
    number.imbue(std::locale::classic());
    double value;
    if (!(number >> value) || !number.eof() || !std::isfinite(value)) {
      Fail(what + ": '" + token + "' is not a finite number");
    }
    values.push_back(value);
  }
  if (values.size() != 3) Fail(what + ": expected 3 numbers, got " + std::to_string(values.size()));
  return Vec3(values[0], values[1], values[2]);
}

std::string Vec3Text(const Vec3& v) {
  const Vec3 w = v + Vec3::Zero();  // -0 + 0 = +0: no "-0" in the text
  return FormatNumber(w[0]) + " " + FormatNumber(w[1]) + " " + FormatNumber(w[2]);
}

Pose ReadOrigin(const XMLElement* e, const std::string& where) {
  const XMLElement* origin = e->FirstChildElement("origin");
  Pose X = Pose::Identity();
  if (!origin) return X;
  const std::string at = where + " <origin>";
  for (const tinyxml2::XMLAttribute* a = origin->FirstAttribute(); a; a = a->Next()) {
    const std::string name = a->Name();
    if (name != "xyz" && name != "rpy") Fail(at + ": unknown attribute '" + name + "' (allowed: xyz, rpy)");
  }
  X.translation() = ReadVec3(origin, "xyz", at, Vec3::Zero());
  X.linear() = RotationOfRpy(ReadVec3(origin, "rpy", at, Vec3::Zero()));
  return X;
}

void WriteOrigin(XMLElement* joint, const Pose& X) {
  XMLElement* origin = joint->FirstChildElement("origin");
  if (!origin) {
    origin = joint->GetDocument()->NewElement("origin");
    joint->InsertAfterChild(joint->FirstChildElement("child"), origin);
  }
  origin->SetAttribute("xyz", Vec3Text(X.translation()).c_str());
  origin->SetAttribute("rpy", Vec3Text(RpyOf(X.linear())).c_str());
}

Mat3 RotationOfRpy(const Vec3& rpy) {
  return (Eigen::AngleAxisd(rpy[2], Vec3::UnitZ()) * Eigen::AngleAxisd(rpy[1], Vec3::UnitY()) *
          Eigen::AngleAxisd(rpy[0], Vec3::UnitX())).toRotationMatrix();
}

// Yaw from the first column, then pitch and roll from Rz(-yaw) R = Ry(pitch) Rx(roll), whose entries used here are
// all of order one: no division by cos(pitch), so near gimbal lock the angles still reproduce R to rounding.
Vec3 RpyOf(const Mat3& R) {
  const double yaw = std::atan2(R(1, 0), R(0, 0));  // any yaw when R(0, 0) = R(1, 0) = 0 (gimbal lock)
  const Mat3 R_pitch_roll = Eigen::AngleAxisd(-yaw, Vec3::UnitZ()).toRotationMatrix() * R;
  const double pitch = std::atan2(-R_pitch_roll(2, 0), R_pitch_roll(0, 0));
  const double roll = std::atan2(-R_pitch_roll(1, 2), R_pitch_roll(1, 1));
  return Vec3(roll, pitch, yaw);
}

}  // namespace scene_xml
}  // namespace implicit_sim
