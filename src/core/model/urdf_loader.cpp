#include "implicit_sim/core/model/urdf_loader.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <locale>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

#include <Eigen/Eigenvalues>
#include <console_bridge/console.h>
#include <tinyxml2.h>
#include <urdf_parser/urdf_parser.h>

#include "implicit_sim/core/base/format.h"
#include "loader_util.h"
#include "mesh_loader.h"
#include "self_collision.h"
#include "urdf_joints.h"

namespace implicit_sim {
using namespace loader;
namespace {

// Density of the shapes without <implicit mass> of a moving link without <inertial> (kg/m^3): water, as MuJoCo's
// default.
constexpr double kDefaultDensity = 1000.0;

Pose ReadOrigin(const tinyxml2::XMLElement* e, const std::string& where) {
  const Vec3 xyz = ReadVec3(e, "xyz", where, Vec3::Zero());
  const Vec3 rpy = ReadVec3(e, "rpy", where, Vec3::Zero());
  Pose X = Pose::Identity();
  X.translation() = xyz;
  X.linear() = (Eigen::AngleAxisd(rpy[2], Vec3::UnitZ()) * Eigen::AngleAxisd(rpy[1], Vec3::UnitY()) *
                Eigen::AngleAxisd(rpy[0], Vec3::UnitX())).toRotationMatrix();
  return X;
}

// One part of an <implicit type="intersection"> element.
Inequality ReadPart(const tinyxml2::XMLElement* part, const std::string& where) {
  const std::string kind = part->Name();
  const std::string at = where + " <" + kind + ">";
  static const std::map<std::string, std::vector<std::string>> kAllowed = {
      {"halfspace", {"normal", "offset", "xyz", "rpy"}},
      {"sphere", {"radius", "xyz", "rpy"}},
      {"ellipsoid", {"semi_axes", "xyz", "rpy"}},
      {"superellipsoid", {"semi_axes", "exponent", "xyz", "rpy"}},
      {"cylinder", {"radius", "xyz", "rpy"}}};
  const auto allowed = kAllowed.find(kind);
  if (allowed != kAllowed.end()) CheckAttributes(part, allowed->second, at);
  Inequality q;
  if (kind == "halfspace") {
    const Vec3 normal = ReadVec3(part, "normal", at, Vec3::UnitZ());
    if (normal.norm() < 1e-12) Fail(at + " attribute 'normal' must be non-zero");
    return Inequality::HalfSpace(normal, ReadScalar(part, "offset", at, -1e9, 1e9, false, 0.0, false));
  } else if (kind == "sphere") {
    q = Inequality::Sphere(ReadScalar(part, "radius", at, 0.0, 1e6, true, 0.0, true));
  } else if (kind == "ellipsoid") {
    q = Inequality::Ellipsoid(ReadVec3(part, "semi_axes", at, Vec3::Zero(), true, true));
  } else if (kind == "superellipsoid") {
    q = Inequality::Superellipsoid(ReadVec3(part, "semi_axes", at, Vec3::Zero(), true, true),
                                   ReadScalar(part, "exponent", at, 2.0, 100.0, false, 0.0, true));
  } else if (kind == "cylinder") {
    q = Inequality::InfiniteCylinder(ReadScalar(part, "radius", at, 0.0, 1e6, true, 0.0, true));
  } else {
    Fail(at + ": unknown part (allowed: halfspace, sphere, ellipsoid, superellipsoid, cylinder)");
  }
  if (q.radii.minCoeff() <= 0.0) Fail(at + ": 'semi_axes' is required and must be > 0");
  q.X_SP = ReadOrigin(part, at);
  return q;
}

// The implicit shape of a link from its <implicit> element or, without one, from the stock geometry (a mesh: its
// convex hull, with one warning).
ConvexShape ReadShape(const std::string& link, const urdf::Collision& collision,
                      const tinyxml2::XMLElement* implicit, const LoaderOptions& options, LoadNotes* notes) {
  const std::string where = "link '" + link + "' <implicit>";
  if (!implicit) {
    const urdf::Geometry* g = collision.geometry.get();
    if (!g) Fail("link '" + link + "': <collision> has no usable <geometry>");
    if (g->type == urdf::Geometry::SPHERE) return MakeSphere(static_cast<const urdf::Sphere*>(g)->radius);
    if (g->type == urdf::Geometry::BOX) {
      const urdf::Vector3& d = static_cast<const urdf::Box*>(g)->dim;
      return MakeBox(Vec3(d.x, d.y, d.z) / 2.0);
    }
    if (g->type == urdf::Geometry::CYLINDER) {
      const auto* c = static_cast<const urdf::Cylinder*>(g);
      return MakeCylinder(c->radius, c->length / 2.0);
    }
    if (g->type != urdf::Geometry::MESH) Fail("link '" + link + "': unknown collision geometry type");
    const auto* mesh = static_cast<const urdf::Mesh*>(g);
    std::string warning;
    ConvexShape hull =
        MeshHullShape(link, mesh->filename, Vec3(mesh->scale.x, mesh->scale.y, mesh->scale.z), options, &warning);
    if (!warning.empty()) notes->Add("mesh/" + link + "/" + mesh->filename, warning);  // empty: a cached hull
    return hull;
  }
  const char* type_text = implicit->Attribute("type");
  if (!type_text) Fail(where + ": missing attribute 'type'");
  const std::string type = type_text;
  static const std::map<std::string, std::vector<std::string>> kAllowed = {
      {"halfspace", {"type", "mass"}},
      {"sphere", {"type", "mass", "radius"}},
      {"ellipsoid", {"type", "mass", "semi_axes"}},
      {"superellipsoid", {"type", "mass", "semi_axes", "exponent"}},
      {"box", {"type", "mass", "size"}},
      {"cylinder", {"type", "mass", "radius", "length"}},
      {"prism", {"type", "mass", "sides", "radius", "length"}},
      {"intersection", {"type", "mass"}}};
  const auto allowed = kAllowed.find(type);
  if (allowed != kAllowed.end()) CheckAttributes(implicit, allowed->second, where + " type '" + type + "'");
  if (type == "halfspace") return MakeHalfSpace();
  if (type == "sphere") return MakeSphere(ReadScalar(implicit, "radius", where, 0.0, 1e6, true, 0.0, true));
  if (type == "ellipsoid") return MakeEllipsoid(ReadVec3(implicit, "semi_axes", where, Vec3::Zero(), true, true));
  if (type == "superellipsoid") {
    return MakeSuperellipsoid(ReadVec3(implicit, "semi_axes", where, Vec3::Zero(), true, true),
                              ReadScalar(implicit, "exponent", where, 2.0, 100.0, false, 0.0, true));
  }
  if (type == "box") return MakeBox(ReadVec3(implicit, "size", where, Vec3::Zero(), true, true) / 2.0);
  if (type == "cylinder") {
    return MakeCylinder(ReadScalar(implicit, "radius", where, 0.0, 1e6, true, 0.0, true),
                        ReadScalar(implicit, "length", where, 0.0, 1e6, true, 0.0, true) / 2.0);
  }
  if (type == "prism") {
    const double sides = ReadScalar(implicit, "sides", where, 3.0, 100000.0, false, 0.0, true);
    if (sides != std::floor(sides)) Fail(where + " attribute 'sides' must be an integer");
    return MakePrism(static_cast<int>(sides), ReadScalar(implicit, "radius", where, 0.0, 1e6, true, 0.0, true),
                     ReadScalar(implicit, "length", where, 0.0, 1e6, true, 0.0, true) / 2.0);
  }
  if (type == "intersection") {
    ConvexShape shape;
    shape.type = ShapeType::kIntersection;
    for (auto* part = implicit->FirstChildElement(); part; part = part->NextSiblingElement()) {
      shape.inequalities.push_back(ReadPart(part, where));
    }
    if (shape.inequalities.empty()) Fail(where + ": an intersection needs at least one part");
    return shape;
  }
  Fail(where + " attribute 'type' = '" + type +
       "' is unknown (allowed: halfspace, sphere, ellipsoid, superellipsoid, box, cylinder, prism, intersection)");
}

// --- Checks of everything urdfdom parses itself, run before urdfdom ---
// urdfdom 3.0.1 drops a malformed <collision>, <visual> or <inertial> (it logs to the console and still returns a
// model) and refuses a bad joint origin with a message that names no attribute. Checking its inputs first gives every
// error the link and attribute, and no element is ever dropped silently.

void CheckOrigin(const tinyxml2::XMLElement* parent, const std::string& where) {
  const tinyxml2::XMLElement* origin = parent->FirstChildElement("origin");
  if (!origin) return;
  if (origin->NextSiblingElement("origin")) Fail(where + ": more than one <origin>");
  const std::string at = where + " <origin>";
  // urdfdom 3.0.1 reads xyz and rpy only; a quaternion (quat_xyzw) would be ignored without a word.
  CheckAttributes(origin, {"xyz", "rpy"}, at);
  if (origin->Attribute("xyz")) CheckNumbers(origin, "xyz", at, 3, false);
  if (origin->Attribute("rpy")) CheckNumbers(origin, "rpy", at, 3, false);
}

// The stock shape inside <geometry> (urdfdom reads its first child element only).
void CheckGeometry(const tinyxml2::XMLElement* owner, const std::string& where) {
  const tinyxml2::XMLElement* geometry = owner->FirstChildElement("geometry");
  if (!geometry) Fail(where + ": missing <geometry>");
  if (geometry->NextSiblingElement("geometry")) Fail(where + ": more than one <geometry>");
  const std::string at = where + " <geometry>";
  const tinyxml2::XMLElement* shape = geometry->FirstChildElement();
  if (!shape) Fail(at + ": no shape element (allowed: sphere, box, cylinder, mesh)");
  if (shape->NextSiblingElement()) {
    Fail(at + ": more than one element (put <implicit> after </geometry>, as a child of <collision>)");
  }
  const std::string kind = shape->Name();
  const std::string shape_at = at + " <" + kind + ">";
  if (kind == "sphere") {
    CheckNumbers(shape, "radius", shape_at, 1, true);
  } else if (kind == "box") {
    CheckNumbers(shape, "size", shape_at, 3, true);
  } else if (kind == "cylinder") {
    CheckNumbers(shape, "radius", shape_at, 1, true);
    CheckNumbers(shape, "length", shape_at, 1, true);
  } else if (kind == "mesh") {
    if (!shape->Attribute("filename")) Fail(shape_at + ": missing attribute 'filename'");
    if (shape->Attribute("scale")) CheckNumbers(shape, "scale", shape_at, 3, false);
  } else if (kind == "implicit") {
    Fail(at + ": <implicit> must follow </geometry> inside <collision>, not be the shape of <geometry>");
  } else {
    Fail(at + ": unknown shape <" + kind + "> (allowed: sphere, box, cylinder, mesh)");
  }
}

void CheckInertial(const tinyxml2::XMLElement* inertial, const std::string& where) {
  const std::string at = where + " <inertial>";
  CheckOrigin(inertial, at);
  const tinyxml2::XMLElement* mass = inertial->FirstChildElement("mass");
  if (!mass) Fail(at + ": missing <mass>");
  CheckNumbers(mass, "value", at + " <mass>", 1, false);
  const tinyxml2::XMLElement* inertia = inertial->FirstChildElement("inertia");
  if (!inertia) Fail(at + ": missing <inertia>");
  for (const char* name : {"ixx", "ixy", "ixz", "iyy", "iyz", "izz"}) {
    CheckNumbers(inertia, name, at + " <inertia>", 1, false);  // kg m^2
  }
}

void CheckLinkElements(const tinyxml2::XMLElement* link, const std::string& name) {
  const std::string where = "link '" + name + "'";
  int inertials = 0;
  for (auto* child = link->FirstChildElement(); child; child = child->NextSiblingElement()) {
    const std::string tag = child->Name();
    if (tag == "inertial") {
      if (++inertials > 1) Fail(where + ": more than one <inertial>");
      CheckInertial(child, where);
    } else if (tag == "collision" || tag == "visual") {
      const std::string at = where + " <" + tag + ">";
      CheckOrigin(child, at);
      CheckGeometry(child, at);
      int implicits = 0;
      for (auto* i = child->FirstChildElement("implicit"); i; i = i->NextSiblingElement("implicit")) ++implicits;
      if (tag == "visual" && implicits > 0) Fail(at + ": <implicit> is read inside <collision> only");
      if (implicits > 1) Fail(at + ": more than one <implicit>");
    }
  }
}

// At most kMaxSceneLinks links and as many joints, counted before anything else reads them.
void CheckElementCounts(const tinyxml2::XMLElement* robot, const std::string& scene) {
  for (const char* tag : {"link", "joint"}) {
    int count = 0;
    for (auto* e = robot->FirstChildElement(tag); e; e = e->NextSiblingElement(tag)) {
      if (++count > kMaxSceneLinks) {
        Fail(scene + ": more than " + std::to_string(kMaxSceneLinks) + " <" + tag +
             "> elements (the loader's limit, kMaxSceneLinks)");
      }
    }
  }
}

// Link and joint names unique, joints between defined links, at least one link, every number finite.
void CheckUrdfStructure(const tinyxml2::XMLElement* robot, const std::string& scene_name) {
  const std::string scene = "scene '" + scene_name + "'";
  if (!robot->Attribute("name")) Fail(scene + ": <robot> has no attribute 'name'");
  std::set<std::string> links;
  for (auto* e = robot->FirstChildElement("link"); e; e = e->NextSiblingElement("link")) {
    const char* name = e->Attribute("name");
    if (!name || !*name) Fail(scene + ": a <link> has no name");
    if (!links.insert(name).second) Fail("link '" + std::string(name) + "' is defined more than once");
    CheckLinkElements(e, name);
  }
  if (links.empty()) Fail(scene + ": no <link> (the root link is 'world' or a robot's base link)");
  std::set<std::string> joints;
  for (auto* j = robot->FirstChildElement("joint"); j; j = j->NextSiblingElement("joint")) {
    const char* name = j->Attribute("name");
    if (!name || !*name) Fail(scene + ": a <joint> has no name");
    const std::string joint = "joint '" + std::string(name) + "'";
    if (!joints.insert(name).second) Fail(joint + " is defined more than once");
    std::string parent, child;
    for (const char* end : {"parent", "child"}) {
      const tinyxml2::XMLElement* e = j->FirstChildElement(end);
      const char* link = e ? e->Attribute("link") : nullptr;
      if (!link) Fail(joint + ": missing <" + end + " link=\"...\"/>");
      if (!links.count(link)) Fail(joint + ": <" + end + "> link '" + link + "' is not defined");
      parent = child;
      child = link;
    }
    // urdfdom leaks the model it was building on a self-joint (found by the fuzz harness): refuse it first.
    if (parent == child) Fail(joint + ": <parent> and <child> are the same link '" + child + "'");
    CheckOrigin(j, joint + " (of link '" + child + "')");  // the origin is the link's initial pose
  }
}

// Collects urdfdom's console messages while it parses (they would otherwise go to stderr).
class UrdfdomLogCapture : public console_bridge::OutputHandler {
 public:
  UrdfdomLogCapture() { console_bridge::useOutputHandler(this); }
  ~UrdfdomLogCapture() override { console_bridge::restorePreviousOutputHandler(); }
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_ERROR && first_error_.empty()) first_error_ = text;
  }
  const std::string& first_error() const { return first_error_; }

 private:
  std::string first_error_;
};

urdf::ModelInterfaceSharedPtr ParseWithUrdfdom(const std::string& xml, const std::string& scene_name) {
  UrdfdomLogCapture capture;
  const urdf::ModelInterfaceSharedPtr model = urdf::parseURDF(xml);
  if (!model) Fail("scene '" + scene_name + "': urdfdom could not parse the URDF (" + capture.first_error() + ")");
  return model;
}

// Elements urdfdom dropped although the XML has them (defence in depth behind CheckUrdfStructure).
void CheckNothingDropped(const tinyxml2::XMLElement* e, const urdf::Link& link) {
  const auto count = [e](const char* tag) {
    int n = 0;
    for (auto* c = e->FirstChildElement(tag); c; c = c->NextSiblingElement(tag)) ++n;
    return n;
  };
  const std::string where = "link '" + link.name + "'";
  if (count("collision") != static_cast<int>(link.collision_array.size())) {
    Fail(where + ": urdfdom dropped a <collision> (check its <origin> and <geometry>)");
  }
  if (count("visual") != static_cast<int>(link.visual_array.size())) {
    Fail(where + ": urdfdom dropped a <visual> (check its <origin> and <geometry>)");
  }
  if ((count("inertial") > 0) != static_cast<bool>(link.inertial)) Fail(where + ": urdfdom dropped the <inertial>");
}

FrictionParams ReadFriction(const tinyxml2::XMLElement* e, const std::string& where, const FrictionParams& base) {
  CheckAttributes(e, {"link1", "link2", "mu", "e_t", "e_o", "e_r", "e_roll"}, where);
  FrictionParams f;
  f.mu = ReadScalar(e, "mu", where, 0.0, 100.0, false, base.mu, false);
  f.e_t = ReadScalar(e, "e_t", where, 0.0, 1e3, true, base.e_t, false);
  f.e_o = ReadScalar(e, "e_o", where, 0.0, 1e3, true, base.e_o, false);
  f.e_r = ReadScalar(e, "e_r", where, 0.0, 1e3, false, base.e_r, false);
  f.e_roll = ReadScalar(e, "e_roll", where, 0.0, 1e3, false, base.e_roll, false);
  return f;
}

// <implicit_sim><sensor name type link|joint [rate]/>: a contact sensor on a link with a body, an IMU on any link with
// a body or a frame link, a force-torque sensor on a joint (its child link's); names unique.
Sensor ReadSensor(const tinyxml2::XMLElement* e, const Model& model) {
  const char* name = e->Attribute("name");
  const std::string where = "<implicit_sim><sensor name='" + std::string(name ? name : "") + "'>";
  CheckAttributes(e, {"name", "type", "link", "joint", "rate"}, where);
  Sensor sensor;
  if (!name || !*name) Fail("<implicit_sim><sensor>: attribute 'name' must be a non-empty name");
  sensor.name = name;
  for (const Sensor& other : model.sensors) {
    if (other.name == sensor.name) Fail(where + ": a second sensor of this name");
  }
  const char* type = e->Attribute("type");
  const std::string type_text = type ? type : "";
  if (type_text != "contact" && type_text != "imu" && type_text != "force_torque") {
    Fail(where + ": attribute 'type' = '" + type_text + "' must be contact, imu or force_torque");
  }
  sensor.type = type_text == "imu"            ? SensorType::kImu
                : type_text == "force_torque" ? SensorType::kForceTorque
                                              : SensorType::kContact;
  sensor.rate_hz = ReadScalar(e, "rate", where, 0.0, 1000.0, true, sensor.rate_hz, false);
  if (sensor.type == SensorType::kForceTorque) {
    if (e->Attribute("link")) Fail(where + ": a force_torque sensor takes attribute 'joint', not 'link'");
    const char* joint = e->Attribute("joint");
    sensor.joint = model.FindJoint(joint ? joint : "");
    if (sensor.joint < 0) {
      Fail(where + ": attribute 'joint' = '" + std::string(joint ? joint : "") +
           "' must name a revolute, continuous, prismatic or fixed joint of the scene whose child link has a body");
    }
    sensor.body = model.joints[sensor.joint].child;
    sensor.link = model.bodies[sensor.body].name;
    return sensor;
  }
  if (e->Attribute("joint")) Fail(where + ": attribute 'joint' is only for a force_torque sensor");
  const char* link = e->Attribute("link");
  sensor.link = link ? link : "";
  sensor.body = model.FindBody(sensor.link);
  if (sensor.body < 0 && sensor.type == SensorType::kImu) {
    for (const FrameLink& frame : model.frames) {
      if (frame.name != sensor.link) continue;
      sensor.body = frame.body;
      sensor.X_LS = frame.X_LF;
    }
  }
  if (sensor.body < 0) {
    Fail(where + ": attribute 'link' must name a link of the scene with a body" +
         (sensor.type == SensorType::kImu ? std::string(" or a frame link on one") : std::string()));
  }
  return sensor;
}

void ReadBodySettings(const tinyxml2::XMLElement* e, Body* body) {
  const std::string where = "<implicit_sim><body link='" + body->name + "'>";
  CheckAttributes(e, {"link", "velocity", "angular_velocity", "force", "torque", "locked"}, where);
  body->v_WB0 = ReadVec3(e, "velocity", where, Vec3::Zero());
  body->w_WB0 = ReadVec3(e, "angular_velocity", where, Vec3::Zero());
  body->f_applied_W = ReadVec3(e, "force", where, Vec3::Zero());
  body->tau_applied_W = ReadVec3(e, "torque", where, Vec3::Zero());
  if (const char* locked = e->Attribute("locked")) {
    static const std::map<std::string, int> kAxes = {{"x", 0}, {"y", 1}, {"z", 2}, {"rx", 3}, {"ry", 4}, {"rz", 5}};
    std::istringstream in(locked);
    std::string token;
    while (in >> token) {
      const auto it = kAxes.find(token);
      if (it == kAxes.end()) Fail(where + " attribute 'locked': '" + token + "' is not one of x y z rx ry rz");
      body->locked[it->second] = true;
    }
  }
  for (int i = 0; i < 6; ++i) {
    const double v0 = i < 3 ? body->v_WB0[i] : body->w_WB0[i - 3];
    if (body->locked[i] && v0 != 0.0) Fail(where + ": a locked axis must start with zero velocity");
  }
}

// Mass, inertia and the body frame (centre of mass) of a moving link.
void CheckInertia(const Mat3& I_B, const std::string& where) {
  const Vec3 p = Eigen::SelfAdjointEigenSolver<Mat3>(I_B).eigenvalues();  // ascending principal moments (kg m^2)
  if (!(p.minCoeff() > 0.0) || p[0] + p[1] < p[2] * (1.0 - 1e-9)) {
    std::ostringstream msg;
    msg.imbue(std::locale::classic());
    msg << where << ": inertia must be positive definite and satisfy the triangle inequality (principal moments "
        << p[0] << ", " << p[1] << ", " << p[2] << " kg m^2)";
    Fail(msg.str());
  }
}

// One <collision> of a link: its shape (X_BS still the shape frame in the collision frame C), the collision frame in
// the link frame L, and its <implicit> element (null for stock geometry).
struct LinkShape {
  ConvexShape shape;
  Pose X_LC = Pose::Identity();
  const tinyxml2::XMLElement* implicit = nullptr;
};

// Mass, inertia and the body frame (centre of mass) of a moving link. Every value is finite here
// (CheckUrdfStructure and ReadShape checked them). Without <inertial>, from the union of its shapes (taken as
// disjoint): each of mass <implicit mass> or else of density kDefaultDensity (then the link is named in
// *from_density); B's origin is the union's centre of mass, its axes the link's.
void ReadInertia(const urdf::Link& link, const std::vector<LinkShape>& shapes, Body* body, Pose* X_LB,
                 std::vector<std::string>* from_density) {
  const std::string where = "link '" + body->name + "'";
  if (link.inertial) {
    const urdf::Inertial& in = *link.inertial;
    if (!(in.mass > 0.0)) {
      Fail(where + ": mass must be > 0 kg, got " + FormatNumber(in.mass) + " (<inertial> <mass> attribute 'value')");
    }
    body->mass = in.mass;
    Mat3 I;
    I << in.ixx, in.ixy, in.ixz, in.ixy, in.iyy, in.iyz, in.ixz, in.iyz, in.izz;
    *X_LB = ToPose(in.origin);
    body->I_B = I;  // URDF gives the inertia in the inertial frame, which is our body frame B
    CheckInertia(I, where + " <inertial> <inertia>");
    return;
  }
  if (shapes.empty()) Fail(where + ": a moving link needs <inertial> or a <collision> to take its mass from");
  double mass = 0.0;          // kg
  Vec3 moment = Vec3::Zero();  // kg m, about L's origin
  Mat3 I_L = Mat3::Zero();     // kg m^2: the shapes' own inertias about their centroids, L's axes
  std::vector<std::pair<double, Vec3>> parts;  // (mass, centroid in L)
  bool density_used = false;
  for (const LinkShape& s : shapes) {
    double volume;  // m^3
    Vec3 c_S;       // centroid in S (m)
    Mat3 J_S;       // m^5, unit density, about the centroid
    try {
      s.shape.UnitDensityMassProperties(&volume, &c_S, &J_S);
    } catch (const std::invalid_argument& e) {
      Fail(where + ": its mass properties cannot come from its shapes (" + e.what() + "); give an <inertial>");
    }
    const double given = ReadScalar(s.implicit, "mass", where + " <implicit>", 0.0, 1e9, true, 0.0, false);
    density_used = density_used || given == 0.0;
    const double density = given > 0.0 ? given / volume : kDefaultDensity;  // kg/m^3
    const Pose X_LS = s.X_LC * s.shape.X_BS;
    parts.emplace_back(density * volume, X_LS * c_S);
    mass += parts.back().first;
    moment += parts.back().first * parts.back().second;
    I_L += density * X_LS.linear() * J_S * X_LS.linear().transpose();
  }
  const Vec3 c_L = moment / mass;  // the union's centre of mass
  for (const auto& [m, c] : parts) {
    const Vec3 d = c - c_L;
    I_L += m * (d.squaredNorm() * Mat3::Identity() - d * d.transpose());  // parallel axes
  }
  if (density_used) from_density->push_back(body->name);
  body->mass = mass;
  *X_LB = Pose::Identity();
  X_LB->translation() = c_L;
  body->I_B = I_L;
  CheckInertia(body->I_B, where + " (inertia from its collision shapes)");
}

void CheckLoaderOptions(const LoaderOptions& options) {
  const Pose& X = options.X_W_root;
  const bool rigid = X.matrix().allFinite() && X.matrix().row(3).isApprox(Eigen::RowVector4d(0, 0, 0, 1)) &&
                     (X.linear().transpose() * X.linear()).isApprox(Mat3::Identity(), 1e-9) &&
                     X.linear().determinant() > 0.0;
  if (!rigid) Fail("LoaderOptions::X_W_root must be a finite rigid transform (rotation orthonormal, det +1)");
  if (options.max_hull_faces < 4 || options.max_hull_faces > 10000) {
    Fail("LoaderOptions::max_hull_faces = " + std::to_string(options.max_hull_faces) +
         " is out of range [4, 10000]");
  }
}

// Where the root link goes: 'world' is the world; another root is welded to it or free at options.X_W_root.
RootPlacement PlaceRoot(const std::string& root, const LoaderOptions& options, const std::string& scene) {
  const Pose& X = options.X_W_root;
  if (root == "world") {
    if (options.floating_root || !X.isApprox(Pose::Identity(), 0.0)) {
      Fail(scene + ": the root link is 'world'; LoaderOptions::floating_root and X_W_root apply to another root");
    }
    return RootPlacement();
  }
  RootPlacement placement;
  placement.fixed = !options.floating_root;
  placement.X_W_root = X;
  return placement;
}

}  // namespace

Model LoadSceneFromString(const std::string& xml, const std::string& scene_name, const LoaderOptions& options) {
  CheckLoaderOptions(options);
  const std::string scene = "scene '" + scene_name + "'";
  if (xml.size() > kMaxSceneBytes) {
    Fail(scene + ": " + std::to_string(xml.size()) + " bytes exceed the limit of " + std::to_string(kMaxSceneBytes) +
         " bytes");
  }
  if (xml.find_first_not_of(" \t\r\n") == std::string::npos) Fail(scene + ": the file is empty");
  tinyxml2::XMLDocument doc;
  if (doc.Parse(xml.c_str(), xml.size()) != tinyxml2::XML_SUCCESS) {
    Fail(scene + ": not well-formed XML (" + std::string(doc.ErrorStr()) + ")");
  }
  const tinyxml2::XMLElement* robot = doc.FirstChildElement("robot");
  if (!robot) Fail(scene + ": no <robot> element");
  CheckElementCounts(robot, scene);
  ThrowIfLoadInterrupted(options.interrupt, scene_name);
  LoadNotes notes;
  // Joints first: urdfdom refuses a revolute joint without <limit> with a message that names nothing.
  for (auto* j = robot->FirstChildElement("joint"); j; j = j->NextSiblingElement("joint")) {
    const char* name = j->Attribute("name");
    CheckJointElement(j, "joint '" + std::string(name ? name : "") + "'", &notes);
  }
  CheckUrdfStructure(robot, scene_name);
  ThrowIfLoadInterrupted(options.interrupt, scene_name);
  const urdf::ModelInterfaceSharedPtr urdf_model = ParseWithUrdfdom(xml, scene_name);
  ThrowIfLoadInterrupted(options.interrupt, scene_name);
  if (!urdf_model->getRoot()) Fail(scene + ": urdfdom found no root link");
  const std::string root = urdf_model->getRoot()->name;
  const RootPlacement placement = PlaceRoot(root, options, scene);
  const tinyxml2::XMLElement* sim = robot->FirstChildElement("implicit_sim");
  if (sim && sim->NextSiblingElement("implicit_sim")) Fail(scene + ": more than one <implicit_sim>");
  Model model;
  model.scene_name = scene_name;
  if (sim) {
    CheckAttributes(sim, {"gravity"}, "<implicit_sim>");
    model.gravity_W = ReadVec3(sim, "gravity", "<implicit_sim>", model.gravity_W);
  }
  const JointStarts joint_starts = ReadJointStarts(sim, *urdf_model, options.joint_positions);

  std::vector<std::string> from_density;  // moving links whose mass came (in part) from kDefaultDensity
  std::vector<urdf::LinkSharedPtr> frame_links;  // links on moving links without a body
  InitialLinkPoses initial_poses(joint_starts, placement);
  std::unordered_map<const urdf::Link*, bool> welded;  // IsWeldedToWorld's answers
  std::unordered_map<const urdf::Link*, int> carrier;  // a frame link's nearest body above
  std::vector<urdf::LinkSharedPtr> links;
  urdf_model->getLinks(links);
  std::map<std::string, urdf::LinkSharedPtr> by_name;
  for (const auto& l : links) by_name[l->name] = l;
  // Keep the file's link order (getLinks is ordered by name). Names are unique and non-empty (CheckUrdfStructure).
  for (auto* e = robot->FirstChildElement("link"); e; e = e->NextSiblingElement("link")) {
    ThrowIfLoadInterrupted(options.interrupt, scene_name);  // a link reads at most one mesh per <collision>
    const std::string name = e->Attribute("name");
    const auto found = by_name.find(name);
    if (found == by_name.end()) {  // urdfdom reads a name with markup-like text differently from the XML
      Fail("link '" + name + "': urdfdom read no link of this name (use plain names: letters, digits, _ - / .)");
    }
    const urdf::LinkSharedPtr& link = found->second;
    CheckNothingDropped(e, *link);
    if (e->FirstChildElement("implicit")) Fail("link '" + name + "': <implicit> belongs inside <collision>");
    if (name == "world") {
      if (root != "world") Fail("link 'world': must be the root link (it hangs on a joint)");
      if (link->collision) Fail("link 'world': must have no <collision> (add a fixed link for static shapes)");
      continue;
    }
    if (!link->parent_joint && name != root) {
      Fail("link '" + name + "': no joint joins it to the tree under '" + root + "'");
    }
    Body body;
    body.name = name;
    body.is_fixed = IsWeldedToWorld(*link, placement, &welded);
    if (!body.is_fixed && IsFrameLink(*link)) {  // a frame on a moving link: no body (placed below)
      frame_links.push_back(link);
      continue;
    }
    std::vector<LinkShape> shapes;  // urdfdom keeps the <collision> elements in document order
    const tinyxml2::XMLElement* collision_xml = e->FirstChildElement("collision");
    for (const urdf::CollisionSharedPtr& collision : link->collision_array) {
      LinkShape s;
      s.implicit = collision_xml->FirstChildElement("implicit");
      s.X_LC = ToPose(collision->origin);
      s.shape = ReadShape(name, *collision, s.implicit, options, &notes);
      shapes.push_back(s);
      collision_xml = collision_xml->NextSiblingElement("collision");
    }
    Pose X_LB = Pose::Identity();
    if (!body.is_fixed) ReadInertia(*link, shapes, &body, &X_LB, &from_density);
    body.X_BL = X_LB.inverse();
    for (LinkShape& s : shapes) {
      s.shape.X_BS = body.X_BL * s.X_LC * s.shape.X_BS;  // a mesh hull's S is off its collision frame
      body.shapes.push_back(std::move(s.shape));
    }
    body.X_WB0 = initial_poses.Of(*link) * X_LB;
    model.bodies.push_back(body);
  }
  if (model.bodies.empty()) Fail("scene '" + scene_name + "': no link besides 'world'");
  model.IndexNames();  // FindBody by hash from here on (joints: after Finalize)
  for (const urdf::LinkSharedPtr& link : frame_links) {
    FrameLink frame;
    frame.name = link->name;
    frame.body = FirstValueUp(*link->getParent(), &carrier, [&](const urdf::Link& l) -> std::optional<int> {
      const int b = model.FindBody(l.name);  // a moving frame hangs on a body
      return b >= 0 ? std::optional<int>(b) : std::nullopt;
    });
    const Body& body = model.bodies[frame.body];
    frame.X_LF = (body.X_WB0 * body.X_BL).inverse() * initial_poses.Of(*link);
    model.frames.push_back(frame);
  }

  FrictionParams default_friction;
  std::map<std::pair<std::string, std::string>, FrictionParams> pair_friction;
  if (sim) {
    for (auto* e = sim->FirstChildElement(); e; e = e->NextSiblingElement()) {
      const std::string tag = e->Name();
      if (tag == "friction") {
        const char* l1 = e->Attribute("link1");
        const char* l2 = e->Attribute("link2");
        if (!l1 && !l2) {
          default_friction = ReadFriction(e, "<implicit_sim><friction>", FrictionParams());
          continue;
        }
        if (!l1 || !l2 || model.FindBody(l1) < 0 || model.FindBody(l2) < 0) {
          Fail("<implicit_sim><friction>: 'link1' and 'link2' must both name links of the scene");
        }
        pair_friction[{l1, l2}] = ReadFriction(
            e, std::string("<implicit_sim><friction link1='") + l1 + "' link2='" + l2 + "'>", default_friction);
      } else if (tag == "body") {
        const char* link = e->Attribute("link");
        const int b = link ? model.FindBody(link) : -1;
        if (b < 0) Fail("<implicit_sim><body>: attribute 'link' must name a link of the scene");
        if (model.bodies[b].is_fixed) Fail("<implicit_sim><body link='" + std::string(link) + "'>: the link is fixed");
        ReadBodySettings(e, &model.bodies[b]);
      } else if (tag != "joint" && tag != "self_collide" && tag != "disable_collisions" && tag != "sensor") {
        // <joint>: ReadJointStarts; <self_collide>, <disable_collisions>: ExcludeSelfCollisions; <sensor>: below
        Fail("<implicit_sim>: unknown element <" + tag +
             "> (allowed: friction, body, joint, self_collide, disable_collisions, sensor)");
      }
    }
  }
  ThrowIfLoadInterrupted(options.interrupt, scene_name);
  BuildJoints(*urdf_model, joint_starts, placement, options.enforce_velocity_limits, &initial_poses, &model, &notes);
  ThrowIfLoadInterrupted(options.interrupt, scene_name);
  ExcludeSelfCollisions(sim, *urdf_model, &model);
  ThrowIfLoadInterrupted(options.interrupt, scene_name);
  model.Finalize([&](int i, int j) {
    for (const auto& key : {std::make_pair(model.bodies[i].name, model.bodies[j].name),
                            std::make_pair(model.bodies[j].name, model.bodies[i].name)}) {
      const auto it = pair_friction.find(key);
      if (it != pair_friction.end()) return it->second;
    }
    return default_friction;
  }, options.interrupt);
  // Sensors once the joints are built and indexed (a force-torque sensor names a joint).
  for (auto* e = sim ? sim->FirstChildElement("sensor") : nullptr; e; e = e->NextSiblingElement("sensor")) {
    model.sensors.push_back(ReadSensor(e, model));
  }
  if (model.moving_bodies.empty()) Fail("scene '" + scene_name + "': no moving body (use a 'floating' joint)");
  const std::string self_overlap = SelfOverlapNote(model);
  if (!self_overlap.empty()) notes.Add("self_overlap", self_overlap);
  if (!from_density.empty()) {
    std::string names;
    for (const std::string& link : from_density) names += (names.empty() ? "'" : ", '") + link + "'";
    notes.Add("density", "implicit_sim: " + std::to_string(from_density.size()) +
                             " moving links without <inertial> take their mass and inertia from their collision shapes "
                             "at " + FormatNumber(kDefaultDensity) + " kg/m^3: " + names);
  }
  for (const std::string& warning : notes.lines()) {
    if (options.warnings) {
      options.warnings->push_back(warning);
    } else {
      std::cerr << warning << std::endl;
    }
  }
  return model;
}

std::string ReadSceneFile(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) Fail("scene file '" + path + "' is not a readable file");
  const std::uintmax_t bytes = std::filesystem::file_size(path, ec);
  if (ec) Fail("scene file '" + path + "' cannot be read (" + ec.message() + ")");
  if (bytes > kMaxSceneBytes) {  // refused before reading it
    Fail("scene file '" + path + "': " + std::to_string(bytes) + " bytes exceed the limit of " +
         std::to_string(kMaxSceneBytes) + " bytes");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) Fail("scene file '" + path + "' cannot be opened");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

Model LoadSceneFromFile(const std::string& path, const LoaderOptions& options) {
  const std::string text = ReadSceneFile(path);
  std::string name = path.substr(path.find_last_of('/') + 1);
  if (name.size() > 5 && name.substr(name.size() - 5) == ".urdf") name.resize(name.size() - 5);
  LoaderOptions file_options = options;
  if (file_options.mesh_directory.empty()) {
    file_options.mesh_directory = std::filesystem::path(path).parent_path().string();
    if (file_options.mesh_directory.empty()) file_options.mesh_directory = ".";
  }
  return LoadSceneFromString(text, name, file_options);
}

}  // namespace implicit_sim
