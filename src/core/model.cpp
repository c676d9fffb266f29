#include "implicit_sim/core/model.h"

#include <algorithm>

#include "implicit_sim/core/state.h"

namespace implicit_sim {

int Model::FindBody(const std::string& name) const {
  for (int i = 0; i < static_cast<int>(bodies.size()); ++i) {
    if (bodies[i].name == name) return i;
  }
  return -1;
}

int Model::FindJoint(const std::string& name) const {
  for (int i = 0; i < static_cast<int>(joints.size()); ++i) {
    if (joints[i].name == name) return i;
  }
  return -1;
}

bool Model::Joined(int i, int j) const {
  for (const Joint& joint : joints) {
    if ((joint.parent == i && joint.child == j) || (joint.parent == j && joint.child == i)) return true;
  }
  return false;
}

const char* JointTypeName(JointType type) {
  switch (type) {
    case JointType::kFixed: return "fixed";
    case JointType::kRevolute: return "revolute";
    case JointType::kContinuous: return "continuous";
    case JointType::kPrismatic: return "prismatic";
  }
  return "unknown";
}

int Model::PairIndex(int i, int j) const {
  if (i == j || i < 0 || j < 0 || i >= static_cast<int>(bodies.size()) || j >= static_cast<int>(bodies.size())) {
    return -1;
  }
  const int lo = std::min(i, j), hi = std::max(i, j);
  const auto begin = pairs.begin() + pairs_of_lower[lo], end = pairs.begin() + pairs_of_lower[lo + 1];
  const auto it = std::lower_bound(begin, end, hi, [](const ContactPair& pair, int body) {
    return std::max(pair.body1, pair.body2) < body;
  });
  return it != end && std::max(it->body1, it->body2) == hi ? static_cast<int>(it - pairs.begin()) : -1;
}

std::string Model::PairName(int pair) const {
  return bodies[pairs[pair].body1].name + "-" + bodies[pairs[pair].body2].name;
}

double Model::ForceScale() const {
  double scale = 1e-3;
  for (int b : moving_bodies) {
    const Body& body = bodies[b];
    scale = std::max(scale, (body.mass * gravity_W + body.f_applied_W).norm());
    scale = std::max(scale, body.mass * std::max(gravity_W.norm(), 1.0));  // at least the weight in 1 m/s^2
  }
  return scale;
}

State State::Initial(const Model& model) {
  State s;
  const int n = model.num_moving();
  s.q.resize(7 * n);
  s.v.resize(6 * n);
  for (int k = 0; k < n; ++k) {
    const Body& body = model.bodies[model.moving_bodies[k]];
    const Eigen::Quaterniond quat(body.X_WB0.linear());
    s.q.segment<3>(7 * k) = body.X_WB0.translation();
    s.q.segment<4>(7 * k + 3) << quat.w(), quat.x(), quat.y(), quat.z();
    s.v.segment<3>(6 * k) = body.v_WB0;
    s.v.segment<3>(6 * k + 3) = body.w_WB0;
  }
  return s;
}

Pose State::X_WB(const Model& model, int body) const {
  const int k = model.velocity_slot[body];
  if (k < 0) return model.bodies[body].X_WB0;
  Pose X = Pose::Identity();
  X.translation() = q.segment<3>(7 * k);
  X.linear() = Eigen::Quaterniond(q[7 * k + 3], q[7 * k + 4], q[7 * k + 5], q[7 * k + 6]).normalized()
                   .toRotationMatrix();
  return X;
}

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
