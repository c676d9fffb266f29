#include "implicit_sim/core/model/state.h"

namespace implicit_sim {

State State::Initial(const Model& model) {
  State s;
  const int n = model.num_moving();
  s.q.resize(model.nq());
  s.v.resize(model.nv());
  for (int k = 0; k < n; ++k) {
    const Body& body = model.bodies[model.moving_bodies[k]];
    const Eigen::Quaterniond quat(body.X_WB0.linear());
    s.q.segment<3>(Model::q_offset(k)) = body.X_WB0.translation();
    s.q.segment<4>(Model::q_offset(k) + 3) << quat.w(), quat.x(), quat.y(), quat.z();
    s.v.segment<3>(Model::v_offset(k)) = body.v_WB0;
    s.v.segment<3>(Model::v_offset(k) + 3) = body.w_WB0;
  }
  return s;
}

Pose State::X_WB(const Model& model, int body) const {
  const int k = model.velocity_slot[body];
  if (k < 0) return model.bodies[body].X_WB0;
  Pose X = Pose::Identity();
  const int iq = Model::q_offset(k);
  X.translation() = q.segment<3>(iq);
  X.linear() = Eigen::Quaterniond(q[iq + 3], q[iq + 4], q[iq + 5], q[iq + 6]).normalized()
                   .toRotationMatrix();
  return X;
}

Pose State::X_WL(const Model& model, int body) const { return X_WB(model, body) * model.bodies[body].X_BL; }

double KineticEnergy(const Model& model, const State& state) {
  double energy = 0.0;
  for (int k = 0; k < model.num_moving(); ++k) {
    const int b = model.moving_bodies[k];
    const Body& body = model.bodies[b];
    const Mat3 R = state.X_WB(model, b).linear();
    const Vec3 w = state.w_WB(k);
    energy += 0.5 * body.mass * state.v_WB(k).squaredNorm() + 0.5 * w.dot(R * body.I_B * R.transpose() * w);
  }
  return energy;
}

}  // namespace implicit_sim
