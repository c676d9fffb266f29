#include "implicit_sim/core/ncp/ncp_summary.h"

#include "implicit_sim/core/base/format.h"

namespace implicit_sim {

const char* NcpTerminationName(NcpTermination termination) {
  switch (termination) {
    case NcpTermination::kConverged: return "converged";
    case NcpTermination::kMaxIterations: return "max_iterations";
    case NcpTermination::kNoDescent: return "no_descent";
    case NcpTermination::kStalled: return "stalled";
    case NcpTermination::kNonFinite: return "non_finite";
    case NcpTermination::kInaccurate: return "inaccurate";
    case NcpTermination::kSolverFailure: return "solver_failure";
    case NcpTermination::kInterrupted: return "interrupted";
  }
  return "unknown";
}

std::string NcpSummary::BriefReport() const {
  return std::string(NcpTerminationName(termination)) + " after " + std::to_string(iterations) +
         " iterations, residual " + FormatNumber(residual) + " (" + std::to_string(residual_evaluations) +
         " evaluations, " + std::to_string(lm_fallbacks) + " LM fallbacks)";
}

}  // namespace implicit_sim
