// What a step did: its status, the rungs of the retry ladder it climbed, its residuals and its faults.
#pragma once

#include <array>
#include <string>

namespace implicit_sim {

// Why a step was not accepted as a good one. With kInitialOverlap, kDiverged, kNoFiniteSolution, kCrossing and
// kInterrupted the state is left exactly as it was before the step (StepReport::advanced is false).
enum class StepFault {
  kNone,
  kNotConverged,      // advanced with the best iterate found, reported as not converged (the retry ladder ran out)
  kNoFiniteSolution,  // every rung produced non-finite values
  kInitialOverlap,    // a cold step started with two bodies overlapping by more than overlap_tolerance
  kDiverged,          // the end velocities exceed max_speed or max_angular_speed
  kCrossing,          // a body passed through another even in the shortest sub-step (step_health.h, FindCrossing)
  kInterrupted,       // Data::interrupt was due (a request or a deadline, base/interrupt.h): the step was abandoned
};
constexpr int kNumStepFaults = 7;            // StepFault's values, kNone included
const char* StepFaultName(StepFault fault);  // "none", "not_converged", "no_finite_solution", "initial_overlap", "diverged",
                                             // "crossing", "interrupted"

struct StepReport {
  bool converged = false;       // the NCP (every sub-step's, if the step was split) was solved to tolerance
  bool advanced = false;        // the state was advanced (false only when no finite solution was found)
  int projected_solves = 0;     // solves whose warm start failed and that were retried with projected multipliers
  int end_frame_retries = 0;    // RATTLE: stage-1 warm starts retried with every pair on its end-of-step frame
  int energy_fallbacks = 0;     // RATTLE: steps that failed the energy guard (energy_guard.h) and were solved again
  int paper_fallbacks = 0;      // RATTLE: steps whose island took the paper's step (after the energy guard, or after a
                                // failed re-solve of stale start frames)
  int stale_frames_kept = 0;    // RATTLE: steps whose re-solve of stale start frames failed and whose first solution,
                                // judged by the energy guard, was kept
  int cold_restarts = 0;        // solves whose warm start failed and that were retried from a cold start
  int proximal_solves = 0;      // solves that went on to the proximal-point rung after the cold start failed
  int smoothed_solves = 0;      // solves that went on to a smoothing continuation after the cold start failed
  int ipopt_solves = 0;         // Ipopt solves (the primary solver, or the ladder rung after the continuation)
  int substeps = 0;             // times a (sub-)step was split into two halves after its solve failed
  int crossings = 0;            // solves rejected because a body passed through another (see FindCrossing) and split
  int broad_phase_additions = 0;  // pairs left out by the broad phase, found overlapping at the step end and added
  int pairs_in_ncp = 0;         // pairs in the NCP of the (last) solve
  int islands = 0;              // islands of the (last) solve (step/islands.h)
  int largest_island = 0;       // moving bodies in the largest of them
  int iterations = 0;           // Newton iterations, all attempts
  int velocity_iterations = 0;  // RATTLE: those of them spent on the velocity stage (stage 2)
  int damping_steps = 0;        // RATTLE: islands that took the paper's step to damp a motion of period 2 h
                                // (Data::velocity_reversals)
  int residual_evaluations = 0; // evaluations of Phi by the solvers (Newton's line search included), all attempts
  int factorizations = 0;       // Newton: factorizations of the direction's linear system, all attempts
  int solves = 0;               // Newton: solves with those factorizations (a condensed direction's refinement too)
  int path_solves = 0;          // solves that followed the smoothing path (retry_ladder.h, rung 1p)
  int path_iterations = 0;      // Newton iterations on the smoothing path (also in iterations)
  // At the smoothing path's switch to the exact problem: the last smoothing mu whose neighbourhood it reached and the
  // exact residual max_i |Phi_i| (the largest over the step's path solves; 0 without one).
  double path_switch_smoothing = 0.0;
  double path_switch_residual = 0.0;
  double residual = 0.0;        // |Phi|_2 of the accepted solution (the largest over sub-steps)
  double complementarity_error = 0.0;
  int active_contacts = 0;      // pairs with normal force > contact_threshold
  double joint_position_error = 0.0;  // the largest violation of a joint's linear equalities at the step end (m)
  double joint_angle_error = 0.0;     // and of its angular equalities (rad); see joints.h
  double wall_time_s = 0.0;
  StepFault fault = StepFault::kNone;
  std::string fault_detail;     // which pair overlaps or which body diverged, with the numbers (empty without fault)
};

// The counters of a StepReport, one row each (as options.h's table is for the options): how the islands of a step
// merge them (MergeIslandReport), whether a run totals them into summary.json (io/run_output.h, in this order), and
// their names in the Python bindings. A new counter is a field above and a row here.
enum class CounterMerge {
  kSum,   // summed over the islands of a step
  kStep,  // set by the step itself (not per island)
};
struct StepCounter {
  const char* name;  // the StepReport field, e.g. "cold_restarts"
  int StepReport::*field;
  CounterMerge merge;
  bool run_total;    // summed over a run into the runner's summary.json
};
constexpr int kNumStepCounters = 24;
const std::array<StepCounter, kNumStepCounters>& StepCounterTable();

// Adds an island's report to the step's: its counters by their rows, the residuals take the largest, converged only if
// both are, the first fault wins.
void MergeIslandReport(const StepReport& island, StepReport* step);

}  // namespace implicit_sim
