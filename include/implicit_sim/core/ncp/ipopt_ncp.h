// A second, independent solver of an NcpProblem: Ipopt on the complementarity-penalty NLP
//     min  sum_i a_i b_i(z)    s.t.  E(z) = 0,  b_i(z) >= 0,  a_i >= 0
// where E are the equation rows and (a_i = scale_i z_i, b_i) the complementarity pairs, both from the raw rows
// (NcpEvalMode::raw). At a solution the objective is 0, i.e. every pair is complementary. The step uses it to
// cross-check the semismooth Newton solver, and as a rung of its retry ladder (followed by a Newton polish).
#pragma once

#include <Eigen/Core>

#include "implicit_sim/core/base/interrupt.h"
#include "implicit_sim/core/ncp/ncp_problem.h"
#include "implicit_sim/core/ncp/ncp_summary.h"

namespace implicit_sim {

struct IpoptNcpOptions {
  int max_iterations = 500;      // [1, 100000]
  double ipopt_tol = 1e-10;      // Ipopt's own "tol" and "acceptable_tol" on the NLP
  double ipopt_acceptable_tol = 1e-8;
  // Converged when Ipopt reports a solution and max(equation residual, complementarity error) (ncp_error.h) is at
  // most this.
  double tolerance = 1e-8;
  // When set and due, Ipopt stops at its next iteration (NcpTermination::kInterrupted).
  const StepInterrupt* interrupt = nullptr;
};

// Solves from *z (the initial guess) in place. Never throws; a failure is reported in the summary (z is then left as
// Ipopt's last iterate if finite). The summary's residual is max(equation residual, complementarity error).
NcpSummary SolveNcpWithIpopt(const NcpProblem& problem, const IpoptNcpOptions& options, Eigen::VectorXd* z);

}  // namespace implicit_sim
