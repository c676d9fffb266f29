// The joint rows of the step NCP (the paper's bilateral constraints, eq. 1 with joints; Section III notes the
// formulation holds with them). Per joint j, in its block at o = joint_offset(j) (m = num_equalities):
//   rows o .. o+m-1     C_i(end-of-step poses) / h = 0: each equality of joints.h holds at the END of the step
//                       (position level, so drift stays at the solver tolerance), in velocity units
//   rows o+m, o+m+1     limits: FB(l_lo / Fs, q - lower) and FB(l_hi / Fs, upper - q), q the end-of-step position
//                       (0 <= limit impulse _|_ distance to the limit >= 0)
//   the next two rows   Coulomb joint friction like the contact friction of step_problem.h: qdot + s_f sigma_f = 0
//                       and FB(sigma_f, 1 - s_f^2), friction force F_c s_f
// and on the body rows the generalized joint force G^T f / Fs with
//   f = sum_i lambda_i G_i + (l_lo - l_hi + F_c s_f - c qdot + tau) G_q,   qdot = G_q . nu (implicit damping c),
//   tau the scene's constant joint effort
// where G_i and G_q are the gradients of the equalities and of the position at the START of the step. Forces along the
// start-of-step gradients with constraints at the end is the SHAKE discretization: with the position update
// p1 = p0 + h v1 it is the symplectic Euler method for a constrained system, so a pendulum's energy oscillates about
// its true value instead of decaying, and the Jacobian needs no second derivatives of the constraints.
// Commanded joint efforts enter as external wrenches (AddJointEffortWrench) along the same G_q.
#include <cmath>

#include "contact_frame.h"
#include "implicit_sim/core/ncp/fischer_burmeister.h"
#include "implicit_sim/core/step/step_problem.h"

namespace implicit_sim {

void StepProblem::BeginJoints() {
  for (int j : joints_) {
    const Joint& joint = model_.joints[j];
    const JointBodies& jb = joint_bodies_[j];
    const Pose X_WP = jb.parent < 0 ? Pose::Identity() : MakePose(start_[jb.parent].p0, start_[jb.parent].R0);
    const Pose X_WC = MakePose(start_[jb.child].p0, start_[jb.child].R0);
    for (int i = 0; i < joint.num_equalities(); ++i) JointEquality(joint, i, X_WP, X_WC, &joint_equality_start_[j][i]);
    JointPosition(joint, X_WP, X_WC, &joint_position_start_[j]);
  }
}

double StepProblem::JointLimitEffort(const Eigen::VectorXd& z, int j) const {
  const Joint& joint = model_.joints[j];
  if (!joint.limited) return 0.0;
  const int col = joint_offset_[j] + joint.num_equalities();
  return z[col] - z[col + 1];
}

void StepProblem::SeedJoints(Eigen::VectorXd* z) const {
  for (int j : joints_) {
    const Joint& joint = model_.joints[j];
    const int o = joint_offset_[j];
    z->segment(o, joint_size(j)).setZero();
    if (!(joint.friction > 0.0)) continue;
    const JointBodies& jb = joint_bodies_[j];
    const BodyStep& c = start_[jb.child];
    const Vec3 zero = Vec3::Zero();
    const bool world = jb.parent < 0;
    const double rate = joint_position_start_[j].Rate(world ? zero : start_[jb.parent].v0,
                                                      world ? zero : start_[jb.parent].w0, c.v0, c.w0);
    const int s_col = o + joint.num_equalities() + (joint.limited ? 2 : 0);
    (*z)[s_col] = rate > 1e-9 ? -1.0 : (rate < -1e-9 ? 1.0 : 0.0);
    (*z)[s_col + 1] = std::abs(rate) > 1e-9 ? std::abs(rate) : 1e-3;  // sigma > 0: see SeedFriction
  }
}

// row += scale * dC/dz for a function C of the end-of-step poses with gradient g: dp = h dv, dtheta = h J_l(h w) dw.
void StepProblem::AddEndGradientRow(int row, const JointGradient& g, const BodyEnd& eP, const BodyEnd& eC,
                                    double scale) const {
  if (!WantJacobian()) return;
  if (eP.col >= 0) {
    AddJ(row, eP.col, Eigen::RowVector3d(scale * h_ * g.dp_P.transpose()));
    AddJ(row, eP.col + 3, Eigen::RowVector3d(scale * g.dth_P.transpose() * eP.dtheta_dw));
  }
  AddJ(row, eC.col, Eigen::RowVector3d(scale * h_ * g.dp_C.transpose()));
  AddJ(row, eC.col + 3, Eigen::RowVector3d(scale * g.dth_C.transpose() * eC.dtheta_dw));
}

// row += scale * d(g . nu)/dz (a rate along the start-of-step gradient g: linear in the velocities).
void StepProblem::AddRateRow(int row, const JointGradient& g, const BodyEnd& eP, const BodyEnd& eC, double scale) const {
  if (!WantJacobian()) return;
  if (eP.col >= 0) {
    AddJ(row, eP.col, Eigen::RowVector3d(scale * g.dp_P.transpose()));
    AddJ(row, eP.col + 3, Eigen::RowVector3d(scale * g.dth_P.transpose()));
  }
  AddJ(row, eC.col, Eigen::RowVector3d(scale * g.dp_C.transpose()));
  AddJ(row, eC.col + 3, Eigen::RowVector3d(scale * g.dth_C.transpose()));
}

// Body rows -= g * force / Fs (the generalized force along g) and their Jacobian column `col` -= g * dforce_dcol / Fs.
void StepProblem::AddJointForce(const JointGradient& g, double force, int col, double dforce_dcol, const BodyEnd& eP,
                                const BodyEnd& eC, Eigen::VectorXd* Phi) const {
  const double s = 1.0 / force_scale_;
  const bool want_J = (WantJacobian()) && col >= 0;
  if (eP.col >= 0) {
    Phi->segment<3>(eP.col) -= s * force * g.dp_P;
    Phi->segment<3>(eP.col + 3) -= s * force * g.dth_P;
    if (want_J) {
      AddJ(eP.col, col, Vec3(-s * dforce_dcol * g.dp_P));
      AddJ(eP.col + 3, col, Vec3(-s * dforce_dcol * g.dth_P));
    }
  }
  Phi->segment<3>(eC.col) -= s * force * g.dp_C;
  Phi->segment<3>(eC.col + 3) -= s * force * g.dth_C;
  if (want_J) {
    AddJ(eC.col, col, Vec3(-s * dforce_dcol * g.dp_C));
    AddJ(eC.col + 3, col, Vec3(-s * dforce_dcol * g.dth_C));
  }
}

void StepProblem::AddJointRows(const Eigen::VectorXd& z, Eigen::VectorXd* Phi) const {
  for (int j : joints_) {
    const Joint& joint = model_.joints[j];
    const int o = joint_offset_[j], m = joint.num_equalities();
    const BodyEnd& eP = ParentEnd(j);
    const BodyEnd& eC = ChildEnd(j);
    const Pose X_WP = MakePose(eP.p, eP.R), X_WC = MakePose(eC.p, eC.R);  // end of step
    JointGradient g;
    for (int i = 0; i < m; ++i) {  // the equalities at the end of the step
      (*Phi)[o + i] = JointEquality(joint, i, X_WP, X_WC, &g) / h_;
      AddEndGradientRow(o + i, g, eP, eC, 1.0 / h_);
      AddJointForce(joint_equality_start_[j][i], z[o + i], o + i, 1.0, eP, eC, Phi);
    }
    if (!joint.has_coordinate()) continue;
    const JointGradient& G_q = joint_position_start_[j];
    if (joint.applied_effort != 0.0) AddJointForce(G_q, stage_share() * joint.applied_effort, -1, 0.0, eP, eC, Phi);
    if (joint.limited) AddJointLimitRows(joint, o + m, z, eP, eC, G_q, Phi);
    if (joint.friction > 0.0) AddJointFrictionRows(joint, o + m + (joint.limited ? 2 : 0), z, eP, eC, G_q, Phi);
    if (joint.damping > 0.0) AddJointDamping(joint, eP, eC, G_q, Phi);
    if (driven_[j]) AddJointDriveRow(j, o + joint.size(), z, eP, eC, G_q, Phi);
  }
}

// 0 <= l_lo _|_ q - lower >= 0 and 0 <= l_hi _|_ upper - q >= 0 at rows col, col + 1; q at the end of the step.
void StepProblem::AddJointLimitRows(const Joint& joint, int col, const Eigen::VectorXd& z, const BodyEnd& eP,
                                    const BodyEnd& eC, const JointGradient& G_q, Eigen::VectorXd* Phi) const {
  const double Fs = force_scale_;
  JointGradient g;
  const double q = JointPosition(joint, MakePose(eP.p, eP.R), MakePose(eC.p, eC.R), &g);
  const FB lo = FischerBurmeister(z[col] / Fs, q - joint.lower, eval_.mode.smoothing, eval_.mode.raw);
  const FB hi = FischerBurmeister(z[col + 1] / Fs, joint.upper - q, eval_.mode.smoothing, eval_.mode.raw);
  (*Phi)[col] = lo.value;
  (*Phi)[col + 1] = hi.value;
  if (WantJacobian()) {
    AddJ(col, col, (lo.da + eval_.mode.regularization) / Fs);
    AddJ(col + 1, col + 1, (hi.da + eval_.mode.regularization) / Fs);
  }
  AddEndGradientRow(col, g, eP, eC, lo.db);
  AddEndGradientRow(col + 1, g, eP, eC, -hi.db);
  AddJointForce(G_q, z[col], col, 1.0, eP, eC, Phi);
  AddJointForce(G_q, -z[col + 1], col + 1, -1.0, eP, eC, Phi);
}

// Coulomb joint friction at rows col, col + 1: qdot + s sigma = 0 and 0 <= sigma _|_ 1 - s^2 >= 0; force F_c s.
void StepProblem::AddJointFrictionRows(const Joint& joint, int col, const Eigen::VectorXd& z, const BodyEnd& eP,
                                       const BodyEnd& eC, const JointGradient& G_q, Eigen::VectorXd* Phi) const {
  const double s = z[col], sigma = z[col + 1];
  (*Phi)[col] = G_q.Rate(eP.v, eP.w, eC.v, eC.w) + s * sigma;  // the end-of-step joint velocity (rad/s or m/s)
  AddRateRow(col, G_q, eP, eC, 1.0);
  const FB fb = FischerBurmeister(sigma, 1.0 - s * s, eval_.mode.smoothing, eval_.mode.raw);
  (*Phi)[col + 1] = fb.value;
  if (WantJacobian()) {
    AddJ(col, col, sigma + eval_.mode.regularization);
    AddJ(col, col + 1, s);
    AddJ(col + 1, col + 1, fb.da);
    AddJ(col + 1, col, -2.0 * fb.db * s);
  }
  const double bound = stage_share() * joint.friction;  // RATTLE stage 1 carries half the step's friction bound
  AddJointForce(G_q, bound * s, col, bound, eP, eC, Phi);
}

// Viscous damping -c qdot along G_q, implicit in the end-of-step velocities.
void StepProblem::AddJointDamping(const Joint& joint, const BodyEnd& eP, const BodyEnd& eC, const JointGradient& G_q,
                                  Eigen::VectorXd* Phi) const {
  const double damping = stage_share() * joint.damping;  // half in each RATTLE stage
  AddJointForce(G_q, -damping * G_q.Rate(eP.v, eP.w, eC.v, eC.w), -1, 0.0, eP, eC, Phi);
  if (!WantJacobian()) return;
  // Body rows of P and C: + (c / Fs) G_q G_q^T over the velocity columns of P and C, in 3 x 3 blocks.
  const double k = damping / force_scale_;
  const Vec3 gP[2] = {G_q.dp_P, G_q.dth_P}, gC[2] = {G_q.dp_C, G_q.dth_C};
  for (const auto& [row, g_row] : {std::make_pair(eP.col, gP), std::make_pair(eC.col, gC)}) {
    for (int i = 0; row >= 0 && i < 2; ++i) {
      for (int k2 = 0; k2 < 2; ++k2) {
        if (eP.col >= 0) AddJ(row + 3 * i, eP.col + 3 * k2, Mat3(k * g_row[i] * gP[k2].transpose()));
        AddJ(row + 3 * i, eC.col + 3 * k2, Mat3(k * g_row[i] * gC[k2].transpose()));
      }
    }
  }
}

}  // namespace implicit_sim
