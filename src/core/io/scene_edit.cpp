#include "implicit_sim/core/io/scene_edit.h"

#include <cmath>
#include <filesystem>
#include <map>
#include <set>
#include <sstream>

#include <tinyxml2.h>

#include "implicit_sim/core/base/format.h"
#include "scene_xml.h"

namespace implicit_sim {
namespace {

using namespace scene_xml;
using tinyxml2::XMLDocument;
using tinyxml2::XMLElement;

constexpr char kAdd[] = "AddToScene: ";

bool PrefixCharAllowed(char c) {
  return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '/' ||
         c == '-';
}

// The arguments that need no parsing: prefix, base_dir, X_WO and the twist.
void CheckAdditionArguments(const SceneAddition& a) {
  for (char c : a.prefix) {
    if (!PrefixCharAllowed(c)) {
      Fail(std::string(kAdd) + "prefix '" + a.prefix + "': character '" + c +
           "' is not allowed (allowed: A-Z a-z 0-9 _ / -)");
    }
  }
  if (!a.base_dir.empty() && !std::filesystem::path(a.base_dir).is_absolute()) {
    Fail(std::string(kAdd) + "base_dir '" + a.base_dir + "' must be an absolute directory (or empty)");
  }
  if (!a.X_WO.matrix().allFinite()) Fail(std::string(kAdd) + "X_WO must be finite (it has a NaN or inf entry)");
  const Mat3 R_WO = a.X_WO.linear();
  if ((R_WO.transpose() * R_WO - Mat3::Identity()).norm() > 1e-9 || R_WO.determinant() < 0.0) {
    Fail(std::string(kAdd) + "the rotation of X_WO is not a rotation (need R^T R = I within 1e-9 and det R = +1)");
  }
  if (!a.v_WO.allFinite()) Fail(std::string(kAdd) + "v_WO must be finite, got " + Vec3Text(a.v_WO) + " m/s");
  if (!a.w_WO.allFinite()) Fail(std::string(kAdd) + "w_WO must be finite, got " + Vec3Text(a.w_WO) + " rad/s");
}

std::set<std::string> NamesOf(XMLElement* robot, const char* tag) {
  std::set<std::string> names;
  for (XMLElement* e : ChildrenNamed(robot, tag)) names.insert(e->Attribute("name"));
  return names;
}

// A robot addition (no link `world`) gets the joint that attaches its single root link to `world`, at the identity
// for now (composed with X_WO like every other top-level origin). A scene addition is left as it is.
void AttachRobotRoot(XMLElement* robot, bool floating_root) {
  const std::set<std::string> links = NamesOf(robot, "link");
  std::set<std::string> roots = links;
  for (XMLElement* joint : ChildrenNamed(robot, "joint")) roots.erase(JointLink(joint, "child"));
  if (links.count("world")) {
    if (!roots.count("world")) Fail(std::string(kAdd) + "addition: link 'world' must be the root, not a child");
    if (links.size() == 1) Fail(std::string(kAdd) + "the addition has no link besides 'world'");
    return;
  }
  if (links.empty()) Fail(std::string(kAdd) + "the addition has no link besides 'world'");
  if (roots.size() != 1) {
    std::string list;
    for (const std::string& r : roots) list += (list.empty() ? "'" : ", '") + r + "'";
    Fail(std::string(kAdd) + "addition: a robot needs exactly one root link, found " + std::to_string(roots.size()) +
         (list.empty() ? " (the joints form a loop)" : ": " + list));
  }
  const std::string root = *roots.begin();
  const std::string joint_name = root + "_joint";
  if (NamesOf(robot, "joint").count(joint_name)) {
    Fail(std::string(kAdd) + "addition: joint '" + joint_name +
         "' already exists; that name is reserved for the joint that attaches the root link to 'world'");
  }
  XMLDocument* doc = robot->GetDocument();
  XMLElement* joint = doc->NewElement("joint");
  joint->SetAttribute("name", joint_name.c_str());
  joint->SetAttribute("type", floating_root ? "floating" : "fixed");
  joint->InsertNewChildElement("parent")->SetAttribute("link", "world");
  joint->InsertNewChildElement("child")->SetAttribute("link", root.c_str());
  XMLElement* root_link = robot->FirstChildElement("link");
  while (root != root_link->Attribute("name")) root_link = root_link->NextSiblingElement("link");
  robot->InsertAfterChild(root_link, joint);
}

// New link and joint names must not exist in the scene.
void CheckNoClash(XMLElement* scene, XMLElement* addition, const std::string& prefix) {
  for (const char* tag : {"link", "joint"}) {
    const std::set<std::string> existing = NamesOf(scene, tag);
    for (const std::string& name : NamesOf(addition, tag)) {
      if (std::string(tag) == "link" && name == "world") continue;
      if (existing.count(prefix + name)) {
        Fail(std::string(kAdd) + tag + " '" + prefix + name + "' already exists in the scene (choose another prefix)");
      }
    }
  }
}

XMLElement* SimOf(XMLElement* robot, bool create) {
  XMLElement* sim = robot->FirstChildElement("implicit_sim");
  if (!sim && create) {
    sim = robot->GetDocument()->NewElement("implicit_sim");
    robot->InsertFirstChild(sim);
  }
  return sim;
}

// The elements of a name: links by name, <implicit_sim><body> entries by link.
std::map<std::string, XMLElement*> ByAttribute(XMLElement* parent, const char* tag, const char* attribute) {
  std::map<std::string, XMLElement*> by_name;
  for (XMLElement* e = parent ? parent->FirstChildElement(tag) : nullptr; e; e = e->NextSiblingElement(tag)) {
    const char* name = e->Attribute(attribute);
    if (name) by_name.emplace(name, e);
  }
  return by_name;
}

// The centre of mass of a link in its link frame, as the loader places it: the <inertial> origin, else (mass from
// <implicit>) the <collision> origin.
Vec3 CentreOfMassInLink(const XMLElement* link, const std::string& where) {
  if (const XMLElement* inertial = link->FirstChildElement("inertial")) {
    return ReadOrigin(inertial, where + " <inertial>").translation();
  }
  if (const XMLElement* collision = link->FirstChildElement("collision")) {
    return ReadOrigin(collision, where + " <collision>").translation();
  }
  return Vec3::Zero();
}

// A locked world axis (<body locked>) must keep zero velocity (the loader refuses anything else).
void CheckLockedAxes(const XMLElement* entry, const Vec3& v, const Vec3& w, const std::string& where) {
  const char* locked = entry->Attribute("locked");
  if (!locked) return;
  static const std::map<std::string, int> kAxes = {{"x", 0}, {"y", 1}, {"z", 2}, {"rx", 3}, {"ry", 4}, {"rz", 5}};
  std::istringstream in(locked);
  std::string token;
  while (in >> token) {
    const auto axis = kAxes.find(token);
    if (axis == kAxes.end()) continue;  // the loader names a bad token
    const double speed = axis->second < 3 ? v[axis->second] : w[axis->second - 3];
    if (speed != 0.0) {
      Fail(where + ": locked axis '" + token + "' would start moving (the spawn twist gives it " +
           Vec3Text(v) + " m/s, " + Vec3Text(w) + " rad/s)");
    }
  }
}

// The rigid motion of O added to the free body on `joint` (floating, parent world, origin already composed).
// `links` and `entries` index the addition's links and <body> entries by name.
void MoveFreeBody(XMLElement* robot, XMLElement* joint, const SceneAddition& a,
                  const std::map<std::string, XMLElement*>& links, const std::map<std::string, XMLElement*>& entries) {
  const std::string link_name = JointLink(joint, "child");
  const std::string where = std::string(kAdd) + "addition link '" + link_name + "'";
  const Pose X_WL = ReadOrigin(joint, where);
  const Vec3 p_WB = X_WL * CentreOfMassInLink(links.at(link_name), where);
  const auto found = entries.find(link_name);
  XMLElement* entry = found == entries.end() ? nullptr : found->second;
  const std::string at = where + " <implicit_sim><body>";
  const Mat3 R_WO = a.X_WO.linear();
  const Vec3 v = R_WO * ReadVec3(entry, "velocity", at, Vec3::Zero()) + a.v_WO +
                 a.w_WO.cross(p_WB - a.X_WO.translation());
  const Vec3 w = R_WO * ReadVec3(entry, "angular_velocity", at, Vec3::Zero()) + a.w_WO;
  if (!entry) {
    if (v.isZero(0.0) && w.isZero(0.0)) return;
    entry = SimOf(robot, true)->InsertNewChildElement("body");
    entry->SetAttribute("link", link_name.c_str());
  }
  CheckLockedAxes(entry, v, w, where);
  if (entry->Attribute("velocity") || !v.isZero(0.0)) entry->SetAttribute("velocity", Vec3Text(v).c_str());
  if (entry->Attribute("angular_velocity") || !w.isZero(0.0)) {
    entry->SetAttribute("angular_velocity", Vec3Text(w).c_str());
  }
}

// Every origin of a joint to `world` becomes X_WO * origin; every free body gets the rigid motion of O.
void PlaceInWorld(XMLElement* robot, const SceneAddition& a) {
  const auto links = ByAttribute(robot, "link", "name");
  const auto entries = ByAttribute(SimOf(robot, false), "body", "link");
  for (XMLElement* joint : ChildrenNamed(robot, "joint")) {
    if (JointLink(joint, "parent") != "world") continue;
    const std::string where = std::string(kAdd) + "addition joint '" + joint->Attribute("name") + "'";
    WriteOrigin(joint, a.X_WO * ReadOrigin(joint, where));
    const char* type = joint->Attribute("type");
    if (type && std::string(type) == "floating") MoveFreeBody(robot, joint, a, links, entries);
  }
}

// Relative file names under <mesh> and <texture> made absolute against base_dir.
void ResolveFileNames(XMLElement* e, const std::string& base_dir) {
  for (XMLElement* child = e->FirstChildElement(); child; child = child->NextSiblingElement()) {
    const std::string tag = child->Name();
    const char* filename = child->Attribute("filename");
    if ((tag == "mesh" || tag == "texture") && filename && *filename && filename[0] != '/' &&
        std::string(filename).find("://") == std::string::npos) {
      const std::filesystem::path absolute = (std::filesystem::path(base_dir) / filename).lexically_normal();
      child->SetAttribute("filename", absolute.string().c_str());
    }
    ResolveFileNames(child, base_dir);
  }
}

// Prefixes attribute `attribute` of `e` (if both exist); the link `world` keeps its name (it is the scene's).
void Rename(XMLElement* e, const char* attribute, const std::string& prefix, bool is_link) {
  const char* name = e ? e->Attribute(attribute) : nullptr;
  if (name && !(is_link && std::string(name) == "world")) e->SetAttribute(attribute, (prefix + name).c_str());
}

// Start options as <implicit_sim> entries of `robot`, in its own names (for an addition, RenameAll then prefixes
// them): joint positions, a <self_collide> per robot and the SRDF's <disable_collisions>. `what`: "AddToScene: ",
// "the addition" or "WithStartEntries: ", "the scene".
void AddStartEntries(XMLElement* robot, const std::map<std::string, double>& joint_positions, bool self_collide,
                     const std::string& srdf, const std::string& caller, const std::string& what) {
  const std::set<std::string> joints = NamesOf(robot, "joint"), links = NamesOf(robot, "link");
  for (const auto& [name, q] : joint_positions) {
    if (!joints.count(name)) Fail(caller + "joint_positions: '" + name + "' is not a joint of " + what);
    if (!std::isfinite(q)) Fail(caller + "joint_positions['" + name + "'] must be finite");
    std::map<std::string, XMLElement*> entries = ByAttribute(SimOf(robot, false), "joint", "name");
    XMLElement* entry = entries.count(name) ? entries[name] : nullptr;
    if (!entry) {
      entry = SimOf(robot, true)->InsertNewChildElement("joint");
      entry->SetAttribute("name", name.c_str());
    }
    entry->SetAttribute("position", FormatNumber(q).c_str());
  }
  if (self_collide) {  // every parent of a joint inside a robot; one per robot would do, more are harmless
    std::set<std::string> parents;
    for (XMLElement* joint : ChildrenNamed(robot, "joint")) {
      const char* type = joint->Attribute("type");
      const std::string parent = JointLink(joint, "parent");
      if (parent != "world" && !(type && std::string(type) == "floating")) parents.insert(parent);
    }
    for (const std::string& link : parents) {
      SimOf(robot, true)->InsertNewChildElement("self_collide")->SetAttribute("link", link.c_str());
    }
  }
  if (srdf.empty()) return;
  XMLDocument srdf_doc;
  if (srdf_doc.Parse(srdf.c_str(), srdf.size()) != tinyxml2::XML_SUCCESS || !srdf_doc.RootElement() ||
      std::string(srdf_doc.RootElement()->Name()) != "robot") {
    Fail(caller + "the SRDF is not an XML document with a root element <robot>");
  }
  for (XMLElement* e = srdf_doc.RootElement()->FirstChildElement("disable_collisions"); e;
       e = e->NextSiblingElement("disable_collisions")) {
    XMLElement* entry = SimOf(robot, true)->InsertNewChildElement("disable_collisions");
    for (const char* attribute : {"link1", "link2"}) {
      const char* link = e->Attribute(attribute);
      if (!link || !links.count(link)) {
        Fail(caller + "SRDF <disable_collisions " + attribute + "='" + (link ? link : "") + "'>: not a link of " +
             what);
      }
      entry->SetAttribute(attribute, link);
    }
    if (e->Attribute("reason")) entry->SetAttribute("reason", e->Attribute("reason"));
  }
}

// Every link and joint name and every reference to one (joint ends, <mimic joint>, <implicit_sim> entries).
void RenameAll(XMLElement* robot, const std::string& prefix) {
  for (XMLElement* link : ChildrenNamed(robot, "link")) Rename(link, "name", prefix, true);
  for (XMLElement* joint : ChildrenNamed(robot, "joint")) {
    Rename(joint, "name", prefix, false);
    Rename(joint->FirstChildElement("parent"), "link", prefix, true);
    Rename(joint->FirstChildElement("child"), "link", prefix, true);
    Rename(joint->FirstChildElement("mimic"), "joint", prefix, false);
  }
  XMLElement* sim = SimOf(robot, false);
  if (sim && sim->NextSiblingElement("implicit_sim")) {
    Fail(std::string(kAdd) + "the addition has more than one <implicit_sim>");
  }
  for (XMLElement* e = sim ? sim->FirstChildElement() : nullptr; e; e = e->NextSiblingElement()) {
    const std::string tag = e->Name();
    if (tag == "friction" || tag == "disable_collisions") {
      Rename(e, "link1", prefix, true);
      Rename(e, "link2", prefix, true);
    } else if (tag == "body" || tag == "self_collide") {
      Rename(e, "link", prefix, true);
    } else if (tag == "joint") {
      Rename(e, "name", prefix, false);
    } else if (tag == "sensor") {
      Rename(e, "name", prefix, false);
      Rename(e, "link", prefix, true);
      Rename(e, "joint", prefix, false);
    } else {
      Fail(std::string(kAdd) + "addition <implicit_sim>: unknown element <" + tag +
           "> (allowed: friction, body, joint, self_collide, disable_collisions, sensor)");
    }
  }
}

// The scene's top-level material named `name`, or null.
XMLElement* MaterialNamed(XMLElement* robot, const std::string& name) {
  for (XMLElement* m : ChildrenNamed(robot, "material")) {
    const char* n = m->Attribute("name");
    if (n && name == n) return m;
  }
  return nullptr;
}

// The addition's top-level materials that the scene defines already: dropped when identical, else renamed with the
// prefix together with the addition's references to them. Returns the materials to copy.
std::vector<XMLElement*> MaterialsToCopy(XMLElement* scene, XMLElement* addition, const std::string& prefix) {
  std::vector<XMLElement*> copy;
  for (XMLElement* material : ChildrenNamed(addition, "material")) {
    const char* name_text = material->Attribute("name");
    const std::string name = name_text ? name_text : "";
    const XMLElement* existing = MaterialNamed(scene, name);
    if (!existing) {
      copy.push_back(material);
      continue;
    }
    if (PrintCompact(*existing) == PrintCompact(*material)) continue;
    const std::string renamed = prefix + name;
    if (prefix.empty() || MaterialNamed(scene, renamed) || MaterialNamed(addition, renamed)) {
      Fail(std::string(kAdd) + "material '" + name + "' of the addition differs from the scene's material '" + name +
           "' and cannot be renamed to '" + renamed + "' (choose another prefix)");
    }
    material->SetAttribute("name", renamed.c_str());
    for (XMLElement* link : ChildrenNamed(addition, "link")) {
      for (XMLElement* v = link->FirstChildElement("visual"); v; v = v->NextSiblingElement("visual")) {
        XMLElement* ref = v->FirstChildElement("material");
        if (ref && ref->Attribute("name") && name == ref->Attribute("name")) ref->SetAttribute("name", renamed.c_str());
      }
    }
    copy.push_back(material);
  }
  return copy;
}

// The addition's prepared elements appended to the scene. Returns the new link names.
std::vector<std::string> Merge(XMLElement* scene, XMLElement* addition, const std::vector<XMLElement*>& materials) {
  XMLDocument* doc = scene->GetDocument();
  std::vector<std::string> added_links;
  for (XMLElement* material : materials) scene->InsertEndChild(material->DeepClone(doc));
  for (XMLElement* e = addition->FirstChildElement(); e; e = e->NextSiblingElement()) {
    const std::string tag = e->Name();
    if (tag == "link" && std::string(e->Attribute("name")) != "world") {
      added_links.push_back(e->Attribute("name"));
      scene->InsertEndChild(e->DeepClone(doc));
    } else if (tag == "joint") {
      scene->InsertEndChild(e->DeepClone(doc));
    }
  }
  XMLElement* sim = SimOf(addition, false);
  for (XMLElement* e = sim ? sim->FirstChildElement() : nullptr; e; e = e->NextSiblingElement()) {
    const bool default_friction =
        std::string(e->Name()) == "friction" && !e->Attribute("link1") && !e->Attribute("link2");
    if (!default_friction) SimOf(scene, true)->InsertEndChild(e->DeepClone(doc));
  }
  return added_links;
}

// The links in `roots` and every link hanging on them through joints.
std::set<std::string> SubtreeLinks(XMLElement* robot, const std::set<std::string>& roots) {
  const auto joints_by_parent = JointsByParent(robot);
  std::set<std::string> links = roots;
  std::vector<std::string> pending(roots.begin(), roots.end());
  while (!pending.empty()) {
    const auto children = joints_by_parent.find(pending.back());
    pending.pop_back();
    if (children == joints_by_parent.end()) continue;
    for (XMLElement* joint : children->second) {
      const std::string child = JointLink(joint, "child");
      if (links.insert(child).second) pending.push_back(child);
    }
  }
  return links;
}

bool Names(const XMLElement* e, const char* attribute, const std::set<std::string>& names) {
  const char* name = e->Attribute(attribute);
  return name && names.count(name) > 0;
}

// Removes the links in `roots`, their subtrees, the joints to and inside them (every joint whose child goes), and the
// <implicit_sim> entries and <gazebo reference> elements naming them. Returns the removed links in document order.
std::vector<std::string> RemoveSubtrees(XMLElement* robot, const std::set<std::string>& roots) {
  const std::set<std::string> links = SubtreeLinks(robot, roots);
  std::set<std::string> joints;
  for (XMLElement* joint : ChildrenNamed(robot, "joint")) {
    if (links.count(JointLink(joint, "child"))) joints.insert(joint->Attribute("name"));
  }
  std::vector<std::string> removed;
  std::vector<XMLElement*> doomed;
  for (XMLElement* e = robot->FirstChildElement(); e; e = e->NextSiblingElement()) {
    const std::string tag = e->Name();
    if (tag == "link" && Names(e, "name", links)) removed.push_back(e->Attribute("name"));
    if ((tag == "link" && Names(e, "name", links)) || (tag == "joint" && Names(e, "name", joints)) ||
        (tag == "gazebo" && Names(e, "reference", links))) {
      doomed.push_back(e);
    }
  }
  XMLElement* sim = SimOf(robot, false);
  for (XMLElement* e = sim ? sim->FirstChildElement() : nullptr; e; e = e->NextSiblingElement()) {
    const std::string tag = e->Name();
    if (Names(e, "link1", links) || Names(e, "link2", links) ||
        ((tag == "body" || tag == "self_collide" || tag == "sensor") && Names(e, "link", links)) ||
        (tag == "joint" && Names(e, "name", joints)) || (tag == "sensor" && Names(e, "joint", joints))) {
      doomed.push_back(e);
    }
  }
  for (XMLElement* e : doomed) e->Parent()->DeleteChild(e);
  return removed;
}

}  // namespace

std::string AddToScene(const std::string& scene_urdf, const SceneAddition& addition,
                       std::vector<std::string>* added_links) {
  CheckAdditionArguments(addition);
  XMLDocument scene_doc;
  XMLElement* scene = ParseRobot(scene_urdf, std::string(kAdd) + "the scene", &scene_doc);
  if (!NamesOf(scene, "link").count("world")) Fail(std::string(kAdd) + "the scene has no link 'world' (its root)");
  XMLDocument addition_doc;
  XMLElement* robot = ParseRobot(addition.urdf, std::string(kAdd) + "the addition", &addition_doc);
  AttachRobotRoot(robot, addition.floating_root);
  CheckNoClash(scene, robot, addition.prefix);
  PlaceInWorld(robot, addition);
  if (!addition.base_dir.empty()) ResolveFileNames(robot, addition.base_dir);
  AddStartEntries(robot, addition.joint_positions, addition.self_collide, addition.srdf, kAdd, "the addition");
  RenameAll(robot, addition.prefix);
  const std::vector<XMLElement*> materials = MaterialsToCopy(scene, robot, addition.prefix);
  const std::vector<std::string> links = Merge(scene, robot, materials);
  if (added_links) *added_links = links;
  return Print(scene_doc);
}

std::string WithStartEntries(const std::string& scene_urdf, const std::map<std::string, double>& joint_positions,
                             const std::string& srdf) {
  constexpr char kStarts[] = "WithStartEntries: ";
  XMLDocument doc;
  XMLElement* scene = ParseRobot(scene_urdf, std::string(kStarts) + "the scene", &doc);
  if (joint_positions.empty() && srdf.empty()) return scene_urdf;
  AddStartEntries(scene, joint_positions, false, srdf, kStarts, "the scene");
  return Print(doc);
}

std::string RemoveFromScene(const std::string& scene_urdf, const std::vector<std::string>& links,
                            std::vector<std::string>* removed_links) {
  XMLDocument doc;
  XMLElement* robot = ParseRobot(scene_urdf, "RemoveFromScene: the scene", &doc);
  const std::set<std::string> existing = NamesOf(robot, "link");
  for (const std::string& link : links) {
    if (link == "world") Fail("RemoveFromScene: link 'world' is the root and cannot be removed");
    if (!existing.count(link)) Fail("RemoveFromScene: link '" + link + "' is not in the scene");
  }
  const std::vector<std::string> removed = RemoveSubtrees(robot, std::set<std::string>(links.begin(), links.end()));
  if (removed_links) *removed_links = removed;
  return Print(doc);
}

std::string RobotDescriptionOf(const std::string& scene_urdf) {
  XMLDocument doc;
  XMLElement* robot = ParseRobot(scene_urdf, "RobotDescriptionOf: the scene", &doc);
  std::set<std::string> free_links;
  for (XMLElement* joint : ChildrenNamed(robot, "joint")) {
    const char* type = joint->Attribute("type");
    const std::string kind = type ? type : "";
    if ((kind == "floating" && JointLink(joint, "parent") == "world") || kind == "planar") {
      free_links.insert(JointLink(joint, "child"));
    }
  }
  RemoveSubtrees(robot, free_links);
  for (XMLElement* sim : ChildrenNamed(robot, "implicit_sim")) robot->DeleteChild(sim);
  return Print(doc);
}

}  // namespace implicit_sim
