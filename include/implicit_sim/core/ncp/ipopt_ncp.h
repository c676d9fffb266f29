// A second, independent solver of the step problem: Ipopt on the complementarity-penalty NLP
//     min  sum_i a_i b_i(z)    s.t.  E(z) = 0,  b_i(z) >= 0,  a_i >= 0
// where E are the equations of the step (Newton-Euler, closest points, normal, friction) and (a_i, b_i) its
// complementarity pairs (StepProblem raw mode). At a solution the objective is 0, i.e. every pair is complementary.
// Used to cross-check the semismooth Newton solver, and as a rung of the retry ladder (followed by a Newton polish).
#pragma once

#include <Eigen/Core>

#include "implicit_sim/core/step/step_problem.h"

namespace implicit_sim {

struct IpoptNcpResult {
  bool solved = false;            // Ipopt reported success or an acceptable point
  int iterations = 0;
  double equation_residual = 0.0; // max |E(z)| at the returned z
  double complementarity = 0.0;   // max |min(a_i, b_i)| at the returned z
};

// Solves from *z (the initial guess) in place; BeginStep and the tangent axes must be set, as for Newton.
// Never throws; a failure is reported in the result (z is then left as Ipopt's last iterate if finite).
IpoptNcpResult SolveStepWithIpopt(StepProblem* problem, int max_iterations, Eigen::VectorXd* z);

}  // namespace implicit_sim
