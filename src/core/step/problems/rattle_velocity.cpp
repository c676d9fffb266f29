#include "implicit_sim/core/step/problems/rattle_velocity.h"

#include <tuple>

#include <Eigen/Cholesky>

#include "implicit_sim/core/ncp/fischer_burmeister.h"
#include "implicit_sim/core/step/rows/drive_rows.h"
#include "implicit_sim/core/step/rows/friction_rows.h"
#include "implicit_sim/core/step/rows/joint_rows.h"
#include "step/contact_frame.h"

namespace implicit_sim {
namespace pi = pair_index;

RattleVelocityProblem::RattleVelocityProblem(const StepLayout& layout, const StepKinematics& kinematics,
                                             const std::vector<JointDrive>& drives)
    : StepProblem(layout, kinematics), drives_(drives) {
  const size_t joints = layout.model().joints.size();
  joint_equality_end_.resize(joints);
  joint_position_end_.resize(joints);
  joint_q_end_.assign(joints, 0.0);
  limit_closed_.assign(joints, {0, 0});
}

void RattleVelocityProblem::Begin(const RattlePositionProblem& stage1, const Eigen::VectorXd& z1,
                                  const Eigen::VectorXd& raw_rows1, Eigen::VectorXd* z2) {
  const StepLayout& layout = this->layout();
  const StepKinematics& kin = kinematics();
  const Model& model = layout.model();
  const double h = kin.h(), Fs = kin.force_scale();
  kin.EndOfStep(z1, &ends1_);  // stage 1's end-of-step poses (paper eq. 2)
  stage1_z_ = z1;
  *z2 = z1;
  half_.resize(ends1_.size());
  for (size_t b = 0; b < ends1_.size(); ++b) {
    const BodyEnd& e = ends1_[b];
    const BodyStart& s = kin.start(static_cast<int>(b));
    BodyHalf& half = half_[b];
    half.p1 = e.p;
    half.R1 = e.R;
    if (e.col < 0) continue;
    // The momenta after stage 1's impulses, m v0 + h f / 2 + impulses and L0 + h tau / 2 + moments: stage 1's rows
    // less their residual (the body rows are equations: raw and reformulated alike), so that stage 2 conserves
    // momentum to round-off whatever tolerance stage 1 met.
    const Body& body = model.bodies[layout.bodies()[b]];
    const double hFs = h * Fs;
    half.v_half = e.v - hFs / body.mass * raw_rows1.segment<3>(e.col);
    half.L_half = DiscreteMomentum(body.I_B, s.R0, e.R, e.w, h, nullptr, nullptr) - hFs * raw_rows1.segment<3>(e.col + 3);
    z2->segment<3>(e.col) = 2.0 * e.v - s.v0;
    z2->segment<3>(e.col + 3) = 2.0 * e.w - s.w0;
    if (layout.blocks().empty() && layout.joints().empty()) {  // free flight: the exact solution (no locked axis)
      const int row = e.col;
      const Vec3 tau_ext = kin.ExternalTorque(row / 6);
      const Mat3 I_W1 = e.R * body.I_B * e.R.transpose();
      bool locked = false;
      for (int k = 0; k < 6; ++k) locked = locked || layout.locked_rows()[row + k];
      if (!locked) z2->segment<3>(row + 3) = I_W1.ldlt().solve(half.L_half + 0.5 * h * tau_ext);
    }
  }
  row_kinds_ = layout.row_kinds();
  const std::vector<PairBlock>& blocks = layout.blocks();
  stage1_force_.resize(blocks.size());
  stage1_torsion_.resize(blocks.size());
  stage1_rolling_.resize(blocks.size());
  closed_.resize(blocks.size());
  for (size_t c = 0; c < blocks.size(); ++c) {
    const PairBlock& blk = blocks[c];
    const FrictionParams& fr = model.pairs[blk.pair].friction;
    const int off = blk.offset;
    const Vec3 n = stage1.uses_start_frame(static_cast<int>(c)) ? Vec3(stage1.start_frames().segment<3>(off + pi::kN))
                                                                 : Vec3(z1.segment<3>(off + pi::kN));
    Vec3 t, o;
    Mat3 dt_dn, do_dn;
    TangentBasis(n, layout.tangent_axes()[c], &t, &o, &dt_dn, &do_dn);
    const double ln = z1[blk.normal_force()];
    stage1_force_[c] = ln * (n + fr.mu * (fr.e_t * z1[off + pi::kSt] * t + fr.e_o * z1[off + pi::kSo] * o));
    stage1_torsion_[c] = fr.mu * fr.e_r * ln * z1[off + pi::kSr] * n;
    stage1_rolling_[c] = ln * RollingMomentPerNormalForce(blk, fr, z1, t, o);
    closed_[c] = IsClosed(z1[off + pi::kD], ln, Fs);
    for (int k = 0; k < blk.k1 + blk.k2; ++k) row_kinds_[off + pi::kAlpha + k] = RowKind::kEquation;
    if (closed_[c]) {
      (*z2)[blk.normal_force()] = 2.0 * ln;
    } else {
      row_kinds_[blk.normal_force()] = row_kinds_[blk.sigma()] = RowKind::kEquation;
    }
  }
  for (int j : layout.joints()) {
    const Joint& joint = model.joints[j];
    const JointBodies& jb = layout.joint_bodies(j);
    const BodyEnd& eP = jb.parent < 0 ? RowContext::kWorld : ends1_[jb.parent];
    const BodyEnd& eC = ends1_[jb.child];
    const Pose X_WP = MakePose(eP.p, eP.R), X_WC = MakePose(eC.p, eC.R);
    for (int i = 0; i < joint.num_equalities(); ++i) JointEquality(joint, i, X_WP, X_WC, &joint_equality_end_[j][i]);
    const double q = JointPosition(joint, X_WP, X_WC, &joint_position_end_[j]);
    joint_q_end_[j] = q;
    if (!joint.limited) continue;
    const int col = layout.joint_offset(j) + joint.num_equalities();
    const double distance[2] = {q - joint.lower, joint.upper - q};
    for (int k = 0; k < 2; ++k) {
      limit_closed_[j][k] = distance[k] <= kClosedGap || z1[col + k] > 1e-12 * Fs;
      if (limit_closed_[j][k]) {
        (*z2)[col + k] = 2.0 * z1[col + k];
      } else {
        row_kinds_[col + k] = RowKind::kEquation;
      }
    }
  }
}

void RattleVelocityProblem::EndsOf(const Eigen::VectorXd& z, std::vector<BodyEnd>* ends) const {
  if (ends->size() != half_.size()) ends->resize(half_.size());
  for (size_t b = 0; b < half_.size(); ++b) {
    BodyEnd& e = (*ends)[b];
    e.col = layout().column(static_cast<int>(b));
    e.p = half_[b].p1;
    e.R = half_[b].R1;
    if (e.col >= 0) {
      e.v = z.segment<3>(e.col);
      e.w = z.segment<3>(e.col + 3);
    } else {
      e.v.setZero();
      e.w.setZero();
    }
    e.dtheta_dw.setZero();
  }
}

void RattleVelocityProblem::AddRows(const RowContext& ctx) const {
  AddFixedGeometryMomentumRows(ctx, half_);
  AddJointRateRows(ctx);
  for (size_t c = 0; c < layout().blocks().size(); ++c) AddPairRows(ctx, static_cast<int>(c));
}

void RattleVelocityProblem::AddPairRows(const RowContext& ctx, int c) const {
  const PairBlock& blk = layout().blocks()[c];
  const FrictionParams& fr = layout().model().pairs[blk.pair].friction;
  const Eigen::VectorXd& z = ctx.z;
  const RowWriter& out = ctx.out;
  const NcpEvalMode& mode = out.mode;
  const int off = blk.offset;
  const bool want_J = out.WantJacobian();
  // The closest-point unknowns stay at stage 1's values.
  for (int k = 0; k < pi::kSt; ++k) out.Phi[off + k] = z[off + k] - stage1_z_[off + k];
  for (int k = pi::kAlpha; k < pi::kAlpha + blk.k1 + blk.k2; ++k) out.Phi[off + k] = z[off + k] - stage1_z_[off + k];
  if (want_J) {
    for (int k = 0; k < pi::kSt; ++k) out.AddJ(off + k, off + k, 1.0);
    for (int k = pi::kAlpha; k < pi::kAlpha + blk.k1 + blk.k2; ++k) out.AddJ(off + k, off + k, 1.0);
  }
  const Vec3 n = stage1_z_.segment<3>(off + pi::kN);
  const BodyEnd& e1 = ctx.ends[blk.body1];
  const BodyEnd& e2 = ctx.ends[blk.body2];
  const Vec3 r1 = stage1_z_.segment<3>(off + pi::kA1) - e1.p, r2 = stage1_z_.segment<3>(off + pi::kA2) - e2.p;
  Vec3 t, o;
  Mat3 dt_dn, do_dn;
  TangentBasis(n, layout().tangent_axes()[c], &t, &o, &dt_dn, &do_dn);
  const Vec3 v_rel = RelativeVelocity(e1.v, e1.w, r1, e2.v, e2.w, r2);
  const Vec3 w_rel = e1.w - e2.w;
  const double Ln = z[blk.normal_force()], sigma = z[blk.sigma()];
  const Vec3 S = z.segment<3>(off + pi::kSt);
  const double Fs = ctx.Fs();
  const bool closed = closed_[c] != 0;
  // coeff * (u^T d(v_rel)/d(nu) + u_w^T d(w_rel)/d(nu)) on `row`, at the fixed levers.
  auto add_rates = [&](int row, double coeff, const Vec3& u, const Vec3& u_w) {
    if (!want_J) return;
    if (e1.col >= 0) {
      out.AddJ(row, e1.col, Eigen::RowVector3d(coeff * u.transpose()));
      out.AddJ(row, e1.col + 3, Eigen::RowVector3d(coeff * (r1.cross(u) + u_w).transpose()));
    }
    if (e2.col >= 0) {
      out.AddJ(row, e2.col, Eigen::RowVector3d(-coeff * u.transpose()));
      out.AddJ(row, e2.col + 3, Eigen::RowVector3d(-coeff * (r2.cross(u) + u_w).transpose()));
    }
  };
  const Vec3 zero = Vec3::Zero();
  // The components t, o, r and, with rolling resistance, the rolling about t and o.
  FrictionRows friction;
  friction.first_row = off + pi::kSt;
  friction.roll_row = blk.roll();
  friction.count = blk.rolling ? 5 : 3;
  const double e[5] = {fr.e_t, fr.e_o, fr.e_r, fr.e_roll, fr.e_roll};
  const Vec3 dirs[5] = {t, o, zero, zero, zero}, dirs_w[5] = {zero, zero, n, t, o};
  const double rates[5] = {t.dot(v_rel), o.dot(v_rel), n.dot(w_rel), t.dot(w_rel), o.dot(w_rel)};
  for (int k = 0; k < friction.count; ++k) {  // a component on locked velocities only: s_k = 0 (friction_rows.h)
    // e_k = 0 (no torsional friction): the component leaves the ellipsoid as a locked one does.
    friction.locked[k] = closed && (e[k] == 0.0 || FrictionComponentLocked(ctx.layout, e1, dirs[k],
                                                                            r1.cross(dirs[k]) + dirs_w[k], e2, dirs[k],
                                                                            r2.cross(dirs[k]) + dirs_w[k]));
    friction.rate[k] = e[k] * rates[k];
    friction.s[k] = z[friction.Row(k)];
  }
  // The friction of the total: e_k rate_k + S_k sigma = 0, 0 <= sigma _|_ 1 - |S|^2 >= 0 (or its projected form); an
  // open pair keeps stage 1's fractions and slip, with the same Jacobian entries.
  friction.sigma = blk.sigma();
  friction.sigma_value = sigma;
  friction.slip = ProjectedSlip(mode, sigma, &friction.dslip_dsigma);
  friction.zeta = 1.0 - S.squaredNorm();
  if (blk.rolling) friction.zeta -= friction.s[3] * friction.s[3] + friction.s[4] * friction.s[4];
  friction.projected = ctx.friction.projected;
  friction.projection_scale = ctx.friction.projection_scale;
  if (!closed) friction.hold = &stage1_z_;
  const auto emit_rate = [&](int k, int row, double coeff) { add_rates(row, coeff * e[k], dirs[k], dirs_w[k]); };
  AddFrictionRows(friction, out, RateGradient(emit_rate));
  // The normal law on the total force: 0 <= Ln / Fs _|_ n . v_rel >= 0 (m/s, like the friction rows: in metres,
  // h (n . v_rel), the tolerance would leave a resting body sinking at tolerance / h).
  if (closed) {
    const FB fb = FischerBurmeister(Ln / Fs, n.dot(v_rel), mode.smoothing, mode.raw);
    out.Phi[blk.normal_force()] = fb.value;
    if (want_J) out.AddJ(blk.normal_force(), blk.normal_force(), (fb.da + mode.regularization) / Fs);
    add_rates(blk.normal_force(), fb.db, n, zero);
  } else {
    out.Phi[blk.normal_force()] = (Ln - stage1_z_[blk.normal_force()]) / Fs;
    if (want_J) out.AddJ(blk.normal_force(), blk.normal_force(), 1.0 / Fs);
    add_rates(blk.normal_force(), 0.0, n, zero);
  }
  // Stage 2's force and torsion: the total of the step less stage 1's.
  const double mu = fr.mu;
  const Vec3 dF_dLn = n + mu * (fr.e_t * S[0] * t + fr.e_o * S[1] * o);
  const Vec3 F = Ln * dF_dLn - stage1_force_[c];
  const Vec3 torsion = mu * fr.e_r * Ln * S[2] * n - stage1_torsion_[c];
  const Vec3 dF_dS[3] = {mu * fr.e_t * Ln * t, mu * fr.e_o * Ln * o, zero};
  const Vec3 dtorsion_dLn = mu * fr.e_r * S[2] * n, dtorsion_dSr = mu * fr.e_r * Ln * n;
  // The rolling moment, mu e_roll Ln (S_q1 t + S_q2 o), less stage 1's.
  const int rq = blk.roll();
  const Vec3 dM_dLn = RollingMomentPerNormalForce(blk, fr, z, t, o);
  const Vec3 M = Ln * dM_dLn - stage1_rolling_[c];
  for (const auto& [e_body, r, sign] : {std::make_tuple(&e1, r1, 1.0), std::make_tuple(&e2, r2, -1.0)}) {
    if (e_body->col < 0) continue;
    const int row = e_body->col;
    const double s = sign / Fs;
    out.Phi.segment<3>(row) -= s * F;
    out.Phi.segment<3>(row + 3) -= s * (r.cross(F) + torsion);
    if (blk.rolling) out.Phi.segment<3>(row + 3) -= s * M;
    if (!want_J) continue;
    out.AddJ(row, blk.normal_force(), Vec3(-s * dF_dLn));
    out.AddJ(row + 3, blk.normal_force(), Vec3(-s * (r.cross(dF_dLn) + dtorsion_dLn)));
    for (int k = 0; k < 2; ++k) {
      out.AddJ(row, off + pi::kSt + k, Vec3(-s * dF_dS[k]));
      out.AddJ(row + 3, off + pi::kSt + k, Vec3(-s * r.cross(dF_dS[k])));
    }
    out.AddJ(row + 3, off + pi::kSr, Vec3(-s * dtorsion_dSr));
    if (blk.rolling) {
      out.AddJ(row + 3, blk.normal_force(), Vec3(-s * dM_dLn));
      out.AddJ(row + 3, rq, Vec3(-s * mu * fr.e_roll * Ln * t));
      out.AddJ(row + 3, rq + 1, Vec3(-s * mu * fr.e_roll * Ln * o));
    }
  }
}

void RattleVelocityProblem::AddJointRateRows(const RowContext& ctx) const {
  const double Fs = ctx.Fs();
  const NcpEvalMode& mode = ctx.out.mode;
  const Eigen::VectorXd& z = ctx.z;
  for (int j : layout().joints()) {
    const Joint& joint = layout().model().joints[j];
    const int o = layout().joint_offset(j), m = joint.num_equalities();
    const BodyEnd& eP = ctx.ParentEnd(j);
    const BodyEnd& eC = ctx.ChildEnd(j);
    for (int i = 0; i < m; ++i) {  // the equalities' rates at the end of the step
      const JointGradient& g = joint_equality_end_[j][i];
      ctx.out.Phi[o + i] = g.Rate(eP.v, eP.w, eC.v, eC.w);
      AddRateRow(ctx, o + i, g, eP, eC, 1.0);
      AddJointForce(ctx, g, z[o + i], o + i, 1.0, eP, eC);
    }
    if (!joint.has_coordinate()) continue;
    const JointGradient& G_q = joint_position_end_[j];
    const double rate = G_q.Rate(eP.v, eP.w, eC.v, eC.w);
    if (joint.applied_effort != 0.0) AddJointForce(ctx, G_q, 0.5 * joint.applied_effort, -1, 0.0, eP, eC);
    if (joint.limited) {  // the total limit multipliers: 0 <= L_lo _|_ qdot >= 0, 0 <= L_hi _|_ -qdot >= 0
      for (int k = 0; k < 2; ++k) {
        const int col = o + m + k;
        const double sign = k == 0 ? 1.0 : -1.0;
        if (limit_closed_[j][k]) {
          const FB fb = FischerBurmeister(z[col] / Fs, sign * rate, mode.smoothing, mode.raw);
          ctx.out.Phi[col] = fb.value;
          if (ctx.out.WantJacobian()) ctx.out.AddJ(col, col, (fb.da + mode.regularization) / Fs);
          AddRateRow(ctx, col, G_q, eP, eC, sign * fb.db);
        } else {
          ctx.out.Phi[col] = (z[col] - stage1_z_[col]) / Fs;
          if (ctx.out.WantJacobian()) ctx.out.AddJ(col, col, 1.0 / Fs);
          AddRateRow(ctx, col, G_q, eP, eC, 0.0);
        }
        AddJointForce(ctx, G_q, sign * (z[col] - stage1_z_[col]), col, sign, eP, eC);
      }
    }
    if (joint.friction > 0.0) {  // the total fraction S
      const int col = o + joint.friction_column();
      const double S = AddJointFrictionRows(ctx, col, G_q, eP, eC);
      AddJointForce(ctx, G_q, joint.friction * (S - 0.5 * stage1_z_[col]), col, joint.friction, eP, eC);
    }
    if (joint.velocity_limited) {  // the total multipliers: 0 <= U_lo _|_ qdot + v_max >= 0, 0 <= U_hi _|_ v_max - qdot
      for (int k = 0; k < 2; ++k) {
        const int col = o + joint.velocity_limit_column() + k;
        const double sign = k == 0 ? 1.0 : -1.0;
        const FB fb = FischerBurmeister(z[col] / Fs, joint.velocity_limit + sign * rate, mode.smoothing, mode.raw);
        ctx.out.Phi[col] = fb.value;
        if (ctx.out.WantJacobian()) ctx.out.AddJ(col, col, (fb.da + mode.regularization) / Fs);
        AddRateRow(ctx, col, G_q, eP, eC, sign * fb.db);
        AddJointForce(ctx, G_q, sign * (z[col] - stage1_z_[col]), col, sign, eP, eC);
      }
    }
    if (joint.damping > 0.0) AddJointDamping(ctx, joint, 0.5, eP, eC, G_q);
    if (joint.mimics()) {  // qdot - c qdot_leader = 0 along the end-of-step gradients, as the equalities' rates
      const int k = joint.mimic_leader, col = o + joint.mimic_column();
      const BodyEnd &eLP = ctx.ParentEnd(k), &eLC = ctx.ChildEnd(k);
      const JointGradient& G_leader = joint_position_end_[k];
      const double c = joint.mimic_multiplier;
      ctx.out.Phi[col] = rate - c * G_leader.Rate(eLP.v, eLP.w, eLC.v, eLC.w);
      AddRateRow(ctx, col, G_q, eP, eC, 1.0);
      AddRateRow(ctx, col, G_leader, eLP, eLC, -c);
      AddJointForce(ctx, G_q, z[col], col, 1.0, eP, eC);
      AddJointForce(ctx, G_leader, -c * z[col], col, -c, eLP, eLC);
    }
    if (layout().driven_joints()[j]) {
      const int col = layout().drive_column(j);
      AddAverageDriveRow(ctx, j, drives_[j], stage1_z_[col], joint_q_end_[j], eP, eC, G_q);
    }
  }
}

}  // namespace implicit_sim
