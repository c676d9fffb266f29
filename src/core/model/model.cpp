#include "implicit_sim/core/model/model.h"

#include <algorithm>


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

BroadPhase MakeBroadPhase(const Model& model) {
  std::vector<const ConvexShape*> shapes;
  for (const Body& body : model.bodies) shapes.push_back(&body.shape);
  return BroadPhase(std::move(shapes), [&model](int i, int j) { return model.PairIndex(i, j); });
}

}  // namespace implicit_sim
