#include "urdf_joints.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "implicit_sim/core/base/format.h"
#include "implicit_sim/core/model/joints.h"
#include "loader_util.h"

namespace implicit_sim {
namespace loader {
namespace {


std::string JointWhere(const urdf::Joint& joint) { return "joint '" + joint.name + "'"; }

bool HasCoordinate(const urdf::Joint& joint) {
  return joint.type == urdf::Joint::REVOLUTE || joint.type == urdf::Joint::CONTINUOUS ||
         joint.type == urdf::Joint::PRISMATIC;
}

bool IsLimited(const urdf::Joint& joint) {
  return joint.type == urdf::Joint::REVOLUTE || joint.type == urdf::Joint::PRISMATIC;
}

Vec3 UnitAxis(const urdf::Joint& joint) {
  const Vec3 a(joint.axis.x, joint.axis.y, joint.axis.z);
  return a.normalized();  // non-zero: CheckJointElement
}

// The motion of the child link frame relative to the joint frame at joint position q.
Pose JointMotion(const urdf::Joint& joint, double q) {
  Pose X = Pose::Identity();
  if (joint.type == urdf::Joint::PRISMATIC) X.translation() = q * UnitAxis(joint);
  if (joint.type == urdf::Joint::REVOLUTE || joint.type == urdf::Joint::CONTINUOUS) {
    X.linear() = Eigen::AngleAxisd(q, UnitAxis(joint)).toRotationMatrix();
  }
  return X;
}

// The number of links above `link`, each link's counted once per `known` (iteratively: a chain of any depth).
int Depth(const urdf::Link& link, std::unordered_map<const urdf::Link*, int>* known) {
  std::vector<const urdf::Link*> chain;  // from `link` upwards: the links whose depth is still to find
  const urdf::Link* l = &link;
  int depth = -1;
  while (true) {
    const auto found = known->find(l);
    if (found != known->end()) {
      depth = found->second;
      break;
    }
    chain.push_back(l);
    const urdf::LinkConstSharedPtr parent = l->getParent();  // the ModelInterface owns its links
    if (!parent) break;
    l = parent.get();
  }
  for (auto it = chain.rbegin(); it != chain.rend(); ++it) (*known)[*it] = ++depth;
  return (*known)[&link];
}

}  // namespace

void CheckJointElement(const tinyxml2::XMLElement* j, const std::string& where, LoadNotes* notes) {
  const char* type_text = j->Attribute("type");
  const std::string type = type_text ? type_text : "";
  static const std::vector<std::string> kTypes = {"floating", "fixed", "revolute", "continuous", "prismatic", "planar"};
  if (std::find(kTypes.begin(), kTypes.end(), type) == kTypes.end()) {
    Fail(where + ": type '" + type +
         "' is not supported (allowed: floating, fixed, revolute, continuous, prismatic, planar)");
  }
  if (const tinyxml2::XMLElement* mimic = j->FirstChildElement("mimic")) {
    const std::string at = where + " <mimic>";
    if (type != "revolute" && type != "continuous" && type != "prismatic") {
      Fail(at + ": only a revolute, continuous or prismatic joint can mimic another");
    }
    CheckAttributes(mimic, {"joint", "multiplier", "offset"}, at);
    if (!mimic->Attribute("joint")) Fail(at + ": missing attribute 'joint'");
    for (const char* name : {"multiplier", "offset"}) {
      if (mimic->Attribute(name)) CheckNumbers(mimic, name, at, 1, false);
    }
  }
  const tinyxml2::XMLElement* axis = j->FirstChildElement("axis");
  if (axis && type != "fixed" && type != "floating") {
    CheckAttributes(axis, {"xyz"}, where + " <axis>");
    CheckNumbers(axis, "xyz", where + " <axis>", 3, false);
    if (ReadVec3(axis, "xyz", where + " <axis>", Vec3::Zero()).norm() < 1e-9) {
      Fail(where + " <axis> attribute 'xyz' must be a non-zero vector");
    }
  }
  const tinyxml2::XMLElement* limit = j->FirstChildElement("limit");
  if (!limit && (type == "revolute" || type == "prismatic")) {
    Fail(where + ": a " + type + " joint needs <limit lower=\"..\" upper=\"..\" effort=\"..\" velocity=\"..\"/>");
  }
  if (limit) {
    const std::string at = where + " <limit>";
    NoteUnknownAttributes(limit, {"lower", "upper", "effort", "velocity"}, notes);
    for (const char* name : {"effort", "velocity"}) CheckNumbers(limit, name, at, 1, false);  // urdfdom needs both
    for (const char* name : {"lower", "upper"}) {
      if (limit->Attribute(name)) CheckNumbers(limit, name, at, 1, false);
    }
  }
  if (const tinyxml2::XMLElement* dynamics = j->FirstChildElement("dynamics")) {
    const std::string at = where + " <dynamics>";
    NoteUnknownAttributes(dynamics, {"damping", "friction"}, notes);
    for (const char* name : {"damping", "friction"}) {
      if (dynamics->Attribute(name)) CheckNumbers(dynamics, name, at, 1, false);
    }
  }
}

JointStarts ReadJointStarts(const tinyxml2::XMLElement* sim, const urdf::ModelInterface& urdf,
                            const std::map<std::string, double>& positions) {
  JointStarts starts;
  for (auto* e = sim ? sim->FirstChildElement("joint") : nullptr; e; e = e->NextSiblingElement("joint")) {
    const char* name = e->Attribute("name");
    const std::string where = "<implicit_sim><joint name='" + std::string(name ? name : "") + "'>";
    CheckAttributes(e, {"name", "position", "velocity", "effort", "enforce_velocity_limit"}, where);
    const urdf::JointConstSharedPtr joint = name ? urdf.getJoint(name) : nullptr;
    if (!joint) Fail(where + ": attribute 'name' must name a joint of the scene");
    if (!HasCoordinate(*joint)) Fail(where + ": the joint must be revolute, continuous or prismatic");
    if (starts.count(name)) Fail(where + " is given more than once");
    const bool limited = IsLimited(*joint);
    const double lower = limited ? joint->limits->lower : -1e6, upper = limited ? joint->limits->upper : 1e6;
    JointStart start;
    start.position = ReadScalar(e, "position", where, lower, upper, false, 0.0, false);
    start.velocity = ReadScalar(e, "velocity", where, -1e5, 1e5, false, 0.0, false);
    const double effort_limit = joint->limits && joint->limits->effort > 0.0 ? joint->limits->effort : 1e9;
    start.effort = ReadScalar(e, "effort", where, -effort_limit, effort_limit, false, 0.0, false);
    if (const char* enforce = e->Attribute("enforce_velocity_limit")) {
      const std::string value = enforce;
      if (value != "true" && value != "false") {
        Fail(where + " attribute 'enforce_velocity_limit' = '" + value + "' must be 'true' or 'false'");
      }
      start.enforce_velocity_limit = value == "true";
    }
    starts[name] = start;
  }
  for (const auto& [name, q] : positions) {
    const std::string where = "LoaderOptions::joint_positions['" + name + "']";
    const urdf::JointConstSharedPtr joint = urdf.getJoint(name);
    if (!joint || !HasCoordinate(*joint) || joint->mimic) {
      Fail(where + ": must name a revolute, continuous or prismatic joint of the scene that mimics none");
    }
    if (!std::isfinite(q) || (IsLimited(*joint) && (q < joint->limits->lower - kJointLimitRoundOff ||
                                                    q > joint->limits->upper + kJointLimitRoundOff))) {
      Fail(where + " = " + FormatNumber(q) + " is out of range [" +
           (IsLimited(*joint) ? FormatNumber(joint->limits->lower) + ", " + FormatNumber(joint->limits->upper)
                              : std::string("finite")) + "]");
    }
    starts[name].position = q;
  }
  for (const auto& [name, joint] : urdf.joints_) {  // the URDF's zero pose where no start is given
    if (!IsLimited(*joint) || joint->mimic || starts.count(name) || !(joint->limits->lower <= joint->limits->upper)) {
      continue;  // an inverted range is refused with its own message
    }
    if (joint->limits->lower > kJointLimitRoundOff || joint->limits->upper < -kJointLimitRoundOff) {
      Fail(JointWhere(*joint) + " starts at 0, outside its limits [" + FormatNumber(joint->limits->lower) + ", " +
           FormatNumber(joint->limits->upper) + "]: give its start position (<implicit_sim><joint position>, "
           "LoaderOptions::joint_positions)");
    }
  }
  // A mimic joint starts where its leader puts it (a start of its own must agree).
  for (const auto& [name, joint] : urdf.joints_) {
    if (!joint->mimic) continue;
    const std::string where = JointWhere(*joint) + " <mimic>";
    const urdf::JointConstSharedPtr leader = urdf.getJoint(joint->mimic->joint_name);
    if (!leader) Fail(where + ": attribute 'joint' = '" + joint->mimic->joint_name + "' names no joint of the scene");
    if (leader == joint || leader->mimic || !HasCoordinate(*leader)) {
      Fail(where + ": joint '" + leader->name + "' must be another revolute, continuous or prismatic joint that "
                   "mimics none");
    }
    const auto lead = starts.find(leader->name);
    JointStart follow;
    if (lead != starts.end()) {
      follow.position = joint->mimic->multiplier * lead->second.position + joint->mimic->offset;
      follow.velocity = joint->mimic->multiplier * lead->second.velocity;
    } else {
      follow.position = joint->mimic->offset;
    }
    const auto own = starts.find(name);
    if (own != starts.end()) {
      if (std::abs(own->second.position - follow.position) > 1e-9 ||
          std::abs(own->second.velocity - follow.velocity) > 1e-9) {
        Fail("<implicit_sim><joint name='" + name + "'>: the joint mimics '" + leader->name +
             "', which puts it at position " + FormatNumber(follow.position) + " and velocity " +
             FormatNumber(follow.velocity));
      }
      follow.effort = own->second.effort;
    }
    if (IsLimited(*joint) && (follow.position < joint->limits->lower - kJointLimitRoundOff ||
                              follow.position > joint->limits->upper + kJointLimitRoundOff)) {
      Fail(where + ": its leader's start puts it at " + FormatNumber(follow.position) + ", outside its limits [" +
           FormatNumber(joint->limits->lower) + ", " + FormatNumber(joint->limits->upper) + "]");
    }
    starts[name] = follow;
  }
  return starts;
}

bool IsWeldedToWorld(const urdf::Link& link, const RootPlacement& root,
                     std::unordered_map<const urdf::Link*, bool>* known) {
  return FirstValueUp(link, known, [&](const urdf::Link& l) -> std::optional<bool> {
    if (!l.parent_joint) return root.fixed;  // the root link
    if (l.parent_joint->type != urdf::Joint::FIXED) return false;
    return std::nullopt;
  });
}

bool IsFrameLink(const urdf::Link& link) {
  return !link.inertial && link.collision_array.empty() && link.parent_joint &&
         link.parent_joint->type == urdf::Joint::FIXED;
}

const Pose& InitialLinkPoses::Of(const urdf::Link& link) {
  // Up to the first link whose pose is known (or the root), then down again, noting each pose on the way. The links
  // belong to the urdf::ModelInterface, so the raw pointers stay valid.
  std::vector<const urdf::Link*> chain;  // from `link` upwards: the links whose pose is still to find
  const urdf::Link* l = &link;
  Pose X_WP;
  while (true) {
    const auto found = known_.find(l);
    if (found != known_.end()) {
      X_WP = found->second;
      break;
    }
    if (!l->parent_joint) {
      X_WP = known_[l] = root_.X_W_root;  // the root link ('world': identity)
      break;
    }
    chain.push_back(l);
    l = l->getParent().get();
  }
  for (auto it = chain.rbegin(); it != chain.rend(); ++it) {
    const urdf::Joint& joint = *(*it)->parent_joint;
    const auto start = starts_.find(joint.name);
    const double q = start == starts_.end() ? 0.0 : start->second.position;
    const Pose X_PJ = ToPose(joint.parent_to_joint_origin_transform);
    if (!X_PJ.matrix().allFinite()) Fail(JointWhere(joint) + ": origin must be finite");
    X_WP = X_WP * X_PJ * JointMotion(joint, q);
    known_[*it] = X_WP;
  }
  return known_.at(&link);
}

namespace {

// Whether the step bounds the joint's rate (Joint::velocity_limited): asked for by the joint's own entry or else by the
// loader's default, for a joint with a coordinate that mimics none (its leader's bound carries it). A joint whose own
// entry asks for it without a <limit velocity> > 0, or that starts faster than its bound, is refused.
void ReadVelocityLimit(const urdf::Joint& u, std::optional<bool> own, bool by_default, Joint* joint) {
  const std::string where = "<implicit_sim><joint name='" + u.name + "'>";
  if (own && *own && (u.mimic || !(joint->velocity_limit > 0.0))) {
    Fail(where + " attribute 'enforce_velocity_limit': " +
         (u.mimic ? std::string("the joint mimics another; bound its leader instead")
                  : "the joint has no <limit velocity> > 0 to enforce"));
  }
  joint->velocity_limited = own.value_or(by_default) && joint->has_coordinate() && !u.mimic &&
                            joint->velocity_limit > 0.0;
  if (joint->velocity_limited && std::abs(joint->initial_velocity) > joint->velocity_limit) {
    Fail(where + ": start velocity " + FormatNumber(joint->initial_velocity) + " is outside its velocity limit [" +
         FormatNumber(-joint->velocity_limit) + ", " + FormatNumber(joint->velocity_limit) + "]");
  }
}

// Joint parameters from urdfdom's joint (whose numbers CheckJointElement found finite), with their ranges.
void ReadJointParameters(const urdf::Joint& u, const JointStarts& starts, bool enforce_velocity_limits, Joint* joint,
                         LoadNotes* notes) {
  const std::string where = JointWhere(u);
  if (u.limits) {
    if (!(u.limits->effort >= 0.0)) Fail(where + " <limit> attribute 'effort' must be >= 0 (0: no clamp)");
    if (!(u.limits->velocity >= 0.0)) Fail(where + " <limit> attribute 'velocity' must be >= 0 (0: none)");
    joint->effort_limit = u.limits->effort;
    joint->velocity_limit = u.limits->velocity;
  }
  joint->limited = IsLimited(u);
  if (joint->limited) {
    joint->lower = u.limits->lower;
    joint->upper = u.limits->upper;
    if (!(joint->lower <= joint->upper)) {
      Fail(where + " <limit>: 'lower' = " + FormatNumber(joint->lower) + " must not exceed 'upper' = " +
           FormatNumber(joint->upper));
    }
    if (u.type == urdf::Joint::REVOLUTE && !(joint->upper - joint->lower < 2.0 * kPi - 1e-9)) {
      joint->limited = false;  // the limits stay in lower and upper for start positions and drive targets
      notes->Add("wide_revolute", "implicit_sim: revolute joints with a range of 2 pi rad or more (the first: " +
                                      where + ", [" + FormatNumber(joint->lower) + ", " + FormatNumber(joint->upper) +
                                      "] rad) turn without limit rows: within one turn neither limit is reached");
    }
  }
  if (u.dynamics && u.type == urdf::Joint::PLANAR) {
    if (u.dynamics->damping != 0.0 || u.dynamics->friction != 0.0) {
      notes->Add("planar_dynamics", "implicit_sim: <dynamics> of planar joints is ignored (the first: " + where +
                                        "): a planar joint has no coordinate to damp or rub");
    }
  } else if (u.dynamics) {
    joint->damping = u.dynamics->damping;
    joint->friction = u.dynamics->friction;
    if (!(joint->damping >= 0.0 && joint->damping <= 1e9)) {
      Fail(where + " <dynamics> attribute 'damping' = " + FormatNumber(joint->damping) + " is out of range [0, 1e9]");
    }
    if (!(joint->friction >= 0.0 && joint->friction <= 1e9)) {
      Fail(where + " <dynamics> attribute 'friction' = " + FormatNumber(joint->friction) +
           " is out of range [0, 1e9]");
    }
  }
  if (u.mimic) {
    joint->mimic_multiplier = u.mimic->multiplier;
    joint->mimic_offset = u.mimic->offset;
    joint->limited = false;  // its leader's limits bound it; its own rows would repeat them at a shared stop
  }
  const auto start = starts.find(u.name);
  if (start != starts.end()) {
    joint->initial_position = start->second.position;
    joint->initial_velocity = start->second.velocity;
    joint->applied_effort = start->second.effort;
  }
  ReadVelocityLimit(u, start == starts.end() ? std::nullopt : start->second.enforce_velocity_limit,
                    enforce_velocity_limits, joint);
}

// The joint frame's axes in the parent's body frame (X_PJ: joint frame in it) and in the child's (X_CL: the child
// link frame in it, the joint frame at position 0), with b1 and b2 normal to the axis.
void SetJointFrames(const Pose& X_PJ, const Pose& X_CL, const Vec3& a, Joint* joint) {
  const Vec3 b1 = a.unitOrthogonal(), b2 = a.cross(b1);
  joint->offset = joint->limited && joint->type == JointType::kRevolute ? 0.5 * (joint->lower + joint->upper) : 0.0;
  const Vec3 b1_offset = std::cos(joint->offset) * b1 + std::sin(joint->offset) * b2;
  Mat3 parent_axes, child_axes;
  parent_axes << a, b1_offset, a.cross(b1_offset);
  child_axes << a, b1, b2;
  joint->p_PJ = X_PJ.translation();
  joint->R_PJ = X_PJ.linear() * parent_axes;
  joint->p_CJ = X_CL.translation();
  joint->R_CJ = X_CL.linear() * child_axes;
}

// The child's initial velocity: its parent's rigid motion plus the joint velocity qd about or along the world axis.
void SetChildVelocity(const Model& model, const Joint& joint, const Pose& X_WJ, const Vec3& a, Body* child) {
  Vec3 v_P = Vec3::Zero(), w_P = Vec3::Zero(), p_P = Vec3::Zero();
  if (joint.parent >= 0) {
    const Body& parent = model.bodies[joint.parent];
    v_P = parent.v_WB0;
    w_P = parent.w_WB0;
    p_P = parent.X_WB0.translation();
  }
  const Vec3 p_C = child->X_WB0.translation(), a_W = X_WJ.linear() * a;
  const double qd = joint.initial_velocity;
  child->w_WB0 = w_P;
  child->v_WB0 = v_P + w_P.cross(p_C - p_P);
  if (joint.type == JointType::kPrismatic) child->v_WB0 += qd * a_W;
  if (joint.type == JointType::kRevolute || joint.type == JointType::kContinuous) {
    child->w_WB0 += qd * a_W;
    child->v_WB0 += qd * a_W.cross(p_C - X_WJ.translation());
  }
}

// The nearest link at or above `link_name` that is a body or 'world' (frame links are none), and the pose X_AL of the
// link frame L of `link_name` in that link's frame A (frame links hang on fixed joints: their origins compose).
std::string NearestBodyLink(const urdf::ModelInterface& urdf, const Model& model, std::string link_name, Pose* X_AL) {
  *X_AL = Pose::Identity();
  while (link_name != "world" && model.FindBody(link_name) < 0) {
    const urdf::JointConstSharedPtr joint = urdf.getLink(link_name)->parent_joint;
    *X_AL = ToPose(joint->parent_to_joint_origin_transform) * *X_AL;
    link_name = joint->parent_link_name;
  }
  return link_name;
}

}  // namespace

void BuildJoints(const urdf::ModelInterface& urdf, const JointStarts& starts, const RootPlacement& root,
                 bool enforce_velocity_limits, InitialLinkPoses* poses, Model* model, LoadNotes* notes) {
  std::vector<urdf::JointSharedPtr> ordered;
  std::unordered_map<const urdf::Link*, int> depths;
  std::unordered_map<const urdf::Joint*, int> child_depth;
  for (const auto& [name, joint] : urdf.joints_) {
    ordered.push_back(joint);
    child_depth[joint.get()] = Depth(*urdf.getLink(joint->child_link_name), &depths);
  }
  // Parents before children: by depth below 'world', then by name (a strict total order: no stable sort needed).
  std::sort(ordered.begin(), ordered.end(), [&](const auto& x, const auto& y) {
    const int dx = child_depth[x.get()], dy = child_depth[y.get()];
    return dx != dy ? dx < dy : x->name < y->name;
  });
  for (const urdf::JointSharedPtr& u : ordered) {
    const std::string where = JointWhere(*u);
    const bool world_parent = u->parent_link_name == "world";
    if (u->type == urdf::Joint::FLOATING) {
      if (!world_parent) Fail(where + ": a floating joint must have 'world' as its parent");
      continue;
    }
    const int child_index = model->FindBody(u->child_link_name);
    if (child_index < 0) continue;  // a frame link
    Body& child = model->bodies[child_index];
    if (child.is_fixed) continue;  // welded to the world
    if (child.v_WB0 != Vec3::Zero() || child.w_WB0 != Vec3::Zero()) {
      Fail("<implicit_sim><body link='" + child.name + "'>: the link hangs on " + where +
           "; give its initial velocity as <implicit_sim><joint name='" + u->name + "' velocity='..'/>");
    }
    Joint joint;
    joint.name = u->name;
    joint.type = u->type == urdf::Joint::FIXED       ? JointType::kFixed
                 : u->type == urdf::Joint::REVOLUTE  ? JointType::kRevolute
                 : u->type == urdf::Joint::PRISMATIC ? JointType::kPrismatic
                 : u->type == urdf::Joint::PLANAR    ? JointType::kPlanar
                                                     : JointType::kContinuous;
    Pose X_AL;  // the URDF parent's link frame in the link frame A of the body it belongs to
    const std::string parent_link = NearestBodyLink(urdf, *model, u->parent_link_name, &X_AL);
    joint.parent = world_parent ? -1 : model->FindBody(parent_link);
    joint.child = child_index;
    ReadJointParameters(*u, starts, enforce_velocity_limits, &joint, notes);
    const Vec3 a = joint.type == JointType::kFixed ? Vec3::UnitX() : UnitAxis(*u);
    const Pose X_AJ = X_AL * ToPose(u->parent_to_joint_origin_transform);  // in the parent body's link frame
    const Pose X_PA = joint.parent < 0 ? Pose::Identity() : model->bodies[joint.parent].X_BL;
    SetJointFrames(X_PA * X_AJ, child.X_BL, a, &joint);
    const Pose X_WJ = poses->Of(*urdf.getLink(parent_link)) * X_AJ;
    SetChildVelocity(*model, joint, X_WJ, a, &child);
    model->joints.push_back(joint);
  }
  for (Joint& joint : model->joints) {  // leaders by name, now that every joint has its index
    const urdf::JointConstSharedPtr u = urdf.getJoint(joint.name);
    if (!u->mimic) continue;
    joint.mimic_leader = model->FindJoint(u->mimic->joint_name);
    if (joint.mimic_leader < 0) {
      Fail(JointWhere(*u) + " <mimic>: joint '" + u->mimic->joint_name + "' moves no body");
    }
  }
}

}  // namespace loader
}  // namespace implicit_sim
