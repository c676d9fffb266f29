#include "implicit_sim/core/step/retry_ladder.h"

#include <algorithm>
#include <cmath>

#include "implicit_sim/core/ncp/ipopt_ncp.h"
#include "implicit_sim/core/step/seeding.h"

namespace implicit_sim {
namespace {

// Above this many unknowns (an island of a pile) the Ipopt rung costs seconds to tens of seconds on its limited-memory
// Hessian, and halving the step is cheaper: such islands try Ipopt only as a last chance, in the shortest sub-step.
constexpr int kIpoptFirstSizeLimit = 600;

// Newton iterations of a warm attempt that has a fallback formulation (RATTLE stage 1's start frames), and the
// residual below which such an attempt is converging to a root nearby and gets the rest of its budget.
constexpr int kStartFrameIterations = 6;
constexpr double kNearRootResidual = 1e-6;

// Newton iterations of each warm rung of a budgeted ladder (LadderReach::kWarmRungs): a warm start converges in a few
// where it converges at all; a step that needs more goes to its scheme's fallback.
constexpr int kWarmRungIterations = 20;

// One ladder's problem, its Newton solver, its iterate *z, the island's workspace (z_start, z_best, z_center, z_cold)
// and the report its rungs count into. Every rung reads and writes only these.
struct Ladder {
  const StepProblem& problem;
  SemismoothNewton& solver;
  Eigen::VectorXd& z;
  IslandSolve& work;
  StepReport* report;
  NcpSummary Solve(const NewtonOptions& newton, double smoothing = 0.0) {
    const size_t traced = newton.trace ? newton.trace->rows.size() : 0;
    const NcpSummary summary = solver.Solve(problem, newton, &z, smoothing);
    Count(summary);
    NameTracedRows(newton.trace, traced);
    return summary;
  }
  // Names the largest row of the trace rows from `first` on.
  void NameTracedRows(NewtonTrace* trace, size_t first) const {
    for (size_t k = first; trace && k < trace->rows.size(); ++k) {
      trace->rows[k].largest_row_name = problem.layout().RowName(trace->rows[k].largest_row_index);
      trace->rows[k].largest_move_name = problem.layout().RowName(trace->rows[k].largest_move_index);
    }
  }
  // Adds a solve's iterations and residual evaluations to the report.
  void Count(const NcpSummary& summary) {
    report->iterations += summary.iterations;
    report->residual_evaluations += summary.residual_evaluations;
    report->factorizations += summary.factorizations;
    report->solves += summary.solves;
  }
};

// The primary solver from work.z_start; the solution goes to z.
NcpSummary SolveFromStart(const StepperOptions& options, Ladder* ladder) {
  ladder->z = ladder->work.z_start;
  if (options.solver != StepperOptions::Solver::kIpopt) return ladder->Solve(options.newton);
  ladder->report->ipopt_solves++;
  const NcpSummary summary = SolveNcpWithIpopt(ladder->problem, options.IpoptOptions(), &ladder->z);
  ladder->Count(summary);
  return summary;
}

// The best attempt of the rungs after the first: its summary, with its iterate in work.z_best.
class BestAttempt {
 public:
  explicit BestAttempt(const NcpSummary& summary) : best_(summary) {}
  const NcpSummary& summary() const { return best_; }
  // Keeps the ladder's z if `summary` (its solve) beats the best so far.
  void Offer(const NcpSummary& summary, Ladder* ladder) {
    if (summary.residual < best_.residual || !std::isfinite(best_.residual)) {
      best_ = summary;
      ladder->work.z_best = ladder->z;
    }
  }

 private:
  NcpSummary best_;
};

// The end of the rungs after the cold start: a Newton solve of the exact problem from z (if finite), counted; true if
// it converged, otherwise its iterate is offered as the best attempt.
bool PolishOrOffer(const StepperOptions& options, Ladder* ladder, BestAttempt* best, NcpSummary* summary) {
  if (!ladder->z.allFinite()) return false;
  *summary = ladder->Solve(options.newton);
  if (summary->converged) return true;
  best->Offer(*summary, ladder);
  return false;
}

// Rung 1b: the start again with projected multipliers (ncp_problem.h): it rescues failed warm starts where Newton
// alternates between the two branches of a loaded contact's friction (a landing pile, a rolling polygon). Keeps the
// better of it and *first (with its iterate in work.z_best); true if it converged.
bool ProjectedRetry(const StepperOptions& projected_options, Ladder* ladder, NcpSummary* first) {
  ladder->report->projected_solves++;
  const NcpSummary projected = SolveFromStart(projected_options, ladder);
  if (projected.residual < first->residual || !std::isfinite(first->residual) || projected.converged) {
    *first = projected;
    ladder->work.z_best = ladder->z;
  }
  return projected.converged;
}

// Rung 1p: the smoothing path (SemismoothNewton::FollowSmoothingPath) from work.z_start, polished on the exact
// problem. Keeps the better of it and *first (with its iterate in work.z_best); true if it converged.
bool SmoothingPath(const StepperOptions& options, Ladder* ladder, NcpSummary* first) {
  ladder->report->path_solves++;
  ladder->z = ladder->work.z_start;
  const size_t traced = options.newton.trace ? options.newton.trace->rows.size() : 0;
  const NcpSummary path = ladder->solver.FollowSmoothingPath(ladder->problem, options.newton, PathOptions(), &ladder->z);
  ladder->NameTracedRows(options.newton.trace, traced);
  ladder->Count(path);
  ladder->report->path_iterations += path.path_iterations;
  if (std::isfinite(path.switch_smoothing)) {
    ladder->report->path_switch_smoothing = std::max(ladder->report->path_switch_smoothing, path.switch_smoothing);
  }
  if (std::isfinite(path.switch_residual)) {
    ladder->report->path_switch_residual = std::max(ladder->report->path_switch_residual, path.switch_residual);
  }
  if (path.residual < first->residual || !std::isfinite(first->residual) || path.converged) {
    *first = path;
    ladder->work.z_best = ladder->z;
  }
  return path.converged;
}

// Rung 2b: proximal point. Newton on the problem perturbed by the weight c (z - z_k) on the contact force and friction
// rows (ncp_problem.h), each round from the last round's end z_k, with c = proximal_weight, / 10, ... down to 1e-6
// m/s, then on the exact problem. Starts from work.z_start (the better of the warm and cold attempts).
bool ProximalPoint(const StepperOptions& options, Ladder* ladder, BestAttempt* best, NcpSummary* summary) {
  ladder->report->proximal_solves++;
  ladder->z = ladder->work.z_start;
  NewtonOptions round = options.newton;
  round.max_iterations = std::min(options.newton.max_iterations, 30);
  round.proximal_center = &ladder->work.z_center;
  for (double c = options.proximal_weight; c >= 1e-6 && ladder->z.allFinite(); c *= 0.1) {
    ladder->work.z_center = ladder->z;
    round.proximal_weight = c;
    *summary = ladder->Solve(round);
  }
  return PolishOrOffer(options, ladder, best, summary);
}

// Rung 3: Newton on the FB functions smoothed by mu = 1e-2, 1e-3, ..., 1e-8, each from the last while they converge,
// then exactly. Starts from z as it is.
bool SmoothingContinuation(const StepperOptions& options, Ladder* ladder, BestAttempt* best, NcpSummary* summary) {
  ladder->report->smoothed_solves++;
  for (double mu = 1e-2; mu > 1e-9 && ladder->z.allFinite(); mu *= 0.1) {
    *summary = ladder->Solve(options.newton, mu);
    // A level that did not converge leaves a point the smaller levels stall at too (the pile steps' traces: 100
    // iterations a level at the same residual): go to the exact polish from there.
    if (!summary->converged) break;
  }
  return PolishOrOffer(options, ladder, best, summary);
}

// Rung 4: Ipopt on the complementarity-penalty NLP from work.z_start, polished by Newton.
bool IpoptThenNewton(const StepperOptions& options, Ladder* ladder, BestAttempt* best, NcpSummary* summary) {
  ladder->report->ipopt_solves++;
  ladder->z = ladder->work.z_start;
  const NcpSummary ipopt = SolveNcpWithIpopt(ladder->problem, options.IpoptOptions(), &ladder->z);
  ladder->Count(ipopt);
  return PolishOrOffer(options, ladder, best, summary);
}

}  // namespace

NcpSummary SolveWithRetryLadder(const Model& model, const StepperOptions& options, const State& state,
                                StepProblem& problem, NewtonSolvers* solvers, IslandSolve* island, bool last_chance,
                                LadderReach reach, StepReport* report) {
  Ladder ladder{problem, solvers->For(problem), island->z, *island, report};
  const bool warm_rungs_only = reach == LadderReach::kWarmRungs;
  if (!island->has_warm_start) {
    SeedColdStart(model, state, problem, &island->layout, &island->z_start);
    return SolveFromStart(options, &ladder);
  }
  // Rung 1: the warm start, with the block predictor's sweeps when it starts far off.
  island->z_start = island->z;
  SeedWarmStart(model, state, problem, &island->layout, &island->z_start);
  if (options.predictor_sweeps > 0) {
    problem.Evaluate(island->z_start, NcpEvalMode(), &island->ncp_error_rows, nullptr);  // a free workspace here
    report->residual_evaluations++;
    if (island->ncp_error_rows.norm() > options.predictor_residual) {
      report->residual_evaluations += island->predictor.Run(problem, options.newton, options.predictor_sweeps, 0.1,
                                                            &island->z_start);
    }
  }
  // With a fallback formulation to go to, the warm attempt gets a short budget: a start frame that has no nearby root
  // is not found by more iterations, and the fallback usually converges in a few.
  StepperOptions budget = options;
  if (warm_rungs_only) budget.newton.max_iterations = std::min(options.newton.max_iterations, kWarmRungIterations);
  StepperOptions warm_options = budget;
  if (problem.HasFallbackFrames()) {
    warm_options.newton.max_iterations = std::min(options.newton.max_iterations, kStartFrameIterations);
  }
  // A sparse island of several pairs (a pile's) gets a short plain warm attempt before the projected one (and rung
  // 1p), except in a budgeted ladder: where a landing's plain warm start converges at all it takes few iterations,
  // and the projected start converges from where it stalls (bench/README.md, the corpus). One pair of many
  // inequalities (the 1000-gon) keeps the full plain attempt: projection fails it (doc/method.md).
  const bool sparse_warm = !warm_rungs_only && !problem.HasFallbackFrames() &&
                           options.solver == StepperOptions::Solver::kNewton &&
                           problem.size() > NewtonSolvers::kDenseSizeLimit && island->layout.blocks().size() > 1;
  if (sparse_warm) {
    warm_options.newton.max_iterations = std::min(options.newton.max_iterations, options.sparse_warm_iterations);
  }
  NcpSummary warm = SolveFromStart(warm_options, &ladder);
  if (!warm.converged && warm.residual <= kNearRootResidual &&
      warm_options.newton.max_iterations < budget.newton.max_iterations) {
    NewtonOptions rest = budget.newton;
    rest.max_iterations -= warm.iterations;
    warm = ladder.Solve(rest);
  }
  // A due interrupt (Data::interrupt) ends the ladder after any rung: the step is abandoned (time_stepper.cpp).
  const auto interrupted = [&options]() { return InterruptDue(options.newton.interrupt); };
  if (warm.converged || interrupted()) return warm;
  if (warm_rungs_only) {  // rung 1a within the budget, and no further
    if (problem.UseFallbackFrames() > 0) {
      report->end_frame_retries++;
      warm = SolveFromStart(budget, &ladder);
    }
    return warm;
  }
  // Rung 1a: the problem's fallback formulation (RATTLE stage 1: every pair on its end-of-step frame; a start frame on
  // the wrong feature, a polygon that tips onto its next face within the step, can leave stage 1 without a solution).
  // Where the fallback fails too (a landing pile's island, whose end frames are the harder problem), the first
  // formulation gets its full budget before the later rungs, which run on the fallback.
  if (problem.UseFallbackFrames() > 0) {
    report->end_frame_retries++;
    warm = SolveFromStart(options, &ladder);
    if (warm.converged) return warm;
    if (warm_options.newton.max_iterations < options.newton.max_iterations && problem.RestoreFrames() > 0) {
      island->z_best = island->z;  // the fallback's attempt, which the later rungs continue from
      const NcpSummary full = SolveFromStart(options, &ladder);
      if (full.converged) return full;
      problem.UseFallbackFrames();
      island->z = island->z_best;
    }
  }
  island->z_best = island->z;  // the failed warm attempt (or the projected one, if better)
  // Every rung from here on projects the multipliers (with projected_retries): they start where the plain rows failed.
  StepperOptions later_options = options;
  later_options.newton.project_multipliers = options.projected_retries;
  if (sparse_warm && options.path_following && SmoothingPath(later_options, &ladder, &warm)) return warm;
  if (options.solver == StepperOptions::Solver::kNewton && options.projected_retries &&
      ProjectedRetry(later_options, &ladder, &warm)) {
    return warm;
  }
  if (interrupted()) return warm;
  // Rung 2: a cold start, keeping the failed warm attempt and its tangent axes.
  report->cold_restarts++;
  island->axes_warm_failed = island->layout.tangent_axes();
  SeedColdStart(model, state, problem, &island->layout, &island->z_start);
  const NcpSummary cold = SolveFromStart(later_options, &ladder);
  if (cold.converged || later_options.solver == StepperOptions::Solver::kIpopt || interrupted()) return cold;
  // The better of the two (with its tangent axes) is kept in z_best, and the Ipopt rung starts from it.
  BestAttempt best(cold);
  if (!(cold.residual < warm.residual) && std::isfinite(warm.residual)) {
    best = BestAttempt(warm);
    island->layout.set_tangent_axes(island->axes_warm_failed);
  } else {
    island->z_best = island->z;
  }
  island->z_start = island->z_best;
  NcpSummary summary;
  if (later_options.proximal_weight > 0.0) {
    island->z_cold = island->z;
    if (ProximalPoint(later_options, &ladder, &best, &summary)) return summary;
    island->z.swap(island->z_cold);  // the continuation starts where the cold attempt ended, as without the rung
  }
  if (!interrupted() && SmoothingContinuation(later_options, &ladder, &best, &summary)) return summary;
  if (!interrupted() && (last_chance || problem.size() <= kIpoptFirstSizeLimit) &&
      IpoptThenNewton(later_options, &ladder, &best, &summary)) {
    return summary;
  }
  island->z = island->z_best;
  return best.summary();
}

NcpSummary SolveFromGuess(const StepperOptions& options, const StepProblem& problem, NewtonSolvers* solvers,
                          Eigen::VectorXd* z, IslandSolve* island, StepReport* report) {
  Ladder ladder{problem, solvers->For(problem), *z, *island, report};
  NewtonOptions budget = options.newton;
  budget.max_iterations = std::min(options.newton.max_iterations, kWarmRungIterations);
  return ladder.Solve(budget);
}

}  // namespace implicit_sim
