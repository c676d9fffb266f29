#include "implicit_sim/core/step/sensors.h"

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

}  // namespace implicit_sim
