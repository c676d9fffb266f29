// The mixed nonlinear complementarity problem of one geometrically implicit step (paper eq. 10-11 and Appendix
// eq. 19-22), in the normal-distance form of doc/method.md (pitfall 1), reformulated with the Fischer-Burmeister function.
//
// A problem holds a set of moving bodies (an island, step/islands.h; by default every moving body of the model) and the
// joints and pairs among them. Unknowns z (everything at the END of the step):
//   per moving body of the problem (the i-th of slots()): nu = (v_WB, w_WB), 6 values, at z[6i] (for the whole model
//   that is z[Model::v_offset(k)] for slot k).
//   per model joint j, a block at joint_offset(j) (see AddJointRows in step_joints.cpp and joints.h):
//     lambda (num_equalities)  multipliers of the joint equalities (N for linear rows, N m for angular rows)
//     l_lo, l_hi              limit multipliers (N m or N), if the joint is limited
//     s_f, sigma_f            friction as a fraction of the Coulomb limit, and the joint's slip speed, if friction > 0
//     u                       the drive effort (N m or N), if the joint is driven (SetDrivenJoints; step_drives.cpp)
//   per contact pair c, a block at offset(c):
//     a1 (3), a2 (3)     closest points on body 1 and body 2, world frame (m)
//     n (3)              unit normal from body 2 towards body 1
//     d                  signed distance along n: a1 - a2 = d n (m); d >= 0 means no interpenetration
//     s_t, s_o, s_r      friction as fractions of the friction ellipsoid: force along t = mu e_t ln s_t (N), along o
//                        = mu e_o ln s_o (N), torsional moment about n = mu e_r ln s_r (N m)
//     alpha (K1)         multipliers of body 1's inequalities: -n = sum alpha_i grad f_i(a1)
//     beta (K2)          multipliers of body 2's inequalities:  n = sum beta_j grad g_j(a2)
//     ln                 normal force (N)
//     sigma              slip multiplier (m/s): the generalized slip speed at a sliding contact
// Equations (rows), scaled so that each is O(1) with the force scale Fs of the model:
//   body rows     m (v - v0)/h - f_app - sum W lambda = 0 and (I_W(R1) w - I_W(R0) w0)/h - tau_app - sum ... = 0,
//                 divided by Fs (paper eq. 1 in impulse form / h; the angular row in momentum form, see AddBodyRows)
//   pair rows     a1 - a2 - d n = 0;  n - sum beta grad g = 0;  -n - sum alpha grad f = 0;  (n.n - 1)/2 = 0
//                 friction (paper eq. 10 with its typo fixed, divided by mu e ln so that it stays regular at ln = 0):
//                   e_t (t.v_rel) + s_t sigma = 0,  e_o (o.v_rel) + s_o sigma = 0,  e_r (n.w_rel) + s_r sigma = 0
//                 complementarity (paper eq. 11 and 19), as FB(a, b) = a + b - sqrt(a^2 + b^2) = 0:
//                   alpha_i _|_ -f_i(a1),  beta_j _|_ -g_j(a2),  ln / Fs _|_ d,  sigma _|_ zeta,
//                   zeta = 1 - s_t^2 - s_o^2 - s_r^2 (the friction ellipsoid of eq. 5 divided by (mu ln)^2)
// Why the normalized friction unknowns (an improvement on the paper's p_t, p_o, p_r): with forces as unknowns a
// separated contact (ln = 0) leaves sigma and the friction forces undetermined and Newton converges only linearly
// there (doc/method.md, pitfall 2). With fractions, sigma equals the generalized slip speed even at a separated
// contact and every friction row keeps a regular Jacobian; for ln > 0 the two forms are equivalent.
// Body 1 and body 2 are at their end-of-step poses p = p0 + h v, R = Exp(h w) R0 (paper eq. 2), so every
// geometric quantity depends on nu: that is what makes the step geometrically implicit.
#pragma once

#include <array>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include "implicit_sim/core/model/joints.h"
#include "implicit_sim/core/model/model.h"
#include "implicit_sim/core/model/state.h"
#include "implicit_sim/core/ncp/ncp_problem.h"

namespace implicit_sim {

// Indices inside one pair block (see above).
namespace pair_index {
constexpr int kA1 = 0, kA2 = 3, kN = 6, kD = 9, kSt = 10, kSo = 11, kSr = 12, kAlpha = 13;
}

struct PairBlock {
  int pair = -1;    // the model pair
  int offset = 0;   // index of the block in z and in the rows
  int body1 = -1;   // the pair's bodies as indices into the problem's bodies (StepProblem::bodies())
  int body2 = -1;
  int k1 = 0;       // number of inequalities of body 1
  int k2 = 0;       // number of inequalities of body 2
  int size() const { return 13 + k1 + k2 + 2; }
  int beta() const { return offset + pair_index::kAlpha + k1; }
  int ln() const { return offset + pair_index::kAlpha + k1 + k2; }
  int sigma() const { return ln() + 1; }
};

struct ContactResult;  // step/data.h

// The stage of a step the problem states (StepperOptions::scheme; doc/method.md, "The second-order step"):
//   kWhole     the paper's step: impulses, levers and inertia at the END of the step (first order);
//   kPosition  stage 1 of the RATTLE step: the same unknowns, rows at half impulses (m (v_half - v0) / h = f / 2 + ...),
//              the contact impulse along the START-of-step frame, the slip on the average of the start and end frames,
//              the Lie-group variational rotation row; the closest points and the gap stay at the END of the step;
//   kVelocity  stage 2: the velocities at the fixed end-of-step geometry of stage 1 (BeginVelocityStage). A pair block
//              holds its frozen closest-point unknowns (rows z - z_stage1 = 0) and, in the ln, s_t, s_o, s_r, sigma
//              slots, the TOTAL normal force, friction fractions and slip speed of the step; joint blocks hold the
//              stage-2 equality multipliers and the total limit and friction unknowns.
enum class StepStage { kWhole = 0, kPosition = 1, kVelocity = 2 };

class StepProblem final : public NcpProblem {
 public:
  // Every moving body and joint of the model; with all_pairs every model pair too, otherwise none until SetActivePairs.
  // With all_bodies false: no moving body, joint or pair until SetBodies (an island's problem: building one of the
  // whole model for each of N islands would cost O(N^2) at the first step).
  explicit StepProblem(const Model& model, bool all_pairs = true, bool all_bodies = true);

  // Restricts the problem to the moving bodies of `slots` (velocity slots, ascending) and the joints `joints` (model
  // joint indices, ascending, each between bodies of `slots` or the world and fixed bodies), with no pair; the pairs
  // follow by SetActivePairs (each with at least one body in `slots`, the other in `slots` or fixed).
  void SetBodies(const std::vector<int>& slots, const std::vector<int>& joints);
  // The moving bodies of the problem (velocity slots, ascending: the i-th has its velocities at z[6i]), its joints.
  const std::vector<int>& slots() const { return slots_; }
  const std::vector<int>& joints() const { return joints_; }
  // The bodies the problem knows (model body indices, ascending): its moving bodies and every fixed body.
  const std::vector<int>& bodies() const { return bodies_; }
  // Where the velocities of model body b are in z (-1 if b is fixed or not in the problem).
  int body_column(int body) const;

  int size() const override { return size_; }
  // Unknowns before the first pair block: the body velocities and the joint blocks.
  int pair_base() const { return pair_base_; }
  int joint_offset(int joint) const { return joint_offset_[joint]; }  // -1 when the joint is not in the problem
  int joint_size(int joint) const { return model_.joints[joint].size() + driven_[joint]; }
  const std::vector<PairBlock>& blocks() const { return blocks_; }
  // The model pairs in the problem, in block order (ascending).
  void ActivePairs(std::vector<int>* pairs) const;
  // Replaces the pairs in the problem by `pairs` (model pair indices, ascending). If z_old is given (laid out for
  // the previous pairs), *z_new receives its body part and the blocks of the pairs that stay, with their tangent axes;
  // the blocks of new pairs are zero and their indices (into blocks()) are listed in *new_blocks.
  void SetActivePairs(const std::vector<int>& pairs, const Eigen::VectorXd* z_old, Eigen::VectorXd* z_new,
                      std::vector<int>* new_blocks);
  // Changes whenever the layout or the stage (and so the sparsity pattern of the Jacobian) changes.
  int pattern_version() const override { return 3 * pattern_version_ + static_cast<int>(stage_); }

  // --- joint drives (joints.h, JointDrive; implemented in step_drives.cpp) ---
  // Which joints carry a drive unknown, per model joint (a fixed joint never does). Lays the problem out anew (a new
  // pattern_version; callers skip an unchanged set): *z_new (not z_old) receives z_old in the new layout with the pairs
  // and their tangent axes kept, a newly driven joint's effort 0 (zero everywhere without z_old).
  void SetDrivenJoints(const std::vector<char>& driven, const Eigen::VectorXd* z_old, Eigen::VectorXd* z_new);
  const std::vector<char>& driven_joints() const { return driven_; }
  // The drives the rows of driven joints read (one per model joint): set before evaluating, kept by pointer.
  void set_joint_drives(const std::vector<JointDrive>* drives) { drives_ = drives; }
  // The drive effort of joint j in a solution z (N m or N; 0 when not driven): in the paper's step, the effort of the
  // step; in RATTLE's stage 1, stage 1's effort; in its stage 2, the step's average of both stages.
  double JointDriveEffort(const Eigen::VectorXd& z, int joint) const;

  // --- the RATTLE step (StepStage; implemented in step_rattle.cpp) ---
  StepStage stage() const { return stage_; }
  void set_stage(StepStage stage) { stage_ = stage; }
  // Stage 1's start-of-step contact frames from z_start, a solution at the start of the step (the previous step's
  // stage 1): per block whose entry of `known` is nonzero and that is closed in z_start (touching or pushing), its
  // normal and closest points. Any other block (a new pair, an impact) uses the end-of-step frame like the paper's
  // step. Call after BeginStep.
  void SetStartFrames(const Eigen::VectorXd& z_start, const std::vector<char>& known);
  bool uses_start_frame(int block) const { return use_start_frame_[block] != 0; }
  // After a stage-1 solution z: the pairs with a start frame whose active inequalities (alpha, beta > 0) differ from
  // the start's (a vertex or face switch of a polytope) fall back to the end-of-step frame; returns how many.
  int FallBackWhereActiveSetsChanged(const Eigen::VectorXd& z);
  // Every pair on the end-of-step frame; returns how many had a start frame.
  int FallBackToEndFrames();
  // In stage 1 of a problem without pairs or joints (a body in free flight): v_half = v0 + h f / (2 m) in *z, the
  // solution of its linear rows, so that a falling body's stage 1 needs no Newton iteration for them.
  void PredictFreeFlight(Eigen::VectorXd* z) const;
  // Fixes the end-of-step geometry of the stage-1 solution z1 for stage 2 (poses, closest points, the stage-1
  // impulses, which pairs and joint limits are closed) and writes stage 2's initial guess into *z2: stage 1 repeated
  // (totals 2 x stage 1's force, the same fractions and slip, v1 = 2 v_half - v0), which Newton finishes in a few
  // iterations. raw_rows1: stage 1's raw rows at z1 (ComputeNcpError's), whose body rows correct the momenta.
  // Leaves the problem in kVelocity.
  void BeginVelocityStage(const Eigen::VectorXd& z1, const Eigen::VectorXd& raw_rows1, Eigen::VectorXd* z2);

  // Stores the start-of-step quantities (poses, velocities, world inertia) and the external wrenches
  // of the step: 6 values per moving body slot (force N, torque N m; world frame, at the centre of mass), or null.
  void BeginStep(const State& start, double h, const Eigen::VectorXd* external_wrench_W);

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

  // Warm-start predictor: translates the closest points of *z with their bodies over the step (a += h v0; not as
  // material points: a rolling sphere's contact point moves with its centre) and sets d = n . (a1 - a2), so that a
  // fast body's warm start stays near the new solution instead of a spurious one (the far sides of two spheres also
  // satisfy the normal cones).
  void PredictClosestPoints(Eigen::VectorXd* z) const;

  // Cold-start friction guess from the start-of-step relative velocity at the points in *z: sigma = the generalized
  // slip speed and s = the sliding direction (sigma = 0, s = 0 is a saddle of the merit function for a sliding or
  // separated contact).
  void SeedFriction(Eigen::VectorXd* z) const;
  void SeedFriction(int block, Eigen::VectorXd* z) const;
  // Cold-start joint unknowns: zero multipliers; joint friction seeded from the start-of-step joint velocity like
  // SeedFriction.
  void SeedJoints(Eigen::VectorXd* z) const;

  // The FB-reformulated residual Phi(z) (or the raw rows) and, if J is not null, its exact generalized Jacobian
  // (n x n), dense or sparse. NcpEvalMode::regularization goes on the Jacobian's diagonal entries of the friction
  // rows and (divided by Fs) of the normal-force rows: a proximal term for the Newton direction (semismooth_newton.h).
  void Evaluate(const Eigen::VectorXd& z, const NcpEvalMode& mode, Eigen::VectorXd* Phi,
                Eigen::MatrixXd* J) const override;
  void EvaluateSparse(const Eigen::VectorXd& z, const NcpEvalMode& mode, Eigen::VectorXd* Phi,
                      SparseJacobian* J) const override;
  // Raw rows: each complementarity row returns b(z), the function side of its pair (-f_i(a1), -g_j(a2), d, zeta);
  // the variable side a is the unknown with the row's own index (scaled by 1/Fs for the normal force).
  bool IsComplementarityRow(int row, double* scale) const override;
  // One block per pair: its closest-point unknowns a1, a2, n, d, alpha, beta, whose rows touch only themselves and
  // the velocities of the pair's bodies.
  void CondensableBlocks(std::vector<int>* starts, std::vector<int>* indices) const override;
  // Friction rows with sigma + max(d, 0) / h in place of sigma (see AddPair); off by default. Keeps the Newton matrix
  // regular at separated pairs; fixed for the life of the problem (Data turns it on).
  void set_regular_separated_friction(bool on) { regular_separated_friction_ = on; }

  // The contact quantities of every pair in the problem for a solution z (one entry per block, in block order).
  void Contacts(const Eigen::VectorXd& z, std::vector<ContactResult>* out) const;

  // The joint limit effort l_lo - l_hi of joint j in a solution z (N m or N, positive towards increasing position; 0
  // for a joint without limits): the step-average effort the limit exerted.
  double JointLimitEffort(const Eigen::VectorXd& z, int joint) const;

  // End-of-step pose of model body b (one of bodies()) for velocities in z.
  Pose EndPose(int body, const Eigen::VectorXd& z) const;

  double force_scale() const { return force_scale_; }

 private:
  struct BodyStep {   // per body, for the current step
    Vec3 p0 = Vec3::Zero();
    Mat3 R0 = Mat3::Identity();
    Vec3 v0 = Vec3::Zero(), w0 = Vec3::Zero();
    Mat3 I_W0 = Mat3::Zero();       // world inertia at the start of the step (kg m^2)
  };
  struct BodyEnd {    // per body, for the current iterate
    Vec3 p = Vec3::Zero();
    Mat3 R = Mat3::Identity();
    Vec3 v = Vec3::Zero(), w = Vec3::Zero();
    Mat3 dtheta_dw = Mat3::Zero();  // h J_l(h w): rotation increment per change of w
    int col = -1;                   // column of v in z (w at col + 3), -1 when fixed
  };
  struct Eval {       // one inequality evaluated at a world point
    double f;
    Vec3 g;           // world gradient
    Mat3 H;           // world Hessian
  };

  void UpdateBodies(const Eigen::VectorXd& z) const;
  // The constant external force (N) and torque (N m) on the i-th moving body of the problem over the step: gravity,
  // the model's applied wrench and BeginStep's external wrench (world frame, at the centre of mass).
  Vec3 ExternalForce(int i) const {
    const Body& body = model_.bodies[bodies_[slot_body_[i]]];
    return body.mass * model_.gravity_W + body.f_applied_W + external_wrench_W_.segment<3>(6 * i);
  }
  Vec3 ExternalTorque(int i) const {
    return model_.bodies[bodies_[slot_body_[i]]].tau_applied_W + external_wrench_W_.segment<3>(6 * i + 3);
  }
  // Stage 1's rotation row: the discrete angular momentum (1/h) R0 vee(F Jd - Jd F^T) / sinc(h |w|), F = R0^T R1 =
  // Exp(h R0^T w), of a body with body inertia I_B (step_rattle.cpp), and its derivatives with respect to the
  // end-of-step rotation increment theta (R1 -> Exp(theta) R1) at fixed w and to w at fixed R1 (either may be null).
  static Vec3 DiscreteMomentum(const Mat3& I_B, const Mat3& R0, const Mat3& R1, const Vec3& w, double h,
                               Mat3* dL_dtheta, Mat3* dL_dw);
  void AddBodyRowsVelocityStage(const Eigen::VectorXd& z, Eigen::VectorXd* Phi) const;
  void AddPairVelocityStage(int c, const Eigen::VectorXd& z, Eigen::VectorXd* Phi) const;
  void AddJointRowsVelocityStage(const Eigen::VectorXd& z, Eigen::VectorXd* Phi) const;
  // The share of a constant joint effort, joint friction bound and damping in the current stage (1/2 in each RATTLE
  // stage, 1 in the paper's step).
  double stage_share() const { return stage_ == StepStage::kWhole ? 1.0 : 0.5; }
  // The index of model body b in bodies_ (-1 if absent).
  int LocalBody(int body) const;
  // `local`: an index into bodies_.
  Eval EvaluateInequality(int local, int k, const Vec3& p_W) const;
  void EvaluateAll(const Eigen::VectorXd& z, Eigen::VectorXd* Phi) const;
  void AddBodyRows(const Eigen::VectorXd& z, Eigen::VectorXd* Phi) const;
  void AddPair(int c, const Eigen::VectorXd& z, Eigen::VectorXd* Phi) const;
  void AddJointRows(const Eigen::VectorXd& z, Eigen::VectorXd* Phi) const;
  // Joint helpers (step_joints.cpp): the start-of-step gradients, the Jacobian of an end-of-step joint function, of a
  // joint rate, and a generalized joint force on the body rows.
  void BeginJoints();
  void AddEndGradientRow(int row, const JointGradient& g, const BodyEnd& eP, const BodyEnd& eC,
                         double scale) const;
  void AddRateRow(int row, const JointGradient& g, const BodyEnd& eP, const BodyEnd& eC, double scale) const;
  void AddJointForce(const JointGradient& g, double force, int col, double dforce_dcol, const BodyEnd& eP,
                     const BodyEnd& eC, Eigen::VectorXd* Phi) const;
  void AddJointLimitRows(const Joint& joint, int col, const Eigen::VectorXd& z, const BodyEnd& eP, const BodyEnd& eC,
                         const JointGradient& G_q, Eigen::VectorXd* Phi) const;
  void AddJointFrictionRows(const Joint& joint, int col, const Eigen::VectorXd& z, const BodyEnd& eP,
                            const BodyEnd& eC, const JointGradient& G_q, Eigen::VectorXd* Phi) const;
  void AddJointDamping(const Joint& joint, const BodyEnd& eP, const BodyEnd& eC, const JointGradient& G_q,
                       Eigen::VectorXd* Phi) const;
  // The drive row of joint j at row col (step_drives.cpp): stage 1 or the paper's step, and stage 2.
  void AddJointDriveRow(int j, int col, const Eigen::VectorXd& z, const BodyEnd& eP, const BodyEnd& eC,
                        const JointGradient& G_q, Eigen::VectorXd* Phi) const;
  void AddJointDriveRowVelocityStage(int j, int col, const Eigen::VectorXd& z, const BodyEnd& eP, const BodyEnd& eC,
                                     const JointGradient& G_q, Eigen::VectorXd* Phi) const;
  double DriveRowScale(const JointDrive& drive) const;
  // The joint offsets and pair_base_ for joints_ and driven_.
  void LayOutJoints();
  struct JointBodies {  // a joint's parent (-1: the world) and child as indices into bodies_
    int parent = -1, child = -1;
  };
  const BodyEnd& ParentEnd(int joint) const {
    const int parent = joint_bodies_[joint].parent;
    return parent < 0 ? world_end_ : end_[parent];
  }
  const BodyEnd& ChildEnd(int joint) const { return end_[joint_bodies_[joint].child]; }
  // Adds `block` to J at (row, col), dense or sparse (every call emits the same entries for the same layout, so that
  // the sparse pattern recorded once stays valid). Rows of locked velocities become "velocity = 0".
  template <typename Block>
  void AddJ(int row, int col, const Block& block) const;
  void AddJ(int row, int col, double value) const;
  void AddJUnlocked(int row, int col, double value) const;  // AddJ that also writes the rows of locked velocities
  bool WantJacobian() const { return eval_.J_dense || eval_.J_sparse; }
  struct ContactWrench {  // the contact force F on body 1 and the torsional moment lr about n, with derivatives
    Vec3 n, F, dF_dln, dF_dst, dF_dso;
    Mat3 dF_dn;
    double lr, dlr_dln, dlr_dsr;
    bool fixed_frame = false;  // n and the lever are constants (stage 1's start frame): no derivative by n, a or v
  };
  void AddContactWrench(int c, int local, double sign, const Vec3& r, const ContactWrench& wrench,
                        Eigen::VectorXd* Phi) const;

  const Model& model_;
  const double model_force_scale_;  // Model::ForceScale(), computed once
  std::vector<int> slots_, joints_, bodies_;
  std::vector<int> fixed_bodies_;    // the model's fixed bodies, ascending
  std::vector<int> slot_body_;       // per moving body of the problem: its index into bodies_
  std::vector<JointBodies> joint_bodies_;  // per model joint (entries of joints_ only)
  std::vector<PairBlock> blocks_;
  std::vector<BodyStep> start_;       // per entry of bodies_
  mutable std::vector<BodyEnd> end_;  // per entry of bodies_: the current iterate's end-of-step bodies (a cache)
  std::vector<Vec3> tangent_axis_;   // per pair
  std::vector<int> joint_offset_;    // per model joint (-1 when not in the problem)
  std::vector<char> driven_;         // per model joint: it carries a drive unknown (the last of its block)
  const std::vector<JointDrive>* drives_ = nullptr;  // per model joint (set_joint_drives)
  std::vector<int> old_joint_offset_, drive_pairs_, drive_new_blocks_;  // SetDrivenJoints' copies of the old layout
  std::vector<char> old_driven_;
  int pair_base_ = 0;
  // Per joint, at the start of the step: the gradients of the equalities and of the position. The joint forces act
  // along them over the step while the equalities hold at its end (the SHAKE discretization; see AddJointRows).
  std::vector<std::array<JointGradient, 6>> joint_equality_start_;
  std::vector<JointGradient> joint_position_start_;
  BodyEnd world_end_;                // the world as a parent: identity pose, no velocity unknowns
  Eigen::VectorXd external_wrench_W_;  // per moving body of the problem: force, torque (world, at the centre of mass)
  int size_ = 0;
  double h_ = 0.0;
  double force_scale_ = 1.0;
  std::vector<char> complementarity_kind_;  // per row: 0 equation, 1 complementarity, 2 normal-force complementarity
  std::vector<char> locked_row_;             // per body row: the velocity is locked
  std::vector<PairBlock> old_blocks_;        // SetActivePairs' copies of the previous layout
  std::vector<Vec3> old_axes_;
  bool regular_separated_friction_ = false;
  int pattern_version_ = 0;
  // The evaluation in progress: its mode and where it writes the Jacobian (at most one non-null; both null: none).
  struct EvalContext {
    NcpEvalMode mode;
    Eigen::MatrixXd* J_dense = nullptr;
    SparseJacobian* J_sparse = nullptr;
  };
  mutable EvalContext eval_;
  // --- the RATTLE step ---
  StepStage stage_ = StepStage::kWhole;
  std::vector<char> use_start_frame_;  // per block: stage 1 acts along the start frame
  Eigen::VectorXd frame_z_;           // the start-of-step solution the start frames come from
  // Stage 2's fixed geometry, per entry of bodies_: the end pose, v_half and the momentum of stage 1.
  struct BodyHalf {
    Vec3 p1 = Vec3::Zero();
    Mat3 R1 = Mat3::Identity();
    Vec3 v_half = Vec3::Zero(), L_half = Vec3::Zero();
  };
  std::vector<BodyHalf> half_;
  // Stage 2 per block: the stage-1 solution's block (the frozen closest points, ln, s, sigma), its force on body 1
  // and torsion vector, and whether the pair is closed at the end of stage 1.
  Eigen::VectorXd stage1_z_;
  Eigen::VectorXd stage1_rows_;  // stage 1's residual at its solution (it corrects the momenta of stage 2)
  std::vector<Vec3> stage1_force_, stage1_torsion_;
  std::vector<char> closed_;
  std::vector<char> velocity_kind_;  // complementarity_kind_ of stage 2 (closed pairs and limits only)
  std::vector<std::array<JointGradient, 6>> joint_equality_end_;  // per joint: the gradients at the end of stage 1
  std::vector<JointGradient> joint_position_end_;
  std::vector<double> joint_q_end_;  // per joint: the position at the end of stage 1 (rad or m)
  std::vector<std::array<char, 2>> limit_closed_;  // per joint: lower, upper limit closed at the end of stage 1
};

}  // namespace implicit_sim
