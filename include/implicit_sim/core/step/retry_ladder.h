// The retry ladder of one step solve: what the stepper tries, in order, until the step NCP is solved.
//   1. warm start: the previous step's solution carried over the step (seeding.h), by the primary solver; on a sparse
//      island of several pairs (more than NewtonSolvers::kDenseSizeLimit unknowns: a pile) within StepperOptions::sparse_warm_iterations
//      Newton iterations (more only where its residual is already below 1e-6);
//   1p. with StepperOptions::path_following (off by default), on such an island, the smoothing path from the same
//      start (SemismoothNewton::FollowSmoothingPath: each smoothing level left after the 1-3 Newton steps that reach
//      its neighbourhood, then at most 6 exact ones);
//   1a. the same start on the problem's fallback formulation, if it has one (StepProblem::UseFallbackFrames: RATTLE's
//       stage 1 with every pair on its end-of-step frame instead of its start frame; StepReport::end_frame_retries);
//   1b. the same start by Newton with projected multipliers (ncp_problem.h; with StepperOptions::projected_retries,
//       the default, this rung and every later Newton solve project);
//   2. cold start: fresh closest points, normals and friction seeds;
//   2b. with StepperOptions::proximal_weight > 0 (the default): proximal point, Newton on the problem perturbed by
//       c (z - z_k) on the contact force and friction rows, each round from the last (z_k), c divided by 10 a round,
//       from the better of rungs 1-2;
//   3. smoothing continuation: Newton on the Fischer-Burmeister functions smoothed by mu = 1e-2, 1e-3, ... 1e-8, each
//      from the last, up to the first level that does not converge, then on the exact problem;
//   4. Ipopt on the complementarity-penalty NLP (ncp/ipopt_ncp.h) from the best of rungs 1-2, polished by Newton.
// Without a warm start the ladder begins at rung 2. With the Ipopt solver as the primary one it stops after rung 2.
// When every rung fails the best finite iterate is kept; the stepper then splits the step (time_stepper.h).
// A scheme with a fallback scheme (IslandScheme::fallback: RATTLE, whose fallback is the paper's step) climbs only
// rungs 1 and 1a, each within a budget of Newton iterations (LadderReach::kWarmRungs); where they fail, the island's
// step is the fallback scheme's, with every rung. Every rung works on any step problem (problems/step_problem.h) and
// its own solvers.
#pragma once

#include "implicit_sim/core/model/model.h"
#include "implicit_sim/core/model/state.h"
#include "implicit_sim/core/ncp/ncp_summary.h"
#include "implicit_sim/core/step/data.h"
#include "implicit_sim/core/step/options.h"
#include "implicit_sim/core/step/problems/step_problem.h"
#include "implicit_sim/core/step/schemes/island_scheme.h"
#include "implicit_sim/core/step/step_report.h"

namespace implicit_sim {

// Solves `problem` (the island's pose problem: its kinematics' BeginStep called for `state`, its layout
// island->layout) from the island's warm start if it has one and leaves the best solution in island->z (and its
// tangent axes in the layout); does not touch the state. Counts the rungs and iterations in *report. The summary is
// that of the accepted solve. The Ipopt rung is tried by problems of up to 600 unknowns, and by larger ones when
// `last_chance` (the shortest sub-step): above that size it costs seconds and halving the step first is cheaper.
enum class LadderReach {
  kAllRungs,   // every rung
  kWarmRungs,  // rungs 1 and 1a, each within a budget of Newton iterations (without a warm start: the cold start)
};
NcpSummary SolveWithRetryLadder(const Model& model, const StepperOptions& options, const State& state,
                                StepProblem& problem, NewtonSolvers* solvers, IslandSolve* island, bool last_chance,
                                LadderReach reach, StepReport* report);

// A later stage (RATTLE's stage 2) from the guess in *z: Newton within the budget of a warm rung. Leaves its iterate
// in *z and counts its iterations in *report.
NcpSummary SolveFromGuess(const StepperOptions& options, const StepProblem& problem, NewtonSolvers* solvers,
                          Eigen::VectorXd* z, IslandSolve* island, StepReport* report);

}  // namespace implicit_sim
