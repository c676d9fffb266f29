#include "implicit_sim/core/step/layout.h"

#include <algorithm>
#include <cmath>

#include "step/contact_frame.h"

namespace implicit_sim {

StepLayout::StepLayout(const Model& model, bool all_pairs, bool all_bodies) : model_(model) {
  joint_bodies_.resize(model.joints.size());
  joint_offset_.assign(model.joints.size(), -1);
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

void StepLayout::SetBodies(const std::vector<int>& slots, const std::vector<int>& joints) {
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
  column_.assign(bodies_.size(), -1);
  slot_body_.assign(slots_.size(), -1);
  locked_row_.assign(6 * slots_.size(), 0);
  for (size_t s = 0; s < slots_.size(); ++s) {
    const int b = model.moving_bodies[slots_[s]];
    const int local = LocalBody(b);
    slot_body_[s] = local;
    column_[local] = static_cast<int>(6 * s);
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

void StepLayout::LayOutJoints() {
  pair_base_ = static_cast<int>(6 * slots_.size());
  std::fill(joint_offset_.begin(), joint_offset_.end(), -1);
  for (int j : joints_) {
    joint_offset_[j] = pair_base_;
    pair_base_ += joint_size(j);
  }
}

int StepLayout::LocalBody(int body) const {
  const auto it = std::lower_bound(bodies_.begin(), bodies_.end(), body);
  return it != bodies_.end() && *it == body ? static_cast<int>(it - bodies_.begin()) : -1;
}

int StepLayout::body_column(int body) const {
  const int local = LocalBody(body);
  return local < 0 ? -1 : column_[local];
}

void StepLayout::SetActivePairs(const std::vector<int>& pairs, const Eigen::VectorXd* z_old, Eigen::VectorXd* z_new,
                                std::vector<int>* new_blocks) {
  old_blocks_ = blocks_;
  old_axes_ = tangent_axis_;
  blocks_.clear();
  size_ = pair_base_;
  for (int pair : pairs) {
    PairBlock block;
    block.pair = pair;
    block.offset = size_;
    block.k1 = static_cast<int>(model_.shape(model_.pairs[pair].geom1).inequalities.size());
    block.k2 = static_cast<int>(model_.shape(model_.pairs[pair].geom2).inequalities.size());
    block.rolling = model_.pairs[pair].friction.e_roll > 0.0 ? 2 : 0;
    block.body1 = LocalBody(model_.pairs[pair].body1);
    block.body2 = LocalBody(model_.pairs[pair].body2);
    blocks_.push_back(block);
    size_ += block.size();
  }
  tangent_axis_.assign(blocks_.size(), Vec3::UnitX());
  row_kinds_.assign(size_, RowKind::kEquation);
  for (int j : joints_) {
    const Joint& joint = model_.joints[j];
    const int o = joint_offset_[j], extra = o + joint.num_equalities();
    if (joint.limited) row_kinds_[extra] = row_kinds_[extra + 1] = RowKind::kForceComplementarity;  // l / Fs _|_ gap
    if (joint.friction > 0.0) row_kinds_[o + joint.friction_column() + 1] = RowKind::kComplementarity;  // sigma_f
    if (joint.velocity_limited) {  // u / Fs _|_ v_max -+ qdot
      row_kinds_[o + joint.velocity_limit_column()] = row_kinds_[o + joint.velocity_limit_column() + 1] =
          RowKind::kForceComplementarity;
    }
  }
  for (const PairBlock& blk : blocks_) {
    for (int i = blk.offset + pair_index::kAlpha; i <= blk.sigma(); ++i) {
      row_kinds_[i] = RowKind::kComplementarity;
    }
    row_kinds_[blk.normal_force()] = RowKind::kForceComplementarity;  // the normal force enters as ln / Fs
  }
  ++pattern_version_;
  // Carry the old solution over: the body part, and the blocks of the pairs that stay (both lists are ascending).
  z_new->setZero(size_);
  new_blocks->clear();
  if (z_old) z_new->head(pair_base_) = z_old->head(pair_base_);
  size_t o = 0;
  for (size_t c = 0; c < blocks_.size(); ++c) {
    while (o < old_blocks_.size() && old_blocks_[o].pair < blocks_[c].pair) ++o;
    if (z_old && o < old_blocks_.size() && old_blocks_[o].pair == blocks_[c].pair) {
      z_new->segment(blocks_[c].offset, blocks_[c].size()) = z_old->segment(old_blocks_[o].offset, blocks_[c].size());
      tangent_axis_[c] = old_axes_[o];
    } else {
      new_blocks->push_back(static_cast<int>(c));
    }
  }
}

void StepLayout::ActivePairs(std::vector<int>* pairs) const {
  pairs->clear();
  for (const PairBlock& blk : blocks_) pairs->push_back(blk.pair);
}

void StepLayout::SetDrivenJoints(const std::vector<char>& driven, const Eigen::VectorXd* z_old,
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

void StepLayout::CondensableBlocks(std::vector<int>* starts, std::vector<int>* indices) const {
  starts->assign(1, 0);
  indices->clear();
  for (const PairBlock& block : blocks_) {
    for (int k = pair_index::kA1; k <= pair_index::kD; ++k) indices->push_back(block.offset + k);
    for (int k = 0; k < block.k1 + block.k2; ++k) indices->push_back(block.offset + pair_index::kAlpha + k);
    starts->push_back(static_cast<int>(indices->size()));
  }
}

double StepLayout::JointLimitEffort(const Eigen::VectorXd& z, int j) const {
  const Joint& joint = model_.joints[j];
  if (!joint.limited) return 0.0;
  const int col = joint_offset_[j] + joint.num_equalities();
  return z[col] - z[col + 1];
}

double StepLayout::JointDriveEffort(const Eigen::VectorXd& z, int joint) const {
  return driven_[joint] ? z[drive_column(joint)] : 0.0;
}

void StepLayout::ResetTangentAxes(const Eigen::VectorXd& z) {
  for (size_t c = 0; c < blocks_.size(); ++c) ResetTangentAxis(static_cast<int>(c), z);
}

void StepLayout::ResetTangentAxis(int c, const Eigen::VectorXd& z) {
  tangent_axis_[c] = LeastAlignedAxis(z.segment<3>(blocks_[c].offset + pair_index::kN));
}

void StepLayout::UpdateTangentAxes(Eigen::VectorXd* z) {
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
    const int roll = blocks_[c].roll();
    const Vec3 roll_dir = blocks_[c].rolling ? Vec3((*z)[roll] * t + (*z)[roll + 1] * o) : Vec3::Zero();
    tangent_axis_[c] = LeastAlignedAxis(n);
    TangentBasis(n, tangent_axis_[c], &t, &o, &dt_dn, &do_dn);
    (*z)[off + pair_index::kSt] = fr.e_t * slip_dir.dot(t);
    (*z)[off + pair_index::kSo] = fr.e_o * slip_dir.dot(o);
    if (blocks_[c].rolling) {
      (*z)[roll] = roll_dir.dot(t);
      (*z)[roll + 1] = roll_dir.dot(o);
    }
  }
}

std::string StepLayout::RowName(int row) const {
  if (row < 0 || row >= size_) return "row " + std::to_string(row) + " (outside the layout)";
  if (row < 6 * static_cast<int>(slots_.size())) {
    static const char* const kAxes[6] = {"v_x", "v_y", "v_z", "w_x", "w_y", "w_z"};
    return "body '" + model_.bodies[model_.moving_bodies[slots_[row / 6]]].name + "' " + kAxes[row % 6];
  }
  if (row < pair_base_) {
    for (int j : joints_) {
      if (row >= joint_offset_[j] && row < joint_offset_[j] + joint_size(j)) {
        return "joint '" + model_.joints[j].name + "' " + std::to_string(row - joint_offset_[j]);
      }
    }
  }
  for (const PairBlock& blk : blocks_) {
    if (row < blk.offset || row >= blk.offset + blk.size()) continue;
    using namespace pair_index;
    const int i = row - blk.offset;
    std::string what;
    if (i < kN) what = (i < kA2 ? "a1_" : "a2_") + std::string(1, "xyz"[i % 3]);
    else if (i < kD) what = std::string("n_") + "xyz"[i - kN];
    else if (i == kD) what = "d";
    else if (i < kAlpha) what = i == kSt ? "s_t" : i == kSo ? "s_o" : "s_r";
    else if (row < blk.beta()) what = "alpha " + std::to_string(row - blk.offset - kAlpha);
    else if (row < blk.normal_force()) what = "beta " + std::to_string(row - blk.beta());
    else if (row == blk.normal_force()) what = "ln";
    else if (row == blk.sigma()) what = "sigma";
    else what = row == blk.roll() ? "s_q1" : "s_q2";
    return "pair '" + model_.PairName(blk.pair) + "' " + what;
  }
  return "row " + std::to_string(row);
}

}  // namespace implicit_sim
