#include "implicit_sim/core/step/problems/step_problem.h"

#include <cmath>

#include "implicit_sim/core/step/rows/friction_rows.h"
#include "step/contact_frame.h"

namespace implicit_sim {
namespace pi = pair_index;

bool StepProblem::IsComplementarityRow(int row, double* scale) const {
  const RowKind kind = row_kinds()[row];
  *scale = kind == RowKind::kForceComplementarity ? 1.0 / kinematics_.force_scale() : 1.0;
  return kind != RowKind::kEquation;
}

void StepProblem::EvaluateInto(const Eigen::VectorXd& z, const RowWriter& out) const {
  EndsOf(z, &ends_);
  out.Phi.setZero(size());
  AddRows(RowContext{layout_, kinematics_, ends_, z, out, friction_form_});
  out.Finish(z);
}

void StepProblem::Evaluate(const Eigen::VectorXd& z, const NcpEvalMode& mode, Eigen::VectorXd* Phi,
                           Eigen::MatrixXd* J) const {
  if (J) J->setZero(size(), size());
  EvaluateInto(z, RowWriter(mode, Phi, J, nullptr, layout_.locked_rows()));
}

void StepProblem::EvaluateSparse(const Eigen::VectorXd& z, const NcpEvalMode& mode, Eigen::VectorXd* Phi,
                                 SparseJacobian* J) const {
  if (J) J->Begin(pattern_version());
  EvaluateInto(z, RowWriter(mode, Phi, nullptr, J, layout_.locked_rows()));
  if (J) J->Finish(size());
}

namespace {

// |s| of a pair's friction fractions: s_t, s_o, s_r and, with rolling resistance, s_q1, s_q2.
double FractionNorm(const Eigen::VectorXd& z, const PairBlock& blk) {
  double norm2 = z.segment<3>(blk.offset + pi::kSt).squaredNorm();
  if (blk.rolling) norm2 += z.segment<2>(blk.roll()).squaredNorm();
  return std::sqrt(norm2);
}

}  // namespace

void StepProblem::Retract(const Eigen::VectorXd& z, Eigen::VectorXd* trial) const {
  constexpr double kOnSphere = 1e-9, kNearSphere = 1e-3;
  for (const PairBlock& blk : layout_.blocks()) {
    const double before = FractionNorm(z, blk), after = FractionNorm(*trial, blk);
    // Only outward: a step along the sphere leaves it outward; a pair moving inward may be starting to stick.
    if (std::abs(before - 1.0) > kOnSphere || after <= 1.0 || after - 1.0 > kNearSphere) continue;
    trial->segment<3>(blk.offset + pi::kSt) /= after;
    if (blk.rolling) trial->segment<2>(blk.roll()) /= after;
  }
}

void StepProblem::SeedVelocities(const State& state, Eigen::VectorXd* z) const {
  const std::vector<int>& slots = layout_.slots();
  for (size_t i = 0; i < slots.size(); ++i) z->segment<6>(6 * i) = state.v.segment<6>(Model::v_offset(slots[i]));
}

void StepProblem::Contacts(const Eigen::VectorXd& z, std::vector<ContactResult>* contacts) const {
  EndsOf(z, &ends_);
  const std::vector<PairBlock>& blocks = layout_.blocks();
  contacts->resize(blocks.size());
  for (size_t c = 0; c < blocks.size(); ++c) {
    const PairBlock& blk = blocks[c];
    const int off = blk.offset;
    ContactResult& out = (*contacts)[c];
    out.pair = blk.pair;
    out.p_WA1 = z.segment<3>(off + pi::kA1);
    out.p_WA2 = z.segment<3>(off + pi::kA2);
    out.n_W = z.segment<3>(off + pi::kN);
    out.gap = z[off + pi::kD];
    out.normal_force = z[blk.normal_force()];
    Vec3 t, o;
    Mat3 dt_dn, do_dn;
    TangentBasis(out.n_W, layout_.tangent_axes()[c], &t, &o, &dt_dn, &do_dn);
    const FrictionParams& fr = layout_.model().pairs[blk.pair].friction;
    const double mu_ln = fr.mu * out.normal_force;
    out.friction_force_W = mu_ln * (fr.e_t * z[off + pi::kSt] * t + fr.e_o * z[off + pi::kSo] * o);
    out.torsional_moment = mu_ln * fr.e_r * z[off + pi::kSr];
    out.rolling_moment_W = out.normal_force * RollingMomentPerNormalForce(blk, fr, z, t, o);
    const BodyEnd& e1 = ends_[blk.body1];
    const BodyEnd& e2 = ends_[blk.body2];
    const Vec3 v_rel = RelativeVelocity(e1.v, e1.w, out.p_WA1 - e1.p, e2.v, e2.w, out.p_WA2 - e2.p);
    out.slip_speed = (v_rel - v_rel.dot(out.n_W) * out.n_W).norm();
  }
}

}  // namespace implicit_sim
