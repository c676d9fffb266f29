#include "implicit_sim/ros/drag_markers.h"

#include <algorithm>

#include "implicit_sim/ros/conversions.h"

namespace implicit_sim {
namespace conv = ros_conversions;
namespace {

constexpr double kMarkerUpdatePeriodS = 0.1;  // wall time between two pose updates of the interactive markers

// The handle of one body: a translucent sphere that drags in the view plane (MOVE_3D; shift drags in depth).
visualization_msgs::InteractiveMarker DragHandle(const Model& model, int body, const Pose& X_WL,
                                                 const std::string& world_frame) {
  const double radius = std::clamp(model.BodyReach(body), 0.02, 1.0);  // m
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

DragMarkers::DragMarkers(ros::NodeHandle pnh, const std::string& world_frame, bool enabled,
                         std::function<void(const Feedback&)> on_feedback)
    : pnh_(pnh), world_frame_(world_frame), on_feedback_(std::move(on_feedback)) {
  if (enabled) {
    server_ = std::make_unique<interactive_markers::InteractiveMarkerServer>(pnh_.resolveName("drag"), "", false);
  }
}

DragMarkers::~DragMarkers() = default;

void DragMarkers::SetUp(const Model& model, const State& state) {
  if (!server_) return;
  server_->clear();
  for (int b : model.moving_bodies) {
    server_->insert(DragHandle(model, b, state.X_WL(model, b), world_frame_), [this](const Feedback& f) {
      using Event = visualization_msgs::InteractiveMarkerFeedback;
      const uint8_t type = f->event_type;
      if (type == Event::MOUSE_DOWN || type == Event::POSE_UPDATE || type == Event::MOUSE_UP) on_feedback_(f);
    });
  }
  server_->applyChanges();
}

void DragMarkers::SetDragged(const std::string& body, bool dragged) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (dragged) {
    dragged_.insert(body);
  } else {
    dragged_.erase(body);
  }
}

void DragMarkers::Follow(const NodeSnapshot& snapshot) {
  if (!server_ || snapshot.version == version_) return;  // nothing moved: nothing to send
  const double now = ros::WallTime::now().toSec();
  if (now < next_update_) return;
  next_update_ = now + kMarkerUpdatePeriodS;
  version_ = snapshot.version;
  const Model& model = *snapshot.model;
  std::set<std::string> dragged;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    dragged = dragged_;
  }
  for (int b : model.moving_bodies) {
    if (dragged.count(model.bodies[b].name)) continue;  // the user's drag moves that one
    server_->setPose(model.bodies[b].name, conv::ToPoseMsg(snapshot.state.X_WL(model, b)));
  }
  server_->applyChanges();
}

}  // namespace implicit_sim
