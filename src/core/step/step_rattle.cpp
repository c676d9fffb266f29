// The two-stage RATTLE step of StepperOptions::Scheme::kRattle (doc/method.md, "The second-order step"): stage 1's
// start frames and rotation row, and the whole of stage 2, the velocity stage at the fixed end-of-step geometry.
//
// Stage 2 (StepStage::kVelocity), per moving body, at the end-of-step pose (p1, R1) of stage 1:
//   m (v1 - v_half) / h = f / 2 + sum F2,   (I_W(R1) w1 - L_half) / h = tau / 2 + sum (r1 x F2 + torsion2)
// per pair closed at the end of stage 1 (gap <= kClosedGap or a stage-1 force), with the TOTAL force Ln of the step
// and the total friction fractions S of its end frame (n1, t1, o1):
//   0 <= Ln / Fs _|_ n1 . v_rel1 >= 0                        (restitution 0 on the total impulse)
//   e_t (t1 . v_rel1) + S_t sigma = 0 (and o, r alike),  0 <= sigma _|_ 1 - |S|^2 >= 0
//   F2 = Ln (n1 + mu (e_t S_t t1 + e_o S_o o1)) - F1,  torsion2 = mu e_r Ln S_r n1 - torsion1
// where F1, torsion1 are stage 1's force and torsion vector: the step's impulse is h (F1 + F2), inside the friction
// ellipsoid of the total. An open pair keeps its stage-1 values (Ln = ln1, S = s1, sigma = sigma1: no stage-2 force).
// Joints: the equalities' rates G_i(q1) . nu1 = 0 with multipliers along G_i(q1); a closed limit 0 <= L _|_ rate;
// friction on the total fraction S; half the damping and effort, as in stage 1; a drive's step-average effort
// (step_drives.cpp).
#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>

#include "contact_frame.h"
#include "implicit_sim/core/ncp/fischer_burmeister.h"
#include "implicit_sim/core/step/step_problem.h"

namespace implicit_sim {
namespace pi = pair_index;
namespace {

// A pair counts as closed for stage 2 when stage 1 left it within this gap (m) or pushing.
constexpr double kClosedGap = 1e-9;
// An inequality counts as active at a closest point when its multiplier exceeds this share of the largest.
constexpr double kActiveShare = 1e-6;

Vec3 Vee(const Mat3& S) { return Vec3(S(2, 1), S(0, 2), S(1, 0)); }

// Whether the multipliers x[0 .. count) have the same active set as y[0 .. count).
bool SameActiveSet(const double* x, const double* y, int count) {
  double x_max = 0.0, y_max = 0.0;
  for (int k = 0; k < count; ++k) {
    x_max = std::max(x_max, x[k]);
    y_max = std::max(y_max, y[k]);
  }
  for (int k = 0; k < count; ++k) {
    if ((x[k] > kActiveShare * x_max) != (y[k] > kActiveShare * y_max)) return false;
  }
  return true;
}

}  // namespace

// Moser-Veselov / Lee-Leok-McClamroch: with Jd = tr(J)/2 I - J and F = R0^T R1 = Exp(h R0^T w), the discrete
// momentum (1/h) R0 vee(F Jd - Jd F^T), divided by g = sinc(h |w|). For R1 -> Exp(theta) R1, F -> Exp(R0^T theta) F
// and vee([e]x B + B^T [e]x) = (tr(B) I - B) e with B = F Jd.
// Why the division by g (our modification): the plain row spins a body about a principal axis by asin(h w) a step
// instead of h w, an O(h^2) phase error that a rolling disc turns into a drift of its position (P1). Divided by g, a
// principal spin is exact for any h w; F still solves the plain row for the momentum g L, and since the plain row
// conserves the energy of a free body for any momentum and the energy is quadratic, the energy is still conserved
// exactly; the row stays symmetric (g depends only on the angle of F), so the step stays second order.
// Near h |w| = pi (g -> 0) a general rotation has no solution: the solve fails and the stepper splits the step.
Vec3 StepProblem::DiscreteMomentum(const Mat3& I_B, const Mat3& R0, const Mat3& R1, const Vec3& w, double h,
                                   Mat3* dL_dtheta, Mat3* dL_dw) {
  const Mat3 Jd = 0.5 * I_B.trace() * Mat3::Identity() - I_B;
  const Mat3 B = R0.transpose() * R1 * Jd;
  const Vec3 L_plain = R0 * Vee(B - B.transpose()) / h;
  // g = sin(a) / a with a = h |w|, and dg/dw = g'(a) h w^T / |w| (series below a = 1e-4).
  const double a = h * w.norm();
  double g, dg_da_over_a;
  if (a < 1e-4) {
    g = 1.0 - a * a / 6.0;
    dg_da_over_a = -1.0 / 3.0 + a * a / 30.0;
  } else {
    g = std::sin(a) / a;
    dg_da_over_a = (a * std::cos(a) - std::sin(a)) / (a * a * a);
  }
  if (dL_dtheta) *dL_dtheta = R0 * (B.trace() * Mat3::Identity() - B) * R0.transpose() / (h * g);
  if (dL_dw) *dL_dw = -L_plain * (dg_da_over_a * h * h * w.transpose()) / (g * g);
  return L_plain / g;
}

// Only a pair closed at the start has a start frame worth acting along: for an impact (a pair apart at the start,
// closed at the end) the start-of-step closest points say nothing about where the bodies meet, so the impulse takes
// the end frame, as in the paper's step.
void StepProblem::SetStartFrames(const Eigen::VectorXd& z_start, const std::vector<char>& known) {
  frame_z_ = z_start;
  for (size_t c = 0; c < blocks_.size(); ++c) {
    const PairBlock& blk = blocks_[c];
    const bool closed = z_start[blk.offset + pi::kD] <= kClosedGap || z_start[blk.ln()] > 1e-12 * force_scale_;
    use_start_frame_[c] = known[c] && closed;
  }
}

int StepProblem::FallBackWhereActiveSetsChanged(const Eigen::VectorXd& z) {
  int count = 0;
  for (size_t c = 0; c < blocks_.size(); ++c) {
    const PairBlock& blk = blocks_[c];
    if (!use_start_frame_[c]) continue;
    const int first = blk.offset + pi::kAlpha;
    if (SameActiveSet(&z[first], &frame_z_[first], blk.k1) &&
        SameActiveSet(&z[blk.beta()], &frame_z_[blk.beta()], blk.k2)) {
      continue;
    }
    use_start_frame_[c] = 0;
    ++count;
  }
  return count;
}

int StepProblem::FallBackToEndFrames() {
  int count = 0;
  for (char& use : use_start_frame_) {
    count += use;
    use = 0;
  }
  return count;
}

void StepProblem::PredictFreeFlight(Eigen::VectorXd* z) const {
  if (stage_ != StepStage::kPosition || !blocks_.empty() || !joints_.empty()) return;
  for (size_t i = 0; i < slots_.size(); ++i) {
    const Body& body = model_.bodies[bodies_[slot_body_[i]]];
    const int row = static_cast<int>(6 * i);
    const Vec3 f_ext = ExternalForce(i);
    for (int k = 0; k < 3; ++k) {
      if (!locked_row_[row + k]) (*z)[row + k] += 0.5 * h_ * f_ext[k] / body.mass;
    }
  }
}

void StepProblem::BeginVelocityStage(const Eigen::VectorXd& z1, const Eigen::VectorXd& raw_rows1,
                                     Eigen::VectorXd* z2) {
  stage_ = StepStage::kPosition;
  UpdateBodies(z1);
  stage1_rows_ = raw_rows1;  // the body rows are equations: raw and reformulated alike
  stage1_z_ = z1;
  *z2 = z1;
  for (size_t b = 0; b < bodies_.size(); ++b) {
    const BodyEnd& e = end_[b];
    const BodyStep& s = start_[b];
    BodyHalf& half = half_[b];
    half.p1 = e.p;
    half.R1 = e.R;
    if (e.col < 0) continue;
    // The momenta after stage 1's impulses, m v0 + h f / 2 + impulses and L0 + h tau / 2 + moments: stage 1's rows
    // less their residual, so that stage 2 conserves momentum to round-off whatever tolerance stage 1 met.
    const Body& body = model_.bodies[bodies_[b]];
    const double hFs = h_ * force_scale_;
    half.v_half = e.v - hFs / body.mass * stage1_rows_.segment<3>(e.col);
    half.L_half = DiscreteMomentum(body.I_B, s.R0, e.R, e.w, h_, nullptr, nullptr) -
                  hFs * stage1_rows_.segment<3>(e.col + 3);
    z2->segment<3>(e.col) = 2.0 * e.v - s.v0;
    z2->segment<3>(e.col + 3) = 2.0 * e.w - s.w0;
    if (blocks_.empty() && joints_.empty()) {  // free flight: stage 2's exact solution (no locked axis: see rows)
      const int row = e.col;
      const Vec3 tau_ext = ExternalTorque(row / 6);
      const Mat3 I_W1 = e.R * body.I_B * e.R.transpose();
      bool locked = false;
      for (int k = 0; k < 6; ++k) locked = locked || locked_row_[row + k];
      if (!locked) z2->segment<3>(row + 3) = I_W1.ldlt().solve(half.L_half + 0.5 * h_ * tau_ext);
    }
  }
  velocity_kind_ = complementarity_kind_;
  for (size_t c = 0; c < blocks_.size(); ++c) {
    const PairBlock& blk = blocks_[c];
    const FrictionParams& fr = model_.pairs[blk.pair].friction;
    const int off = blk.offset;
    const Vec3 n = use_start_frame_[c] ? Vec3(frame_z_.segment<3>(off + pi::kN)) : Vec3(z1.segment<3>(off + pi::kN));
    Vec3 t, o;
    Mat3 dt_dn, do_dn;
    TangentBasis(n, tangent_axis_[c], &t, &o, &dt_dn, &do_dn);
    const double ln = z1[blk.ln()];
    stage1_force_[c] = ln * (n + fr.mu * (fr.e_t * z1[off + pi::kSt] * t + fr.e_o * z1[off + pi::kSo] * o));
    stage1_torsion_[c] = fr.mu * fr.e_r * ln * z1[off + pi::kSr] * n;
    closed_[c] = z1[off + pi::kD] <= kClosedGap || ln > 1e-12 * force_scale_;
    for (int k = 0; k < blk.k1 + blk.k2; ++k) velocity_kind_[off + pi::kAlpha + k] = 0;
    if (closed_[c]) {
      (*z2)[blk.ln()] = 2.0 * ln;
    } else {
      velocity_kind_[blk.ln()] = velocity_kind_[blk.sigma()] = 0;
    }
  }
  for (int j : joints_) {
    const Joint& joint = model_.joints[j];
    const BodyEnd& eP = ParentEnd(j);
    const BodyEnd& eC = ChildEnd(j);
    const Pose X_WP = MakePose(eP.p, eP.R), X_WC = MakePose(eC.p, eC.R);
    for (int i = 0; i < joint.num_equalities(); ++i) JointEquality(joint, i, X_WP, X_WC, &joint_equality_end_[j][i]);
    const double q = JointPosition(joint, X_WP, X_WC, &joint_position_end_[j]);
    joint_q_end_[j] = q;
    if (!joint.limited) continue;
    const int col = joint_offset_[j] + joint.num_equalities();
    const double distance[2] = {q - joint.lower, joint.upper - q};
    for (int k = 0; k < 2; ++k) {
      limit_closed_[j][k] = distance[k] <= kClosedGap || z1[col + k] > 1e-12 * force_scale_;
      if (limit_closed_[j][k]) {
        (*z2)[col + k] = 2.0 * z1[col + k];
      } else {
        velocity_kind_[col + k] = 0;
      }
    }
  }
  stage_ = StepStage::kVelocity;
}

void StepProblem::AddBodyRowsVelocityStage(const Eigen::VectorXd& z, Eigen::VectorXd* Phi) const {
  const double Fs = force_scale_;
  for (size_t i = 0; i < slots_.size(); ++i) {
    const int local = slot_body_[i];
    const Body& body = model_.bodies[bodies_[local]];
    const BodyHalf& half = half_[local];
    const int row = static_cast<int>(6 * i);
    const Vec3 f_ext = ExternalForce(i);
    const Vec3 tau_ext = ExternalTorque(i);
    const Mat3 I_W1 = half.R1 * body.I_B * half.R1.transpose();
    Phi->segment<3>(row) = (body.mass * (z.segment<3>(row) - half.v_half) / h_ - 0.5 * f_ext) / Fs;
    Phi->segment<3>(row + 3) = ((I_W1 * z.segment<3>(row + 3) - half.L_half) / h_ - 0.5 * tau_ext) / Fs;
    AddJ(row, row, Mat3(Mat3::Identity() * body.mass / (h_ * Fs)));
    AddJ(row + 3, row + 3, Mat3(I_W1 / (h_ * Fs)));
  }
}

void StepProblem::AddPairVelocityStage(int c, const Eigen::VectorXd& z, Eigen::VectorXd* Phi) const {
  const PairBlock& blk = blocks_[c];
  const FrictionParams& fr = model_.pairs[blk.pair].friction;
  const int off = blk.offset;
  const bool want_J = WantJacobian();
  // The closest-point unknowns stay at stage 1's values.
  for (int k = 0; k < pi::kSt; ++k) (*Phi)[off + k] = z[off + k] - stage1_z_[off + k];
  for (int k = pi::kAlpha; k < pi::kAlpha + blk.k1 + blk.k2; ++k) (*Phi)[off + k] = z[off + k] - stage1_z_[off + k];
  if (want_J) {
    for (int k = 0; k < pi::kSt; ++k) AddJ(off + k, off + k, 1.0);
    for (int k = pi::kAlpha; k < pi::kAlpha + blk.k1 + blk.k2; ++k) AddJ(off + k, off + k, 1.0);
  }
  const Vec3 n = stage1_z_.segment<3>(off + pi::kN);
  const BodyEnd& e1 = end_[blk.body1];
  const BodyEnd& e2 = end_[blk.body2];
  const Vec3 r1 = stage1_z_.segment<3>(off + pi::kA1) - e1.p, r2 = stage1_z_.segment<3>(off + pi::kA2) - e2.p;
  Vec3 t, o;
  Mat3 dt_dn, do_dn;
  TangentBasis(n, tangent_axis_[c], &t, &o, &dt_dn, &do_dn);
  const Vec3 v_rel = RelativeVelocity(e1.v, e1.w, r1, e2.v, e2.w, r2);
  const Vec3 w_rel = e1.w - e2.w;
  const double Ln = z[blk.ln()], sigma = z[blk.sigma()];
  const Vec3 S = z.segment<3>(off + pi::kSt);
  const double Fs = force_scale_;
  const bool closed = closed_[c] != 0;
  const double on = closed ? 1.0 : 0.0;  // an open pair emits the closed rows' entries as zeros
  // coeff * (u^T d(v_rel)/d(nu) + u_w^T d(w_rel)/d(nu)) on `row`, at the fixed levers.
  auto add_rates = [&](int row, double coeff, const Vec3& u, const Vec3& u_w) {
    if (!want_J) return;
    if (e1.col >= 0) {
      AddJ(row, e1.col, Eigen::RowVector3d(coeff * u.transpose()));
      AddJ(row, e1.col + 3, Eigen::RowVector3d(coeff * (r1.cross(u) + u_w).transpose()));
    }
    if (e2.col >= 0) {
      AddJ(row, e2.col, Eigen::RowVector3d(-coeff * u.transpose()));
      AddJ(row, e2.col + 3, Eigen::RowVector3d(-coeff * (r2.cross(u) + u_w).transpose()));
    }
  };
  const Vec3 zero = Vec3::Zero();
  const double e[3] = {fr.e_t, fr.e_o, fr.e_r};
  const Vec3 dirs[3] = {t, o, zero}, dirs_w[3] = {zero, zero, n};
  const double rates[3] = {t.dot(v_rel), o.dot(v_rel), n.dot(w_rel)};
  const bool clamp = eval_.mode.project_multipliers && !eval_.mode.raw && sigma < 0.0;
  const double slip = clamp ? 0.0 : sigma;
  for (int k = 0; k < 3; ++k) {
    const int row = off + pi::kSt + k;
    if (closed) {
      (*Phi)[row] = e[k] * rates[k] + S[k] * slip;
    } else {
      (*Phi)[row] = S[k] - stage1_z_[row];
    }
    add_rates(row, on * e[k], dirs[k], dirs_w[k]);
    if (want_J) {
      AddJ(row, row, closed ? slip + eval_.mode.regularization : 1.0);
      AddJ(row, blk.sigma(), closed && !clamp ? S[k] : 0.0);
    }
  }
  // The normal law on the total force: 0 <= Ln / Fs _|_ n . v_rel >= 0 (m/s, like the friction rows: in metres,
  // h (n . v_rel), the tolerance would leave a resting body sinking at tolerance / h).
  if (closed) {
    const FB fb = FischerBurmeister(Ln / Fs, n.dot(v_rel), eval_.mode.smoothing, eval_.mode.raw);
    (*Phi)[blk.ln()] = fb.value;
    if (want_J) AddJ(blk.ln(), blk.ln(), (fb.da + eval_.mode.regularization) / Fs);
    add_rates(blk.ln(), fb.db, n, zero);
  } else {
    (*Phi)[blk.ln()] = (Ln - stage1_z_[blk.ln()]) / Fs;
    if (want_J) AddJ(blk.ln(), blk.ln(), 1.0 / Fs);
    add_rates(blk.ln(), 0.0, n, zero);
  }
  // The friction ellipsoid of the total: 0 <= sigma _|_ 1 - |S|^2 >= 0.
  if (closed) {
    const FB fb = FischerBurmeister(sigma, 1.0 - S.squaredNorm(), eval_.mode.smoothing, eval_.mode.raw);
    (*Phi)[blk.sigma()] = fb.value;
    if (want_J) {
      AddJ(blk.sigma(), blk.sigma(), fb.da);
      for (int k = 0; k < 3; ++k) AddJ(blk.sigma(), off + pi::kSt + k, -2.0 * fb.db * S[k]);
    }
  } else {
    (*Phi)[blk.sigma()] = sigma - stage1_z_[blk.sigma()];
    if (want_J) {
      AddJ(blk.sigma(), blk.sigma(), 1.0);
      for (int k = 0; k < 3; ++k) AddJ(blk.sigma(), off + pi::kSt + k, 0.0);
    }
  }
  // Stage 2's force and torsion: the total of the step less stage 1's.
  const double mu = fr.mu;
  const Vec3 dF_dLn = n + mu * (fr.e_t * S[0] * t + fr.e_o * S[1] * o);
  const Vec3 F = Ln * dF_dLn - stage1_force_[c];
  const Vec3 torsion = mu * fr.e_r * Ln * S[2] * n - stage1_torsion_[c];
  const Vec3 dF_dS[3] = {mu * fr.e_t * Ln * t, mu * fr.e_o * Ln * o, zero};
  const Vec3 dtorsion_dLn = mu * fr.e_r * S[2] * n, dtorsion_dSr = mu * fr.e_r * Ln * n;
  for (const auto& [e_body, r, sign] : {std::make_tuple(&e1, r1, 1.0), std::make_tuple(&e2, r2, -1.0)}) {
    if (e_body->col < 0) continue;
    const int row = e_body->col;
    const double s = sign / Fs;
    Phi->segment<3>(row) -= s * F;
    Phi->segment<3>(row + 3) -= s * (r.cross(F) + torsion);
    if (!want_J) continue;
    AddJ(row, blk.ln(), Vec3(-s * dF_dLn));
    AddJ(row + 3, blk.ln(), Vec3(-s * (r.cross(dF_dLn) + dtorsion_dLn)));
    for (int k = 0; k < 2; ++k) {
      AddJ(row, off + pi::kSt + k, Vec3(-s * dF_dS[k]));
      AddJ(row + 3, off + pi::kSt + k, Vec3(-s * r.cross(dF_dS[k])));
    }
    AddJ(row + 3, off + pi::kSr, Vec3(-s * dtorsion_dSr));
  }
}

void StepProblem::AddJointRowsVelocityStage(const Eigen::VectorXd& z, Eigen::VectorXd* Phi) const {
  const double Fs = force_scale_;
  for (int j : joints_) {
    const Joint& joint = model_.joints[j];
    const int o = joint_offset_[j], m = joint.num_equalities();
    const BodyEnd& eP = ParentEnd(j);
    const BodyEnd& eC = ChildEnd(j);
    for (int i = 0; i < m; ++i) {  // the equalities' rates at the end of the step
      const JointGradient& g = joint_equality_end_[j][i];
      (*Phi)[o + i] = g.Rate(eP.v, eP.w, eC.v, eC.w);
      AddRateRow(o + i, g, eP, eC, 1.0);
      AddJointForce(g, z[o + i], o + i, 1.0, eP, eC, Phi);
    }
    if (!joint.has_coordinate()) continue;
    const JointGradient& G_q = joint_position_end_[j];
    const double rate = G_q.Rate(eP.v, eP.w, eC.v, eC.w);
    if (joint.applied_effort != 0.0) AddJointForce(G_q, 0.5 * joint.applied_effort, -1, 0.0, eP, eC, Phi);
    if (joint.limited) {  // the total limit multipliers: 0 <= L_lo _|_ qdot >= 0, 0 <= L_hi _|_ -qdot >= 0
      for (int k = 0; k < 2; ++k) {
        const int col = o + m + k;
        const double sign = k == 0 ? 1.0 : -1.0;
        if (limit_closed_[j][k]) {
          const FB fb = FischerBurmeister(z[col] / Fs, sign * rate, eval_.mode.smoothing, eval_.mode.raw);
          (*Phi)[col] = fb.value;
          if (WantJacobian()) AddJ(col, col, (fb.da + eval_.mode.regularization) / Fs);
          AddRateRow(col, G_q, eP, eC, sign * fb.db);
        } else {
          (*Phi)[col] = (z[col] - stage1_z_[col]) / Fs;
          if (WantJacobian()) AddJ(col, col, 1.0 / Fs);
          AddRateRow(col, G_q, eP, eC, 0.0);
        }
        AddJointForce(G_q, sign * (z[col] - stage1_z_[col]), col, sign, eP, eC, Phi);
      }
    }
    if (joint.friction > 0.0) {  // the total fraction S: qdot + S sigma = 0, 0 <= sigma _|_ 1 - S^2 >= 0
      const int col = o + m + (joint.limited ? 2 : 0);
      const double S = z[col], sigma = z[col + 1];
      (*Phi)[col] = rate + S * sigma;
      AddRateRow(col, G_q, eP, eC, 1.0);
      const FB fb = FischerBurmeister(sigma, 1.0 - S * S, eval_.mode.smoothing, eval_.mode.raw);
      (*Phi)[col + 1] = fb.value;
      if (WantJacobian()) {
        AddJ(col, col, sigma + eval_.mode.regularization);
        AddJ(col, col + 1, S);
        AddJ(col + 1, col + 1, fb.da);
        AddJ(col + 1, col, -2.0 * fb.db * S);
      }
      AddJointForce(G_q, joint.friction * (S - 0.5 * stage1_z_[col]), col, joint.friction, eP, eC, Phi);
    }
    if (joint.damping > 0.0) AddJointDamping(joint, eP, eC, G_q, Phi);
    if (driven_[j]) AddJointDriveRowVelocityStage(j, o + joint.size(), z, eP, eC, G_q, Phi);
  }
}

}  // namespace implicit_sim
