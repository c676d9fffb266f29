#include "implicit_sim/core/ncp/semismooth_newton.h"

#include "implicit_sim/core/base/format.h"

#include <algorithm>
#include <cmath>

namespace implicit_sim {

bool NewtonOptions::IsValid(std::string* error) const {
  if (!(tolerance > 0.0 && tolerance < 1.0)) {
    *error = "solver tolerance must be in (0, 1), got " + FormatNumber(tolerance);
    return false;
  }
  if (max_iterations < 1 || max_iterations > 100000) {
    *error = "solver max_iterations must be in [1, 100000], got " + std::to_string(max_iterations);
    return false;
  }
  if (!(sparse_regularization >= 0.0 && sparse_regularization < 1.0)) {
    *error = "solver sparse_regularization must be in [0, 1), got " + FormatNumber(sparse_regularization);
    return false;
  }
  if (!(lm_damping >= 0.0 && lm_damping < 1.0)) {
    *error = "solver lm_damping must be in [0, 1), got " + FormatNumber(lm_damping);
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
    lu_dense_ = Eigen::PartialPivLU<Eigen::MatrixXd>(n);
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
    return;
  }
  problem->set_jacobian_regularization(options.sparse_regularization);
  if (sparse_) {
    problem->EvaluateSparse(z, &Phi_, &J_sparse_);
  } else {
    problem->Evaluate(z, &Phi_, &J_);
  }
  problem->set_jacobian_regularization(0.0);
}

bool SemismoothNewton::Direction(const NewtonOptions& options, double merit, bool least_squares) {
  const double damping = options.lm_damping * std::max(1.0, merit);
  if (!sparse_) {
    if (!least_squares) {
      // The Newton direction J dz = -Phi by LU with partial pivoting. (The LM normal equations alone square J's
      // condition number, which grows as 1/h: P3 at h = 0.001 stalled at |Phi| = 1e-7 in its first steps.)
      lu_dense_.compute(J_);
      // A (numerically) singular J, such as the locked axes of the planar disc give: no Newton direction. (Its LU
      // direction would be huge and send the line search through 33 halvings before the LM direction is tried.)
      if (!(lu_dense_.rcond() > 1e-13)) return false;
      dz_.noalias() = lu_dense_.solve(-Phi_);
      return dz_.allFinite();
    }
    // Levenberg-Marquardt: (J^T J + lambda I) dz = -J^T Phi.
    normal_.setZero();
    normal_.selfadjointView<Eigen::Lower>().rankUpdate(J_.transpose());  // lower triangle of J^T J: half the work
    normal_.diagonal().array() += damping;
    rhs_.noalias() = -J_.transpose() * Phi_;
    ldlt_.compute(normal_);
    dz_ = ldlt_.solve(rhs_);
    return dz_.allFinite();
  }
  const Eigen::SparseMatrix<double>& J = J_sparse_.matrix;
  if (!least_squares) {
    if (!lu_.Factorize(J, J_sparse_.pattern_version)) return false;
    dz_ = -Phi_;
    return lu_.Solve(&dz_) && dz_.allFinite();
  }
  normal_sparse_ = J.transpose() * J;
  for (int i = 0; i < normal_sparse_.rows(); ++i) normal_sparse_.coeffRef(i, i) += damping;
  rhs_ = -(J.transpose() * Phi_);
  sparse_ldlt_.compute(normal_sparse_);
  if (sparse_ldlt_.info() != Eigen::Success) return false;
  dz_ = sparse_ldlt_.solve(rhs_);
  return dz_.allFinite();
}

double SemismoothNewton::LineSearch(StepProblem* problem, const NewtonOptions& options, const Eigen::VectorXd& z,
                                    double merit) {
  // Armijo backtracking on the merit 0.5 |Phi|^2; the accepted point is left in z_trial_.
  for (double step = 1.0; step >= options.min_step; step *= 0.5) {
    z_trial_ = z + step * dz_;
    problem->Evaluate(z_trial_, &Phi_trial_, nullptr);
    const double trial_merit = 0.5 * Phi_trial_.squaredNorm();
    if (std::isfinite(trial_merit) && trial_merit <= merit * (1.0 - 2.0 * options.armijo * step)) return step;
  }
  return 0.0;
}

NewtonResult SemismoothNewton::Solve(StepProblem* problem, const NewtonOptions& options, Eigen::VectorXd* z) {
  NewtonResult result;
  Resize(problem->size());
  if (sparse_) lu_.ForgetPivots();  // a solve depends on its inputs only
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
    // The LU direction first; where J is singular, the Levenberg-Marquardt one, a descent direction whenever
    // J^T Phi != 0. In dense mode also where the LU direction does not decrease the merit; in sparse mode that is
    // left to the retry ladder, because J^T J fills in (the 1000-gon's body couples to all its 1000 multipliers).
    const bool lu_ok = Direction(options, merit, false);
    bool accepted = lu_ok && LineSearch(problem, options, *z, merit) > 0.0;
    if (!accepted && (!lu_ok || !sparse_)) {
      ++lm_fallbacks_;
      accepted = Direction(options, merit, true) && LineSearch(problem, options, *z, merit) > 0.0;
    }
    if (!accepted) break;  // no decrease: stalled (Phi_ still belongs to *z)
    z->swap(z_trial_);
    Evaluate(problem, options, *z, true);
    merit = 0.5 * Phi_.squaredNorm();
  }
  result.residual = std::sqrt(2.0 * merit);
  result.converged = std::isfinite(merit) && result.residual <= tolerance();
  return result;
}

}  // namespace implicit_sim
