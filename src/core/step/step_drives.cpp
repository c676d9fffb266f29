// Joint drives (joints.h, JointDrive) as rows of the step NCP: per driven joint j one unknown u, the drive effort
// (N m or N), the last of the joint's block (StepProblem::SetDrivenJoints), with the box law (doc/method.md, "Joint
// drives")
//   u = mid(-E, E, P),  P = kp e(q_target, q) + kd (v_target - qdot)
// where q and qdot are the joint position and rate at the END of the step (implicit, hence stable at any gain), e the
// position error and E = Joint::effort_limit (P itself when E = 0). The row is (u - mid(-E, E, P)) / S with
// S = Fs + kp h + kd (times 1 rad/s or 1 m/s): a force row for soft gains, a velocity-level constraint row like the
// joint equalities' for stiff ones. mid is the min-map of the box complementarity problem -E <= u <= E _|_ u - P,
// piecewise linear: its generalized Jacobian takes the slope 1 inside the box (and on its edge), 0 outside. The
// effort acts along the position gradient G_q like the joint's damping and constant effort (step_joints.cpp).
//
// Paper's step: share 1, P at the end of the step (implicit Euler). RATTLE: stage 1 applies u1 / 2 with P at the end
// of stage 1 (q1 and the stage's velocity); stage 2's unknown is the step's average effort U, applying U - u1 / 2, with
//   2 U - u1 = mid(-E, E, kp e(q_target, q1) + (kd + kp h / 2) (v_target - qdot1))
// the spring taken at the position half a step past q1 along the end velocity, q1 + h/2 (qdot1 - v_target) (relative
// to the moving target): without that term a stiff spring pins q1 and leaves qdot1 ringing at +-qdot (an eigenvalue
// -1 of the step for kp -> infinity); with it the step damps every mode for any gain and h.
#include <cmath>

#include "contact_frame.h"
#include "implicit_sim/core/step/step_problem.h"

namespace implicit_sim {
namespace {

// mid(-E, E, P) with E = joint.effort_limit (P itself when E is 0), and its derivative by P.
struct ClampedEffort {
  double value, slope;
};
ClampedEffort ClampToEffortLimit(const Joint& joint, double P) {
  const double E = joint.effort_limit;
  if (!(E > 0.0) || std::abs(P) <= E) return {P, 1.0};
  return {P > 0.0 ? E : -E, 0.0};
}

}  // namespace

void StepProblem::SetDrivenJoints(const std::vector<char>& driven, const Eigen::VectorXd* z_old,
                                  Eigen::VectorXd* z_new) {
  old_joint_offset_ = joint_offset_;
  old_driven_ = driven_;
  for (size_t j = 0; j < driven_.size(); ++j) driven_[j] = driven[j] && model_.joints[j].has_coordinate();
  LayOutJoints();
  ActivePairs(&drive_pairs_);
  // The same pairs anew: z_new zero in the new layout; old_blocks_ and old_axes_ keep the old layout.
  SetActivePairs(drive_pairs_, nullptr, z_new, &drive_new_blocks_);
  tangent_axis_ = old_axes_;
  if (!z_old) return;
  z_new->head(6 * slots_.size()) = z_old->head(6 * slots_.size());
  for (int j : joints_) {
    const int n = model_.joints[j].size();
    z_new->segment(joint_offset_[j], n) = z_old->segment(old_joint_offset_[j], n);
    if (driven_[j] && old_driven_[j]) (*z_new)[joint_offset_[j] + n] = (*z_old)[old_joint_offset_[j] + n];
  }
  for (size_t c = 0; c < blocks_.size(); ++c) {
    z_new->segment(blocks_[c].offset, blocks_[c].size()) = z_old->segment(old_blocks_[c].offset, blocks_[c].size());
  }
}

double StepProblem::JointDriveEffort(const Eigen::VectorXd& z, int joint) const {
  return driven_[joint] ? z[joint_offset_[joint] + model_.joints[joint].size()] : 0.0;
}

// S = Fs + kp h + kd: kp h + kd is the effort per unit of end-of-step joint rate (N m s/rad or N s/m), taken per
// 1 rad/s or 1 m/s.
double StepProblem::DriveRowScale(const JointDrive& drive) const {
  return force_scale_ + drive.stiffness * h_ + drive.damping;
}

void StepProblem::AddJointDriveRow(int j, int col, const Eigen::VectorXd& z, const BodyEnd& eP, const BodyEnd& eC,
                                   const JointGradient& G_q, Eigen::VectorXd* Phi) const {
  const Joint& joint = model_.joints[j];
  const JointDrive& drive = (*drives_)[j];
  JointGradient g;
  const double q = JointPosition(joint, MakePose(eP.p, eP.R), MakePose(eC.p, eC.R), &g);  // end of step
  const double rate = G_q.Rate(eP.v, eP.w, eC.v, eC.w);
  const ClampedEffort target = ClampToEffortLimit(
      joint, drive.stiffness * JointDrivePositionError(joint, drive.position_target, q) +
                 drive.damping * (drive.velocity_target - rate));
  const double inv_scale = 1.0 / DriveRowScale(drive);
  (*Phi)[col] = (z[col] - target.value) * inv_scale;
  if (WantJacobian()) AddJ(col, col, inv_scale);
  AddEndGradientRow(col, g, eP, eC, target.slope * drive.stiffness * inv_scale);
  AddRateRow(col, G_q, eP, eC, target.slope * drive.damping * inv_scale);
  const double share = stage_share();  // RATTLE stage 1 applies half its effort
  AddJointForce(G_q, share * z[col], col, share, eP, eC, Phi);
}

void StepProblem::AddJointDriveRowVelocityStage(int j, int col, const Eigen::VectorXd& z, const BodyEnd& eP,
                                                const BodyEnd& eC, const JointGradient& G_q,
                                                Eigen::VectorXd* Phi) const {
  const Joint& joint = model_.joints[j];
  const JointDrive& drive = (*drives_)[j];
  const double rate_gain = drive.damping + 0.5 * h_ * drive.stiffness;  // N m s/rad or N s/m
  const double rate = G_q.Rate(eP.v, eP.w, eC.v, eC.w);
  const ClampedEffort target = ClampToEffortLimit(
      joint, drive.stiffness * JointDrivePositionError(joint, drive.position_target, joint_q_end_[j]) +
                 rate_gain * (drive.velocity_target - rate));
  const double stage1 = stage1_z_[col];
  const double inv_scale = 1.0 / DriveRowScale(drive);
  (*Phi)[col] = (z[col] - 0.5 * (stage1 + target.value)) * inv_scale;
  if (WantJacobian()) AddJ(col, col, inv_scale);
  AddRateRow(col, G_q, eP, eC, 0.5 * target.slope * rate_gain * inv_scale);
  AddJointForce(G_q, z[col] - 0.5 * stage1, col, 1.0, eP, eC, Phi);
}

}  // namespace implicit_sim
