#include "implicit_sim/core/model/joints.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace implicit_sim {
namespace {

// (x_C - x_P) . U with U = R_P R_PJ e_k.
double LinearRow(const Joint& joint, int k, const Pose& X_WP, const Pose& X_WC, JointGradient* g) {
  const Vec3 U = X_WP.linear() * joint.R_PJ.col(k);
  const Vec3 r_C = X_WC.linear() * joint.p_CJ;  // joint origin from the child's centre of mass
  const Vec3 x_C = X_WC.translation() + r_C;
  const Vec3 x_P = X_WP * joint.p_PJ;
  if (g) {
    g->dp_C = U;
    g->dth_C = r_C.cross(U);
    g->dp_P = -U;
    g->dth_P = U.cross(x_C - X_WP.translation());  // from x_P and from U turning with the parent
  }
  return (x_C - x_P).dot(U);
}

// U_i . W_j with U_i = R_P R_PJ e_i, W_j = R_C R_CJ e_j.
double AngularRow(const Joint& joint, int i, int j, const Pose& X_WP, const Pose& X_WC, JointGradient* g) {
  const Vec3 U = X_WP.linear() * joint.R_PJ.col(i);
  const Vec3 W = X_WC.linear() * joint.R_CJ.col(j);
  if (g) {
    g->dp_P.setZero();
    g->dp_C.setZero();
    g->dth_P = U.cross(W);
    g->dth_C = W.cross(U);
  }
  return U.dot(W);
}

}  // namespace

bool IsLinearEquality(const Joint& joint, int i) {
  return i < (joint.type == JointType::kPrismatic ? 2 : joint.type == JointType::kPlanar ? 1 : 3);
}

double JointEquality(const Joint& joint, int i, const Pose& X_WP, const Pose& X_WC, JointGradient* gradient) {
  if (joint.type == JointType::kPlanar) {  // the origin's offset along a; a . b1 and a . b2 (the child turns about a)
    return i == 0 ? LinearRow(joint, 0, X_WP, X_WC, gradient) : AngularRow(joint, 0, i, X_WP, X_WC, gradient);
  }
  const bool prismatic = joint.type == JointType::kPrismatic;
  if (IsLinearEquality(joint, i)) return LinearRow(joint, prismatic ? i + 1 : i, X_WP, X_WC, gradient);
  const int k = i - (prismatic ? 2 : 3);  // 0: (a, b1), 1: (a, b2), 2: (b1, b2)
  return AngularRow(joint, k == 2 ? 1 : 0, k == 2 ? 2 : k + 1, X_WP, X_WC, gradient);
}

double JointPosition(const Joint& joint, const Pose& X_WP, const Pose& X_WC, JointGradient* gradient) {
  switch (joint.type) {
    case JointType::kFixed:
    case JointType::kPlanar:
      if (gradient) *gradient = JointGradient();
      return 0.0;
    case JointType::kPrismatic:
      return LinearRow(joint, 0, X_WP, X_WC, gradient);
    case JointType::kRevolute:
    case JointType::kContinuous:
      break;
  }
  // theta = offset + atan2(y, x), x = U_1 . W_1, y = U_2 . W_1; d theta = (x dy - y dx) / (x^2 + y^2) with
  // dx/dtheta_C = W_1 x U_1 and dy/dtheta_C = W_1 x U_2 (and the opposite for the parent).
  const Vec3 U1 = X_WP.linear() * joint.R_PJ.col(1), U2 = X_WP.linear() * joint.R_PJ.col(2);
  const Vec3 W1 = X_WC.linear() * joint.R_CJ.col(1);
  const double x = U1.dot(W1), y = U2.dot(W1);
  if (gradient) {
    const Vec3 c = (x * W1.cross(U2) - y * W1.cross(U1)) / std::max(x * x + y * y, 1e-300);
    gradient->dp_P.setZero();
    gradient->dp_C.setZero();
    gradient->dth_C = c;
    gradient->dth_P = -c;
  }
  return joint.offset + std::atan2(y, x);
}

Pose ParentPose(const Model& model, const State& state, const Joint& joint) {
  return joint.parent < 0 ? Pose::Identity() : state.X_WB(model, joint.parent);
}

namespace {
struct BodyVelocity {
  Vec3 v = Vec3::Zero(), w = Vec3::Zero();
};
BodyVelocity VelocityOf(const Model& model, const State& state, int body) {
  const int k = body < 0 ? -1 : model.velocity_slot[body];
  if (k < 0) return {};
  return {state.v_WB(k), state.w_WB(k)};
}
}  // namespace

double JointPosition(const Model& model, const State& state, int j) {
  const Joint& joint = model.joints[j];
  return JointPosition(joint, ParentPose(model, state, joint), state.X_WB(model, joint.child), nullptr);
}

double JointVelocity(const Model& model, const State& state, int j) {
  const Joint& joint = model.joints[j];
  JointGradient g;
  JointPosition(joint, ParentPose(model, state, joint), state.X_WB(model, joint.child), &g);
  const BodyVelocity P = VelocityOf(model, state, joint.parent), C = VelocityOf(model, state, joint.child);
  return g.Rate(P.v, P.w, C.v, C.w);
}

void JointDrift(const Model& model, const State& state, double* position_m, double* angle_rad) {
  *position_m = *angle_rad = 0.0;
  for (const Joint& joint : model.joints) {
    const Pose X_WP = ParentPose(model, state, joint), X_WC = state.X_WB(model, joint.child);
    for (int i = 0; i < joint.num_equalities(); ++i) {
      const double error = std::abs(JointEquality(joint, i, X_WP, X_WC, nullptr));
      double& worst = IsLinearEquality(joint, i) ? *position_m : *angle_rad;
      worst = std::max(worst, IsLinearEquality(joint, i) ? error : std::asin(std::min(error, 1.0)));
    }
  }
}

double ClampJointEffort(const Joint& joint, double commanded) {
  const double limit = joint.effort_limit > 0.0 ? joint.effort_limit : INFINITY;
  return std::clamp(commanded, -limit, limit);
}

bool CheckJointDrive(const Joint& joint, const JointDrive& drive, std::string* error) {
  std::string problem;
  if (!std::isfinite(drive.position_target) || !std::isfinite(drive.velocity_target)) {
    problem = "targets must be finite";
  } else if (!(drive.stiffness >= 0.0 && drive.stiffness <= kMaxJointDriveGain) ||
             !(drive.damping >= 0.0 && drive.damping <= kMaxJointDriveGain)) {
    problem = "stiffness and damping must be in [0, 1e12] (kMaxJointDriveGain)";
  } else if (JointDriveActive(drive) && !joint.has_coordinate()) {
    problem = "a fixed joint cannot be driven";
  } else if (JointDriveActive(drive) && joint.mimics()) {
    problem = "the joint mimics another joint (drive that one)";
  } else if (JointDriveActive(drive) && joint.limited &&
             !(drive.position_target >= joint.lower - kJointLimitRoundOff &&
               drive.position_target <= joint.upper + kJointLimitRoundOff)) {
    problem = "position target outside the joint limits [" + std::to_string(joint.lower) + ", " +
              std::to_string(joint.upper) + "]";
  }
  if (problem.empty()) return true;
  if (error) {
    *error = "joint drive of joint '" + joint.name + "' refused: " + problem + " (position_target " +
             std::to_string(drive.position_target) + ", velocity_target " + std::to_string(drive.velocity_target) +
             ", stiffness " + std::to_string(drive.stiffness) + ", damping " + std::to_string(drive.damping) + ")";
  }
  return false;
}

double JointDrivePositionError(const Joint& joint, double position_target, double q) {
  constexpr double kTwoPi = 6.28318530717958647692;
  const bool angle = joint.type == JointType::kRevolute || joint.type == JointType::kContinuous;
  return angle && !joint.limited ? std::remainder(position_target - q, kTwoPi) : position_target - q;
}

double JointDriveEffortAt(const Joint& joint, const JointDrive& drive, double q, double qdot) {
  return ClampJointEffort(joint, drive.stiffness * JointDrivePositionError(joint, drive.position_target, q) +
                                     drive.damping * (drive.velocity_target - qdot) + drive.gravity_effort);
}

void SubtreeMassMoments(const Model& model, const State& state, std::vector<double>* mass,
                        std::vector<Vec3>* first_moment_W) {
  mass->resize(model.bodies.size());
  first_moment_W->resize(model.bodies.size());
  for (size_t b = 0; b < model.bodies.size(); ++b) {
    (*mass)[b] = model.bodies[b].mass;
    (*first_moment_W)[b] = model.bodies[b].mass * state.X_WB(model, static_cast<int>(b)).translation();
  }
  // Joints list parents before children: from the leaves up, each child's sums are final when added to its parent.
  for (size_t k = model.joints.size(); k-- > 0;) {
    const Joint& joint = model.joints[k];
    if (joint.parent < 0) continue;
    (*mass)[joint.parent] += (*mass)[joint.child];
    (*first_moment_W)[joint.parent] += (*first_moment_W)[joint.child];
  }
}

double JointGravityEffort(const Model& model, const State& state, int j, const std::vector<double>& subtree_mass,
                          const std::vector<Vec3>& subtree_first_moment_W) {
  const Joint& joint = model.joints[j];
  if (!joint.has_coordinate()) return 0.0;
  const Pose X_WC = state.X_WB(model, joint.child);
  const Vec3 a_W = X_WC.linear() * joint.R_CJ.col(0), p_WO = X_WC * joint.p_CJ;
  const double m = subtree_mass[joint.child];                                     // kg
  const Vec3 weight_W = m * model.gravity_W;                                      // N
  const Vec3 moment_WO = (subtree_first_moment_W[joint.child] - m * p_WO).cross(model.gravity_W);  // N m about O
  return joint.type == JointType::kPrismatic ? -a_W.dot(weight_W) : -a_W.dot(moment_WO);
}

void AddJointEffortWrench(const Model& model, const State& state, const Eigen::VectorXd& efforts,
                          Eigen::VectorXd* wrench_W) {
  if (efforts.size() != static_cast<int>(model.joints.size()) || wrench_W->size() != model.nv()) {
    throw std::invalid_argument("joint efforts: expected " + std::to_string(model.joints.size()) +
                                " efforts and a wrench vector of " + std::to_string(model.nv()));
  }
  if (!efforts.allFinite()) throw std::invalid_argument("joint efforts must be finite");
  for (size_t j = 0; j < model.joints.size(); ++j) {
    const Joint& joint = model.joints[j];
    if (!joint.has_coordinate() || efforts[j] == 0.0) continue;
    const double effort = ClampJointEffort(joint, efforts[j]);
    JointGradient g;
    JointPosition(joint, ParentPose(model, state, joint), state.X_WB(model, joint.child), &g);
    for (const auto& [body, dp, dth] : {std::make_tuple(joint.parent, g.dp_P, g.dth_P),
                                        std::make_tuple(joint.child, g.dp_C, g.dth_C)}) {
      const int k = body < 0 ? -1 : model.velocity_slot[body];
      if (k < 0) continue;
      wrench_W->segment<3>(Model::v_offset(k)) += effort * dp;
      wrench_W->segment<3>(Model::v_offset(k) + 3) += effort * dth;
    }
  }
}

}  // namespace implicit_sim
