#include "implicit_sim/core/model/state.h"

#include <cmath>

#include "implicit_sim/core/base/format.h"

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

namespace {

// "body 'ball' (q[3:7], its quaternion w, x, y, z)": where a value of the state lives, for messages.
std::string StateEntry(const Model& model, int slot, const char* vector, int begin, int end, const char* what) {
  return "body '" + model.bodies[model.moving_bodies[slot]].name + "' (" + vector + "[" + std::to_string(begin) + ":" +
         std::to_string(end) + "], " + what + ")";
}

}  // namespace

bool CheckState(const Model& model, const State& state, std::string* error) {
  auto fail = [error](const std::string& message) {
    if (error) *error = "state: " + message;
    return false;
  };
  if (state.q.size() != model.nq() || state.v.size() != model.nv()) {
    return fail("size does not match the model: q must hold " + std::to_string(model.nq()) + " values (got " +
                std::to_string(state.q.size()) + ") and v " + std::to_string(model.nv()) + " (got " +
                std::to_string(state.v.size()) + "), 7 and 6 per moving body");
  }
  if (!std::isfinite(state.t)) return fail("t must be finite, got " + FormatNumber(state.t));
  for (int k = 0; k < model.num_moving(); ++k) {
    const int iq = Model::q_offset(k), iv = Model::v_offset(k);
    if (!state.q.segment<3>(iq).allFinite()) {
      return fail(StateEntry(model, k, "q", iq, iq + 3, "its position p_WB in m") + " must be finite");
    }
    if (!state.q.segment<4>(iq + 3).allFinite()) {
      return fail(StateEntry(model, k, "q", iq + 3, iq + 7, "its quaternion w, x, y, z") + " must be finite");
    }
    const double norm = state.q.segment<4>(iq + 3).norm();
    if (!(std::abs(norm - 1.0) <= kUnitQuaternionTolerance)) {
      return fail(StateEntry(model, k, "q", iq + 3, iq + 7, "its quaternion w, x, y, z") +
                  " must be a unit quaternion (norm within " + FormatNumber(kUnitQuaternionTolerance) +
                  " of 1), got norm " + FormatNumber(norm) + ": normalize it");
    }
    if (!state.v.segment<3>(iv).allFinite()) {
      return fail(StateEntry(model, k, "v", iv, iv + 3, "its velocity v_WB in m/s") + " must be finite");
    }
    if (!state.v.segment<3>(iv + 3).allFinite()) {
      return fail(StateEntry(model, k, "v", iv + 3, iv + 6, "its angular velocity w_WB in rad/s") + " must be finite");
    }
  }
  return true;
}

}  // namespace implicit_sim
