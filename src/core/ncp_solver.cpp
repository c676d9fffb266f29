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
  if (!(sparse_regularization >= 0.0 && sparse_regularization < 1.0)) {
    *error = "solver sparse_regularization must be in [0, 1), got " + std::to_string(sparse_regularization);
    return false;
  }
  if (!(lm_damping >= 0.0 && lm_damping < 1.0)) {
    *error = "solver lm_damping must be in [0, 1), got " + std::to_string(lm_damping);
    return false;
  }
  return true;
}

SemismoothNewton::SemismoothNewton(int n, bool sparse) : sparse_(sparse) { Resize(n); }

void SemismoothNewton::Resize(int n) {
  if (Phi_.size() == n) return;
  if (!sparse_) {
    J_.resize(n, n);
    normal_.resize(n, n);
    ldlt_ = Eigen::LDLT<Eigen::MatrixXd>(n);
  }
  Phi_.resize(n);
  Phi_trial_.resize(n);
  z_trial_.resize(n);
  rhs_.resize(n);
  dz_.resize(n);
}

void SemismoothNewton::Evaluate(StepProblem* problem, const NewtonOptions& options, const Eigen::VectorXd& z,
                                bool jacobian) {
  if (!jacobian) {
    problem->Evaluate(z, &Phi_, nullptr);
  } else if (sparse_) {
    problem->set_jacobian_regularization(options.sparse_regularization);
    problem->EvaluateSparse(z, &Phi_, &J_sparse_);
    problem->set_jacobian_regularization(0.0);
  } else {
    problem->Evaluate(z, &Phi_, &J_);
  }
}

bool SemismoothNewton::Direction(const NewtonOptions& options, double merit) {
  if (!sparse_) {
    // Levenberg-Marquardt direction: (J^T J + lambda I) dz = -J^T Phi.
    normal_.setZero();
    normal_.selfadjointView<Eigen::Lower>().rankUpdate(J_.transpose());  // lower triangle of J^T J: half the work
    normal_.diagonal().array() += options.lm_damping * std::max(1.0, merit);
    rhs_.noalias() = -J_.transpose() * Phi_;
    ldlt_.compute(normal_);
    dz_ = ldlt_.solve(rhs_);
    return dz_.allFinite();
  }
  const Eigen::SparseMatrix<double>& J = J_sparse_.matrix;
  if (lu_.Factorize(J, J_sparse_.pattern_version)) {
    dz_ = -Phi_;
    if (lu_.Solve(&dz_) && dz_.allFinite()) return true;
  }
  // The LU failed (a structurally singular Jacobian): the Levenberg-Marquardt normal equations instead.
  ++lm_fallbacks_;
  normal_sparse_ = J.transpose() * J;
  for (int i = 0; i < normal_sparse_.rows(); ++i) normal_sparse_.coeffRef(i, i) += options.lm_damping * std::max(1.0, merit);
  rhs_ = -(J.transpose() * Phi_);
  sparse_ldlt_.compute(normal_sparse_);
  if (sparse_ldlt_.info() != Eigen::Success) return false;
  dz_ = sparse_ldlt_.solve(rhs_);
  return dz_.allFinite();
}

NewtonResult SemismoothNewton::Solve(StepProblem* problem, const NewtonOptions& options, Eigen::VectorXd* z) {
  NewtonResult result;
  Resize(problem->size());
  Evaluate(problem, options, *z, true);
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
    if (!Direction(options, merit)) break;
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
    Evaluate(problem, options, *z, true);
    merit = 0.5 * Phi_.squaredNorm();
  }
  result.residual = std::sqrt(2.0 * merit);
  result.converged = std::isfinite(merit) && result.residual <= tolerance();
  return result;
}

}  // namespace implicit_sim
