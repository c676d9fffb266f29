// The geometrically implicit time stepper: one mixed NCP per step (paper Sections III-IV), solved by semismooth
// Newton. Usage:
//   StepperOptions options;  options.h = 0.01;
//   Data data(model);        // every derived quantity and the solver workspace, allocated once
//   State state = State::Initial(model);
//   StepReport report = Step(model, options, &state, &data);
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "implicit_sim/core/broad_phase.h"
#include "implicit_sim/core/model.h"
#include "implicit_sim/core/ncp_solver.h"
#include "implicit_sim/core/state.h"
#include "implicit_sim/core/step_problem.h"

namespace implicit_sim {

struct StepperOptions {
  enum class Solver { kNewton, kIpopt };
  static constexpr double kIpoptTolerance = 1e-8;  // an Ipopt solve converged: equations and pairs within this
  double h = 0.01;                // time step (s), in (0, 1]
  Solver solver = Solver::kNewton;  // the primary solver; Newton's retry ladder also tries Ipopt
  NewtonOptions newton;
  int ipopt_max_iterations = 500; // [1, 100000]
  double contact_threshold = 1e-9;  // a pair counts as an active contact when its normal force exceeds this (N)
  // Broad phase (when Data uses one): a pair enters the NCP when the bounding spheres of its bodies, each grown by the
  // motion possible within the step (h |v| + h |w| |offset| + |g| h^2 / 2) plus this margin, overlap. (m, [0, 10])
  double broad_phase_margin = 0.005;
  // Health checks (see StepFault). A step whose end velocities exceed these diverged (m/s, rad/s; (0, 1e12]).
  double max_speed = 1e5;
  double max_angular_speed = 1e6;
  // A cold step (the first, or after a reset or a set state) refuses to start from bodies overlapping by more than
  // this (m, [0, 1]): the step's end-of-step contact would throw them apart with an impulse of overlap / h.
  double overlap_tolerance = 1e-6;
  bool IsValid(std::string* error) const;
};

// Why a step was not accepted as a good one. With kInitialOverlap, kDiverged and kNoFiniteSolution the state is left
// exactly as it was before the step (StepReport::advanced is false).
enum class StepFault {
  kNone,
  kNotConverged,      // advanced with the best iterate found, reported as not converged (the retry ladder ran out)
  kNoFiniteSolution,  // every rung produced non-finite values
  kInitialOverlap,    // a cold step started with two bodies overlapping by more than overlap_tolerance
  kDiverged,          // the end velocities exceed max_speed or max_angular_speed
};
const char* StepFaultName(StepFault fault);  // "none", "not_converged", "no_finite_solution", "initial_overlap", "diverged"

struct StepReport {
  bool converged = false;       // the NCP (every sub-step's, if the step was split) was solved to tolerance
  bool advanced = false;        // the state was advanced (false only when no finite solution was found)
  int cold_restarts = 0;        // solves whose warm start failed and that were retried from a cold start
  int smoothed_solves = 0;      // solves that went on to a smoothing continuation after the cold start failed
  int ipopt_solves = 0;         // Ipopt solves (the primary solver, or the ladder rung after the continuation)
  int substeps = 0;             // times a (sub-)step was split into two halves after its solve failed
  int broad_phase_additions = 0;  // pairs left out by the broad phase, found overlapping at the step end and added
  int pairs_in_ncp = 0;         // pairs in the NCP of the (last) solve
  int iterations = 0;           // Newton iterations, all attempts
  double residual = 0.0;        // |Phi|_2 of the accepted solution (the largest over sub-steps)
  double complementarity_error = 0.0;
  int active_contacts = 0;      // pairs with normal force > contact_threshold
  double joint_position_error = 0.0;  // the largest violation of a joint's linear equalities at the step end (m)
  double joint_angle_error = 0.0;     // and of its angular equalities (rad); see joints.h
  double wall_time_s = 0.0;
  StepFault fault = StepFault::kNone;
  std::string fault_detail;     // which pair overlaps or which body diverged, with the numbers (empty without fault)
};

class Data {
 public:
  static constexpr int kMaxSubstepDepth = 4;  // a failed step is split down to h / 16
  static constexpr int kMaxBroadPhaseRounds = 4;  // re-solves of one step after its end-of-step check added pairs
  // kAuto: every pair in every NCP (a dense solve) for models with at most kAllPairsLimit pairs, where that is
  // cheaper than the bookkeeping and every pair's exact gap is reported at every step; the broad phase with the
  // sparse solve above that.
  enum class PairSelection { kAuto, kAllPairs, kBroadPhase };
  static constexpr int kAllPairsLimit = 16;
  // NCPs with more unknowns than this are solved in sparse mode (see ncp_solver.h) even with every pair in them: a
  // 1000-gon disc has one pair with about 1000 unknowns, whose dense LU took seconds per step.
  static constexpr int kDenseSizeLimit = 200;
  explicit Data(const Model& model, PairSelection selection = PairSelection::kAuto);
  const bool broad_phase;
  StepProblem problem;
  const bool sparse;  // broad_phase or more than kDenseSizeLimit unknowns
  SemismoothNewton solver;
  BroadPhase broad;
  Eigen::VectorXd z;            // the last solution (warm start of the next step)
  Eigen::VectorXd z_start;      // the initial guess of the current step
  bool has_warm_start = false;
  // Workspace of the retry paths, allocated once.
  Eigen::VectorXd z_best;
  std::vector<Vec3> axes_warm_failed;
  std::vector<Eigen::VectorXd> z_backup;  // per sub-step depth
  std::vector<std::vector<int>> pairs_backup;  // per sub-step depth: the pairs z_backup is laid out for
  // Broad-phase workspace.
  std::vector<int> pairs, candidates, forced_pairs, merged, new_blocks;
  std::vector<Pose> X_WB;
  std::vector<double> inflation;
  Eigen::VectorXd z_remap;
  State state_backup;  // the state before the step, restored when the step is not accepted
  // The contact results of the last step: one per pair in its NCP (contacts[i].pair is the model pair). With every
  // pair in the NCP, contacts[c] belongs to model pair c.
  std::vector<ContactResult> contacts;
};

// Everything a step reads besides the State: whether there is a warm start, the previous solution z (velocities,
// closest points, normals, multipliers), the pairs z is laid out for and the friction tangent axes. A step is a
// function of (State, WarmStart) alone (the sparse LU chooses its pivots afresh in every solve), so saving both and
// restoring them continues a run bit-identically.
struct WarmStart {
  bool valid = false;
  std::vector<int> pairs;  // model pair indices, ascending
  Eigen::VectorXd z;
  std::vector<Vec3> tangent_axes;
};
void SaveWarmStart(const Data& data, WarmStart* out);
// Throws std::invalid_argument (and changes nothing) if `saved` was not taken from a Data of this model.
void RestoreWarmStart(const Model& model, const WarmStart& saved, Data* data);
// Forgets the warm start: the next step starts cold, exactly like the first step of a new Data (a reset).
void ClearWarmStart(Data* data);

// Advances *state by one step of options.h. A cold step (no warm start) first checks that no two bodies overlap; a
// step whose end velocities exceed options.max_speed / max_angular_speed is undone. StepReport::fault says what went
// wrong; the state is never left non-finite. `external_wrench_W`, if given, holds 6 values per moving body slot:
// force (N) then torque (N m), world frame, at the centre of mass, constant over the step (added to the model's
// constant applied wrench). Throws std::invalid_argument for invalid options, a state or wrench vector whose size
// does not match the model, or a non-finite wrench (and then changes nothing); solver trouble is reported, never
// thrown.
StepReport Step(const Model& model, const StepperOptions& options, State* state, Data* data,
                const Eigen::VectorXd* external_wrench_W = nullptr);

}  // namespace implicit_sim
