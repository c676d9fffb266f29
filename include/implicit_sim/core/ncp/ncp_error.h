// An independent check of a candidate solution of an NcpProblem, from its raw rows (no Fischer-Burmeister function,
// no smoothing, no regularization): the largest |E_i(z)| over the equations and the largest |min(a_i, b_i(z))| over
// the complementarity pairs, in the problem's scaled units. Both are 0 exactly at a solution.
#pragma once

#include <Eigen/Core>

#include "implicit_sim/core/ncp/ncp_problem.h"

namespace implicit_sim {

struct NcpError {
  double equations = 0.0;
  double complementarity = 0.0;
};

// `raw_rows` is workspace (resized to the problem's size, which allocates only when that changes).
NcpError ComputeNcpError(const NcpProblem& problem, const Eigen::VectorXd& z, Eigen::VectorXd* raw_rows);

}  // namespace implicit_sim
