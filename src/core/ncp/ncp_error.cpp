#include "implicit_sim/core/ncp/ncp_error.h"

#include <algorithm>
#include <cmath>

namespace implicit_sim {

NcpError ComputeNcpError(const NcpProblem& problem, const Eigen::VectorXd& z, Eigen::VectorXd* raw_rows) {
  NcpEvalMode raw;
  raw.raw = true;  // complementarity rows give b(z); the variable side a is scale * z[i]
  problem.Evaluate(z, raw, raw_rows, nullptr);
  NcpError error;
  for (int i = 0; i < problem.size(); ++i) {
    double scale;
    if (problem.IsComplementarityRow(i, &scale)) {
      error.complementarity = std::max(error.complementarity, std::abs(std::min(scale * z[i], (*raw_rows)[i])));
    } else {
      error.equations = std::max(error.equations, std::abs((*raw_rows)[i]));
    }
  }
  return error;
}

}  // namespace implicit_sim
