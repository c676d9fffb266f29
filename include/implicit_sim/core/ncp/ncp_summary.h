// What a solve of an NcpProblem did, for every solver (semismooth_newton.h, ipopt_ncp.h).
#pragma once

#include <limits>
#include <string>

namespace implicit_sim {

enum class NcpTermination {
  kConverged,      // the residual is within the solver's tolerance
  kMaxIterations,  // the iteration limit was reached first
  kNoDescent,      // no step along the search direction decreased the merit (a stall)
  kStalled,        // steps were taken, but the residual made no progress over a window (NewtonOptions::stall_window)
  kNonFinite,      // the residual at the iterate is not finite
  kInaccurate,     // the solver reported a solution whose error (ncp_error.h) exceeds the tolerance
  kSolverFailure,  // the solver reported a failure of its own (Ipopt: infeasible, restoration failed, ...)
  kInterrupted,    // its StepInterrupt (base/interrupt.h) was due: stopped between iterations
};
const char* NcpTerminationName(NcpTermination termination);  // "converged", "max_iterations", ...

struct NcpSummary {
  bool converged = false;
  NcpTermination termination = NcpTermination::kMaxIterations;
  int iterations = 0;
  // The convergence measure at the returned z: Newton |Phi|_2; Ipopt max(equation_residual, complementarity).
  double residual = 0.0;
  int residual_evaluations = 0;  // evaluations of Phi (with or without the Jacobian)
  int lm_fallbacks = 0;          // Newton: LU directions replaced by the Levenberg-Marquardt one
  int factorizations = 0;        // Newton: factorizations of the direction's linear system (LU, condensed LU, LDLT)
  int solves = 0;                // Newton: solves with a factorization (refinements of a condensed direction included)
  // The smoothing path (SemismoothNewton::FollowSmoothingPath): its Newton iterations (also counted in iterations),
  // and at its switch to the exact problem the smoothing mu and the exact residual max_i |Phi_i|; NaN: no path.
  int path_iterations = 0;
  double switch_smoothing = std::numeric_limits<double>::quiet_NaN();
  double switch_residual = std::numeric_limits<double>::quiet_NaN();
  // Ipopt: the error of the returned z (ncp_error.h); Newton leaves them NaN (its residual is |Phi|_2).
  double equation_residual = std::numeric_limits<double>::quiet_NaN();
  double complementarity = std::numeric_limits<double>::quiet_NaN();
  // One line: "converged in 4 iterations, residual 3.1e-14 (7 evaluations, 0 LM fallbacks)".
  std::string BriefReport() const;
};

}  // namespace implicit_sim
