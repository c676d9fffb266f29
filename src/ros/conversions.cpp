#include "implicit_sim/ros/conversions.h"

#include <cmath>

#include "implicit_sim/core/base/format.h"
#include "implicit_sim/core/geometry/surface_mesh.h"
#include "implicit_sim/core/step/time_stepper.h"

namespace implicit_sim {
namespace ros_conversions {
namespace {


std_msgs::ColorRGBA Color(float r, float g, float b, float a) {
  std_msgs::ColorRGBA c;
  c.r = r;
  c.g = g;
  c.b = b;
  c.a = a;
  return c;
}

// A TRIANGLE_LIST of the boundary (MakeSurfaceMesh: rays on a 32 x 64 latitude-longitude grid), in the shape frame.
void RayCastMesh(const ConvexShape& shape, visualization_msgs::Marker* marker) {
  const SurfaceMesh mesh = MakeSurfaceMesh(shape, 32);
  marker->type = visualization_msgs::Marker::TRIANGLE_LIST;
  marker->scale.x = marker->scale.y = marker->scale.z = 1.0;
  marker->points.reserve(3 * mesh.triangles.size());
  for (const std::array<int, 3>& triangle : mesh.triangles) {
    for (int vertex : triangle) marker->points.push_back(ToPointMsg(mesh.vertices[vertex]));
  }
}

}  // namespace

geometry_msgs::Vector3 ToVectorMsg(const Vec3& v) {
  geometry_msgs::Vector3 m;
  m.x = v.x();
  m.y = v.y();
  m.z = v.z();
  return m;
}

geometry_msgs::Point ToPointMsg(const Vec3& p) {
  geometry_msgs::Point m;
  m.x = p.x();
  m.y = p.y();
  m.z = p.z();
  return m;
}

geometry_msgs::Pose ToPoseMsg(const Pose& X) {
  geometry_msgs::Pose m;
  m.position = ToPointMsg(X.translation());
  const Eigen::Quaterniond q(X.linear());
  m.orientation.w = q.w();
  m.orientation.x = q.x();
  m.orientation.y = q.y();
  m.orientation.z = q.z();
  return m;
}

geometry_msgs::Transform ToTransformMsg(const Pose& X) {
  const geometry_msgs::Pose p = ToPoseMsg(X);
  geometry_msgs::Transform t;
  t.translation.x = p.position.x;
  t.translation.y = p.position.y;
  t.translation.z = p.position.z;
  t.rotation = p.orientation;
  return t;
}

Vec3 ToVec3(const geometry_msgs::Vector3& v) { return Vec3(v.x, v.y, v.z); }
Vec3 ToVec3(const geometry_msgs::Point& p) { return Vec3(p.x, p.y, p.z); }

implicit_sim::BodyState ToBodyStateMsg(const Model& model, const State& state, int body) {
  implicit_sim::BodyState msg;
  msg.name = model.bodies[body].name;
  const Pose X_WL = state.X_WL(model, body);
  msg.pose = ToPoseMsg(X_WL);
  const int slot = model.velocity_slot[body];
  if (slot >= 0) {
    const Vec3 w = state.w_WB(slot);
    const Vec3 v_L = state.v_WB(slot) + w.cross(X_WL.translation() - state.X_WB(model, body).translation());
    msg.twist.linear = ToVectorMsg(v_L);
    msg.twist.angular = ToVectorMsg(w);
  }
  return msg;
}

bool SetBodyStateFromMsg(const Model& model, int body, const implicit_sim::BodyState& msg, State* state,
                         std::string* error) {
  const int slot = model.velocity_slot[body];
  if (slot < 0) {
    *error = "body '" + model.bodies[body].name + "' is fixed";
    return false;
  }
  const auto& o = msg.pose.orientation;
  const Eigen::Vector4d q(o.w, o.x, o.y, o.z);
  const Vec3 p_L = ToVec3(msg.pose.position), v_L = ToVec3(msg.twist.linear), w = ToVec3(msg.twist.angular);
  if (!q.allFinite() || !p_L.allFinite() || !v_L.allFinite() || !w.allFinite()) {
    *error = "pose and twist must be finite";
    return false;
  }
  if (q.norm() < 1e-9) {
    *error = "orientation quaternion must be non-zero (got norm " + FormatNumber(q.norm()) + ")";
    return false;
  }
  Pose X_WL = Pose::Identity();
  X_WL.translation() = p_L;
  X_WL.linear() = Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized().toRotationMatrix();
  const Body& b = model.bodies[body];
  const Pose X_WB = X_WL * b.X_BL.inverse();
  const Vec3 v_B = v_L + w.cross(X_WB.translation() - p_L);
  static const char* kAxes[6] = {"x", "y", "z", "rx", "ry", "rz"};
  for (int i = 0; i < 6; ++i) {
    const double value = i < 3 ? v_B[i] : w[i - 3];
    if (b.locked[i] && std::abs(value) > 1e-12) {
      *error = std::string("body '") + b.name + "' has its axis " + kAxes[i] + " locked: its velocity must be 0";
      return false;
    }
  }
  const Eigen::Quaterniond quat(X_WB.linear());
  const int iq = Model::q_offset(slot), iv = Model::v_offset(slot);
  state->q.segment<3>(iq) = X_WB.translation();
  state->q.segment<4>(iq + 3) << quat.w(), quat.x(), quat.y(), quat.z();
  state->v.segment<3>(iv) = v_B;
  state->v.segment<3>(iv + 3) = w;
  return true;
}

implicit_sim::ContactState ToContactMsg(const Model& model, int pair, const ContactResult& c) {
  implicit_sim::ContactState msg;
  msg.link1 = model.bodies[model.pairs[pair].body1].name;
  msg.link2 = model.bodies[model.pairs[pair].body2].name;
  msg.a1 = ToPointMsg(c.p_WA1);
  msg.a2 = ToPointMsg(c.p_WA2);
  msg.normal = ToVectorMsg(c.n_W);
  msg.gap = c.gap;
  msg.normal_force = c.normal_force;
  msg.friction_force = ToVectorMsg(c.friction_force_W);
  msg.torsional_moment = c.torsional_moment;
  msg.slip_speed = c.slip_speed;
  return msg;
}

implicit_sim::BodyStates ToBodyStatesMsg(const Model& model, const State& state, const ros::Time& stamp,
                                         const std::string& world_frame) {
  implicit_sim::BodyStates msg;
  msg.header.stamp = stamp;
  msg.header.frame_id = world_frame;
  for (int b : model.moving_bodies) msg.bodies.push_back(ToBodyStateMsg(model, state, b));
  for (int b = 0; b < static_cast<int>(model.bodies.size()); ++b) {
    if (model.bodies[b].is_fixed) msg.bodies.push_back(ToBodyStateMsg(model, state, b));
  }
  return msg;
}

implicit_sim::Contacts ToContactsMsg(const Model& model, const std::vector<ContactResult>& contacts, double threshold,
                                     const ros::Time& stamp, const std::string& world_frame) {
  implicit_sim::Contacts msg;
  msg.header.stamp = stamp;
  msg.header.frame_id = world_frame;
  for (const ContactResult& contact : contacts) {
    if (IsActiveContact(contact, threshold)) msg.contacts.push_back(ToContactMsg(model, contact.pair, contact));
  }
  return msg;
}

implicit_sim::StepStats ToStepStatsMsg(const StepReport& r, double sim_time, uint64_t step, double rtf,
                                       const std::string& world_frame) {
  implicit_sim::StepStats msg;
  msg.header.stamp.fromSec(sim_time);
  msg.header.frame_id = world_frame;
  msg.step = step;
  msg.converged = r.converged;
  msg.advanced = r.advanced;
  msg.status = !r.advanced ? "failed" : r.converged ? "converged" : "not converged";
  msg.iterations = r.iterations;
  msg.residual = r.residual;
  msg.complementarity_error = r.complementarity_error;
  msg.active_contacts = r.active_contacts;
  msg.cold_restarts = r.cold_restarts;
  msg.smoothed_solves = r.smoothed_solves;
  msg.ipopt_solves = r.ipopt_solves;
  msg.substeps = r.substeps;
  msg.wall_time = r.wall_time_s;
  msg.real_time_factor = rtf;
  return msg;
}

std::vector<geometry_msgs::TransformStamped> ToLinkTransforms(const Model& model, const State& state,
                                                              const std::vector<char>& on_tf, const ros::Time& stamp,
                                                              const std::string& world_frame) {
  std::vector<geometry_msgs::TransformStamped> transforms;
  const auto add = [&](const std::string& link, const Pose& X_WL) {
    geometry_msgs::TransformStamped t;
    t.header.stamp = stamp;
    t.header.frame_id = world_frame;
    t.child_frame_id = link;
    t.transform = ToTransformMsg(X_WL);
    transforms.push_back(t);
  };
  for (int b : model.moving_bodies) {
    if (on_tf[b]) add(model.bodies[b].name, state.X_WL(model, b));
  }
  const size_t frames_start = model.bodies.size();
  for (size_t f = 0; f < model.frames.size(); ++f) {
    const FrameLink& frame = model.frames[f];
    if (on_tf[frames_start + f]) add(frame.name, state.X_WL(model, frame.body) * frame.X_LF);
  }
  return transforms;
}

std::vector<geometry_msgs::TransformStamped> ToStaticTransforms(const Model& model, const std::string& world_frame) {
  std::vector<geometry_msgs::TransformStamped> transforms;
  for (const Body& body : model.bodies) {
    if (!body.is_fixed) continue;
    geometry_msgs::TransformStamped t;
    t.header.frame_id = world_frame;
    t.child_frame_id = body.name;
    t.transform = ToTransformMsg(body.X_WB0 * body.X_BL);
    transforms.push_back(t);
  }
  return transforms;
}

visualization_msgs::MarkerArray ShapeMarkers(const Model& model) {
  visualization_msgs::MarkerArray out;
  for (int g = 0; g < static_cast<int>(model.geoms.size()); ++g) {  // one marker per shape (id: its Model::geoms index)
    const Body& body = model.bodies[model.geoms[g].body];
    const ConvexShape& shape = model.shape(g);
    if (shape.inequalities.empty()) continue;
    visualization_msgs::Marker m;
    m.header.frame_id = body.name;
    m.ns = "shapes";
    m.id = g;
    m.action = visualization_msgs::Marker::ADD;
    m.frame_locked = true;
    m.pose = ToPoseMsg(body.X_BL.inverse() * shape.X_BS);  // the shape frame in the link frame
    m.color = body.is_fixed ? Color(0.6f, 0.6f, 0.65f, 0.6f) : Color(0.95f, 0.55f, 0.15f, 0.9f);
    const Vec3 s = shape.size;
    switch (shape.type) {
      case ShapeType::kSphere:
      case ShapeType::kEllipsoid:
        m.type = visualization_msgs::Marker::SPHERE;
        m.scale = ToVectorMsg(2.0 * s);
        break;
      case ShapeType::kBox:
        m.type = visualization_msgs::Marker::CUBE;
        m.scale = ToVectorMsg(2.0 * s);
        break;
      case ShapeType::kCylinder:
        m.type = visualization_msgs::Marker::CYLINDER;
        m.scale = ToVectorMsg(Vec3(2.0 * s[0], 2.0 * s[0], 2.0 * s[2]));
        break;
      case ShapeType::kHalfSpace: {  // a 10 m x 10 m slab just below the plane z = 0 of the shape frame
        m.type = visualization_msgs::Marker::CUBE;
        m.scale = ToVectorMsg(Vec3(10.0, 10.0, 0.002));
        m.pose = ToPoseMsg(body.X_BL.inverse() * shape.X_BS * Pose(Eigen::Translation3d(0, 0, -0.001)));
        break;
      }
      default:
        RayCastMesh(shape, &m);
    }
    out.markers.push_back(m);
  }
  return out;
}

void AppendContactMarkers(int pair, const ContactResult& c, bool active,
                          const std::string& world_frame, double force_scale, double size,
                          visualization_msgs::MarkerArray* out) {
  const char* namespaces[3] = {"contact_points", "contact_normals", "contact_forces"};
  for (int k = 0; k < 3; ++k) {
    visualization_msgs::Marker m;
    m.header.frame_id = world_frame;
    m.ns = namespaces[k];
    m.id = pair;
    m.pose.orientation.w = 1.0;
    if (!active) {
      m.action = visualization_msgs::Marker::DELETE;
      out->markers.push_back(m);
      continue;
    }
    m.action = visualization_msgs::Marker::ADD;
    if (k == 0) {
      m.type = visualization_msgs::Marker::SPHERE;
      m.pose.position = ToPointMsg(c.p_WA1);
      m.scale.x = m.scale.y = m.scale.z = size;
      m.color = Color(0.9f, 0.1f, 0.1f, 1.0f);
    } else {
      m.type = visualization_msgs::Marker::ARROW;
      const Vec3 force = c.normal_force * c.n_W + c.friction_force_W;
      const Vec3 start = k == 1 ? c.p_WA2 : c.p_WA1;
      const Vec3 end = k == 1 ? Vec3(c.p_WA2 + 6.0 * size * c.n_W) : Vec3(c.p_WA1 + force_scale * force);
      m.points = {ToPointMsg(start), ToPointMsg(end)};
      m.scale.x = 0.4 * size;  // shaft diameter
      m.scale.y = 0.8 * size;  // head diameter
      m.scale.z = 0.0;
      m.color = k == 1 ? Color(0.1f, 0.4f, 0.95f, 1.0f) : Color(0.1f, 0.8f, 0.2f, 1.0f);
    }
    out->markers.push_back(m);
  }
}

}  // namespace ros_conversions
}  // namespace implicit_sim
