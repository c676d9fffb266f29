// The Fischer-Burmeister reformulation of a complementarity pair 0 <= a _|_ b >= 0 as FB(a, b) = 0, for the rows of
// an NcpProblem (ncp_problem.h).
#pragma once

#include <cmath>

namespace implicit_sim {

// Fischer-Burmeister function and an element of its generalized Jacobian (at a = b = 0 any point of the
// subdifferential works; we take the one on the diagonal).
struct FB {
  double value, da, db;
};
// With raw = true, b and its derivative instead (NcpEvalMode::raw).
// With smoothing mu > 0: a + b - sqrt(a^2 + b^2 + 2 mu^2), smooth everywhere, whose root set a, b > 0, a b = mu^2
// tends to the complementarity set as mu -> 0 (smoothing continuation, Chen-Harker-Kanzow-Smale).
inline FB FischerBurmeister(double a, double b, double mu, bool raw) {
  if (raw) return {b, 0.0, 1.0};  // the complementarity function b itself (for the Ipopt formulation)
  const double r = std::sqrt(a * a + b * b + 2.0 * mu * mu);
  if (r < 1e-14) return {a + b - r, 1.0 - 1.0 / std::sqrt(2.0), 1.0 - 1.0 / std::sqrt(2.0)};
  return {a + b - r, 1.0 - a / r, 1.0 - b / r};
}

}  // namespace implicit_sim
