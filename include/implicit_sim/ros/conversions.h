// Static converters between the ROS-free core and ROS messages (the thin ROS layer, as grid_map_ros does it).
#pragma once

#include <string>

#include <geometry_msgs/Pose.h>
#include <geometry_msgs/Transform.h>
#include <geometry_msgs/Twist.h>
#include <visualization_msgs/MarkerArray.h>

#include "implicit_sim/BodyState.h"
#include "implicit_sim/ContactState.h"
#include "implicit_sim/core/model/model.h"
#include "implicit_sim/core/model/state.h"
#include "implicit_sim/core/step/data.h"

namespace implicit_sim {
namespace ros_conversions {

geometry_msgs::Pose ToPoseMsg(const Pose& X);
geometry_msgs::Transform ToTransformMsg(const Pose& X);
Vec3 ToVec3(const geometry_msgs::Vector3& v);
Vec3 ToVec3(const geometry_msgs::Point& p);

// Pose of a body's URDF link frame in the world (fixed bodies: their constant pose).
Pose LinkPose(const Model& model, const State& state, int body);

// Link pose and the twist of the link frame origin (world frame).
implicit_sim::BodyState ToBodyStateMsg(const Model& model, const State& state, int body);

// Writes a requested link pose and twist into the state of a moving body. Returns false with `error` set (and
// changes nothing) for a non-finite value, a zero quaternion, or a velocity on a locked axis; normalizes the
// quaternion.
bool SetBodyStateFromMsg(const Model& model, int body, const implicit_sim::BodyState& msg, State* state,
                         std::string* error);

implicit_sim::ContactState ToContactMsg(const Model& model, int pair, const ContactResult& contact);

// Markers of the true implicit shapes, one per body with a shape, in the body's link frame (frame_locked):
// SPHERE (scaled for an ellipsoid), CUBE, CYLINDER where exact, a thin CUBE for a half-space, and a TRIANGLE_LIST
// ray-cast from the implicit inequalities otherwise (prisms, superellipsoids, intersections).
visualization_msgs::MarkerArray ShapeMarkers(const Model& model);

// Contact markers for pair `pair` in the world frame: the point a1, the normal at a2, and the contact force at a1 as an
// arrow of length |F| * force_scale (m/N); `size` (m) is the point's diameter. With active = false, DELETE actions
// for the same ids.
void AppendContactMarkers(int pair, const ContactResult& contact, bool active,
                          const std::string& world_frame, double force_scale, double size,
                          visualization_msgs::MarkerArray* out);

}  // namespace ros_conversions
}  // namespace implicit_sim
