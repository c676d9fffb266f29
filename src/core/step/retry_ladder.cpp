#include "implicit_sim/core/step/retry_ladder.h"

#include <cmath>

#include "implicit_sim/core/ncp/ipopt_ncp.h"
#include "implicit_sim/core/step/seeding.h"

namespace implicit_sim {
namespace {

// The primary solver from data->z_start; the solution goes to data->z.
NcpSummary SolveFromStart(const StepperOptions& options, Data* data, StepReport* report) {
  data->z = data->z_start;
  NcpSummary summary;
  if (options.solver == StepperOptions::Solver::kIpopt) {
    report->ipopt_solves++;
    summary = SolveNcpWithIpopt(data->problem, options.IpoptOptions(), &data->z);
  } else {
    summary = data->solver.Solve(data->problem, options.newton, &data->z);
  }
  report->iterations += summary.iterations;
  report->residual_evaluations += summary.residual_evaluations;
  return summary;
}

// The best attempt of the rungs after the cold start: its summary, with its iterate in data->z_best.
class BestAttempt {
 public:
  explicit BestAttempt(const NcpSummary& summary) : best_(summary) {}
  const NcpSummary& summary() const { return best_; }
  // Keeps data->z if `summary` (its solve) beats the best so far.
  void Offer(const NcpSummary& summary, Data* data) {
    if (summary.residual < best_.residual || !std::isfinite(best_.residual)) {
      best_ = summary;
      data->z_best = data->z;
    }
  }

 private:
  NcpSummary best_;
};

// A Newton solve of the exact problem from data->z, counted; true if it converged.
bool NewtonPolish(const StepperOptions& options, Data* data, StepReport* report, NcpSummary* summary) {
  *summary = data->solver.Solve(data->problem, options.newton, &data->z);
  report->iterations += summary->iterations;
  report->residual_evaluations += summary->residual_evaluations;
  return summary->converged;
}

// Rung 3: Newton on the FB functions smoothed by mu = 1e-2, 1e-3, ..., 1e-8, each from the last, then exactly.
// Starts from data->z as the cold start left it.
bool SmoothingContinuation(const StepperOptions& options, Data* data, StepReport* report, BestAttempt* best,
                           NcpSummary* summary) {
  report->smoothed_solves++;
  for (double mu = 1e-2; mu > 1e-9 && data->z.allFinite(); mu *= 0.1) {
    *summary = data->solver.Solve(data->problem, options.newton, &data->z, mu);
    report->iterations += summary->iterations;
    report->residual_evaluations += summary->residual_evaluations;
  }
  if (!data->z.allFinite()) return false;
  if (NewtonPolish(options, data, report, summary)) return true;
  best->Offer(*summary, data);
  return false;
}

// Rung 4: Ipopt on the complementarity-penalty NLP from data->z_start, polished by Newton.
bool IpoptThenNewton(const StepperOptions& options, Data* data, StepReport* report, BestAttempt* best,
                     NcpSummary* summary) {
  report->ipopt_solves++;
  data->z = data->z_start;
  const NcpSummary ipopt = SolveNcpWithIpopt(data->problem, options.IpoptOptions(), &data->z);
  report->iterations += ipopt.iterations;
  report->residual_evaluations += ipopt.residual_evaluations;
  if (!data->z.allFinite()) return false;
  if (NewtonPolish(options, data, report, summary)) return true;
  best->Offer(*summary, data);
  return false;
}

}  // namespace

NcpSummary SolveWithRetryLadder(const Model& model, const StepperOptions& options, const State& state, Data* data,
                                StepReport* report) {
  StepProblem& problem = data->problem;
  if (!data->has_warm_start) {
    SeedColdStart(model, state, &problem, &data->z_start);
    return SolveFromStart(options, data, report);
  }
  // Rung 1: the warm start.
  data->z_start = data->z;
  SeedWarmStart(model, state, &problem, &data->z_start);
  const NcpSummary warm = SolveFromStart(options, data, report);
  if (warm.converged) return warm;
  // Rung 2: a cold start, keeping the failed warm attempt and its tangent axes.
  report->cold_restarts++;
  data->z_best = data->z;
  data->axes_warm_failed = problem.tangent_axes();
  SeedColdStart(model, state, &problem, &data->z_start);
  const NcpSummary cold = SolveFromStart(options, data, report);
  if (cold.converged || options.solver == StepperOptions::Solver::kIpopt) return cold;
  // The better of the two (with its tangent axes) is kept in z_best, and the Ipopt rung starts from it.
  BestAttempt best(cold);
  if (!(cold.residual < warm.residual) && std::isfinite(warm.residual)) {
    best = BestAttempt(warm);
    problem.set_tangent_axes(data->axes_warm_failed);
  } else {
    data->z_best = data->z;
  }
  data->z_start = data->z_best;
  NcpSummary summary;
  if (SmoothingContinuation(options, data, report, &best, &summary)) return summary;
  if (IpoptThenNewton(options, data, report, &best, &summary)) return summary;
  data->z = data->z_best;
  return best.summary();
}

}  // namespace implicit_sim
