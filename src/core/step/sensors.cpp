#include "implicit_sim/core/step/sensors.h"

#include "implicit_sim/core/model/joints.h"

namespace implicit_sim {
namespace {

// The velocity of the world point p_W moving with `body` (m/s; 0 for a fixed body).
Vec3 PointVelocity(const Model& model, const State& state, int body, const Vec3& p_W) {
  const int slot = model.velocity_slot[body];
  if (slot < 0) return Vec3::Zero();
  return state.v_WB(slot) + state.w_WB(slot).cross(p_W - state.X_WB(model, body).translation());
}

}  // namespace

void ReadContactSensor(const Model& model, const State& state, const Sensor& sensor,
                       const std::vector<ContactResult>& contacts, double threshold, ContactSensorReading* reading) {
  reading->contacts.clear();
  reading->force_W.setZero();
  reading->moment_W.setZero();
  const Vec3 p_WL = state.X_WL(model, sensor.body).translation();
  for (size_t c = 0; c < contacts.size(); ++c) {
    const ContactResult& contact = contacts[c];
    if (contact.pair < 0 || !(contact.normal_force > threshold)) continue;
    const ContactPair& pair = model.pairs[contact.pair];
    if (pair.body1 != sensor.body && pair.body2 != sensor.body) continue;
    // On body 1: the normal force along n (from body 2 towards body 1), friction, the torsional and rolling moments;
    // body 2 takes the opposite, at its own closest point.
    const double sign = pair.body1 == sensor.body ? 1.0 : -1.0;
    const Vec3 f_W = sign * (contact.normal_force * contact.n_W + contact.friction_force_W);
    const Vec3 p_WC = pair.body1 == sensor.body ? contact.p_WA1 : contact.p_WA2;
    reading->contacts.push_back(static_cast<int>(c));
    reading->force_W += f_W;
    reading->moment_W += (p_WC - p_WL).cross(f_W) +
                         sign * (contact.torsional_moment * contact.n_W + contact.rolling_moment_W);
  }
}

ImuReading ReadImu(const Model& model, const Sensor& sensor, const State& before, const State& after, double h) {
  const Pose X_WS_before = before.X_WL(model, sensor.body) * sensor.X_LS;
  const Pose X_WS = after.X_WL(model, sensor.body) * sensor.X_LS;
  const Vec3 v_before = PointVelocity(model, before, sensor.body, X_WS_before.translation());
  const Vec3 v_after = PointVelocity(model, after, sensor.body, X_WS.translation());
  const int slot = model.velocity_slot[sensor.body];
  const Vec3 w_W = slot < 0 ? Vec3::Zero() : after.w_WB(slot);
  const Mat3 R_SW = X_WS.linear().transpose();
  ImuReading reading;
  reading.q_WS = Eigen::Quaterniond(X_WS.linear()).normalized();
  reading.w_S = R_SW * w_W;
  reading.a_S = R_SW * ((v_after - v_before) / h - model.gravity_W);
  return reading;
}

ForceTorqueReading ReadForceTorque(const Model& model, const Sensor& sensor, const State& before, const State& after,
                                   double h, StepperOptions::Scheme scheme,
                                   const std::vector<ContactResult>& contacts,
                                   const Eigen::VectorXd* external_wrench_W, const Eigen::VectorXd* joint_efforts,
                                   std::vector<char>* in_subtree) {
  const Joint& joint = model.joints[sensor.joint];
  in_subtree->assign(model.bodies.size(), 0);
  (*in_subtree)[joint.child] = 1;
  for (const Joint& other : model.joints) {  // parents before children
    if (other.parent >= 0 && (*in_subtree)[other.parent]) (*in_subtree)[other.child] = 1;
  }
  const Pose X_WL = before.X_WL(model, sensor.body);
  const Vec3 p_WL = X_WL.translation();
  Vec3 force_W = Vec3::Zero(), moment_W = Vec3::Zero();  // on the subtree, about p_WL
  // Each body's Newton-Euler residual over the step: the joint forces on it.
  for (int k = 0; k < model.num_moving(); ++k) {
    const int b = model.moving_bodies[k];
    if (!(*in_subtree)[b]) continue;
    const Body& body = model.bodies[b];
    const Pose X_WB0 = before.X_WB(model, b), X_WB1 = after.X_WB(model, b);
    const Mat3 R0 = X_WB0.linear(), R1 = X_WB1.linear();
    const Vec3 L0 = R0 * body.I_B * R0.transpose() * before.w_WB(k);
    const Vec3 L1 = R1 * body.I_B * R1.transpose() * after.w_WB(k);
    Vec3 f = body.mass * (after.v_WB(k) - before.v_WB(k)) / h - body.mass * model.gravity_W - body.f_applied_W;
    Vec3 tau = (L1 - L0) / h - body.tau_applied_W;
    if (external_wrench_W) {
      f -= external_wrench_W->segment<3>(Model::v_offset(k));
      tau -= external_wrench_W->segment<3>(Model::v_offset(k) + 3);
    }
    // The paper's step applies joint forces at the start-of-step centres of mass (SHAKE); RATTLE half there, half at
    // the end (its velocity stage).
    const Vec3 p_WB = scheme == StepperOptions::Scheme::kRattle
                          ? Vec3(0.5 * (X_WB0.translation() + X_WB1.translation()))
                          : Vec3(X_WB0.translation());
    moment_W += (p_WB - p_WL).cross(f) + tau;
    force_W += f;
  }
  // Less the contacts' forces and moments on subtree bodies (a contact inside the subtree cancels).
  for (const ContactResult& contact : contacts) {
    if (contact.pair < 0) continue;
    const ContactPair& pair = model.pairs[contact.pair];
    for (const int side : {1, 2}) {
      const int b = side == 1 ? pair.body1 : pair.body2;
      if (b < 0 || !(*in_subtree)[b]) continue;
      const double sign = side == 1 ? 1.0 : -1.0;
      const Vec3 f_W = sign * (contact.normal_force * contact.n_W + contact.friction_force_W);
      const Vec3 p_WC = side == 1 ? contact.p_WA1 : contact.p_WA2;
      force_W -= f_W;
      moment_W -= (p_WC - p_WL).cross(f_W) + sign * (contact.torsional_moment * contact.n_W + contact.rolling_moment_W);
    }
  }
  // Plus the joint's own commanded effort along its position gradient at the start (AddJointEffortWrench's).
  if (joint_efforts && joint.has_coordinate() && (*joint_efforts)[sensor.joint] != 0.0) {
    JointGradient g;
    JointPosition(joint, ParentPose(model, before, joint), before.X_WB(model, joint.child), &g);
    const double effort = ClampJointEffort(joint, (*joint_efforts)[sensor.joint]);
    force_W += effort * g.dp_C;
    moment_W += (before.X_WB(model, joint.child).translation() - p_WL).cross(effort * g.dp_C) + effort * g.dth_C;
  }
  ForceTorqueReading reading;
  reading.force_L = X_WL.linear().transpose() * force_W;
  reading.torque_L = X_WL.linear().transpose() * moment_W;
  return reading;
}

}  // namespace implicit_sim
