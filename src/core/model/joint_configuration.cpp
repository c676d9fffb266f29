#include "implicit_sim/core/model/joint_configuration.h"

#include <cmath>
#include <vector>

#include <Eigen/Geometry>

#include "implicit_sim/core/base/format.h"
#include "implicit_sim/core/model/joints.h"

namespace implicit_sim {
namespace {

bool CheckRequest(const Model& model, int j, double q, std::string* error) {
  if (j < 0 || j >= static_cast<int>(model.joints.size())) {
    *error = "joint index " + std::to_string(j) + " out of range [0, " + std::to_string(model.joints.size()) + ")";
    return false;
  }
  const Joint& joint = model.joints[j];
  const std::string where = "joint '" + joint.name + "'";
  if (!joint.has_coordinate()) {
    *error = where + " is " + JointTypeName(joint.type) + ": it has no position to set";
  } else if (joint.mimics()) {
    *error = where + " mimics '" + model.joints[joint.mimic_leader].name + "': set that joint instead";
  } else if (!std::isfinite(q)) {
    *error = where + ": position must be finite";
  } else if (joint.limited && (q < joint.lower - kJointLimitRoundOff || q > joint.upper + kJointLimitRoundOff)) {
    *error = where + ": position " + FormatNumber(q) + " is outside its limits [" + FormatNumber(joint.lower) + ", " +
             FormatNumber(joint.upper) + "]";
  }
  return error->empty();
}

void SetPose(const Model& model, int body, const Pose& X_WB, State* state) {
  const int slot = model.velocity_slot[body];
  const Eigen::Quaterniond q(X_WB.linear());
  state->q.segment<3>(Model::q_offset(slot)) = X_WB.translation();
  state->q.segment<4>(Model::q_offset(slot) + 3) << q.w(), q.x(), q.y(), q.z();
  state->v.segment<6>(Model::v_offset(slot)).setZero();
}

}  // namespace

Pose ChildPoseAtPosition(const Joint& joint, const Pose& X_WP, double q) {
  const Mat3 R_WJ = X_WP.linear() * joint.R_PJ;  // the parent's joint frame: columns a, b1, b2
  Vec3 x_C = X_WP * joint.p_PJ;
  Mat3 R_WC;
  if (joint.type == JointType::kPrismatic) {
    R_WC = R_WJ * joint.R_CJ.transpose();
    x_C += q * R_WJ.col(0);
  } else {
    const double turn = joint.type == JointType::kFixed ? 0.0 : q - joint.offset;
    R_WC = R_WJ * Eigen::AngleAxisd(turn, Vec3::UnitX()).toRotationMatrix() * joint.R_CJ.transpose();
  }
  Pose X_WC = Pose::Identity();
  X_WC.linear() = R_WC;
  X_WC.translation() = x_C - R_WC * joint.p_CJ;
  return X_WC;
}

bool SetJointPositions(const Model& model, const std::map<int, double>& positions, State* state, std::string* error) {
  error->clear();
  for (const auto& [j, q] : positions) {
    if (!CheckRequest(model, j, q, error)) return false;
  }
  const int n = static_cast<int>(model.joints.size());
  std::vector<double> target(n);
  for (int j = 0; j < n; ++j) target[j] = JointPosition(model, *state, j);
  for (const auto& [j, q] : positions) target[j] = q;
  // Each joint to place once its parent is final: a joint is (re)placed when named, when its parent body moved, or
  // when its leader is set; moving a body re-queues the joints below it. A tree, so this ends after at most
  // depth sweeps.
  std::vector<bool> pending(n, false);
  for (int j = 0; j < n; ++j) {
    const Joint& joint = model.joints[j];
    pending[j] = positions.count(j) > 0 || (joint.mimics() && positions.count(joint.mimic_leader) > 0);
  }
  State next = *state;
  for (bool changed = true; changed;) {
    changed = false;
    for (int j = 0; j < n; ++j) {
      if (!pending[j]) continue;
      const Joint& joint = model.joints[j];
      if (joint.mimics()) target[j] = joint.mimic_multiplier * target[joint.mimic_leader] + joint.mimic_offset;
      // A planar joint has no coordinate: its child keeps its pose relative to the parent.
      const Pose X_WC = joint.type == JointType::kPlanar
                            ? Pose(ParentPose(model, next, joint) * ParentPose(model, *state, joint).inverse() *
                                   state->X_WB(model, joint.child))
                            : ChildPoseAtPosition(joint, ParentPose(model, next, joint), target[j]);
      SetPose(model, joint.child, X_WC, &next);
      pending[j] = false;
      for (int k = 0; k < n; ++k) pending[k] = pending[k] || model.joints[k].parent == joint.child;
      changed = true;
    }
  }
  *state = next;
  return true;
}

}  // namespace implicit_sim
