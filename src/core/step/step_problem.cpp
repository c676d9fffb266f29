#include "implicit_sim/core/step/step_problem.h"

#include <algorithm>
#include <cmath>

#include "contact_frame.h"
#include "implicit_sim/core/base/rotation.h"
#include "implicit_sim/core/ncp/fischer_burmeister.h"
#include "implicit_sim/core/step/data.h"

namespace implicit_sim {
namespace pi = pair_index;
StepProblem::StepProblem(const Model& model, bool all_pairs, bool all_bodies)
    : model_(model), model_force_scale_(model.ForceScale()), force_scale_(model_force_scale_) {
  joint_equality_start_.resize(model.joints.size());
  joint_position_start_.resize(model.joints.size());
  joint_bodies_.resize(model.joints.size());
  joint_offset_.assign(model.joints.size(), -1);
  joint_equality_end_.resize(model.joints.size());
  joint_position_end_.resize(model.joints.size());
  limit_closed_.assign(model.joints.size(), {0, 0});
  joint_q_end_.assign(model.joints.size(), 0.0);
  driven_.assign(model.joints.size(), 0);
  for (int b = 0; b < static_cast<int>(model.bodies.size()); ++b) {
    if (model.velocity_slot[b] < 0) fixed_bodies_.push_back(b);
  }
  std::vector<int> slots(all_bodies ? model.num_moving() : 0), joints(all_bodies ? model.joints.size() : 0);
  for (size_t k = 0; k < slots.size(); ++k) slots[k] = static_cast<int>(k);
  for (size_t j = 0; j < joints.size(); ++j) joints[j] = static_cast<int>(j);
  SetBodies(slots, joints);
  std::vector<int> pairs;
  for (int c = 0; all_bodies && all_pairs && c < static_cast<int>(model.pairs.size()); ++c) pairs.push_back(c);
  std::vector<int> new_blocks;
  Eigen::VectorXd z;
  SetActivePairs(pairs, nullptr, &z, &new_blocks);
}

void StepProblem::SetBodies(const std::vector<int>& slots, const std::vector<int>& joints) {
  const Model& model = model_;
  slots_ = slots;
  joints_ = joints;
  // The moving bodies of `slots` and every fixed body, merged in ascending order (moving_bodies is ascending).
  bodies_.clear();
  size_t f = 0;
  for (int k : slots_) {
    const int b = model.moving_bodies[k];
    while (f < fixed_bodies_.size() && fixed_bodies_[f] < b) bodies_.push_back(fixed_bodies_[f++]);
    bodies_.push_back(b);
  }
  bodies_.insert(bodies_.end(), fixed_bodies_.begin() + f, fixed_bodies_.end());
  start_.assign(bodies_.size(), BodyStep());
  end_.assign(bodies_.size(), BodyEnd());
  half_.assign(bodies_.size(), BodyHalf());
  slot_body_.assign(slots_.size(), -1);
  locked_row_.assign(6 * slots_.size(), 0);
  external_wrench_W_.setZero(6 * slots_.size());
  for (size_t s = 0; s < slots_.size(); ++s) {
    const int b = model.moving_bodies[slots_[s]];
    const int local = LocalBody(b);
    slot_body_[s] = local;
    end_[local].col = static_cast<int>(6 * s);
    for (int r = 0; r < 6; ++r) locked_row_[6 * s + r] = model.bodies[b].locked[r];
  }
  LayOutJoints();
  for (int j : joints_) {
    const Joint& joint = model.joints[j];
    joint_bodies_[j].parent = joint.parent < 0 ? -1 : LocalBody(joint.parent);
    joint_bodies_[j].child = LocalBody(joint.child);
  }
  std::vector<int> new_blocks;
  Eigen::VectorXd z;
  SetActivePairs({}, nullptr, &z, &new_blocks);
}

void StepProblem::LayOutJoints() {
  pair_base_ = static_cast<int>(6 * slots_.size());
  std::fill(joint_offset_.begin(), joint_offset_.end(), -1);
  for (int j : joints_) {
    joint_offset_[j] = pair_base_;
    pair_base_ += joint_size(j);
  }
}

int StepProblem::LocalBody(int body) const {
  const auto it = std::lower_bound(bodies_.begin(), bodies_.end(), body);
  return it != bodies_.end() && *it == body ? static_cast<int>(it - bodies_.begin()) : -1;
}

int StepProblem::body_column(int body) const {
  const int local = LocalBody(body);
  return local < 0 ? -1 : end_[local].col;
}

void StepProblem::SetActivePairs(const std::vector<int>& pairs, const Eigen::VectorXd* z_old, Eigen::VectorXd* z_new,
                                 std::vector<int>* new_blocks) {
  old_blocks_ = blocks_;
  old_axes_ = tangent_axis_;
  const std::vector<PairBlock>& old_blocks = old_blocks_;
  const std::vector<Vec3>& old_axes = old_axes_;
  blocks_.clear();
  size_ = pair_base_;
  for (int pair : pairs) {
    PairBlock block;
    block.pair = pair;
    block.offset = size_;
    block.k1 = static_cast<int>(model_.bodies[model_.pairs[pair].body1].shape.inequalities.size());
    block.k2 = static_cast<int>(model_.bodies[model_.pairs[pair].body2].shape.inequalities.size());
    block.body1 = LocalBody(model_.pairs[pair].body1);
    block.body2 = LocalBody(model_.pairs[pair].body2);
    blocks_.push_back(block);
    size_ += block.size();
  }
  tangent_axis_.assign(blocks_.size(), Vec3::UnitX());
  use_start_frame_.assign(blocks_.size(), 0);
  closed_.assign(blocks_.size(), 0);
  stage1_force_.assign(blocks_.size(), Vec3::Zero());
  stage1_torsion_.assign(blocks_.size(), Vec3::Zero());
  frame_z_.setZero(size_);
  stage1_z_.setZero(size_);
  stage1_rows_.setZero(size_);
  complementarity_kind_.assign(size_, 0);
  for (int j : joints_) {
    const Joint& joint = model_.joints[j];
    const int extra = joint_offset_[j] + joint.num_equalities();
    if (joint.limited) complementarity_kind_[extra] = complementarity_kind_[extra + 1] = 2;  // l / Fs _|_ distance
    if (joint.friction > 0.0) complementarity_kind_[extra + (joint.limited ? 3 : 1)] = 1;  // sigma_f
  }
  for (const PairBlock& blk : blocks_) {
    for (int i = blk.offset + pi::kAlpha; i < blk.offset + blk.size(); ++i) complementarity_kind_[i] = 1;
    complementarity_kind_[blk.ln()] = 2;  // the normal force enters as ln / Fs
  }
  velocity_kind_ = complementarity_kind_;
  ++pattern_version_;
  // Carry the old solution over: the body part, and the blocks of the pairs that stay (both lists are ascending).
  z_new->setZero(size_);
  new_blocks->clear();
  if (z_old) z_new->head(pair_base_) = z_old->head(pair_base_);
  size_t o = 0;
  for (size_t c = 0; c < blocks_.size(); ++c) {
    while (o < old_blocks.size() && old_blocks[o].pair < blocks_[c].pair) ++o;
    if (z_old && o < old_blocks.size() && old_blocks[o].pair == blocks_[c].pair) {
      z_new->segment(blocks_[c].offset, blocks_[c].size()) = z_old->segment(old_blocks[o].offset, blocks_[c].size());
      tangent_axis_[c] = old_axes[o];
    } else {
      new_blocks->push_back(static_cast<int>(c));
    }
  }
}

void StepProblem::ActivePairs(std::vector<int>* pairs) const {
  pairs->clear();
  for (const PairBlock& blk : blocks_) pairs->push_back(blk.pair);
}

bool StepProblem::IsComplementarityRow(int row, double* scale) const {
  const std::vector<char>& kind = stage_ == StepStage::kVelocity ? velocity_kind_ : complementarity_kind_;
  *scale = kind[row] == 2 ? 1.0 / force_scale_ : 1.0;
  return kind[row] != 0;
}

void StepProblem::CondensableBlocks(std::vector<int>* starts, std::vector<int>* indices) const {
  starts->assign(1, 0);
  indices->clear();
  for (const PairBlock& block : blocks_) {
    for (int k = pair_index::kA1; k <= pair_index::kD; ++k) indices->push_back(block.offset + k);
    for (int k = 0; k < block.k1 + block.k2; ++k) indices->push_back(block.offset + pair_index::kAlpha + k);
    starts->push_back(static_cast<int>(indices->size()));
  }
}

void StepProblem::BeginStep(const State& start, double h, const Eigen::VectorXd* external_wrench_W) {
  const Model& model = model_;
  h_ = h;
  force_scale_ = model_force_scale_;
  for (size_t s = 0; s < slots_.size(); ++s) {
    if (external_wrench_W) {
      external_wrench_W_.segment<6>(6 * s) = external_wrench_W->segment<6>(Model::v_offset(slots_[s]));
      force_scale_ = std::max(force_scale_, external_wrench_W_.segment<3>(6 * s).norm());
    } else {
      external_wrench_W_.segment<6>(6 * s).setZero();
    }
  }
  for (size_t i = 0; i < bodies_.size(); ++i) {
    const int b = bodies_[i];
    const Body& body = model.bodies[b];
    const Pose X_WB = start.X_WB(model, b);
    BodyStep& s = start_[i];
    s.p0 = X_WB.translation();
    s.R0 = X_WB.linear();
    const int k = model.velocity_slot[b];
    s.v0 = k < 0 ? Vec3::Zero() : start.v_WB(k);
    s.w0 = k < 0 ? Vec3::Zero() : start.w_WB(k);
    s.I_W0 = s.R0 * body.I_B * s.R0.transpose();
  }
  BeginJoints();
}

void StepProblem::UpdateBodies(const Eigen::VectorXd& z) const {
  for (size_t b = 0; b < end_.size(); ++b) {
    BodyEnd& e = end_[b];
    const BodyStep& s = start_[b];
    if (stage_ == StepStage::kVelocity) {  // stage 2: the geometry is fixed at the end of stage 1
      e.p = half_[b].p1;
      e.R = half_[b].R1;
      if (e.col >= 0) {
        e.v = z.segment<3>(e.col);
        e.w = z.segment<3>(e.col + 3);
      }
      e.dtheta_dw.setZero();
      continue;
    }
    if (e.col < 0) {
      e.p = s.p0;
      e.R = s.R0;
      continue;
    }
    e.v = z.segment<3>(e.col);
    e.w = z.segment<3>(e.col + 3);
    EndOfStepPose(s.p0, s.R0, e.v, e.w, h_, &e.p, &e.R);  // paper eq. 2
    e.dtheta_dw = h_ * LeftJacobianSO3(h_ * e.w);
  }
}

Pose StepProblem::EndPose(int body, const Eigen::VectorXd& z) const {
  const int local = LocalBody(body);
  const BodyStep& s = start_[local];
  Pose X = Pose::Identity();
  const int col = end_[local].col;
  X.translation() = s.p0;
  X.linear() = s.R0;
  if (col < 0) return X;
  Vec3 p;
  Mat3 R;
  EndOfStepPose(s.p0, s.R0, z.segment<3>(col), z.segment<3>(col + 3), h_, &p, &R);  // paper eq. 2
  X.translation() = p;
  X.linear() = R;
  return X;
}

StepProblem::Eval StepProblem::EvaluateInequality(int local, int k, const Vec3& p_W) const {
  const ConvexShape& shape = model_.bodies[bodies_[local]].shape;
  const BodyEnd& e = end_[local];
  const Mat3 R_WS = e.R * shape.X_BS.linear();
  const Vec3 p_WS = e.p + e.R * shape.X_BS.translation();
  Eval out;
  Vec3 g_S;
  Mat3 H_S;
  shape.inequalities[k].Evaluate(R_WS.transpose() * (p_W - p_WS), &out.f, &g_S, &H_S);
  out.g = R_WS * g_S;
  out.H = R_WS * H_S * R_WS.transpose();
  return out;
}

template <typename Block>
void StepProblem::AddJ(int row, int col, const Block& block) const {
  if (eval_.J_dense) {  // rows of locked velocities are overwritten at the end of EvaluateAll
    eval_.J_dense->block(row, col, block.rows(), block.cols()) += block;
  } else if (eval_.J_sparse) {
    for (int j = 0; j < block.cols(); ++j) {
      for (int i = 0; i < block.rows(); ++i) AddJ(row + i, col + j, static_cast<double>(block(i, j)));
    }
  }
}

void StepProblem::AddJ(int row, int col, double value) const {
  if (eval_.J_sparse && row < static_cast<int>(locked_row_.size()) && locked_row_[row]) return;  // left out
  AddJUnlocked(row, col, value);
}

void StepProblem::AddJUnlocked(int row, int col, double value) const {
  if (eval_.J_dense) {
    (*eval_.J_dense)(row, col) += value;
  } else if (eval_.J_sparse) {
    eval_.J_sparse->Add(row, col, value);
  }
}

void StepProblem::EvaluateAll(const Eigen::VectorXd& z, Eigen::VectorXd* Phi) const {
  UpdateBodies(z);
  Phi->setZero(size_);
  if (stage_ == StepStage::kVelocity) {
    AddBodyRowsVelocityStage(z, Phi);
    AddJointRowsVelocityStage(z, Phi);
    for (size_t c = 0; c < blocks_.size(); ++c) AddPairVelocityStage(static_cast<int>(c), z, Phi);
  } else {
    AddBodyRows(z, Phi);
    AddJointRows(z, Phi);
    for (size_t c = 0; c < blocks_.size(); ++c) AddPair(static_cast<int>(c), z, Phi);
  }
  // Locked degrees of freedom: the row of a locked velocity becomes "velocity = 0" (AddJ skipped its other entries).
  for (int row = 0; row < static_cast<int>(locked_row_.size()); ++row) {
    if (!locked_row_[row]) continue;
    (*Phi)[row] = z[row];
    if (eval_.J_dense) eval_.J_dense->row(row).setZero();
    AddJUnlocked(row, row, 1.0);
  }
}

void StepProblem::Evaluate(const Eigen::VectorXd& z, const NcpEvalMode& mode, Eigen::VectorXd* Phi,
                           Eigen::MatrixXd* J) const {
  if (J) J->setZero(size_, size_);
  eval_ = {mode, J, nullptr};
  EvaluateAll(z, Phi);
  eval_ = EvalContext();
}

void StepProblem::EvaluateSparse(const Eigen::VectorXd& z, const NcpEvalMode& mode, Eigen::VectorXd* Phi,
                                 SparseJacobian* J) const {
  if (J) J->Begin(pattern_version_);
  eval_ = {mode, nullptr, J};
  EvaluateAll(z, Phi);
  eval_ = EvalContext();
  if (J) J->Finish(size_);
}

// Newton-Euler in impulse form divided by h (paper eq. 1 discretized): force units, scaled by 1/Fs.
void StepProblem::AddBodyRows(const Eigen::VectorXd& z, Eigen::VectorXd* Phi) const {
  const double Fs = force_scale_;
  for (size_t i = 0; i < slots_.size(); ++i) {
    const Body& body = model_.bodies[bodies_[slot_body_[i]]];
    const BodyStep& s = start_[slot_body_[i]];
    const int row = static_cast<int>(6 * i);
    const Vec3 f_ext = ExternalForce(i);
    const Vec3 tau_ext = ExternalTorque(i);
    const BodyEnd& e = end_[slot_body_[i]];
    AddJ(row, row, Mat3(Mat3::Identity() * body.mass / (h_ * Fs)));
    if (stage_ == StepStage::kPosition) {
      // RATTLE stage 1: m (v_half - v0) = h/2 f + impulses, and the Lie-group variational (Moser-Veselov) rotation
      // row L_disc(w_half) = L0 + h/2 tau + impulse moments (doc/method.md, "The second-order step").
      Phi->segment<3>(row) = (body.mass * (z.segment<3>(row) - s.v0) / h_ - 0.5 * f_ext) / Fs;
      Mat3 dL_dtheta, dL_dw;
      const Vec3 L_half = DiscreteMomentum(body.I_B, s.R0, e.R, e.w, h_, &dL_dtheta, &dL_dw);
      Phi->segment<3>(row + 3) = ((L_half - s.I_W0 * s.w0) / h_ - 0.5 * tau_ext) / Fs;
      AddJ(row + 3, row + 3, Mat3((dL_dtheta * e.dtheta_dw + dL_dw) / (h_ * Fs)));
      continue;
    }
    Phi->segment<3>(row) = (body.mass * (z.segment<3>(row) - s.v0) / h_ - f_ext) / Fs;
    // Angular momentum form: (I_W(R1) w1 - I_W(R0) w0) / h = torque, with the inertia at the end-of-step
    // orientation R1 = Exp(h w1) R0. It holds the gyroscopic effect implicitly and conserves angular momentum exactly
    // without torque (doc/method.md, pitfall 7).
    const Mat3 I_W1 = e.R * body.I_B * e.R.transpose();
    const Vec3 w1 = z.segment<3>(row + 3);
    Phi->segment<3>(row + 3) = ((I_W1 * w1 - s.I_W0 * s.w0) / h_ - tau_ext) / Fs;
    // d(I_W w)/dtheta = I_W [w]x - [I_W w]x for R -> Exp(dtheta) R, and dtheta/dw1 = h J_l(h w1).
    AddJ(row + 3, row + 3, Mat3((I_W1 + (I_W1 * Skew(w1) - Skew(I_W1 * w1)) * e.dtheta_dw) / (h_ * Fs)));
  }
}

// Adds -sign * (F, r x F + lr n) / Fs to the body rows of `body` (sign +1 for body 1, -1 for body 2).
void StepProblem::AddContactWrench(int c, int local, double sign, const Vec3& r, const ContactWrench& w,
                                   Eigen::VectorXd* Phi) const {
  const BodyEnd& e = end_[local];
  if (e.col < 0) return;
  const PairBlock& blk = blocks_[c];
  const int off = blk.offset, row = e.col;
  const int a_col = off + (sign > 0 ? pi::kA1 : pi::kA2);
  const double s = sign / force_scale_;
  Phi->segment<3>(row) -= s * w.F;
  Phi->segment<3>(row + 3) -= s * (r.cross(w.F) + w.lr * w.n);
  if (!WantJacobian()) return;
  const Mat3 rx = Skew(r), Fx = Skew(w.F);
  const double moving = w.fixed_frame ? 0.0 : 1.0;  // a fixed frame emits the same entries, as zeros
  AddJ(row, off + pi::kN, Mat3(-(moving * s * w.dF_dn)));
  AddJ(row, blk.ln(), Vec3(-(s * w.dF_dln)));
  AddJ(row, off + pi::kSt, Vec3(-(s * w.dF_dst)));
  AddJ(row, off + pi::kSo, Vec3(-(s * w.dF_dso)));
  AddJ(row + 3, a_col, Mat3(moving * s * Fx));         // d(r x F)/da = -[F]x
  AddJ(row + 3, e.col, Mat3(-(moving * s * h_ * Fx)));  // r = a - p0 - h v
  AddJ(row + 3, off + pi::kN, Mat3(-(moving * s * (rx * w.dF_dn + w.lr * Mat3::Identity()))));
  AddJ(row + 3, blk.ln(), Vec3(-(s * (rx * w.dF_dln + w.dlr_dln * w.n))));
  AddJ(row + 3, off + pi::kSt, Vec3(-(s * rx * w.dF_dst)));
  AddJ(row + 3, off + pi::kSo, Vec3(-(s * rx * w.dF_dso)));
  AddJ(row + 3, off + pi::kSr, Vec3(-(s * w.dlr_dsr * w.n)));
}

void StepProblem::AddPair(int c, const Eigen::VectorXd& z, Eigen::VectorXd* Phi) const {
  const ContactPair& pair = model_.pairs[blocks_[c].pair];
  const FrictionParams& fr = pair.friction;
  const PairBlock& blk = blocks_[c];
  const int off = blk.offset;
  const Vec3 a1 = z.segment<3>(off + pi::kA1), a2 = z.segment<3>(off + pi::kA2), n = z.segment<3>(off + pi::kN);
  const double d = z[off + pi::kD], st = z[off + pi::kSt], so = z[off + pi::kSo], sr = z[off + pi::kSr];
  const double ln = z[blk.ln()], sigma = z[blk.sigma()];
  const BodyEnd& e1 = end_[blk.body1];
  const BodyEnd& e2 = end_[blk.body2];
  const Vec3 r1 = a1 - e1.p, r2 = a2 - e2.p;
  const Mat3 I3 = Mat3::Identity();
  const bool want_J = WantJacobian();
  auto add = [this, want_J](int row, int col, const auto& block) {
    if (want_J) AddJ(row, col, block);
  };
  auto add1 = [this, want_J](int row, int col, double value) {
    if (want_J) AddJ(row, col, value);
  };

  // a1 - a2 - d n = 0 (the closest points are d apart along n).
  Phi->segment<3>(off) = a1 - a2 - d * n;
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
  };
  const Side sides[2] = {{blk.body2, off + 3, off + pi::kA2, blk.beta(), blk.k2, 1.0, a2, r2, &e2},
                         {blk.body1, off + 6, off + pi::kA1, off + pi::kAlpha, blk.k1, -1.0, a1, r1, &e1}};
  for (const Side& side : sides) {
    Phi->segment<3>(side.rows) = side.n_sign * n;
    add(side.rows, off + pi::kN, side.n_sign * I3);
    for (int k = 0; k < side.count; ++k) {
      const Eval ev = EvaluateInequality(side.body, k, side.a);
      const double mult = z[side.mult_col + k];
      Phi->segment<3>(side.rows) -= mult * ev.g;
      add(side.rows, side.mult_col + k, -ev.g);
      add(side.rows, side.a_col, -mult * ev.H);
      const FB fb = FischerBurmeister(mult, -ev.f, eval_.mode.smoothing, eval_.mode.raw);
      const int fb_row = side.mult_col + k;
      (*Phi)[fb_row] = fb.value;
      add1(fb_row, side.mult_col + k, fb.da);
      add(fb_row, side.a_col, Eigen::RowVector3d(-fb.db * ev.g.transpose()));
      if (side.e->col >= 0) {  // the body moves: f and grad f depend on its end pose
        const Mat3& dth = side.e->dtheta_dw;
        add(side.rows, side.e->col, mult * h_ * ev.H);
        add(side.rows, side.e->col + 3, Mat3(-mult * (ev.H * Skew(side.r) - Skew(ev.g)) * dth));
        add(fb_row, side.e->col, Eigen::RowVector3d(fb.db * h_ * ev.g.transpose()));
        add(fb_row, side.e->col + 3, Eigen::RowVector3d(fb.db * side.r.cross(ev.g).transpose() * dth));
      }
    }
  }

  // |n|^2 = 1.
  (*Phi)[off + 9] = 0.5 * (n.squaredNorm() - 1.0);
  add(off + 9, off + pi::kN, Eigen::RowVector3d(n.transpose()));

  // Friction (paper eq. 10 with its typo fixed, divided by mu e ln): with the friction forces written as fractions of
  // the friction ellipsoid, lt = mu e_t ln s_t (and s_o, s_r alike), the rows e_t (t.v_rel) + s_t sigma = 0,
  // e_o (o.v_rel) + s_o sigma = 0, e_r (n.w_rel) + s_r sigma = 0 stay regular when ln = 0 (a separated contact).
  Vec3 t, o;
  Mat3 dt_dn, do_dn;
  TangentBasis(n, tangent_axis_[c], &t, &o, &dt_dn, &do_dn);
  const Vec3 v_rel = RelativeVelocity(e1.v, e1.w, r1, e2.v, e2.w, r2);
  const Vec3 w_rel = e1.w - e2.w;
  // RATTLE stage 1 with a start frame (n0, t0, o0 and the levers r1_0, r2_0 of the start-of-step closest points):
  // the impulse acts along it, and the slip is measured on the average of the start and end frames,
  // u_bar = 1/2 (W(q0) + W(q1))^T nu (doc/method.md, "The second-order step"). end_weight is the end frame's share.
  const bool start_frame = stage_ == StepStage::kPosition && use_start_frame_[c];
  const double end_weight = start_frame ? 0.5 : 1.0;
  Vec3 n0 = n, t0 = t, o0 = o, r1_0 = r1, r2_0 = r2;
  if (start_frame) {
    n0 = frame_z_.segment<3>(off + pi::kN);
    Mat3 unused1, unused2;
    TangentBasis(n0, tangent_axis_[c], &t0, &o0, &unused1, &unused2);
    r1_0 = frame_z_.segment<3>(off + pi::kA1) - start_[blk.body1].p0;
    r2_0 = frame_z_.segment<3>(off + pi::kA2) - start_[blk.body2].p0;
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
      add(row, side.e->col, Eigen::RowVector3d(s * u.transpose() * (I3 - h_ * Skew(side.e->w)) + s0 * u0.transpose()));
      add(row, side.e->col + 3, Eigen::RowVector3d(-s * u.transpose() * Skew(side.r) - s0 * u0.transpose() * Skew(r0[i])));
    }
  };
  // At a separated contact (d > 0, so ln = 0) the friction fractions are physically void, and with no slip
  // (sigma = 0) nothing would determine them: the Jacobian is singular wherever two bodies rest near each other
  // without touching. The LM step of the dense solver copes; for the sparse LU the rows use sigma + max(d, 0) / h in
  // place of sigma (set_regular_separated_friction), which fixes s at a separated contact and is exactly the paper's
  // row at a touching one (d = 0).
  // With NcpEvalMode::project_multipliers the rows take the slip speed as max(sigma, 0), equal at every solution: a
  // negative iterate would make friction push along the slip (the wrong branch, between which and the right one
  // Newton then alternates in a landing pile) or, at sigma = -d / h, leave s undetermined.
  const bool clamp = eval_.mode.project_multipliers && !eval_.mode.raw && sigma < 0.0;
  const double slip = clamp ? 0.0 : sigma;
  const double dslip_dsigma = clamp ? 0.0 : 1.0;
  const double sigma_eff = regular_separated_friction_ ? slip + std::max(d, 0.0) / h_ : slip;
  const double dsigma_dd = regular_separated_friction_ && d > 0.0 ? 1.0 / h_ : 0.0;
  const int rt = off + 10, ro = off + 11, rr = off + 12;
  (*Phi)[rt] = fr.e_t * slip_t + st * sigma_eff;
  (*Phi)[ro] = fr.e_o * slip_o + so * sigma_eff;
  (*Phi)[rr] = fr.e_r * n_bar.dot(w_rel) + sr * sigma_eff;
  // The proximal rung's term (ncp_problem.h) on the friction rows, weight cp in m/s per unit of s.
  const double cp = eval_.mode.raw ? 0.0 : eval_.mode.proximal_weight;
  if (cp > 0.0) {
    const Eigen::VectorXd& center = *eval_.mode.proximal_center;
    (*Phi)[rt] += cp * (st - center[off + pi::kSt]);
    (*Phi)[ro] += cp * (so - center[off + pi::kSo]);
    (*Phi)[rr] += cp * (sr - center[off + pi::kSr]);
  }
  if (want_J) {
    add(rt, off + pi::kN, Eigen::RowVector3d(end_weight * fr.e_t * v_rel.transpose() * dt_dn));
    add(ro, off + pi::kN, Eigen::RowVector3d(end_weight * fr.e_o * v_rel.transpose() * do_dn));
    add(rr, off + pi::kN, Eigen::RowVector3d(end_weight * fr.e_r * w_rel.transpose()));
    add_rel_velocity(rt, end_weight * fr.e_t, t, start_weight * fr.e_t, t0);
    add_rel_velocity(ro, end_weight * fr.e_o, o, start_weight * fr.e_o, o0);
    if (e1.col >= 0) add(rr, e1.col + 3, Eigen::RowVector3d(fr.e_r * n_bar.transpose()));
    if (e2.col >= 0) add(rr, e2.col + 3, Eigen::RowVector3d(-fr.e_r * n_bar.transpose()));
    // The diagonal entries carry the sparse solver's proximal regularization (never Phi).
    add1(rt, off + pi::kSt, sigma_eff + eval_.mode.regularization + cp);
    add1(ro, off + pi::kSo, sigma_eff + eval_.mode.regularization + cp);
    add1(rr, off + pi::kSr, sigma_eff + eval_.mode.regularization + cp);
    add1(rt, blk.sigma(), st * dslip_dsigma);
    add1(ro, blk.sigma(), so * dslip_dsigma);
    add1(rr, blk.sigma(), sr * dslip_dsigma);
    add1(rt, off + pi::kD, st * dsigma_dd);
    add1(ro, off + pi::kD, so * dsigma_dd);
    add1(rr, off + pi::kD, sr * dsigma_dd);
  }

  // Non-penetration (paper eq. 11 with the signed distance d as gap): ln / Fs _|_ d.
  // With the proximal term the gap side reads d + cp h (ln - ln_c) / Fs (a velocity weight times the step: metres).
  const double Fs = force_scale_;
  const double proximal_gap = cp > 0.0 ? cp * h_ * (ln - (*eval_.mode.proximal_center)[blk.ln()]) / Fs : 0.0;
  const FB fb_n = FischerBurmeister(ln / Fs, d + proximal_gap, eval_.mode.smoothing, eval_.mode.raw);
  (*Phi)[blk.ln()] = fb_n.value;
  add1(blk.ln(), blk.ln(), (fb_n.da + eval_.mode.regularization + fb_n.db * cp * h_) / Fs);
  add1(blk.ln(), off + pi::kD, fb_n.db);

  // Friction ellipsoid (paper eq. 5 divided by (mu ln)^2): sigma _|_ 1 - s_t^2 - s_o^2 - s_r^2.
  const FB fb_s = FischerBurmeister(sigma, 1.0 - st * st - so * so - sr * sr, eval_.mode.smoothing, eval_.mode.raw);
  (*Phi)[blk.sigma()] = fb_s.value;
  add1(blk.sigma(), blk.sigma(), fb_s.da);
  add1(blk.sigma(), off + pi::kSt, -2.0 * fb_s.db * st);
  add1(blk.sigma(), off + pi::kSo, -2.0 * fb_s.db * so);
  add1(blk.sigma(), off + pi::kSr, -2.0 * fb_s.db * sr);

  // The contact wrench on both bodies (paper eq. 1: W_n p_n + W_t p_t + W_o p_o + W_r p_r), with
  // lt = mu e_t ln s_t, lo = mu e_o ln s_o, lr = mu e_r ln s_r.
  // In RATTLE stage 1 with a start frame, along n0, t0, o0 at the start levers (no derivative by n, a or v).
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
  AddContactWrench(c, blk.body1, +1.0, r1_0, w, Phi);
  AddContactWrench(c, blk.body2, -1.0, r2_0, w, Phi);
}

void StepProblem::Contacts(const Eigen::VectorXd& z, std::vector<ContactResult>* contacts) const {
  UpdateBodies(z);
  contacts->resize(blocks_.size());
  for (size_t c = 0; c < blocks_.size(); ++c) {
    const ContactPair& pair = model_.pairs[blocks_[c].pair];
    const PairBlock& blk = blocks_[c];
    const int off = blk.offset;
    ContactResult& out = (*contacts)[c];
    out.pair = blk.pair;
    out.p_WA1 = z.segment<3>(off + pi::kA1);
    out.p_WA2 = z.segment<3>(off + pi::kA2);
    out.n_W = z.segment<3>(off + pi::kN);
    out.gap = z[off + pi::kD];
    out.normal_force = z[blk.ln()];
    Vec3 t, o;
    Mat3 dt_dn, do_dn;
    TangentBasis(out.n_W, tangent_axis_[c], &t, &o, &dt_dn, &do_dn);
    const FrictionParams& fr = pair.friction;
    const double mu_ln = fr.mu * out.normal_force;
    out.friction_force_W = mu_ln * (fr.e_t * z[off + pi::kSt] * t + fr.e_o * z[off + pi::kSo] * o);
    out.torsional_moment = mu_ln * fr.e_r * z[off + pi::kSr];
    const BodyEnd& e1 = end_[blk.body1];
    const BodyEnd& e2 = end_[blk.body2];
    const Vec3 v_rel = RelativeVelocity(e1.v, e1.w, out.p_WA1 - e1.p, e2.v, e2.w, out.p_WA2 - e2.p);
    out.slip_speed = (v_rel - v_rel.dot(out.n_W) * out.n_W).norm();
  }
}

}  // namespace implicit_sim
