#include "implicit_sim/core/step/seeding.h"

#include <algorithm>
#include <cmath>

#include "contact_frame.h"
#include "implicit_sim/core/geometry/support.h"

namespace implicit_sim {

ClosestPointsResult QuickClosestPoints(const ConvexShape& shape1, const Pose& X_WB1, const ConvexShape& shape2,
                                       const Pose& X_WB2) {
  ClosestPointsResult cp;
  if (ClosedFormClosestPoints(shape1, X_WB1, shape2, X_WB2, &cp)) return cp;
  // The support-function descent, stationary or not (never the oracle).
  if (DescentClosestPoints(shape1, X_WB1, shape2, X_WB2, /*require_stationary=*/false, &cp)) return cp;
  const Vec3 u = ((X_WB1 * shape1.X_BS).translation() - (X_WB2 * shape2.X_BS).translation()).normalized();
  cp.solved = u.allFinite() && SupportPoint(shape1, X_WB1, -u, &cp.p_W1) && SupportPoint(shape2, X_WB2, u, &cp.p_W2);
  if (cp.solved) cp.distance = std::max(0.0, u.dot(cp.p_W1 - cp.p_W2));
  return cp;
}

void SeedPair(const Model& model, const State& state, int c, const StepProblem& problem, Eigen::VectorXd* z,
              bool use_oracle) {
  const PairBlock& blk = problem.blocks()[c];
  const ContactPair& pair = model.pairs[blk.pair];
  const Body& body1 = model.bodies[pair.body1];
  const Body& body2 = model.bodies[pair.body2];
  const Pose X_WB1 = state.X_WB(model, pair.body1), X_WB2 = state.X_WB(model, pair.body2);
  const ClosestPointsResult cp = use_oracle ? FindClosestPoints(body1.shape, X_WB1, body2.shape, X_WB2)
                                            : QuickClosestPoints(body1.shape, X_WB1, body2.shape, X_WB2);
  Vec3 p1 = cp.p_W1, p2 = cp.p_W2;
  if (!cp.solved || !p1.allFinite() || !p2.allFinite()) {  // fall back to the body origins
    p1 = X_WB1.translation();
    p2 = X_WB2.translation();
  }
  Vec3 n;
  double grad2 = 1.0;
  MostActiveInequality(body2.shape, X_WB2, p2, &n, &grad2);
  if (cp.distance > 1e-9) n = (p1 - p2).normalized();  // separated: along the closest points
  z->segment(blk.offset, blk.size()).setZero();
  z->segment<3>(blk.offset + pair_index::kA1) = p1;
  z->segment<3>(blk.offset + pair_index::kA2) = p2;
  z->segment<3>(blk.offset + pair_index::kN) = n;
  (*z)[blk.offset + pair_index::kD] = n.dot(p1 - p2);
  // -n = sum alpha grad f(a1), n = sum beta grad g(a2): every active inequality's multiplier (edges, corners, rims).
  SeedNormalConeMultipliers(body1.shape, X_WB1, p1, -n, z->data() + blk.offset + pair_index::kAlpha);
  SeedNormalConeMultipliers(body2.shape, X_WB2, p2, n, z->data() + blk.beta());
  (*z)[blk.ln()] = cp.distance < 1e-6 ? 0.5 * problem.force_scale() : 0.0;
}

namespace {

// The state's velocities of the problem's moving bodies (a free flight's half step in RATTLE's stage 1).
void SeedVelocities(const State& state, const StepProblem& problem, Eigen::VectorXd* z) {
  const std::vector<int>& slots = problem.slots();
  for (size_t i = 0; i < slots.size(); ++i) z->segment<6>(6 * i) = state.v.segment<6>(Model::v_offset(slots[i]));
  problem.PredictFreeFlight(z);
}

}  // namespace

void SeedColdStart(const Model& model, const State& state, StepProblem* problem, Eigen::VectorXd* z) {
  SeedVelocities(state, *problem, z);
  problem->SeedJoints(z);
  for (int c = 0; c < static_cast<int>(problem->blocks().size()); ++c) SeedPair(model, state, c, *problem, z);
  problem->ResetTangentAxes(*z);
  problem->SeedFriction(z);
}

void SeedWarmStart(const Model& model, const State& state, StepProblem* problem, Eigen::VectorXd* z) {
  SeedVelocities(state, *problem, z);  // the previous solution's velocities are the state's
  problem->UpdateTangentAxes(z);
  problem->PredictClosestPoints(z);
}

void StepProblem::ResetTangentAxes(const Eigen::VectorXd& z) {
  for (size_t c = 0; c < blocks_.size(); ++c) ResetTangentAxis(static_cast<int>(c), z);
}

void StepProblem::ResetTangentAxis(int c, const Eigen::VectorXd& z) {
  tangent_axis_[c] = LeastAlignedAxis(z.segment<3>(blocks_[c].offset + pair_index::kN));
}

void StepProblem::UpdateTangentAxes(Eigen::VectorXd* z) {
  for (size_t c = 0; c < blocks_.size(); ++c) {
    const int off = blocks_[c].offset;
    const Vec3 n = z->segment<3>(off + pair_index::kN);
    if (std::abs(tangent_axis_[c].dot(n)) < 0.9 * n.norm()) continue;
    const FrictionParams& fr = model_.pairs[blocks_[c].pair].friction;
    Vec3 t, o;
    Mat3 dt_dn, do_dn;
    TangentBasis(n, tangent_axis_[c], &t, &o, &dt_dn, &do_dn);
    // -v_tangential / sigma, independent of the basis.
    const Vec3 slip_dir = (*z)[off + pair_index::kSt] / fr.e_t * t + (*z)[off + pair_index::kSo] / fr.e_o * o;
    tangent_axis_[c] = LeastAlignedAxis(n);
    TangentBasis(n, tangent_axis_[c], &t, &o, &dt_dn, &do_dn);
    (*z)[off + pair_index::kSt] = fr.e_t * slip_dir.dot(t);
    (*z)[off + pair_index::kSo] = fr.e_o * slip_dir.dot(o);
  }
}

void StepProblem::PredictClosestPoints(Eigen::VectorXd* z) const {
  for (size_t c = 0; c < blocks_.size(); ++c) {
    const int off = blocks_[c].offset;
    for (const auto& [body, column] : {std::make_pair(blocks_[c].body1, off + pair_index::kA1),
                                       std::make_pair(blocks_[c].body2, off + pair_index::kA2)}) {
      z->segment<3>(column) += h_ * start_[body].v0;
    }
    const Vec3 n = z->segment<3>(off + pair_index::kN);
    (*z)[off + pair_index::kD] = n.dot(z->segment<3>(off + pair_index::kA1) - z->segment<3>(off + pair_index::kA2));
  }
}

void StepProblem::SeedFriction(Eigen::VectorXd* z) const {
  for (size_t c = 0; c < blocks_.size(); ++c) SeedFriction(static_cast<int>(c), z);
}

void StepProblem::SeedFriction(int c, Eigen::VectorXd* z) const {
  const ContactPair& pair = model_.pairs[blocks_[c].pair];
  const FrictionParams& fr = pair.friction;
  const PairBlock& blk = blocks_[c];
  const int off = blk.offset;
  const BodyStep& s1 = start_[blk.body1];
  const BodyStep& s2 = start_[blk.body2];
  const Vec3 n = z->segment<3>(off + pair_index::kN).normalized();
  const Vec3 v_rel = RelativeVelocity(s1.v0, s1.w0, z->segment<3>(off + pair_index::kA1) - s1.p0, s2.v0, s2.w0,
                                      z->segment<3>(off + pair_index::kA2) - s2.p0);
  Vec3 t, o;
  Mat3 dt_dn, do_dn;
  TangentBasis(n, tangent_axis_[c], &t, &o, &dt_dn, &do_dn);
  const Vec3 slip(fr.e_t * t.dot(v_rel), fr.e_o * o.dot(v_rel), fr.e_r * n.dot(s1.w0 - s2.w0));
  const double sigma = slip.norm();
  z->segment<3>(off + pair_index::kSt) = sigma > 1e-9 ? Vec3(-slip / sigma) : Vec3::Zero();
  // No slip yet: sigma = 0, s = 0 would be a saddle of the merit function, so start from sigma > 0 (the rows
  // e (t.v_rel) + s sigma then determine s, and sigma moves to the slip speed or to 0 when the contact sticks).
  (*z)[blk.sigma()] = sigma > 1e-9 ? sigma : 1e-3;
}

}  // namespace implicit_sim
