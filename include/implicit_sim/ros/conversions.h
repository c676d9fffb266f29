// Static converters between the ROS-free core and ROS messages (the thin ROS layer, as grid_map_ros does it).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <geometry_msgs/Pose.h>
#include <geometry_msgs/Transform.h>
#include <geometry_msgs/TransformStamped.h>
#include <geometry_msgs/Twist.h>
#include <ros/time.h>
#include <visualization_msgs/MarkerArray.h>

#include "implicit_sim/BodyState.h"
#include "implicit_sim/BodyStates.h"
#include "implicit_sim/ContactState.h"
#include "implicit_sim/Contacts.h"
#include "implicit_sim/StepStats.h"
#include "implicit_sim/core/model/model.h"
#include "implicit_sim/core/model/state.h"
#include "implicit_sim/core/step/data.h"

namespace implicit_sim {

struct StepReport;  // core/step/time_stepper.h

namespace ros_conversions {

geometry_msgs::Pose ToPoseMsg(const Pose& X);
geometry_msgs::Point ToPointMsg(const Vec3& p);
geometry_msgs::Vector3 ToVectorMsg(const Vec3& v);
geometry_msgs::Transform ToTransformMsg(const Pose& X);
Vec3 ToVec3(const geometry_msgs::Vector3& v);
Vec3 ToVec3(const geometry_msgs::Point& p);

// Link pose and the twist of the link frame origin (world frame).
implicit_sim::BodyState ToBodyStateMsg(const Model& model, const State& state, int body);

// Writes a requested link pose and twist into the state of a moving body. Returns false with `error` set (and
// changes nothing) for a non-finite value, a zero quaternion, or a velocity on a locked axis; normalizes the
// quaternion.
bool SetBodyStateFromMsg(const Model& model, int body, const implicit_sim::BodyState& msg, State* state,
                         std::string* error);

implicit_sim::ContactState ToContactMsg(const Model& model, int pair, const ContactResult& contact);

// Every body: the moving ones in slot order, then the fixed ones.
implicit_sim::BodyStates ToBodyStatesMsg(const Model& model, const State& state, const ros::Time& stamp,
                                         const std::string& world_frame);

// Whether a contact result is shown (~contacts, contact markers): its normal force exceeds threshold (N).
inline bool IsActiveContact(const ContactResult& contact, double threshold) {
  return contact.normal_force > threshold;
}

// The active contacts (IsActiveContact) among `contacts`.
implicit_sim::Contacts ToContactsMsg(const Model& model, const std::vector<ContactResult>& contacts, double threshold,
                                     const ros::Time& stamp, const std::string& world_frame);

// The statistics of step number `step`, which ended at sim_time (s); rtf is the real-time factor to report.
implicit_sim::StepStats ToStepStatsMsg(const StepReport& report, double sim_time, uint64_t step, double rtf,
                                       const std::string& world_frame);

// world_frame -> link transforms of the moving bodies b with on_tf[b] set and of the frame links f (Model::frames)
// with on_tf[bodies + f] set.
std::vector<geometry_msgs::TransformStamped> ToLinkTransforms(const Model& model, const State& state,
                                                              const std::vector<char>& on_tf, const ros::Time& stamp,
                                                              const std::string& world_frame);

// world_frame -> link transforms of the fixed bodies (for /tf_static; no stamp).
std::vector<geometry_msgs::TransformStamped> ToStaticTransforms(const Model& model, const std::string& world_frame);

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
