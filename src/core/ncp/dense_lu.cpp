#include "implicit_sim/core/ncp/dense_lu.h"

#include <utility>

namespace implicit_sim {

void DenseLu::Factorize(const Eigen::MatrixXd& A) {
  lu_ = A;
  finite_ = lu_.allFinite();
  norm1_ = lu_.rows() ? lu_.cwiseAbs().colwise().sum().maxCoeff() : 0.0;
  const Eigen::Index n = lu_.rows();
  row_swaps_.resize(n);
  below_.resize(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    Eigen::Index pivot_row = 0;
    lu_.col(k).tail(n - k).cwiseAbs().maxCoeff(&pivot_row);
    pivot_row += k;
    row_swaps_[k] = static_cast<int>(pivot_row);
    if (pivot_row != k) lu_.row(k).swap(lu_.row(pivot_row));
    const double pivot = lu_(k, k);
    if (pivot == 0.0) continue;  // an exactly singular column: nothing to eliminate with
    // The multipliers below the pivot, and the rows they reach: a contact Jacobian is mostly zeros, and skipping them
    // changes no arithmetic that is done.
    int reached = 0;
    for (Eigen::Index i = k + 1; i < n; ++i) {
      if (lu_(i, k) == 0.0) continue;
      lu_(i, k) /= pivot;
      below_[reached++] = static_cast<int>(i);
    }
    if (reached == 0) continue;
    for (Eigen::Index j = k + 1; j < n; ++j) {
      const double u = lu_(k, j);
      if (u == 0.0) continue;
      for (int r = 0; r < reached; ++r) lu_(below_[r], j) -= lu_(below_[r], k) * u;
    }
  }
}

double DenseLu::PivotRatio() const {
  if (!finite_) return 0.0;
  if (lu_.rows() == 0) return 1.0;
  const auto pivots = lu_.diagonal().cwiseAbs();
  const double largest = pivots.maxCoeff();
  return largest > 0.0 ? pivots.minCoeff() / largest : 0.0;
}

double DenseLu::ConditionEstimate() {
  // Hager's estimate of |A^-1|_1 (Higham, Accuracy and Stability of Numerical Algorithms, Algorithm 15.4): at most
  // five pairs of solves with A and A^T, climbing to the column of A^-1 with the largest 1-norm.
  const Eigen::Index n = lu_.rows();
  if (n == 0) return 1.0;
  if (!finite_ || norm1_ == 0.0) return 0.0;
  x_.setConstant(n, 1.0 / static_cast<double>(n));
  double inverse_norm = 0.0;
  Eigen::Index last_column = -1;
  for (int iteration = 0; iteration < 5; ++iteration) {
    y_ = x_;
    Solve(&y_);
    if (!y_.allFinite()) return 0.0;
    inverse_norm = y_.lpNorm<1>();
    z_ = y_.unaryExpr([](double v) { return v >= 0.0 ? 1.0 : -1.0; });
    SolveTransposed(&z_);
    Eigen::Index column = 0;
    const double largest = z_.cwiseAbs().maxCoeff(&column);
    if (column == last_column || largest <= z_.dot(x_)) break;
    x_.setZero();
    x_[column] = 1.0;
    last_column = column;
  }
  return inverse_norm > 0.0 ? 1.0 / (norm1_ * inverse_norm) : 0.0;
}

void DenseLu::SolveTransposed(Eigen::VectorXd* b) const {
  // A^T = U^T L^T P: solve with U^T, then L^T, then undo the row swaps in reverse order.
  lu_.triangularView<Eigen::Upper>().transpose().solveInPlace(*b);
  lu_.triangularView<Eigen::UnitLower>().transpose().solveInPlace(*b);
  for (Eigen::Index k = lu_.rows() - 1; k >= 0; --k) {
    if (row_swaps_[k] != k) std::swap((*b)[k], (*b)[row_swaps_[k]]);
  }
}

void DenseLu::Solve(Eigen::VectorXd* b) const {
  for (Eigen::Index k = 0; k < lu_.rows(); ++k) {
    if (row_swaps_[k] != k) std::swap((*b)[k], (*b)[row_swaps_[k]]);
  }
  lu_.triangularView<Eigen::UnitLower>().solveInPlace(*b);
  lu_.triangularView<Eigen::Upper>().solveInPlace(*b);
}

}  // namespace implicit_sim
