// Data(model): everything a step derives from the Model and the State, and the solver workspace, allocated once
// (MuJoCo's mjData, Pinocchio's Data). A Data belongs to the Model it was built from: Step checks that, and the Model
// must outlive it. Also the contact results of a step and the warm start (save, restore, clear).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "implicit_sim/core/base/interrupt.h"
#include "implicit_sim/core/base/thread_pool.h"
#include "implicit_sim/core/geometry/broad_phase.h"
#include "implicit_sim/core/model/joints.h"
#include "implicit_sim/core/model/model.h"
#include "implicit_sim/core/model/state.h"
#include "implicit_sim/core/step/block_predictor.h"
#include "implicit_sim/core/step/contact_result.h"
#include "implicit_sim/core/step/kinematics.h"
#include "implicit_sim/core/step/layout.h"
#include "implicit_sim/core/step/options.h"
#include "implicit_sim/core/step/schemes/island_scheme.h"
#include "implicit_sim/core/step/step_report.h"

namespace implicit_sim {

// One island's solve (step/islands.h): the moving bodies joined by pairs in the NCP or by joints, with their joints and
// pairs, as a layout of its own with its own scheme (its problems and solvers), warm start, retry ladder and sub-steps.
struct IslandSolve {
  // drives: Data::joint_drives, read by the problems of the island's scheme.
  IslandSolve(const Model& model, const std::vector<JointDrive>& drives);
  ~IslandSolve();
  // --- membership (ascending): velocity slots, model joints, model pairs and their blocks in Data::layout ---
  std::vector<int> slots, joints, pairs, blocks;
  std::vector<int> next_slots, next_joints, next_pairs, new_blocks;  // PartitionIslands' workspace
  // --- the island's layout, the kinematics of its step, and its scheme (built for StepperOptions::scheme) ---
  StepLayout layout;
  StepKinematics kinematics;
  const std::vector<JointDrive>& drives;
  std::unique_ptr<IslandScheme> scheme;
  // The scheme for options.scheme (built anew only when the scheme changes).
  IslandScheme& SchemeFor(const StepperOptions& options);
  BlockPredictor predictor;  // StepperOptions::predictor_sweeps
  // --- the warm start (gathered from Data::z) and the workspace of the island's retry ladder and sub-steps ---
  bool has_warm_start = false;
  Eigen::VectorXd z;               // the solution of the pose problem (the warm start of the next solve)
  Eigen::VectorXd z_start;         // the initial guess of the current solve
  Eigen::VectorXd z_best;          // the best iterate of the ladder so far
  Eigen::VectorXd z_center;        // the proximal rung's centre
  Eigen::VectorXd z_cold;          // the cold attempt's end, kept across the proximal rung for the continuation
  Eigen::VectorXd ncp_error_rows;  // the raw rows of the accepted solution (ncp_error.h)
  // Per block, whether z holds the pair's closest points at the start of the step (RATTLE's start frames).
  std::vector<char> frame_known;
  std::vector<Vec3> axes_warm_failed;
  std::vector<Eigen::VectorXd> z_backup;  // per sub-step depth
  // RATTLE: this step tries the scheme's first-order fallback within the warm rungs, to damp a mode the step does not
  // resolve (see Data::velocity_reversals); set before the island is solved, cleared when that step fails.
  bool damping = false;
  // --- outputs of the island's step ---
  StepReport report;
  bool advanced = false;
  std::vector<ContactResult> contacts;  // one per pair, in the order of `pairs`
  std::vector<double> joint_limit_effort;  // one per joint, in the order of `joints` (see Data::joint_limit_effort)
  std::vector<double> joint_drive_effort;  // one per joint, in the order of `joints` (see Data::joint_drive_effort)
};

class Data {
  const Model* model_;

 public:
  static constexpr int kMaxSubstepDepth = 4;  // a failed step is split down to h / 16
  static constexpr int kMaxBroadPhaseRounds = 4;  // re-solves of one step after its end-of-step check added pairs
  // kAuto: every pair in every NCP for models with at most kAllPairsLimit pairs, where that is cheaper than the
  // bookkeeping and every pair's exact gap is reported at every step; the broad phase above that.
  enum class PairSelection { kAuto, kAllPairs, kBroadPhase };
  static constexpr int kAllPairsLimit = 16;
  explicit Data(const Model& model, PairSelection selection = PairSelection::kAuto);
  ~Data();
  Data(const Data&) = delete;  // its kinematics and islands refer to its own layout and drives
  Data& operator=(const Data&) = delete;
  // Whether this Data was built from `model` (the very object: the step problem and the broad phase refer to it).
  bool BelongsTo(const Model& model) const { return &model == model_; }
  // Lays the problem and the solution vectors out for `pairs` (model pair indices, ascending), carrying z_old over
  // into z_remap (the blocks of new pairs are zero and listed in new_blocks).
  void LayOut(const std::vector<int>& pairs, const Eigen::VectorXd* z_old);
  // Lays the problem out for the joints whose entry of joint_drives is active (a drive unknown each), carrying z over;
  // a newly driven joint's effort starts at the drive's effort in `state` (the start of the step). Returns whether
  // the layout changed. Step calls it.
  bool LayOutDrives(const State& state);
  // Levenberg-Marquardt fallbacks of every island's Newton solver so far.
  int lm_fallbacks() const;

  // --- the layout of the whole model: the layout of the warm start z (its pairs and their tangent axes), and the
  // step's start (for the seeds of pairs the broad phase adds) ---
  const bool broad_phase;
  StepLayout layout;
  StepKinematics kinematics;
  // --- the warm start (see WarmStart) ---
  Eigen::VectorXd z;            // the last solution (warm start of the next step)
  bool has_warm_start = false;
  // --- the islands of the current step (the first num_islands entries; step/islands.h) and their threads ---
  std::vector<std::unique_ptr<IslandSolve>> islands;
  int num_islands = 0;
  std::vector<int> island_root;     // per velocity slot: union-find parent (the root is an island's lowest slot)
  std::vector<int> island_of_slot;  // per velocity slot: its island
  std::unique_ptr<ThreadPool> pool;  // built by the first step with more than one thread
  State state_backup;  // the state before the step, restored when the step is not accepted
  // --- broad-phase workspace ---
  BroadPhase broad;
  std::vector<int> pairs, candidates, forced_pairs, merged, new_blocks;
  std::vector<Pose> X_WB;          // per body
  std::vector<double> inflation;   // per shape (Model::geoms), m
  Eigen::VectorXd z_remap;
  // RATTLE: per pair of the NCP, whether z holds its closest points at the start of the step (see IslandSolve).
  std::vector<char> frame_known;
  // RATTLE: per velocity slot, the steps in a row (at most 2) whose end velocity reversed the body's start velocity (a
  // negative kinetic-energy product). Two in a row is a motion of period 2 h, which a second-order step does not
  // resolve and does not damp (a flat face ringing on its one contact point); a body alone in its island then tries
  // the paper's step, which damps it, and stays on it while at rest (time_stepper.cpp). Part of the warm start.
  std::vector<int> velocity_reversals;
  std::vector<char> driven;  // LayOutDrives' workspace: per model joint, whether its drive is active
  // Per body, for the drives' gravity feed-forward: its subtree's mass (kg) and first moment (kg m),
  // SubtreeMassMoments (reserved when built, so the warm step allocates nothing).
  std::vector<double> subtree_mass;
  std::vector<Vec3> subtree_first_moment_W;
  // --- input: one PD drive per model joint (joints.h, JointDrive), all inactive as built; set them before Step, like
  // MuJoCo's mjData.ctrl. Step refuses invalid ones (CheckJointDrive). Turning drives on or off changes the layout of
  // z (LayOutDrives); the warm start is carried over. ---
  std::vector<JointDrive> joint_drives;
  // --- input: a cooperative stop (base/interrupt.h; null: none), owned by the caller. When it is due (a request from
  // another thread or a signal handler, or a deadline), the step's solvers stop between factorizations and Step
  // returns StepFault::kInterrupted with the state as before the step (the next step then starts cold). ---
  const StepInterrupt* interrupt = nullptr;
  // --- outputs: the contact results of the last step, one per pair in its NCP (contacts[i].pair is the model
  // pair). With every pair in the NCP, contacts[c] belongs to model pair c. ---
  std::vector<ContactResult> contacts;
  // The step-average effort each joint's limits exerted in the last step (N m or N, positive towards increasing
  // position; 0 for a joint without limits or not yet stepped), one per model joint (StepLayout::JointLimitEffort of
  // the step's solution: with the RATTLE scheme, its total over both stages).
  std::vector<double> joint_limit_effort;
  // The effort each joint's drive applied in the last step (N m or N, positive towards increasing position; 0 for a
  // joint without an active drive or not yet stepped), one per model joint: with the RATTLE scheme the step's average
  // over both stages (StepLayout::JointDriveEffort).
  std::vector<double> joint_drive_effort;
};

// Everything a step reads besides the State and the drives (Data::joint_drives): whether there is a warm start, the
// previous solution z (velocities, closest points, normals, multipliers, drive efforts), the pairs and driven joints
// z is laid out for and the friction tangent axes. A step is a function of (State, WarmStart, drives) alone (the sparse
// LU chooses its pivots afresh in every solve), so saving them and restoring them continues a run bit-identically.
struct WarmStart {
  bool valid = false;
  std::vector<int> pairs;  // model pair indices, ascending
  Eigen::VectorXd z;
  std::vector<Vec3> tangent_axes;
  std::vector<int> driven_joints;  // model joints with a drive unknown in z (ascending)
  std::vector<int> velocity_reversals;  // per velocity slot (Data::velocity_reversals); empty: none
};
void SaveWarmStart(const Data& data, WarmStart* out);
// Throws std::invalid_argument (and changes nothing) if `saved` was not taken from a Data of this model.
void RestoreWarmStart(const Model& model, const WarmStart& saved, Data* data);
// Forgets the warm start: the next step starts cold, exactly like the first step of a new Data (a reset).
void ClearWarmStart(Data* data);

}  // namespace implicit_sim
