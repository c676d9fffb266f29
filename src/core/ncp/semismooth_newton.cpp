#include "implicit_sim/core/ncp/semismooth_newton.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace implicit_sim {
namespace {

// From this many unknowns a singular dense J's direction comes from the column-pivoting QR (see Direction).
constexpr Eigen::Index kColumnQrMinSize = 128;

}  // namespace

SemismoothNewton::SemismoothNewton(int n, bool sparse) : sparse_(sparse) { Resize(n); }

void SemismoothNewton::Resize(int n) {
  if (Phi_.size() == n) return;
  if (!sparse_) {
    J_.resize(n, n);
    normal_.resize(n, n);
    lu_singular_ = Eigen::PartialPivLU<Eigen::MatrixXd>(n);
    // Only the singular direction's factorization that this size uses (see Direction).
    if (n < kColumnQrMinSize) full_lu_.Reserve(n);
    column_qr_ = n < kColumnQrMinSize ? Eigen::ColPivHouseholderQR<Eigen::MatrixXd>()
                                      : Eigen::ColPivHouseholderQR<Eigen::MatrixXd>(n, n);
    ldlt_ = Eigen::LDLT<Eigen::MatrixXd>(n);
  }
  Phi_.resize(n);
  Phi_trial_.resize(n);
  z_trial_.resize(n);
  rhs_.resize(n);
  dz_.resize(n);
}

void SemismoothNewton::Evaluate(const NcpProblem& problem, const Eigen::VectorXd& z, bool jacobian) {
  ++summary_->residual_evaluations;
  if (!jacobian) {
    problem.Evaluate(z, mode_, &Phi_, nullptr);
    return;
  }
  if (sparse_) {
    problem.EvaluateSparse(z, mode_, &Phi_, &J_sparse_);
  } else {
    problem.Evaluate(z, mode_, &Phi_, &J_);
  }
}

bool SemismoothNewton::CondensedDirection(const Eigen::SparseMatrix<double>& J) {
  // The condensed LU works with each closest-point block's explicit inverse, which loses digits where a block is ill
  // conditioned (a nearly flat patch, a nearly degenerate normal cone): its direction is checked by its linear
  // residual, refined once, and left to the LU of the whole matrix if still inaccurate.
  constexpr double kRelativeLinearResidual = 1e-8;
  dz_ = -Phi_;
  ++summary_->solves;
  if (!condensed_lu_.Solve(&dz_)) return false;
  const double bound = kRelativeLinearResidual * Phi_.norm();
  for (int refinement = 0;; ++refinement) {
    rhs_.noalias() = J * dz_;
    rhs_ += Phi_;  // the linear residual J dz + Phi
    const double residual = rhs_.norm();
    if (!std::isfinite(residual)) return false;
    if (residual <= bound) return true;
    if (refinement == 1) return false;
    rhs_ = -rhs_;
    ++summary_->solves;
    if (!condensed_lu_.Solve(&rhs_)) return false;
    dz_ += rhs_;
  }
}

namespace {

constexpr double kConditionBound = 1e-13;  // a reciprocal condition number below it counts as singular

bool DenseLuNearlySingular(DenseLu* lu) {
  // The condition estimate runs several triangular solves (a fifth of a small scene's step). A (numerically) singular
  // matrix leaves a tiny pivot, so where the pivots span less than 1e6 the estimate is skipped: every such matrix among
  // the 1.2 million dense factorizations of test_core passed it (bench/README.md).
  return lu->PivotRatio() < 1e-6 && !(lu->ConditionEstimate() > kConditionBound);
}

}  // namespace

bool SemismoothNewton::Direction(const NewtonOptions& options, double merit, bool least_squares) {
  const double damping = options.lm_damping * std::max(1.0, merit);
  if (!sparse_) {
    if (!least_squares) {
      // The Newton direction J dz = -Phi by LU with partial pivoting. (The LM normal equations alone square J's
      // condition number, which grows as 1/h; doc/method.md, pitfall 8.)
      // Our LU skips the zeros of these mostly-zero matrices (DenseLu).
      lu_dense_.Factorize(J_);
      ++summary_->factorizations;
      ++summary_->solves;
      if (!DenseLuNearlySingular(&lu_dense_)) {
        dz_ = -Phi_;
        lu_dense_.Solve(&dz_);
        return dz_.allFinite();
      }
      // Singular in exact arithmetic (a flat face's free closest points): Eigen's blocked LU leaves round-off where
      // ours has exact zeros, and its estimate often passes such a J. Its direction is kept where it does (the
      // grippers' box contacts take fewer cold restarts with it than with a direction that leaves them unmoved).
      lu_singular_.compute(J_);
      ++summary_->factorizations;
      if (lu_singular_.rcond() > kConditionBound) {
        dz_.noalias() = lu_singular_.solve(-Phi_);
        return dz_.allFinite();
      }
      // A (numerically) singular J, such as a planar body's line contact or a flat face on a floor gives: its LU
      // direction would be huge and exhaust the line search. A rank-revealing factorization's basic solution leaves the
      // unknowns it finds undetermined where they are: the fully pivoted LU's on small islands, the column-pivoting
      // QR's on large ones, where the LU's search over the whole matrix dominated the step (bench/README.md).
      ++summary_->factorizations;
      if (J_.rows() < kColumnQrMinSize) {
        full_lu_.Factorize(J_);
        rhs_ = -Phi_;
        full_lu_.Solve(rhs_, &dz_);
      } else {
        column_qr_.compute(J_);
        dz_.noalias() = column_qr_.solve(-Phi_);
      }
      return dz_.allFinite();
    }
    // Levenberg-Marquardt: (J^T J + lambda I) dz = -J^T Phi.
    normal_.setZero();
    normal_.selfadjointView<Eigen::Lower>().rankUpdate(J_.transpose());  // lower triangle of J^T J: half the work
    normal_.diagonal().array() += damping;
    rhs_.noalias() = -J_.transpose() * Phi_;
    ldlt_.compute(normal_);
    ++summary_->factorizations;
    ++summary_->solves;
    dz_ = ldlt_.solve(rhs_);
    return dz_.allFinite();
  }
  const Eigen::SparseMatrix<double>& J = J_sparse_.matrix;
  if (!least_squares) {
    if (condense_) {
      ++summary_->factorizations;
      if (condensed_lu_.Factorize(J, J_sparse_.pattern_version()) && CondensedDirection(J)) return true;
    }
    ++summary_->factorizations;
    if (!lu_.Factorize(J, J_sparse_.pattern_version())) return false;
    ++summary_->solves;
    dz_ = -Phi_;
    return lu_.Solve(&dz_) && dz_.allFinite();
  }
  normal_sparse_ = J.transpose() * J;
  for (int i = 0; i < normal_sparse_.rows(); ++i) normal_sparse_.coeffRef(i, i) += damping;
  rhs_ = -(J.transpose() * Phi_);
  sparse_ldlt_.compute(normal_sparse_);
  ++summary_->factorizations;
  if (sparse_ldlt_.info() != Eigen::Success) return false;
  ++summary_->solves;
  dz_ = sparse_ldlt_.solve(rhs_);
  return dz_.allFinite();
}

double SemismoothNewton::LineSearch(const NcpProblem& problem, const NewtonOptions& options,
                                    const Eigen::VectorXd& z, double merit) {
  // Armijo backtracking on the merit 0.5 |Phi|^2 against the largest of the last line_search_memory merits
  // (Grippo-Lampariello-Lucidi; memory 1 is the monotone search); the accepted point is left in z_trial_. The
  // directional derivative of the merit along a Newton direction is -|Phi|^2 = -2 merit.
  double reference = merit;
  for (int i = 0; i < std::min(history_count_, options.line_search_memory); ++i) {
    reference = std::max(reference, history_[(history_next_ + kMaxMemory - 1 - i) % kMaxMemory]);
  }
  // Only the exact problem's solutions lie on the retraction's set (a proximal or smoothed one's need not).
  const bool retract = options.retract_sliding && sparse_ && mode_.smoothing == 0.0 && mode_.proximal_weight == 0.0;
  for (double step = 1.0; step >= options.min_step; step *= 0.5) {
    z_trial_ = z + step * dz_;
    if (retract) problem.Retract(z, &z_trial_);
    ++summary_->residual_evaluations;
    problem.Evaluate(z_trial_, mode_, &Phi_trial_, nullptr);
    const double trial_merit = 0.5 * Phi_trial_.squaredNorm();
    const double bound = options.line_search_memory > 1 ? reference - 2.0 * options.armijo * step * merit
                                                        : merit * (1.0 - 2.0 * options.armijo * step);
    if (std::isfinite(trial_merit) && trial_merit <= bound) return step;
  }
  return 0.0;
}

bool SemismoothNewton::Stalled(const NewtonOptions& options, int iteration) const {
  constexpr double kStallRatio = 0.9;
  const int window = options.stall_window;
  if (window <= 0 || iteration < window) return false;
  const auto begin = residuals_.begin();
  const double before = *std::min_element(begin, begin + iteration - window + 1);
  const double recent = *std::min_element(begin + iteration - window + 1, begin + iteration + 1);
  return recent > kStallRatio * before;
}

void SemismoothNewton::RememberMerit(double merit) {
  history_[history_next_] = merit;
  history_next_ = (history_next_ + 1) % kMaxMemory;
  history_count_ = std::min(history_count_ + 1, kMaxMemory);
}

void SemismoothNewton::BeginSolve(const NcpProblem& problem, const NewtonOptions& options, double smoothing,
                                  NcpSummary* summary) {
  summary_ = summary;
  mode_ = NcpEvalMode();
  mode_.smoothing = smoothing;
  mode_.project_multipliers = options.project_multipliers;
  mode_.proximal_weight = options.proximal_center ? options.proximal_weight : 0.0;
  mode_.proximal_center = options.proximal_center;
  mode_.regularization = options.sparse_regularization;
  Resize(problem.size());
  if (sparse_) lu_.ForgetPivots();  // a solve depends on its inputs only
  condense_ = false;
  if (sparse_ && options.condense_blocks) {
    problem.CondensableBlocks(&block_starts_, &block_indices_);
    condensed_lu_.SetBlocks(block_starts_, block_indices_);
    condensed_lu_.ForgetPivots();
    condense_ = condensed_lu_.has_blocks();
  }
  history_count_ = history_next_ = 0;
  // Grows once to the largest iteration limit (a warm step allocates nothing).
  if (options.stall_window > 0 && static_cast<int>(residuals_.size()) < options.max_iterations) {
    residuals_.resize(options.max_iterations);
  }
  if (options.trace) ++options.trace->solves;
}

bool SemismoothNewton::Step(const NcpProblem& problem, const NewtonOptions& options, double merit, int iteration,
                            Eigen::VectorXd* z) {
  RememberMerit(merit);
  NewtonTraceRow row{options.trace ? options.trace->solves - 1 : 0, iteration, mode_.smoothing, std::sqrt(2.0 * merit)};
  if (options.trace) {
    Eigen::Index largest = 0;
    row.largest_row = Phi_.size() ? Phi_.cwiseAbs().maxCoeff(&largest) : 0.0;
    row.largest_row_index = static_cast<int>(largest);
    row.rows_above_floor = static_cast<int>((Phi_.array().abs() > 1e-13).count());
  }
  // The LU direction first; where J is singular, the Levenberg-Marquardt one, a descent direction whenever
  // J^T Phi != 0. In dense mode also where the LU direction does not decrease the merit; in sparse mode that is
  // left to the retry ladder, because J^T J fills in (the 1000-gon's body couples to all its 1000 multipliers).
  const bool lu_ok = Direction(options, merit, false);
  double step = lu_ok ? LineSearch(problem, options, *z, merit) : 0.0;
  const bool least_squares = step == 0.0 && (!lu_ok || !sparse_);
  if (least_squares) {
    ++lm_fallbacks_;
    ++summary_->lm_fallbacks;
    if (Direction(options, merit, true)) step = LineSearch(problem, options, *z, merit);
  }
  if (options.trace) {
    row.step = step;
    row.least_squares = least_squares;
    Eigen::Index largest = 0;
    row.largest_move = dz_.size() ? dz_.cwiseAbs().maxCoeff(&largest) : 0.0;
    row.largest_move_index = static_cast<int>(largest);
    options.trace->rows.push_back(row);
  }
  if (step == 0.0) return false;  // no decrease: stalled (Phi_ still belongs to *z)
  z->swap(z_trial_);
  return true;
}

NcpSummary SemismoothNewton::Solve(const NcpProblem& problem, const NewtonOptions& options, Eigen::VectorXd* z,
                                   double smoothing) {
  NcpSummary summary;
  BeginSolve(problem, options, smoothing, &summary);
  // delta enters the Jacobian only, never Phi; the first one from the residual at the start.
  if (options.residual_regularization > 0.0) {
    Evaluate(problem, *z, false);
    mode_.regularization += options.residual_regularization * Phi_.norm();
  }
  Evaluate(problem, *z, true);
  double merit = 0.5 * Phi_.squaredNorm();
  // Relative part: rows such as a1 - a2 - d n carry coordinates, whose rounding error grows with their size.
  const auto tolerance = [&]() { return options.tolerance * (1.0 + z->lpNorm<Eigen::Infinity>()); };
  summary.termination = NcpTermination::kMaxIterations;
  for (summary.iterations = 0; summary.iterations < options.max_iterations; ++summary.iterations) {
    summary.residual = std::sqrt(2.0 * merit);
    if (!std::isfinite(merit)) {
      summary.termination = NcpTermination::kNonFinite;
      break;
    }
    if (summary.residual <= tolerance()) break;
    if (options.stall_window > 0) residuals_[summary.iterations] = summary.residual;
    if (Stalled(options, summary.iterations)) {
      summary.termination = NcpTermination::kStalled;
      break;
    }
    if (InterruptDue(options.interrupt)) {
      summary.termination = NcpTermination::kInterrupted;
      break;
    }
    if (!Step(problem, options, merit, summary.iterations, z)) {
      summary.termination = NcpTermination::kNoDescent;
      break;
    }
    // The new Jacobian's delta from the last residual (Phi and J come from one evaluation).
    mode_.regularization = options.sparse_regularization + options.residual_regularization * std::sqrt(2.0 * merit);
    Evaluate(problem, *z, true);
    merit = 0.5 * Phi_.squaredNorm();
  }
  summary.residual = std::sqrt(2.0 * merit);
  summary.converged = std::isfinite(merit) && summary.residual <= tolerance();
  if (summary.converged) summary.termination = NcpTermination::kConverged;
  summary_ = nullptr;
  return summary;
}

NcpSummary SemismoothNewton::FollowSmoothingPath(const NcpProblem& problem, const NewtonOptions& options,
                                                 const PathOptions& path, Eigen::VectorXd* z) {
  NcpSummary summary;
  BeginSolve(problem, options, 0.0, &summary);
  Evaluate(problem, *z, false);
  double exact_residual = Phi_.lpNorm<Eigen::Infinity>();
  double mu = std::min(path.initial_smoothing, exact_residual);
  double reached = std::numeric_limits<double>::quiet_NaN();  // the last level whose neighbourhood was reached
  int level_steps = 0;
  bool raised = false;
  while (std::isfinite(exact_residual) && mu > path.final_smoothing && exact_residual > path.switch_residual) {
    mode_.smoothing = mu;
    Evaluate(problem, *z, true);
    const double level_residual = Phi_.lpNorm<Eigen::Infinity>();
    if (!std::isfinite(level_residual)) break;
    if (level_residual <= path.neighbourhood * mu) {  // in the level's neighbourhood: the next, smaller mu
      mode_.smoothing = 0.0;
      Evaluate(problem, *z, false);
      exact_residual = Phi_.lpNorm<Eigen::Infinity>();
      reached = mu;
      // Superlinear where the residual allows it, but at most 10x a level: a larger cut leaves the iterate outside
      // the next level's neighbourhood, where Newton on the smoothed rows stalls as it does on the exact ones.
      mu = std::max(path.max_reduction * mu, std::min(0.2 * mu, std::pow(level_residual, 1.5)));
      level_steps = 0;
      raised = false;
      history_count_ = history_next_ = 0;  // the merits of another level do not compare
      continue;
    }
    if (summary.path_iterations == path.max_iterations || InterruptDue(options.interrupt)) break;
    if (level_steps == path.steps_per_level) {  // the level is too tight for this iterate: widen it once
      if (raised) break;                         // or, widened, still not reached: leave the path
      mu *= 2.0;
      raised = true;
      level_steps = 0;
      history_count_ = history_next_ = 0;
      continue;
    }
    if (!Step(problem, options, 0.5 * Phi_.squaredNorm(), summary.path_iterations, z)) break;
    ++summary.path_iterations;
    ++level_steps;
  }
  summary.switch_smoothing = reached;
  mode_.smoothing = 0.0;
  Evaluate(problem, *z, false);
  summary.switch_residual = Phi_.lpNorm<Eigen::Infinity>();
  NewtonOptions polish = options;
  polish.max_iterations = path.polish_iterations;
  NcpSummary exact = Solve(problem, polish, z);
  exact.iterations += summary.path_iterations;
  exact.path_iterations = summary.path_iterations;
  exact.residual_evaluations += summary.residual_evaluations;
  exact.factorizations += summary.factorizations;
  exact.solves += summary.solves;
  exact.lm_fallbacks += summary.lm_fallbacks;
  exact.switch_smoothing = summary.switch_smoothing;
  exact.switch_residual = summary.switch_residual;
  return exact;
}

}  // namespace implicit_sim
