// Wrenches, joint efforts, mouse drags and a reset applied to the node's World; the wrench of the next step. Drives
// and trajectories are in world_drives.cpp.
#include "implicit_sim/ros/world_commands.h"

#include <algorithm>
#include <cmath>

#include "implicit_sim/core/base/format.h"
#include "implicit_sim/core/model/joints.h"
#include "implicit_sim/core/model/wrench.h"
#include "implicit_sim/core/step/time_stepper.h"
#include "implicit_sim/ros/conversions.h"

namespace implicit_sim {
namespace conv = ros_conversions;
namespace {


// Sets *error when a commanded force (N) or torque (N m) is non-finite or larger than kMaxCommand.
bool CheckWrenchValues(const Vec3& force, const Vec3& torque, std::string* error) {
  if (!force.allFinite() || !torque.allFinite()) {
    *error = "wrench must be finite";
  } else if (force.norm() > kMaxCommand || torque.norm() > kMaxCommand) {
    *error = "wrench too large: |force| and |torque| must be <= 1e9 (N, N m)";
  } else {
    return true;
  }
  return false;
}

// The drag springs' wrenches: each pulls its grabbed point G to its target, critically damped at drag_frequency (Hz)
// for the body's mass (stiffness m w^2, damping 2 m w).
void AddDragWrenches(double drag_frequency, World* world) {
  World& w = *world;
  const Model& model = *w.model;
  const double omega = 2.0 * kPi * drag_frequency;  // rad/s
  for (const DragSpring& drag : w.drags) {
    const Body& body = model.bodies[drag.body];
    const Pose X_WL = w.state.X_WL(model, drag.body);
    const Vec3 p_WG = X_WL * drag.p_LG;
    const int slot = model.velocity_slot[drag.body];
    const Vec3 p_WBcm = w.state.X_WB(model, drag.body).translation();
    const Vec3 v_WG = w.state.v_WB(slot) + w.state.w_WB(slot).cross(p_WG - p_WBcm);
    const Vec3 f_W = body.mass * omega * omega * (drag.target_W - p_WG) - 2.0 * body.mass * omega * v_WG;  // N
    AddWrenchAtPoint(model, w.state, drag.body, -1, p_WG, f_W, Vec3::Zero(), &w.wrench_W);
  }
}

}  // namespace

int FindBodyOrFail(const Model& model, const std::string& name, bool must_move, std::string* error) {
  const int b = model.FindBody(name);
  if (b < 0) {
    *error = "unknown body '" + name + "'";
  } else if (must_move && model.bodies[b].is_fixed) {
    *error = "body '" + name + "' is fixed";
    return -1;
  }
  return b;
}

bool SetWrenchCommand(const CommandContext&, const implicit_sim::BodyWrench& msg, World* world, std::string* error) {
  const Vec3 f = conv::ToVec3(msg.wrench.force), tau = conv::ToVec3(msg.wrench.torque);
  const int b = FindBodyOrFail(*world->model, msg.body, true, error);
  if (b < 0 || !CheckWrenchValues(f, tau, error)) return false;
  const int v = Model::v_offset(world->model->velocity_slot[b]);
  world->commanded_W.segment<3>(v) = f;
  world->commanded_W.segment<3>(v + 3) = tau;
  return true;
}

bool AddTimedWrench(const CommandContext& context, const implicit_sim::ApplyBodyWrench::Request& req, World* world,
                    std::string* error) {
  const int b = FindBodyOrFail(*world->model, req.body, true, error);
  int frame_body = -1;
  if (!req.reference_frame.empty() && req.reference_frame != context.world_frame) {
    frame_body = world->model->FindBody(req.reference_frame);
    if (frame_body < 0) *error = "unknown reference_frame '" + req.reference_frame + "'";
  }
  TimedWrench w{b, frame_body, conv::ToVec3(req.reference_point), conv::ToVec3(req.wrench.force),
                conv::ToVec3(req.wrench.torque), std::max(req.start_time, context.sim_time), -1.0};
  if (error->empty() && (!w.point.allFinite() || !std::isfinite(req.start_time) || !std::isfinite(req.duration))) {
    *error = "reference_point, start_time and duration must be finite";
  }
  if (error->empty()) CheckWrenchValues(w.force, w.torque, error);  // sets error when refused
  if (error->empty() && req.duration == 0.0) *error = "duration must be > 0 s, or < 0 for until cleared";
  if (!error->empty()) return false;
  if (req.duration > 0.0) w.end = w.start + req.duration;
  world->wrenches.push_back(w);
  return true;
}

bool SetJointEfforts(const std::vector<std::string>& names, const std::vector<double>& efforts, World* world,
                     std::string* error) {
  const Model& model = *world->model;
  if (names.size() != efforts.size()) {
    *error = "name and effort must have the same length (" + std::to_string(names.size()) + " names, " +
             std::to_string(efforts.size()) + " efforts)";
    return false;
  }
  std::vector<int> joints(names.size());
  for (size_t i = 0; i < names.size(); ++i) {
    joints[i] = model.FindJoint(names[i]);
    if (joints[i] < 0 || !model.joints[joints[i]].has_coordinate()) {
      *error = "no revolute, continuous or prismatic joint '" + names[i] + "' in the scene";
      return false;
    }
    if (!std::isfinite(efforts[i]) || std::abs(efforts[i]) > kMaxCommand) {
      *error = "effort of joint '" + names[i] + "' = " + FormatNumber(efforts[i]) +
               " must be finite with |effort| <= 1e9 (N m or N)";
      return false;
    }
  }
  for (size_t i = 0; i < names.size(); ++i) world->joint_efforts[joints[i]] = efforts[i];
  return true;
}

bool SetJointEffortCommand(const CommandContext&, const sensor_msgs::JointState& msg, World* world,
                           std::string* error) {
  return SetJointEfforts(msg.name, msg.effort, world, error);
}

DragEvent ApplyDragFeedback(const visualization_msgs::InteractiveMarkerFeedback& feedback, World* world) {
  using Feedback = visualization_msgs::InteractiveMarkerFeedback;
  World& w = *world;
  const Model& model = *w.model;
  const int body = model.FindBody(feedback.marker_name);
  if (body < 0 || model.bodies[body].is_fixed) return DragEvent::kNone;  // a marker of a world replaced meanwhile
  const Vec3 p_WM = conv::ToVec3(feedback.pose.position);  // the marker's origin now
  if (!p_WM.allFinite()) return DragEvent::kNone;
  auto drag = std::find_if(w.drags.begin(), w.drags.end(), [body](const DragSpring& d) { return d.body == body; });
  if (feedback.event_type == Feedback::MOUSE_UP) {
    if (drag != w.drags.end()) w.drags.erase(drag);
    return DragEvent::kRelease;
  }
  DragEvent event = DragEvent::kMove;
  if (drag == w.drags.end()) {  // the grab: the clicked point (or the marker origin), fixed in the link frame
    const Pose X_WL = w.state.X_WL(model, body);
    const Vec3 grab = feedback.mouse_point_valid ? conv::ToVec3(feedback.mouse_point) : X_WL.translation();
    if (!grab.allFinite()) return DragEvent::kNone;
    w.drags.push_back(DragSpring{body, X_WL.inverse() * grab, grab, p_WM - grab});
    drag = w.drags.end() - 1;
    event = DragEvent::kGrab;
  }
  drag->target_W = p_WM - drag->p_GM_W;  // the grabbed point follows the marker
  return event;
}

void ComputeStepWrench(const CommandContext& context, double h, World* world) {
  UpdateTrajectoryDrives(context.sim_time + h, world);  // drives act at the end of the step
  World& w = *world;
  const Model& model = *w.model;
  w.wrench_W.setZero();
  const double t = context.sim_time + 1e-9;
  for (int k = 0; k < model.num_moving(); ++k) {  // ~wrench_cmd: at the link origin, world frame
    const int b = model.moving_bodies[k];
    const int v = Model::v_offset(k);
    AddWrenchAtPoint(model, w.state, b, -1, w.state.X_WL(model, b).translation(), w.commanded_W.segment<3>(v),
                     w.commanded_W.segment<3>(v + 3), &w.wrench_W);
  }
  for (const TimedWrench& tw : w.wrenches) {
    if (t < tw.start || (tw.end >= 0.0 && t >= tw.end)) continue;
    AddWrenchAtPoint(model, w.state, tw.body, tw.frame_body, tw.point, tw.force, tw.torque, &w.wrench_W);
  }
  if (!model.joints.empty()) AddJointEffortWrench(model, w.state, w.joint_efforts, &w.wrench_W);
  AddDragWrenches(context.live.drag_frequency, world);
}

void ResetWorldState(World* world) {
  World& w = *world;
  w.state = w.initial_state;
  ClearWarmStart(w.data.get());
  // No forces, but the vector keeps its size: it follows the core's pair layout (Data::LayOut), and a step whose
  // layout is unchanged writes its results into it by index (clearing it made them vanish after ~reset).
  for (ContactResult& contact : w.data->contacts) {
    const int pair = contact.pair;
    contact = ContactResult();
    contact.pair = pair;
  }
  w.wrenches.clear();
  w.commanded_W.setZero();
  w.joint_efforts.setZero();
  std::fill(w.data->joint_drives.begin(), w.data->joint_drives.end(), JointDrive());
  w.trajectories.clear();
  w.drags.clear();
}

}  // namespace implicit_sim
