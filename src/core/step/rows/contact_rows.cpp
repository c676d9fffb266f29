#include "implicit_sim/core/step/rows/contact_rows.h"

#include <algorithm>

#include "implicit_sim/core/base/rotation.h"
#include "implicit_sim/core/ncp/fischer_burmeister.h"
#include "implicit_sim/core/step/rows/friction_rows.h"
#include "step/contact_frame.h"

namespace implicit_sim {
namespace pi = pair_index;
namespace {

struct InequalityAt {  // one inequality evaluated at a world point
  double f;
  Vec3 g;  // world gradient
  Mat3 H;  // world Hessian
};

// Inequality k of `shape` on bodies()[local] at the body's end-of-step pose, at p_W.
InequalityAt EvaluateInequality(const RowContext& ctx, const ConvexShape& shape, int local, int k, const Vec3& p_W) {
  const BodyEnd& e = ctx.ends[local];
  const Mat3 R_WS = e.R * shape.X_BS.linear();
  const Vec3 p_WS = e.p + e.R * shape.X_BS.translation();
  InequalityAt out;
  Vec3 g_S;
  Mat3 H_S;
  shape.inequalities[k].Evaluate(R_WS.transpose() * (p_W - p_WS), &out.f, &g_S, &H_S);
  out.g = R_WS * g_S;
  out.H = R_WS * H_S * R_WS.transpose();
  return out;
}

// The contact force F on body 1 and the torsional moment lr about n, with their derivatives.
struct ContactWrench {
  Vec3 n, F, dF_dln, dF_dst, dF_dso;
  Mat3 dF_dn;
  double lr, dlr_dln, dlr_dsr;
  // The rolling moment M = mu e_roll ln (s_q1 t + s_q2 o) on body 1 (zero without rolling resistance, roll_col < 0).
  int roll_col = -1;
  Vec3 M = Vec3::Zero(), dM_dln = Vec3::Zero(), dM_dq1 = Vec3::Zero(), dM_dq2 = Vec3::Zero();
  Mat3 dM_dn = Mat3::Zero();
  bool fixed_frame = false;  // n and the lever are constants (stage 1's start frame): no derivative by n, a or v
};

// Adds -sign * (F, r x F + lr n + M) / Fs to the body rows of bodies()[local] (sign +1 for body 1, -1 for body 2).
void AddContactWrench(const RowContext& ctx, int c, int local, double sign, const Vec3& r, const ContactWrench& w) {
  const BodyEnd& e = ctx.ends[local];
  if (e.col < 0) return;
  const PairBlock& blk = ctx.layout.blocks()[c];
  const int off = blk.offset, row = e.col;
  const int a_col = off + (sign > 0 ? pi::kA1 : pi::kA2);
  const double s = sign / ctx.Fs();
  const double h = ctx.h();
  const RowWriter& out = ctx.out;
  out.Phi.segment<3>(row) -= s * w.F;
  out.Phi.segment<3>(row + 3) -= s * (r.cross(w.F) + w.lr * w.n);
  if (w.roll_col >= 0) out.Phi.segment<3>(row + 3) -= s * w.M;
  if (!out.WantJacobian()) return;
  const Mat3 rx = Skew(r), Fx = Skew(w.F);
  const double moving = w.fixed_frame ? 0.0 : 1.0;  // a fixed frame emits the same entries, as zeros
  out.AddJ(row, off + pi::kN, Mat3(-(moving * s * w.dF_dn)));
  out.AddJ(row, blk.normal_force(), Vec3(-(s * w.dF_dln)));
  out.AddJ(row, off + pi::kSt, Vec3(-(s * w.dF_dst)));
  out.AddJ(row, off + pi::kSo, Vec3(-(s * w.dF_dso)));
  out.AddJ(row + 3, a_col, Mat3(moving * s * Fx));        // d(r x F)/da = -[F]x
  out.AddJ(row + 3, e.col, Mat3(-(moving * s * h * Fx)));  // r = a - p0 - h v
  out.AddJ(row + 3, off + pi::kN, Mat3(-(moving * s * (rx * w.dF_dn + w.lr * Mat3::Identity() + w.dM_dn))));
  out.AddJ(row + 3, blk.normal_force(), Vec3(-(s * (rx * w.dF_dln + w.dlr_dln * w.n + w.dM_dln))));
  if (w.roll_col >= 0) {
    out.AddJ(row + 3, w.roll_col, Vec3(-(s * w.dM_dq1)));
    out.AddJ(row + 3, w.roll_col + 1, Vec3(-(s * w.dM_dq2)));
  }
  out.AddJ(row + 3, off + pi::kSt, Vec3(-(s * rx * w.dF_dst)));
  out.AddJ(row + 3, off + pi::kSo, Vec3(-(s * rx * w.dF_dso)));
  out.AddJ(row + 3, off + pi::kSr, Vec3(-(s * w.dlr_dsr * w.n)));
}

}  // namespace

void AddContactRows(const RowContext& ctx, int c, const ContactRowOptions& options) {
  const PairBlock& blk = ctx.layout.blocks()[c];
  const FrictionParams& fr = ctx.model().pairs[blk.pair].friction;
  const Eigen::VectorXd& z = ctx.z;
  const RowWriter& out = ctx.out;
  const NcpEvalMode& mode = out.mode;
  const double h = ctx.h();
  const int off = blk.offset;
  const Vec3 a1 = z.segment<3>(off + pi::kA1), a2 = z.segment<3>(off + pi::kA2), n = z.segment<3>(off + pi::kN);
  const double d = z[off + pi::kD], st = z[off + pi::kSt], so = z[off + pi::kSo], sr = z[off + pi::kSr];
  const double ln = z[blk.normal_force()], sigma = z[blk.sigma()];
  const BodyEnd& e1 = ctx.ends[blk.body1];
  const BodyEnd& e2 = ctx.ends[blk.body2];
  const Vec3 r1 = a1 - e1.p, r2 = a2 - e2.p;
  const Mat3 I3 = Mat3::Identity();
  const bool want_J = out.WantJacobian();
  auto add = [&out, want_J](int row, int col, const auto& block) {
    if (want_J) out.AddJ(row, col, block);
  };
  auto add1 = [&out, want_J](int row, int col, double value) {
    if (want_J) out.AddJ(row, col, value);
  };

  // a1 - a2 - d n = 0 (the closest points are d apart along n).
  out.Phi.segment<3>(off) = a1 - a2 - d * n;
  add(off, off + pi::kA1, I3);
  add(off, off + pi::kA2, -I3);
  add(off, off + pi::kN, -d * I3);
  add(off, off + pi::kD, -n);

  // Normal cones (Appendix eq. 20-22 in the normal form): n = sum beta grad g(a2), -n = sum alpha grad f(a1),
  // with alpha_i _|_ -f_i(a1) and beta_j _|_ -g_j(a2).
  struct Side {
    int body, rows, a_col, mult_col, count;
    double n_sign;
    Vec3 a, r;
    const BodyEnd* e;
    const ConvexShape* shape;
  };
  const ContactPair& pair = ctx.model().pairs[blk.pair];
  const Side sides[2] = {
      {blk.body2, off + 3, off + pi::kA2, blk.beta(), blk.k2, 1.0, a2, r2, &e2, &ctx.model().shape(pair.geom2)},
      {blk.body1, off + 6, off + pi::kA1, off + pi::kAlpha, blk.k1, -1.0, a1, r1, &e1, &ctx.model().shape(pair.geom1)}};
  for (const Side& side : sides) {
    out.Phi.segment<3>(side.rows) = side.n_sign * n;
    add(side.rows, off + pi::kN, side.n_sign * I3);
    for (int k = 0; k < side.count; ++k) {
      const InequalityAt ev = EvaluateInequality(ctx, *side.shape, side.body, k, side.a);
      const double mult = z[side.mult_col + k];
      out.Phi.segment<3>(side.rows) -= mult * ev.g;
      add(side.rows, side.mult_col + k, -ev.g);
      add(side.rows, side.a_col, -mult * ev.H);
      const FB fb = FischerBurmeister(mult, -ev.f, mode.smoothing, mode.raw);
      const int fb_row = side.mult_col + k;
      out.Phi[fb_row] = fb.value;
      add1(fb_row, side.mult_col + k, fb.da);
      add(fb_row, side.a_col, Eigen::RowVector3d(-fb.db * ev.g.transpose()));
      if (side.e->col >= 0) {  // the body moves: f and grad f depend on its end pose
        const Mat3& dth = side.e->dtheta_dw;
        add(side.rows, side.e->col, mult * h * ev.H);
        add(side.rows, side.e->col + 3, Mat3(-mult * (ev.H * Skew(side.r) - Skew(ev.g)) * dth));
        add(fb_row, side.e->col, Eigen::RowVector3d(fb.db * h * ev.g.transpose()));
        add(fb_row, side.e->col + 3, Eigen::RowVector3d(fb.db * side.r.cross(ev.g).transpose() * dth));
      }
    }
  }

  // |n|^2 = 1.
  out.Phi[off + 9] = 0.5 * (n.squaredNorm() - 1.0);
  add(off + 9, off + pi::kN, Eigen::RowVector3d(n.transpose()));

  // Friction: the rates along the frame. With a start frame (n0, t0, o0 and the levers r1_0, r2_0 of the
  // start-of-step closest points) the impulse acts along it, and the slip is measured on the average of the start and
  // end frames, u_bar = 1/2 (W(q0) + W(q1))^T nu. end_weight is the end frame's share.
  Vec3 t, o;
  Mat3 dt_dn, do_dn;
  TangentBasis(n, ctx.layout.tangent_axes()[c], &t, &o, &dt_dn, &do_dn);
  const Vec3 v_rel = RelativeVelocity(e1.v, e1.w, r1, e2.v, e2.w, r2);
  const Vec3 w_rel = e1.w - e2.w;
  const bool start_frame = options.start_frame != nullptr;
  const double end_weight = start_frame ? 0.5 : 1.0;
  Vec3 n0 = n, t0 = t, o0 = o, r1_0 = r1, r2_0 = r2;
  if (start_frame) {
    const Eigen::VectorXd& frame_z = *options.start_frame;
    n0 = frame_z.segment<3>(off + pi::kN);
    Mat3 unused1, unused2;
    TangentBasis(n0, ctx.layout.tangent_axes()[c], &t0, &o0, &unused1, &unused2);
    r1_0 = frame_z.segment<3>(off + pi::kA1) - ctx.kinematics.start(blk.body1).p0;
    r2_0 = frame_z.segment<3>(off + pi::kA2) - ctx.kinematics.start(blk.body2).p0;
  }
  const Vec3 v_rel0 = RelativeVelocity(e1.v, e1.w, r1_0, e2.v, e2.w, r2_0);
  const double start_weight = 1.0 - end_weight;
  const double slip_t = end_weight * t.dot(v_rel) + start_weight * t0.dot(v_rel0);
  const double slip_o = end_weight * o.dot(v_rel) + start_weight * o0.dot(v_rel0);
  const Vec3 n_bar = end_weight * n + start_weight * n0;
  // Adds coeff * u^T d(v_rel)/d(unknowns) to `row`, and the start frame's coeff0 * u0^T d(v_rel0)/d(nu).
  auto add_rel_velocity = [&](int row, double coeff, const Vec3& u, double coeff0, const Vec3& u0) {
    const Vec3 r0[2] = {r1_0, r2_0};
    const Side* both[2] = {&sides[1], &sides[0]};
    for (int i = 0; i < 2; ++i) {
      const Side& side = *both[i];
      if (side.e->col < 0) continue;
      const double s = i == 0 ? coeff : -coeff;
      add(row, side.a_col, Eigen::RowVector3d(s * u.transpose() * Skew(side.e->w)));
      const double s0 = i == 0 ? coeff0 : -coeff0;
      add(row, side.e->col, Eigen::RowVector3d(s * u.transpose() * (I3 - h * Skew(side.e->w)) + s0 * u0.transpose()));
      add(row, side.e->col + 3, Eigen::RowVector3d(-s * u.transpose() * Skew(side.r) - s0 * u0.transpose() * Skew(r0[i])));
    }
  };
  // At a separated contact (d > 0, so ln = 0) the friction fractions are physically void, and with no slip
  // (sigma = 0) nothing would determine them: the Jacobian is singular wherever two bodies rest near each other
  // without touching. The LM step of the dense solver copes; for the sparse LU the rows use sigma + max(d, 0) / h
  // (ContactRowOptions::regular_separated_friction).
  FrictionRows friction;
  friction.first_row = off + pi::kSt;
  friction.count = 3;
  friction.sigma = blk.sigma();
  friction.sigma_value = sigma;
  friction.rate[0] = fr.e_t * slip_t;
  friction.rate[1] = fr.e_o * slip_o;
  friction.rate[2] = fr.e_r * n_bar.dot(w_rel);
  friction.s[0] = st;
  friction.s[1] = so;
  friction.s[2] = sr;
  const double slip = ProjectedSlip(mode, sigma, &friction.dslip_dsigma);
  friction.slip = options.regular_separated_friction ? slip + std::max(d, 0.0) / h : slip;
  friction.gap = off + pi::kD;
  friction.dslip_dgap = options.regular_separated_friction && d > 0.0 ? 1.0 / h : 0.0;
  friction.zeta = 1.0 - st * st - so * so - sr * sr;
  // Components whose rates read only locked velocities, in the end frame and the start frame (a planar body's o and
  // torsion): their slip rows hold s_k = 0 and the rate's derivatives below are emitted as zeros.
  const auto locked_along = [&](const Vec3& u, const Vec3& u0) {
    return FrictionComponentLocked(ctx.layout, e1, u, r1.cross(u), e2, u, r2.cross(u)) &&
           FrictionComponentLocked(ctx.layout, e1, u0, r1_0.cross(u0), e2, u0, r2_0.cross(u0));
  };
  const auto locked_about = [&](const Vec3& u) {
    return FrictionComponentLocked(ctx.layout, e1, Vec3::Zero(), u, e2, Vec3::Zero(), u);
  };
  friction.locked[0] = locked_along(t, t0);
  friction.locked[1] = locked_along(o, o0);
  friction.locked[2] = fr.e_r == 0.0 || locked_about(n_bar);  // e_r = 0: no torsional friction
  // Rolling resistance: e_roll (t_bar . w_rel) + s_q1 slip = 0 and likewise about o_bar (the averaged frame, as n_bar).
  const bool rolling = blk.rolling > 0;
  const Vec3 t_bar = end_weight * t + start_weight * t0, o_bar = end_weight * o + start_weight * o0;
  const int rq = blk.roll();
  if (rolling) {
    friction.count = 5;
    friction.roll_row = rq;
    friction.rate[3] = fr.e_roll * t_bar.dot(w_rel);
    friction.rate[4] = fr.e_roll * o_bar.dot(w_rel);
    friction.locked[3] = locked_about(t_bar);
    friction.locked[4] = locked_about(o_bar);
    friction.s[3] = z[rq];
    friction.s[4] = z[rq + 1];
    friction.zeta -= z[rq] * z[rq] + z[rq + 1] * z[rq + 1];
  }
  // The proximal rung's term (ncp_problem.h), weight cp in m/s per unit of s.
  const double cp = mode.raw ? 0.0 : mode.proximal_weight;
  friction.proximal_weight = cp;
  if (cp > 0.0) friction.proximal_center = mode.proximal_center;
  // coeff times the gradient of rate_k (its frame and velocity derivatives) into `row`.
  const Vec3 roll_axes[2] = {t_bar, o_bar};
  const Mat3* daxis_dn[2] = {&dt_dn, &do_dn};
  const auto emit_rate = [&](int k, int row, double coeff) {
    if (!want_J) return;
    if (k == 0) {
      add(row, off + pi::kN, Eigen::RowVector3d(coeff * end_weight * fr.e_t * v_rel.transpose() * dt_dn));
      add_rel_velocity(row, coeff * end_weight * fr.e_t, t, coeff * start_weight * fr.e_t, t0);
    } else if (k == 1) {
      add(row, off + pi::kN, Eigen::RowVector3d(coeff * end_weight * fr.e_o * v_rel.transpose() * do_dn));
      add_rel_velocity(row, coeff * end_weight * fr.e_o, o, coeff * start_weight * fr.e_o, o0);
    } else if (k == 2) {
      add(row, off + pi::kN, Eigen::RowVector3d(coeff * end_weight * fr.e_r * w_rel.transpose()));
      if (e1.col >= 0) add(row, e1.col + 3, Eigen::RowVector3d(coeff * fr.e_r * n_bar.transpose()));
      if (e2.col >= 0) add(row, e2.col + 3, Eigen::RowVector3d(-coeff * fr.e_r * n_bar.transpose()));
    } else {  // the rolling about t_bar (k = 3) or o_bar (k = 4)
      const Vec3& axis = roll_axes[k - 3];
      add(row, off + pi::kN, Eigen::RowVector3d(coeff * end_weight * fr.e_roll * w_rel.transpose() * *daxis_dn[k - 3]));
      if (e1.col >= 0) add(row, e1.col + 3, Eigen::RowVector3d(coeff * fr.e_roll * axis.transpose()));
      if (e2.col >= 0) add(row, e2.col + 3, Eigen::RowVector3d(-coeff * fr.e_roll * axis.transpose()));
    }
  };
  friction.projected = ctx.friction.projected;
  friction.projection_scale = ctx.friction.projection_scale;
  friction.separation = options.regular_separated_friction ? std::max(d, 0.0) / h : 0.0;
  AddFrictionRows(friction, out, RateGradient(emit_rate));

  // Non-penetration (paper eq. 11 with the signed distance d as gap): ln / Fs _|_ d.
  // With the proximal term the gap side reads d + cp h (ln - ln_c) / Fs (a velocity weight times the step: metres).
  const double Fs = ctx.Fs();
  const double proximal_gap = cp > 0.0 ? cp * h * (ln - (*mode.proximal_center)[blk.normal_force()]) / Fs : 0.0;
  const FB fb_n = FischerBurmeister(ln / Fs, d + proximal_gap, mode.smoothing, mode.raw);
  out.Phi[blk.normal_force()] = fb_n.value;
  add1(blk.normal_force(), blk.normal_force(), (fb_n.da + mode.regularization + fb_n.db * cp * h) / Fs);
  add1(blk.normal_force(), off + pi::kD, fb_n.db);

  // The contact wrench on both bodies with lt = mu e_t ln s_t, lo = mu e_o ln s_o, lr = mu e_r ln s_r; with a start
  // frame along n0, t0, o0 at the start levers (no derivative by n, a or v).
  ContactWrench w;
  w.n = n0;
  w.fixed_frame = start_frame;
  const double mu = fr.mu;
  const Vec3 friction_dir = mu * (fr.e_t * st * t0 + fr.e_o * so * o0);
  w.F = ln * (n0 + friction_dir);
  w.dF_dn = ln * (I3 + mu * (fr.e_t * st * dt_dn + fr.e_o * so * do_dn));
  w.dF_dln = n0 + friction_dir;
  w.dF_dst = mu * fr.e_t * ln * t0;
  w.dF_dso = mu * fr.e_o * ln * o0;
  w.lr = mu * fr.e_r * ln * sr;
  w.dlr_dln = mu * fr.e_r * sr;
  w.dlr_dsr = mu * fr.e_r * ln;
  if (rolling) {
    const double sq1 = z[rq], sq2 = z[rq + 1], m = mu * fr.e_roll;
    w.roll_col = rq;
    w.dM_dln = RollingMomentPerNormalForce(blk, fr, z, t0, o0);
    w.M = ln * w.dM_dln;
    w.dM_dq1 = m * ln * t0;
    w.dM_dq2 = m * ln * o0;
    w.dM_dn = m * ln * (sq1 * dt_dn + sq2 * do_dn);
  }
  AddContactWrench(ctx, c, blk.body1, +1.0, r1_0, w);
  AddContactWrench(ctx, c, blk.body2, -1.0, r2_0, w);
}

}  // namespace implicit_sim
