// Pushing bodies with the mouse: one interactive marker per moving body (~drag, rviz's InteractiveMarkers display).
// Dragging it pulls the grabbed point of the body towards the marker with a critically damped spring of natural
// frequency ~drag_frequency (stiffness m w^2, damping 2 m w, m the body's mass), like the perturbation tools of desktop
// simulators; the spring is drawn as an arrow (~markers, ns "drag") and released when the drag ends.
#include "implicit_sim/ros/sim_node.h"  // first: its generated service type Step precedes the core's function Step

#include <algorithm>
#include <cmath>
#include <set>

#include <visualization_msgs/InteractiveMarkerFeedback.h>

#include "implicit_sim/core/model/wrench.h"
#include "implicit_sim/ros/conversions.h"

namespace implicit_sim {
namespace conv = ros_conversions;
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kMarkerUpdatePeriodS = 0.1;  // wall time between two pose updates of the interactive markers

// The handle of one body: a translucent sphere that drags in the view plane (MOVE_3D; shift drags in depth).
visualization_msgs::InteractiveMarker DragHandle(const Model& model, int body, const Pose& X_WL,
                                                 const std::string& world_frame) {
  const double radius = std::clamp(model.bodies[body].shape.BoundingRadius(), 0.02, 1.0);  // m
  visualization_msgs::InteractiveMarker handle;
  handle.header.frame_id = world_frame;
  handle.name = model.bodies[body].name;
  handle.description = "drag " + handle.name;
  handle.pose = conv::ToPoseMsg(X_WL);
  handle.scale = static_cast<float>(2.5 * radius);
  visualization_msgs::InteractiveMarkerControl control;
  control.name = "move";
  control.interaction_mode = visualization_msgs::InteractiveMarkerControl::MOVE_3D;
  control.always_visible = true;
  visualization_msgs::Marker sphere;
  sphere.type = visualization_msgs::Marker::SPHERE;
  sphere.scale.x = sphere.scale.y = sphere.scale.z = 0.5 * radius;
  sphere.color.r = 0.2f, sphere.color.g = 0.6f, sphere.color.b = 1.0f, sphere.color.a = 0.5f;
  control.markers.push_back(sphere);
  handle.controls.push_back(control);
  return handle;
}

}  // namespace

void SimNode::SetUpDragMarkers(const Model& model, const State& state) {
  if (!params_.interactive_markers) return;
  if (!drag_server_) drag_server_ = std::make_unique<interactive_markers::InteractiveMarkerServer>(
                         pnh_.resolveName("drag"), "", false);
  drag_server_->clear();
  for (int b : model.moving_bodies) {
    drag_server_->insert(DragHandle(model, b, state.X_WL(model, b), params_.world_frame),
                         [this](const visualization_msgs::InteractiveMarkerFeedbackConstPtr& f) { OnDrag(f); });
  }
  drag_server_->applyChanges();
}

void SimNode::OnDrag(const visualization_msgs::InteractiveMarkerFeedbackConstPtr& feedback) {
  using Feedback = visualization_msgs::InteractiveMarkerFeedback;
  if (feedback->event_type != Feedback::MOUSE_DOWN && feedback->event_type != Feedback::POSE_UPDATE &&
      feedback->event_type != Feedback::MOUSE_UP) {
    return;
  }
  PostBetweenSteps([this, feedback] {
    World& w = *world_;
    const Model& model = *w.model;
    const int body = model.FindBody(feedback->marker_name);
    if (body < 0 || model.bodies[body].is_fixed) return;  // a marker of a world that was replaced meanwhile
    const Vec3 p_WM = conv::ToVec3(feedback->pose.position);  // the marker's origin now
    if (!p_WM.allFinite()) return;
    auto drag = std::find_if(w.drags.begin(), w.drags.end(), [body](const DragSpring& d) { return d.body == body; });
    if (feedback->event_type == Feedback::MOUSE_UP) {
      if (drag != w.drags.end()) w.drags.erase(drag);
      std::lock_guard<std::mutex> lock(drag_mutex_);
      dragged_.erase(model.bodies[body].name);
      return;
    }
    if (drag == w.drags.end()) {  // the grab: the clicked point (or the marker origin), fixed in the link frame
      const Pose X_WL = w.state.X_WL(model, body);
      const Vec3 grab = feedback->mouse_point_valid ? conv::ToVec3(feedback->mouse_point) : X_WL.translation();
      if (!grab.allFinite()) return;
      w.drags.push_back(DragSpring{body, X_WL.inverse() * grab, grab, p_WM - grab});
      JournalUnreplayable("~drag");
      std::lock_guard<std::mutex> lock(drag_mutex_);
      dragged_.insert(model.bodies[body].name);
      drag = w.drags.end() - 1;
    }
    drag->target_W = p_WM - drag->p_GM_W;  // the grabbed point follows the marker
  });
}

void SimNode::AddDragWrenches() {
  World& w = *world_;
  const Model& model = *w.model;
  const double omega = 2.0 * kPi * Live().drag_frequency;  // rad/s
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

void SimNode::UpdateDragMarkers(const NodeSnapshot& snapshot) {
  if (!drag_server_ || snapshot.version == drag_version_) return;  // nothing moved: nothing to send
  const double now = ros::WallTime::now().toSec();
  if (now < next_drag_update_) return;
  next_drag_update_ = now + kMarkerUpdatePeriodS;
  drag_version_ = snapshot.version;
  const Model& model = *snapshot.model;
  std::set<std::string> dragged;
  {
    std::lock_guard<std::mutex> lock(drag_mutex_);
    dragged = dragged_;
  }
  for (int b : model.moving_bodies) {
    if (dragged.count(model.bodies[b].name)) continue;  // the user's drag moves that one
    drag_server_->setPose(model.bodies[b].name, conv::ToPoseMsg(snapshot.state.X_WL(model, b)));
  }
  drag_server_->applyChanges();
}

}  // namespace implicit_sim
