#include "implicit_sim/core/step/rows/joint_rows.h"

#include "implicit_sim/core/ncp/fischer_burmeister.h"
#include "implicit_sim/core/step/rows/drive_rows.h"
#include "implicit_sim/core/step/rows/friction_rows.h"
#include "step/contact_frame.h"

namespace implicit_sim {
namespace {

// 0 <= l_lo _|_ q - lower >= 0 and 0 <= l_hi _|_ upper - q >= 0 at rows col, col + 1; q at the end of the step.
void AddJointLimitRows(const RowContext& ctx, const Joint& joint, int col, const BodyEnd& eP, const BodyEnd& eC,
                       const JointGradient& G_q) {
  const double Fs = ctx.Fs();
  const NcpEvalMode& mode = ctx.out.mode;
  JointGradient g;
  const double q = JointPosition(joint, MakePose(eP.p, eP.R), MakePose(eC.p, eC.R), &g);
  const FB lo = FischerBurmeister(ctx.z[col] / Fs, q - joint.lower, mode.smoothing, mode.raw);
  const FB hi = FischerBurmeister(ctx.z[col + 1] / Fs, joint.upper - q, mode.smoothing, mode.raw);
  ctx.out.Phi[col] = lo.value;
  ctx.out.Phi[col + 1] = hi.value;
  if (ctx.out.WantJacobian()) {
    ctx.out.AddJ(col, col, (lo.da + mode.regularization) / Fs);
    ctx.out.AddJ(col + 1, col + 1, (hi.da + mode.regularization) / Fs);
  }
  AddEndGradientRow(ctx, col, g, eP, eC, lo.db);
  AddEndGradientRow(ctx, col + 1, g, eP, eC, -hi.db);
  AddJointForce(ctx, G_q, ctx.z[col], col, 1.0, eP, eC);
  AddJointForce(ctx, G_q, -ctx.z[col + 1], col + 1, -1.0, eP, eC);
}

// 0 <= u_lo _|_ qdot + v_max >= 0 and 0 <= u_hi _|_ v_max - qdot >= 0 at rows col, col + 1 (Joint::velocity_limited):
// qdot is the joint rate of the velocities that move the bodies over the step (the paper's v_{l+1}, RATTLE's v_{1/2}).
void AddVelocityLimitRows(const RowContext& ctx, const Joint& joint, int col, const BodyEnd& eP, const BodyEnd& eC,
                          const JointGradient& G_q) {
  const double Fs = ctx.Fs();
  const NcpEvalMode& mode = ctx.out.mode;
  const double rate = G_q.Rate(eP.v, eP.w, eC.v, eC.w);
  const FB lo = FischerBurmeister(ctx.z[col] / Fs, rate + joint.velocity_limit, mode.smoothing, mode.raw);
  const FB hi = FischerBurmeister(ctx.z[col + 1] / Fs, joint.velocity_limit - rate, mode.smoothing, mode.raw);
  ctx.out.Phi[col] = lo.value;
  ctx.out.Phi[col + 1] = hi.value;
  if (ctx.out.WantJacobian()) {
    ctx.out.AddJ(col, col, (lo.da + mode.regularization) / Fs);
    ctx.out.AddJ(col + 1, col + 1, (hi.da + mode.regularization) / Fs);
  }
  AddRateRow(ctx, col, G_q, eP, eC, lo.db);
  AddRateRow(ctx, col + 1, G_q, eP, eC, -hi.db);
  AddJointForce(ctx, G_q, ctx.z[col], col, 1.0, eP, eC);
  AddJointForce(ctx, G_q, -ctx.z[col + 1], col + 1, -1.0, eP, eC);
}

// (q - c q_leader - offset) / h = 0 at the end of the step, its multiplier along both joints' start gradients.
void AddMimicRow(const RowContext& ctx, int j) {
  const Joint& joint = ctx.model().joints[j];
  const int k = joint.mimic_leader, row = ctx.layout.joint_offset(j) + joint.mimic_column();
  const Joint& leader = ctx.model().joints[k];
  const BodyEnd &eP = ctx.ParentEnd(j), &eC = ctx.ChildEnd(j), &eLP = ctx.ParentEnd(k), &eLC = ctx.ChildEnd(k);
  const double h = ctx.h(), c = joint.mimic_multiplier;
  JointGradient g, g_leader;
  const double q = JointPosition(joint, MakePose(eP.p, eP.R), MakePose(eC.p, eC.R), &g);
  const double q_leader = JointPosition(leader, MakePose(eLP.p, eLP.R), MakePose(eLC.p, eLC.R), &g_leader);
  ctx.out.Phi[row] = (q - c * q_leader - joint.mimic_offset) / h;
  AddEndGradientRow(ctx, row, g, eP, eC, 1.0 / h);
  AddEndGradientRow(ctx, row, g_leader, eLP, eLC, -c / h);
  AddJointForce(ctx, ctx.kinematics.position_gradient(j), ctx.z[row], row, 1.0, eP, eC);
  AddJointForce(ctx, ctx.kinematics.position_gradient(k), -c * ctx.z[row], row, -c, eLP, eLC);
}

}  // namespace

void AddJointRows(const RowContext& ctx, double share, const std::vector<JointDrive>& drives) {
  const double h = ctx.h();
  for (int j : ctx.layout.joints()) {
    const Joint& joint = ctx.model().joints[j];
    const int o = ctx.layout.joint_offset(j), m = joint.num_equalities();
    const BodyEnd& eP = ctx.ParentEnd(j);
    const BodyEnd& eC = ctx.ChildEnd(j);
    const Pose X_WP = MakePose(eP.p, eP.R), X_WC = MakePose(eC.p, eC.R);  // end of step
    JointGradient g;
    for (int i = 0; i < m; ++i) {  // the equalities at the end of the step
      ctx.out.Phi[o + i] = JointEquality(joint, i, X_WP, X_WC, &g) / h;
      AddEndGradientRow(ctx, o + i, g, eP, eC, 1.0 / h);
      AddJointForce(ctx, ctx.kinematics.equality_gradient(j, i), ctx.z[o + i], o + i, 1.0, eP, eC);
    }
    if (!joint.has_coordinate()) continue;
    const JointGradient& G_q = ctx.kinematics.position_gradient(j);
    if (joint.applied_effort != 0.0) AddJointForce(ctx, G_q, share * joint.applied_effort, -1, 0.0, eP, eC);
    if (joint.limited) AddJointLimitRows(ctx, joint, o + m, eP, eC, G_q);
    if (joint.friction > 0.0) {
      const int col = o + joint.friction_column();
      const double s = AddJointFrictionRows(ctx, col, G_q, eP, eC);
      const double bound = share * joint.friction;  // RATTLE stage 1 carries half the step's friction bound
      AddJointForce(ctx, G_q, bound * s, col, bound, eP, eC);
    }
    if (joint.velocity_limited) AddVelocityLimitRows(ctx, joint, o + joint.velocity_limit_column(), eP, eC, G_q);
    if (joint.damping > 0.0) AddJointDamping(ctx, joint, share, eP, eC, G_q);
    if (joint.mimics()) AddMimicRow(ctx, j);
    if (ctx.layout.driven_joints()[j]) AddDriveRow(ctx, j, drives[j], share, eP, eC, G_q);
  }
}

double AddJointFrictionRows(const RowContext& ctx, int col, const JointGradient& G_q, const BodyEnd& eP,
                            const BodyEnd& eC) {
  FrictionRows friction;
  friction.first_row = col;
  friction.count = 1;
  friction.sigma = col + 1;
  friction.rate[0] = G_q.Rate(eP.v, eP.w, eC.v, eC.w);  // the end-of-step joint velocity (rad/s or m/s)
  friction.s[0] = ctx.z[col];
  friction.sigma_value = ctx.z[col + 1];
  friction.slip = ctx.z[col + 1];
  friction.zeta = 1.0 - friction.s[0] * friction.s[0];
  friction.projected = ctx.friction.projected;
  friction.projection_scale = ctx.friction.projection_scale;
  const auto emit_rate = [&](int, int row, double coeff) { AddRateRow(ctx, row, G_q, eP, eC, coeff); };
  AddFrictionRows(friction, ctx.out, RateGradient(emit_rate));
  return friction.s[0];
}

void AddEndGradientRow(const RowContext& ctx, int row, const JointGradient& g, const BodyEnd& eP, const BodyEnd& eC,
                       double scale) {
  if (!ctx.out.WantJacobian()) return;
  const double h = ctx.h();
  if (eP.col >= 0) {
    ctx.out.AddJ(row, eP.col, Eigen::RowVector3d(scale * h * g.dp_P.transpose()));
    ctx.out.AddJ(row, eP.col + 3, Eigen::RowVector3d(scale * g.dth_P.transpose() * eP.dtheta_dw));
  }
  ctx.out.AddJ(row, eC.col, Eigen::RowVector3d(scale * h * g.dp_C.transpose()));
  ctx.out.AddJ(row, eC.col + 3, Eigen::RowVector3d(scale * g.dth_C.transpose() * eC.dtheta_dw));
}

void AddRateRow(const RowContext& ctx, int row, const JointGradient& g, const BodyEnd& eP, const BodyEnd& eC,
                double scale) {
  if (!ctx.out.WantJacobian()) return;
  if (eP.col >= 0) {
    ctx.out.AddJ(row, eP.col, Eigen::RowVector3d(scale * g.dp_P.transpose()));
    ctx.out.AddJ(row, eP.col + 3, Eigen::RowVector3d(scale * g.dth_P.transpose()));
  }
  ctx.out.AddJ(row, eC.col, Eigen::RowVector3d(scale * g.dp_C.transpose()));
  ctx.out.AddJ(row, eC.col + 3, Eigen::RowVector3d(scale * g.dth_C.transpose()));
}

void AddJointForce(const RowContext& ctx, const JointGradient& g, double force, int col, double dforce_dcol,
                   const BodyEnd& eP, const BodyEnd& eC) {
  const double s = 1.0 / ctx.Fs();
  const bool want_J = ctx.out.WantJacobian() && col >= 0;
  Eigen::VectorXd& Phi = ctx.out.Phi;
  if (eP.col >= 0) {
    Phi.segment<3>(eP.col) -= s * force * g.dp_P;
    Phi.segment<3>(eP.col + 3) -= s * force * g.dth_P;
    if (want_J) {
      ctx.out.AddJ(eP.col, col, Vec3(-s * dforce_dcol * g.dp_P));
      ctx.out.AddJ(eP.col + 3, col, Vec3(-s * dforce_dcol * g.dth_P));
    }
  }
  Phi.segment<3>(eC.col) -= s * force * g.dp_C;
  Phi.segment<3>(eC.col + 3) -= s * force * g.dth_C;
  if (want_J) {
    ctx.out.AddJ(eC.col, col, Vec3(-s * dforce_dcol * g.dp_C));
    ctx.out.AddJ(eC.col + 3, col, Vec3(-s * dforce_dcol * g.dth_C));
  }
}

void AddJointDamping(const RowContext& ctx, const Joint& joint, double share, const BodyEnd& eP, const BodyEnd& eC,
                     const JointGradient& G_q) {
  const double damping = share * joint.damping;
  AddJointForce(ctx, G_q, -damping * G_q.Rate(eP.v, eP.w, eC.v, eC.w), -1, 0.0, eP, eC);
  if (!ctx.out.WantJacobian()) return;
  // Body rows of P and C: + (c / Fs) G_q G_q^T over the velocity columns of P and C, in 3 x 3 blocks.
  const double k = damping / ctx.Fs();
  const Vec3 gP[2] = {G_q.dp_P, G_q.dth_P}, gC[2] = {G_q.dp_C, G_q.dth_C};
  for (const auto& [row, g_row] : {std::make_pair(eP.col, gP), std::make_pair(eC.col, gC)}) {
    for (int i = 0; row >= 0 && i < 2; ++i) {
      for (int k2 = 0; k2 < 2; ++k2) {
        if (eP.col >= 0) ctx.out.AddJ(row + 3 * i, eP.col + 3 * k2, Mat3(k * g_row[i] * gP[k2].transpose()));
        ctx.out.AddJ(row + 3 * i, eC.col + 3 * k2, Mat3(k * g_row[i] * gC[k2].transpose()));
      }
    }
  }
}

}  // namespace implicit_sim
