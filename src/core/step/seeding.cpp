#include "implicit_sim/core/step/seeding.h"

#include <algorithm>
#include <cmath>

#include "step/contact_frame.h"
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

void SeedPair(const Model& model, const State& state, int c, const StepLayout& layout, double force_scale,
              Eigen::VectorXd* z, bool use_oracle) {
  const PairBlock& blk = layout.blocks()[c];
  const ContactPair& pair = model.pairs[blk.pair];
  const ConvexShape& shape1 = model.shape(pair.geom1);
  const ConvexShape& shape2 = model.shape(pair.geom2);
  const Pose X_WB1 = state.X_WB(model, pair.body1), X_WB2 = state.X_WB(model, pair.body2);
  const ClosestPointsResult cp = use_oracle ? FindClosestPoints(shape1, X_WB1, shape2, X_WB2)
                                            : QuickClosestPoints(shape1, X_WB1, shape2, X_WB2);
  Vec3 p1 = cp.p_W1, p2 = cp.p_W2;
  if (!cp.solved || !p1.allFinite() || !p2.allFinite()) {  // fall back to the body origins
    p1 = X_WB1.translation();
    p2 = X_WB2.translation();
  }
  Vec3 n;
  double grad2 = 1.0;
  MostActiveInequality(shape2, X_WB2, p2, &n, &grad2);
  if (cp.distance > 1e-9) n = (p1 - p2).normalized();  // separated: along the closest points
  z->segment(blk.offset, blk.size()).setZero();
  z->segment<3>(blk.offset + pair_index::kA1) = p1;
  z->segment<3>(blk.offset + pair_index::kA2) = p2;
  z->segment<3>(blk.offset + pair_index::kN) = n;
  (*z)[blk.offset + pair_index::kD] = n.dot(p1 - p2);
  // -n = sum alpha grad f(a1), n = sum beta grad g(a2): every active inequality's multiplier (edges, corners, rims).
  SeedNormalConeMultipliers(shape1, X_WB1, p1, -n, z->data() + blk.offset + pair_index::kAlpha);
  SeedNormalConeMultipliers(shape2, X_WB2, p2, n, z->data() + blk.beta());
  (*z)[blk.normal_force()] = cp.distance < 1e-6 ? 0.5 * force_scale : 0.0;
}

void SeedFriction(const StepLayout& layout, const StepKinematics& kinematics, Eigen::VectorXd* z) {
  for (size_t c = 0; c < layout.blocks().size(); ++c) SeedFriction(layout, kinematics, static_cast<int>(c), z);
}

void SeedFriction(const StepLayout& layout, const StepKinematics& kinematics, int c, Eigen::VectorXd* z) {
  const PairBlock& blk = layout.blocks()[c];
  const FrictionParams& fr = layout.model().pairs[blk.pair].friction;
  const int off = blk.offset;
  const BodyStart& s1 = kinematics.start(blk.body1);
  const BodyStart& s2 = kinematics.start(blk.body2);
  const Vec3 n = z->segment<3>(off + pair_index::kN).normalized();
  const Vec3 v_rel = RelativeVelocity(s1.v0, s1.w0, z->segment<3>(off + pair_index::kA1) - s1.p0, s2.v0, s2.w0,
                                      z->segment<3>(off + pair_index::kA2) - s2.p0);
  Vec3 t, o;
  Mat3 dt_dn, do_dn;
  TangentBasis(n, layout.tangent_axes()[c], &t, &o, &dt_dn, &do_dn);
  const Vec3 slip(fr.e_t * t.dot(v_rel), fr.e_o * o.dot(v_rel), fr.e_r * n.dot(s1.w0 - s2.w0));
  const Vec3 w_rel = s1.w0 - s2.w0;
  const double roll[2] = {blk.rolling ? fr.e_roll * t.dot(w_rel) : 0.0, blk.rolling ? fr.e_roll * o.dot(w_rel) : 0.0};
  const double rate = std::sqrt(slip.squaredNorm() + roll[0] * roll[0] + roll[1] * roll[1]);
  // The slip rows rate_k + s_k (sigma + max(d, 0) / h) = 0 (contact_rows.cpp, separated pairs regularized) solved for
  // the start velocities and the gap d in z: a pair whose gap rate covers its rate, d / h >= |rate|, has sigma = 0 and
  // |s| <= 1; else |s| = 1 and sigma = |rate| - d / h. Seeding a separated pair with |s| = 1 (as a touching one) left
  // it a residual of d / h: 14 for a palm 0.14 m above the floor at h = 0.01 s, which stalled the warm start of a
  // whole jam. (The gap predicted at the step end instead of d was measured and not kept: doc/method.md, "Jams".)
  const double gap_rate = std::max((*z)[off + pair_index::kD], 0.0) / kinematics.h();  // m/s
  const double divisor = std::max(rate, gap_rate);
  const double scale = divisor > 1e-9 ? -1.0 / divisor : 0.0;
  z->segment<3>(off + pair_index::kSt) = scale * slip;
  for (int k = 0; k < blk.rolling; ++k) (*z)[blk.roll() + k] = scale * roll[k];
  // No slip yet and touching: sigma = 0, s = 0 would be a saddle of the merit function, so start from sigma > 0 (the
  // rows e (t.v_rel) + s sigma then determine s, and sigma moves to the slip speed or to 0 when the contact sticks).
  // A separated pair's rows determine s through d / h instead.
  const double sigma = rate - gap_rate;
  (*z)[blk.sigma()] = sigma > 1e-9 ? sigma : gap_rate > 1e-9 ? 0.0 : 1e-3;
}

namespace {

// Zero joint multipliers; joint friction seeded from the start-of-step joint velocity like SeedFriction.
void SeedJoints(const StepLayout& layout, const StepKinematics& kinematics, Eigen::VectorXd* z) {
  for (int j : layout.joints()) {
    const Joint& joint = layout.model().joints[j];
    const int o = layout.joint_offset(j);
    z->segment(o, layout.joint_size(j)).setZero();
    if (!(joint.friction > 0.0)) continue;
    const JointBodies& jb = layout.joint_bodies(j);
    const BodyStart& c = kinematics.start(jb.child);
    const Vec3 zero = Vec3::Zero();
    const bool world = jb.parent < 0;
    const double rate = kinematics.position_gradient(j).Rate(world ? zero : kinematics.start(jb.parent).v0,
                                                             world ? zero : kinematics.start(jb.parent).w0, c.v0, c.w0);
    const int s_col = o + joint.friction_column();
    (*z)[s_col] = rate > 1e-9 ? -1.0 : (rate < -1e-9 ? 1.0 : 0.0);
    (*z)[s_col + 1] = std::abs(rate) > 1e-9 ? std::abs(rate) : 1e-3;  // sigma > 0: see SeedFriction
  }
}

void PredictClosestPoints(const StepLayout& layout, const StepKinematics& kinematics, Eigen::VectorXd* z) {
  const double h = kinematics.h();
  for (const PairBlock& blk : layout.blocks()) {
    const int off = blk.offset;
    for (const auto& [body, column] :
         {std::make_pair(blk.body1, off + pair_index::kA1), std::make_pair(blk.body2, off + pair_index::kA2)}) {
      z->segment<3>(column) += h * kinematics.start(body).v0;
    }
    const Vec3 n = z->segment<3>(off + pair_index::kN);
    (*z)[off + pair_index::kD] = n.dot(z->segment<3>(off + pair_index::kA1) - z->segment<3>(off + pair_index::kA2));
  }
}


// A pair that carried no load in the last solution (ln = 0) and did not slip (sigma = 0) carries no information
// about its friction: its fractions are whatever the last solve left, and at sigma = 0 the slip rows
// e (t . v_rel) + s sigma do not determine them. Where the predicted gap closes (d <= 0 after PredictClosestPoints),
// Newton's first direction would move those fractions by rate / delta (delta = 1e-9, the proximal diagonal): 1e8 in a
// landing pile, a step length of 1e-9, a failed warm start. Such a pair starts from the cold start's friction seeds
// (SeedFriction); a pair predicted apart keeps its fractions, which its separated rows determine.
void ReseedUnloadedFriction(const StepLayout& layout, const StepKinematics& kinematics, Eigen::VectorXd* z) {
  const double no_load = 1e-9 * kinematics.force_scale();  // N
  constexpr double kNoSlip = 1e-9;                          // m/s
  for (int c = 0; c < static_cast<int>(layout.blocks().size()); ++c) {
    const PairBlock& blk = layout.blocks()[c];
    const bool unloaded = (*z)[blk.normal_force()] <= no_load && (*z)[blk.sigma()] <= kNoSlip;
    if (unloaded && (*z)[blk.offset + pair_index::kD] <= 0.0) SeedFriction(layout, kinematics, c, z);
  }
}

}  // namespace

void SeedColdStart(const Model& model, const State& state, const StepProblem& problem, StepLayout* layout,
                   Eigen::VectorXd* z) {
  const StepKinematics& kinematics = problem.kinematics();
  problem.SeedVelocities(state, z);
  SeedJoints(*layout, kinematics, z);
  for (int c = 0; c < static_cast<int>(layout->blocks().size()); ++c) {
    SeedPair(model, state, c, *layout, kinematics.force_scale(), z);
  }
  layout->ResetTangentAxes(*z);
  SeedFriction(*layout, kinematics, z);
}

void SeedWarmStart(const Model&, const State& state, const StepProblem& problem, StepLayout* layout,
                   Eigen::VectorXd* z) {
  problem.SeedVelocities(state, z);  // the previous solution's velocities are the state's
  layout->UpdateTangentAxes(z);
  PredictClosestPoints(*layout, problem.kinematics(), z);
  ReseedUnloadedFriction(*layout, problem.kinematics(), z);
}

}  // namespace implicit_sim
