// The layout of a step's unknowns z (and of its rows, one per unknown): which moving bodies, joints and contact pairs a
// step problem holds, where each one's unknowns sit in z, and the friction tangent axes of its pairs (the memory that
// a warm start carries from step to step). Every problem of a step (problems/) reads the same layout.
//
// Unknowns z (everything at the END of the step; doc/method.md):
//   per moving body of the layout (the i-th of slots()): nu = (v_WB, w_WB), 6 values, at z[6i] (for the whole model
//   that is z[Model::v_offset(k)] for slot k).
//   per model joint j, a block at joint_offset(j) (rows/joint_rows.h):
//     lambda (num_equalities)  multipliers of the joint equalities (N for linear rows, N m for angular rows)
//     l_lo, l_hi              limit multipliers (N m or N), if the joint is limited
//     s_f, sigma_f            friction as a fraction of the Coulomb limit, and the joint's slip speed, if friction > 0
//     u                       the drive effort (N m or N), if the joint is driven (SetDrivenJoints; rows/drive_rows.h)
//   per contact pair c, a block at blocks()[c].offset (rows/contact_rows.h, rows/friction_rows.h):
//     a1 (3), a2 (3)     closest points on body 1 and body 2, world frame (m)
//     n (3)              unit normal from body 2 towards body 1
//     d                  signed distance along n: a1 - a2 = d n (m); d >= 0 means no interpenetration
//     s_t, s_o, s_r      friction as fractions of the friction ellipsoid: force along t = mu e_t ln s_t (N), along o
//                        = mu e_o ln s_o (N), torsional moment about n = mu e_r ln s_r (N m)
//     alpha (K1)         multipliers of body 1's inequalities: -n = sum alpha_i grad f_i(a1)
//     beta (K2)          multipliers of body 2's inequalities:  n = sum beta_j grad g_j(a2)
//     ln                 normal force (N)
//     sigma              slip multiplier (m/s): the generalized slip speed at a sliding contact
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "implicit_sim/core/model/model.h"

namespace implicit_sim {

// Indices inside one pair block (see above).
namespace pair_index {
constexpr int kA1 = 0, kA2 = 3, kN = 6, kD = 9, kSt = 10, kSo = 11, kSr = 12, kAlpha = 13;
}

struct PairBlock {
  int pair = -1;    // the model pair
  int offset = 0;   // index of the block in z and in the rows
  int body1 = -1;   // the pair's bodies as indices into the layout's bodies (StepLayout::bodies())
  int body2 = -1;
  int k1 = 0;       // number of inequalities of body 1
  int k2 = 0;       // number of inequalities of body 2
  int rolling = 0;  // 2 with rolling resistance (FrictionParams::e_roll > 0): the fractions s_q1, s_q2 after sigma
  int size() const { return 13 + k1 + k2 + 2 + rolling; }
  int beta() const { return offset + pair_index::kAlpha + k1; }
  int normal_force() const { return offset + pair_index::kAlpha + k1 + k2; }
  int sigma() const { return normal_force() + 1; }
  int roll() const { return normal_force() + 2; }  // s_q1 (about t), s_q2 (about o); only with rolling
};

// A joint's parent (-1: the world) and child as indices into StepLayout::bodies().
struct JointBodies {
  int parent = -1, child = -1;
};

// How a row's unknown enters its complementarity condition (NcpProblem::IsComplementarityRow).
enum class RowKind : char { kEquation = 0, kComplementarity = 1, kForceComplementarity = 2 /* unknown / Fs */ };

class StepLayout {
 public:
  // Every moving body and joint of the model; with all_pairs every model pair too, otherwise none until SetActivePairs.
  // With all_bodies false: no moving body, joint or pair until SetBodies (an island's layout: building one of the
  // whole model for each of N islands would cost O(N^2) at the first step).
  explicit StepLayout(const Model& model, bool all_pairs = true, bool all_bodies = true);
  const Model& model() const { return model_; }

  // Restricts the layout to the moving bodies of `slots` (velocity slots, ascending) and the joints `joints` (model
  // joint indices, ascending, each between bodies of `slots` or the world and fixed bodies), with no pair; the pairs
  // follow by SetActivePairs (each with at least one body in `slots`, the other in `slots` or fixed).
  void SetBodies(const std::vector<int>& slots, const std::vector<int>& joints);
  // The moving bodies (velocity slots, ascending: the i-th has its velocities at z[6i]) and the joints.
  const std::vector<int>& slots() const { return slots_; }
  const std::vector<int>& joints() const { return joints_; }
  // The bodies the layout knows (model body indices, ascending): its moving bodies and every fixed body.
  const std::vector<int>& bodies() const { return bodies_; }
  // The index into bodies() of model body b (-1 if absent), and of the i-th moving body.
  int LocalBody(int body) const;
  int slot_body(int i) const { return slot_body_[i]; }
  // Where the velocities of bodies()[local] are in z (-1 for a fixed body); of model body b (-1 if fixed or absent).
  int column(int local) const { return column_[local]; }
  int body_column(int body) const;
  const JointBodies& joint_bodies(int joint) const { return joint_bodies_[joint]; }

  int size() const { return size_; }
  // Unknowns before the first pair block: the body velocities and the joint blocks.
  int pair_base() const { return pair_base_; }
  int joint_offset(int joint) const { return joint_offset_[joint]; }  // -1 when the joint is not in the layout
  int joint_size(int joint) const { return model_.joints[joint].size() + driven_[joint]; }
  const std::vector<PairBlock>& blocks() const { return blocks_; }
  // The model pairs in the layout, in block order (ascending).
  void ActivePairs(std::vector<int>* pairs) const;
  // Replaces the pairs by `pairs` (model pair indices, ascending). If z_old is given (laid out for the previous
  // pairs), *z_new receives its body part and the blocks of the pairs that stay, with their tangent axes; the blocks
  // of new pairs are zero and their indices (into blocks()) are listed in *new_blocks.
  void SetActivePairs(const std::vector<int>& pairs, const Eigen::VectorXd* z_old, Eigen::VectorXd* z_new,
                      std::vector<int>* new_blocks);
  // Which joints carry a drive unknown, per model joint (a fixed joint never does). Lays z out anew: *z_new (not
  // z_old) receives z_old in the new layout with the pairs and their tangent axes kept, a newly driven joint's effort
  // 0 (zero everywhere without z_old).
  void SetDrivenJoints(const std::vector<char>& driven, const Eigen::VectorXd* z_old, Eigen::VectorXd* z_new);
  const std::vector<char>& driven_joints() const { return driven_; }
  // Changes whenever the layout (and so the sparsity pattern of every problem's Jacobian) changes.
  int pattern_version() const { return pattern_version_; }

  // Per row: how its unknown enters a complementarity condition in the paper's step (problems narrow it down).
  const std::vector<RowKind>& row_kinds() const { return row_kinds_; }
  // What row `row` of the step problem is, for traces: e.g. "body 'ball_3' w_y", "joint 'lift' 2",
  // "pair 'ball_3-floor' sigma" (the unknown of its complementarity, or its closest-point coordinate).
  std::string RowName(int row) const;
  // Per body row (the first 6 slots().size() rows): the velocity is locked (Body::locked).
  const std::vector<char>& locked_rows() const { return locked_row_; }
  // One block per pair: its closest-point unknowns a1, a2, n, d, alpha, beta (NcpProblem::CondensableBlocks).
  void CondensableBlocks(std::vector<int>* starts, std::vector<int>* indices) const;

  // The joint limit effort l_lo - l_hi of joint j in a solution z (N m or N, positive towards increasing position; 0
  // for a joint without limits), and its drive effort (0 when not driven).
  double JointLimitEffort(const Eigen::VectorXd& z, int joint) const;
  double JointDriveEffort(const Eigen::VectorXd& z, int joint) const;
  int drive_column(int joint) const { return joint_offset_[joint] + model_.joints[joint].size(); }

  // The tangent basis (t, o) of a pair is built from n and a world reference axis fixed for the whole step
  // (doc/method.md, pitfall 3). UpdateTangentAxes keeps each pair's axis while |axis . n| < 0.9 for the normal in *z and
  // otherwise switches to the world axis least aligned with n, re-expressing s_t, s_o of *z in the new basis so that
  // a warm start stays a warm start. ResetTangentAxes picks the least aligned axis for every pair.
  void UpdateTangentAxes(Eigen::VectorXd* z);
  void ResetTangentAxes(const Eigen::VectorXd& z);
  void ResetTangentAxis(int block, const Eigen::VectorXd& z);
  const std::vector<Vec3>& tangent_axes() const { return tangent_axis_; }
  void set_tangent_axes(const std::vector<Vec3>& axes) { tangent_axis_ = axes; }
  void set_tangent_axis(int block, const Vec3& axis) { tangent_axis_[block] = axis; }

 private:
  void LayOutJoints();  // the joint offsets and pair_base_ for joints_ and driven_

  const Model& model_;
  std::vector<int> slots_, joints_, bodies_;
  std::vector<int> fixed_bodies_;    // the model's fixed bodies, ascending
  std::vector<int> slot_body_;       // per moving body: its index into bodies_
  std::vector<int> column_;          // per entry of bodies_: its velocity column in z, -1 when fixed
  std::vector<JointBodies> joint_bodies_;  // per model joint (entries of joints_ only)
  std::vector<PairBlock> blocks_;
  std::vector<Vec3> tangent_axis_;   // per pair
  std::vector<int> joint_offset_;    // per model joint (-1 when not in the layout)
  std::vector<char> driven_;         // per model joint: it carries a drive unknown (the last of its block)
  std::vector<RowKind> row_kinds_;
  std::vector<char> locked_row_;
  int pair_base_ = 0;
  int size_ = 0;
  int pattern_version_ = 0;
  // Copies of the previous layout (SetActivePairs, SetDrivenJoints), kept to avoid allocating in a step.
  std::vector<PairBlock> old_blocks_;
  std::vector<Vec3> old_axes_;
  std::vector<int> old_joint_offset_, drive_pairs_, drive_new_blocks_;
  std::vector<char> old_driven_;
};

}  // namespace implicit_sim
