#include "implicit_sim/core/ncp_solver.h"

#include <algorithm>
#include <cmath>

namespace implicit_sim {

bool NewtonOptions::IsValid(std::string* error) const {
  if (!(tolerance > 0.0 && tolerance < 1.0)) {
    *error = "solver tolerance must be in (0, 1), got " + std::to_string(tolerance);
    return false;
  }
  if (max_iterations < 1 || max_iterations > 100000) {
    *error = "solver max_iterations must be in [1, 100000], got " + std::to_string(max_iterations);
    return false;
  }
  if (!(lm_damping >= 0.0 && lm_damping < 1.0)) {
    *error = "solver lm_damping must be in [0, 1), got " + std::to_string(lm_damping);
    return false;
  }
  return true;
}

SemismoothNewton::SemismoothNewton(int n)
    : J_(n, n), normal_(n, n), Phi_(n), Phi_trial_(n), z_trial_(n), rhs_(n), dz_(n), ldlt_(n) {}

NewtonResult SemismoothNewton::Solve(StepProblem* problem, const NewtonOptions& options, Eigen::VectorXd* z) {
  NewtonResult result;
  problem->Evaluate(*z, &Phi_, &J_);
  double merit = 0.5 * Phi_.squaredNorm();
  // Relative part: rows such as a1 - a2 - d n carry coordinates, whose rounding error grows with their size.
  const auto tolerance = [&]() { return options.tolerance * (1.0 + z->lpNorm<Eigen::Infinity>()); };
  for (result.iterations = 0; result.iterations < options.max_iterations; ++result.iterations) {
    result.residual = std::sqrt(2.0 * merit);
    if (!std::isfinite(merit)) break;
    if (result.residual <= tolerance()) {
      result.converged = true;
      return result;
    }
    // Levenberg-Marquardt direction: (J^T J + lambda I) dz = -J^T Phi.
    normal_.setZero();
    normal_.selfadjointView<Eigen::Lower>().rankUpdate(J_.transpose());  // lower triangle of J^T J: half the work
    normal_.diagonal().array() += options.lm_damping * std::max(1.0, merit);
    rhs_.noalias() = -J_.transpose() * Phi_;
    ldlt_.compute(normal_);
    dz_ = ldlt_.solve(rhs_);
    if (!dz_.allFinite()) break;
    // Armijo backtracking on the merit 0.5 |Phi|^2.
    double step = 1.0, trial_merit = merit;
    while (step >= options.min_step) {
      z_trial_ = *z + step * dz_;
      problem->Evaluate(z_trial_, &Phi_trial_, nullptr);
      trial_merit = 0.5 * Phi_trial_.squaredNorm();
      if (std::isfinite(trial_merit) && trial_merit <= merit * (1.0 - 2.0 * options.armijo * step)) break;
      step *= 0.5;
    }
    if (step < options.min_step) break;  // no decrease along dz: stalled (Phi_ still belongs to *z)
    z->swap(z_trial_);
    problem->Evaluate(*z, &Phi_, &J_);
    merit = 0.5 * Phi_.squaredNorm();
  }
  result.residual = std::sqrt(2.0 * merit);
  result.converged = std::isfinite(merit) && result.residual <= tolerance();
  return result;
}

}  // namespace implicit_sim
