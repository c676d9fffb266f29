#include "implicit_sim/core/step/step_report.h"

#include <algorithm>

namespace implicit_sim {
namespace {

using R = StepReport;
constexpr CounterMerge kSum = CounterMerge::kSum, kStep = CounterMerge::kStep;
constexpr std::array<StepCounter, kNumStepCounters> kCounters{{
    {"projected_solves", &R::projected_solves, kSum, false},
    {"cold_restarts", &R::cold_restarts, kSum, true},
    {"end_frame_retries", &R::end_frame_retries, kSum, true},
    {"proximal_solves", &R::proximal_solves, kSum, true},
    {"smoothed_solves", &R::smoothed_solves, kSum, true},
    {"ipopt_solves", &R::ipopt_solves, kSum, true},
    {"substeps", &R::substeps, kSum, true},
    {"crossings", &R::crossings, kSum, true},
    {"broad_phase_additions", &R::broad_phase_additions, kStep, true},
    {"iterations", &R::iterations, kSum, false},
    {"residual_evaluations", &R::residual_evaluations, kSum, false},
    {"pairs_in_ncp", &R::pairs_in_ncp, kStep, false},
    {"islands", &R::islands, kStep, false},
    {"largest_island", &R::largest_island, kStep, false},
    {"active_contacts", &R::active_contacts, kStep, false},
    {"energy_fallbacks", &R::energy_fallbacks, kSum, true},
    {"paper_fallbacks", &R::paper_fallbacks, kSum, true},
    {"stale_frames_kept", &R::stale_frames_kept, kSum, true},
    {"velocity_iterations", &R::velocity_iterations, kSum, false},
    {"damping_steps", &R::damping_steps, kSum, true},
    {"factorizations", &R::factorizations, kSum, true},
    {"solves", &R::solves, kSum, true},
    {"path_solves", &R::path_solves, kSum, true},
    {"path_iterations", &R::path_iterations, kSum, true},
}};

}  // namespace

const std::array<StepCounter, kNumStepCounters>& StepCounterTable() { return kCounters; }

void MergeIslandReport(const StepReport& island, StepReport* step) {
  step->converged = step->converged && island.converged;
  for (const StepCounter& counter : kCounters) {
    if (counter.merge == CounterMerge::kSum) step->*counter.field += island.*counter.field;
  }
  step->residual = std::max(step->residual, island.residual);
  step->complementarity_error = std::max(step->complementarity_error, island.complementarity_error);
  step->path_switch_smoothing = std::max(step->path_switch_smoothing, island.path_switch_smoothing);
  step->path_switch_residual = std::max(step->path_switch_residual, island.path_switch_residual);
  if (step->fault == StepFault::kNone && island.fault != StepFault::kNone) {
    step->fault = island.fault;
    step->fault_detail = island.fault_detail;
  }
}

const char* StepFaultName(StepFault fault) {
  switch (fault) {
    case StepFault::kNone: return "none";
    case StepFault::kNotConverged: return "not_converged";
    case StepFault::kNoFiniteSolution: return "no_finite_solution";
    case StepFault::kInitialOverlap: return "initial_overlap";
    case StepFault::kDiverged: return "diverged";
    case StepFault::kCrossing: return "crossing";
    case StepFault::kInterrupted: return "interrupted";
  }
  return "unknown";
}

}  // namespace implicit_sim
