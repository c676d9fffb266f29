#include "implicit_sim/core/step/retry_ladder.h"

#include <cmath>

#include "implicit_sim/core/ncp/ipopt_ncp.h"
#include "implicit_sim/core/step/seeding.h"

namespace implicit_sim {
namespace {

// Above this many unknowns (an island of a pile) the Ipopt rung costs seconds to tens of seconds on its limited-memory
// Hessian, and halving the step is cheaper: such islands try Ipopt only as a last chance, in the shortest sub-step.
constexpr int kIpoptFirstSizeLimit = 600;

// Adds a solve's iterations and residual evaluations to the report.
void Count(const NcpSummary& summary, StepReport* report) {
  report->iterations += summary.iterations;
  report->residual_evaluations += summary.residual_evaluations;
}

// The primary solver from island->z_start; the solution goes to island->z.
NcpSummary SolveFromStart(const StepperOptions& options, IslandSolve* island, StepReport* report) {
  island->z = island->z_start;
  NcpSummary summary;
  if (options.solver == StepperOptions::Solver::kIpopt) {
    report->ipopt_solves++;
    summary = SolveNcpWithIpopt(island->problem, options.IpoptOptions(), &island->z);
  } else {
    summary = island->solver().Solve(island->problem, options.newton, &island->z);
  }
  Count(summary, report);
  return summary;
}

// The best attempt of the rungs after the cold start: its summary, with its iterate in island->z_best.
class BestAttempt {
 public:
  explicit BestAttempt(const NcpSummary& summary) : best_(summary) {}
  const NcpSummary& summary() const { return best_; }
  // Keeps island->z if `summary` (its solve) beats the best so far.
  void Offer(const NcpSummary& summary, IslandSolve* island) {
    if (summary.residual < best_.residual || !std::isfinite(best_.residual)) {
      best_ = summary;
      island->z_best = island->z;
    }
  }

 private:
  NcpSummary best_;
};

// The end of the rungs after the cold start: a Newton solve of the exact problem from island->z (if finite),
// counted; true if it converged, otherwise its iterate is offered as the best attempt.
bool PolishOrOffer(const StepperOptions& options, IslandSolve* island, StepReport* report, BestAttempt* best,
                   NcpSummary* summary) {
  if (!island->z.allFinite()) return false;
  *summary = island->solver().Solve(island->problem, options.newton, &island->z);
  Count(*summary, report);
  if (summary->converged) return true;
  best->Offer(*summary, island);
  return false;
}

// Rung 2b: proximal point. Newton on the problem perturbed by the weight c (z - z_k) on the contact force and friction
// rows (ncp_problem.h), each round from the last round's end z_k, with c = proximal_weight, / 10, ... down to 1e-6
// m/s, then on the exact problem. Starts from island->z_start (the better of the warm and cold attempts).
bool ProximalPoint(const StepperOptions& options, IslandSolve* island, StepReport* report, BestAttempt* best,
                   NcpSummary* summary) {
  report->proximal_solves++;
  island->z = island->z_start;
  NewtonOptions round = options.newton;
  round.max_iterations = std::min(options.newton.max_iterations, 30);
  round.proximal_center = &island->z_center;
  for (double c = options.proximal_weight; c >= 1e-6 && island->z.allFinite(); c *= 0.1) {
    island->z_center = island->z;
    round.proximal_weight = c;
    *summary = island->solver().Solve(island->problem, round, &island->z);
    Count(*summary, report);
  }
  return PolishOrOffer(options, island, report, best, summary);
}

// Rung 3: Newton on the FB functions smoothed by mu = 1e-2, 1e-3, ..., 1e-8, each from the last, then exactly.
// Starts from island->z as the cold start left it.
bool SmoothingContinuation(const StepperOptions& options, IslandSolve* island, StepReport* report, BestAttempt* best,
                           NcpSummary* summary) {
  report->smoothed_solves++;
  for (double mu = 1e-2; mu > 1e-9 && island->z.allFinite(); mu *= 0.1) {
    *summary = island->solver().Solve(island->problem, options.newton, &island->z, mu);
    Count(*summary, report);
  }
  return PolishOrOffer(options, island, report, best, summary);
}

// Rung 4: Ipopt on the complementarity-penalty NLP from island->z_start, polished by Newton.
bool IpoptThenNewton(const StepperOptions& options, IslandSolve* island, StepReport* report, BestAttempt* best,
                     NcpSummary* summary) {
  report->ipopt_solves++;
  island->z = island->z_start;
  const NcpSummary ipopt = SolveNcpWithIpopt(island->problem, options.IpoptOptions(), &island->z);
  Count(ipopt, report);
  return PolishOrOffer(options, island, report, best, summary);
}

}  // namespace

NcpSummary SolveWithRetryLadder(const Model& model, const StepperOptions& options, const State& state, IslandSolve* island,
                                bool last_chance, StepReport* report) {
  StepProblem& problem = island->problem;
  if (!island->has_warm_start) {
    SeedColdStart(model, state, &problem, &island->z_start);
    return SolveFromStart(options, island, report);
  }
  // Rung 1: the warm start, with the block predictor's sweeps when it starts far off.
  island->z_start = island->z;
  SeedWarmStart(model, state, &problem, &island->z_start);
  if (options.predictor_sweeps > 0) {
    problem.Evaluate(island->z_start, NcpEvalMode(), &island->ncp_error_rows, nullptr);  // a free workspace here
    report->residual_evaluations++;
    if (island->ncp_error_rows.norm() > options.predictor_residual) {
      report->residual_evaluations += island->predictor.Run(problem, options.newton, options.predictor_sweeps, 0.1,
                                                            &island->z_start);
    }
  }
  NcpSummary warm = SolveFromStart(options, island, report);
  if (warm.converged) return warm;
  // Rung 1a (RATTLE stage 1): the warm start again with every pair on its end-of-step frame; a start frame on the
  // wrong feature (a polygon that tips onto its next face within the step) can leave stage 1 without a solution.
  if (problem.FallBackToEndFrames() > 0) {
    report->end_frame_retries++;
    warm = SolveFromStart(options, island, report);
    if (warm.converged) return warm;
  }
  island->z_best = island->z;  // the failed warm attempt (or the projected one, if better)
  // Every rung from here on projects the multipliers (with projected_retries): they start where the plain rows failed.
  StepperOptions later_options = options;
  later_options.newton.project_multipliers = options.projected_retries;
  // Rung 1b: the warm start again with projected multipliers (ncp_problem.h): it rescues failed warm starts where
  // Newton alternates between the two branches of a loaded contact's friction (a landing pile, a rolling polygon).
  if (options.solver == StepperOptions::Solver::kNewton && options.projected_retries) {
    report->projected_solves++;
    const NcpSummary projected = SolveFromStart(later_options, island, report);
    if (projected.converged) return projected;
    if (projected.residual < warm.residual || !std::isfinite(warm.residual)) {
      warm = projected;
      island->z_best = island->z;
    }
  }
  // Rung 2: a cold start, keeping the failed warm attempt and its tangent axes.
  report->cold_restarts++;
  island->axes_warm_failed = problem.tangent_axes();
  SeedColdStart(model, state, &problem, &island->z_start);
  const NcpSummary cold = SolveFromStart(later_options, island, report);
  if (cold.converged || later_options.solver == StepperOptions::Solver::kIpopt) return cold;
  // The better of the two (with its tangent axes) is kept in z_best, and the Ipopt rung starts from it.
  BestAttempt best(cold);
  if (!(cold.residual < warm.residual) && std::isfinite(warm.residual)) {
    best = BestAttempt(warm);
    problem.set_tangent_axes(island->axes_warm_failed);
  } else {
    island->z_best = island->z;
  }
  island->z_start = island->z_best;
  NcpSummary summary;
  if (later_options.proximal_weight > 0.0) {
    island->z_cold = island->z;
    if (ProximalPoint(later_options, island, report, &best, &summary)) return summary;
    island->z.swap(island->z_cold);  // the continuation starts where the cold attempt ended, as without the rung
  }
  if (SmoothingContinuation(later_options, island, report, &best, &summary)) return summary;
  if ((last_chance || problem.size() <= kIpoptFirstSizeLimit) &&
      IpoptThenNewton(later_options, island, report, &best, &summary)) {
    return summary;
  }
  island->z = island->z_best;
  return best.summary();
}

NcpSummary SolveVelocityStage(const StepperOptions& options, IslandSolve* island, StepReport* report) {
  StepProblem& problem = island->problem;
  island->z_start = island->z_velocity;  // stage 1's initial guess is no longer needed
  NcpSummary best = island->solver().Solve(problem, options.newton, &island->z_velocity);
  Count(best, report);
  if (best.converged) return best;
  island->z_best = island->z_velocity;
  NewtonOptions projected = options.newton;
  projected.project_multipliers = true;
  report->projected_solves++;
  island->z_velocity = island->z_start;
  NcpSummary summary = island->solver().Solve(problem, projected, &island->z_velocity);
  Count(summary, report);
  if (summary.converged) return summary;
  if (summary.residual < best.residual || !std::isfinite(best.residual)) {
    best = summary;
    island->z_best = island->z_velocity;
  }
  report->smoothed_solves++;
  island->z_velocity = island->z_start;
  for (double mu = 1e-2; mu > 1e-9 && island->z_velocity.allFinite(); mu *= 0.1) {
    summary = island->solver().Solve(problem, projected, &island->z_velocity, mu);
    Count(summary, report);
  }
  if (island->z_velocity.allFinite()) {
    summary = island->solver().Solve(problem, projected, &island->z_velocity);
    Count(summary, report);
    if (summary.converged) return summary;
    if (summary.residual < best.residual || !std::isfinite(best.residual)) return summary;
  }
  island->z_velocity = island->z_best;
  return best;
}

}  // namespace implicit_sim
