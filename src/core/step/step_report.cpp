#include "implicit_sim/core/step/step_report.h"

namespace implicit_sim {

const char* StepFaultName(StepFault fault) {
  switch (fault) {
    case StepFault::kNone: return "none";
    case StepFault::kNotConverged: return "not_converged";
    case StepFault::kNoFiniteSolution: return "no_finite_solution";
    case StepFault::kInitialOverlap: return "initial_overlap";
    case StepFault::kDiverged: return "diverged";
    case StepFault::kCrossing: return "crossing";
  }
  return "unknown";
}

}  // namespace implicit_sim
