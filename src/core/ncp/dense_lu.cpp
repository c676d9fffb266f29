#include "implicit_sim/core/ncp/dense_lu.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace implicit_sim {
namespace {

// Both LUs skip zeros: a contact Jacobian is mostly zeros, and skipping them changes no arithmetic that is done.

// Divides the nonzero entries below the pivot (k, k) of *lu by it and lists their rows in *below; returns how many.
int ScaleBelowPivot(Eigen::MatrixXd* lu, Eigen::Index k, Eigen::VectorXi* below) {
  const double pivot = (*lu)(k, k);
  int reached = 0;
  for (Eigen::Index i = k + 1; i < lu->rows(); ++i) {
    if ((*lu)(i, k) == 0.0) continue;
    (*lu)(i, k) /= pivot;
    (*below)[reached++] = static_cast<int>(i);
  }
  return reached;
}

// Eliminates column j's entries in the `reached` rows listed in `below` with the multipliers of column k.
void EliminateColumn(Eigen::MatrixXd* lu, Eigen::Index k, Eigen::Index j, const Eigen::VectorXi& below, int reached) {
  const double u = (*lu)(k, j);
  for (int r = 0; r < reached; ++r) (*lu)(below[r], j) -= (*lu)(below[r], k) * u;
}

}  // namespace

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
    if (lu_(k, k) == 0.0) continue;  // an exactly singular column: nothing to eliminate with
    const int reached = ScaleBelowPivot(&lu_, k, &below_);
    if (reached == 0) continue;
    for (Eigen::Index j = k + 1; j < n; ++j) {
      if (lu_(k, j) != 0.0) EliminateColumn(&lu_, k, j, below_, reached);
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

void CompletePivotLu::UpdateColumnMax(Eigen::Index j, Eigen::Index first_row) {
  double largest = -1.0;
  Eigen::Index row = first_row;
  for (Eigen::Index i = first_row; i < lu_.rows(); ++i) {
    const double magnitude = std::abs(lu_(i, j));
    if (magnitude > largest) {  // the first of equal magnitudes, as Eigen's maxCoeff
      largest = magnitude;
      row = i;
    }
  }
  column_max_[j] = largest;
  column_max_row_[j] = static_cast<int>(row);
}

void CompletePivotLu::Reserve(int n) {
  lu_.resize(n, n);
  row_swaps_.resize(n);
  column_swaps_.resize(n);
  below_.resize(n);
  column_max_.resize(n);
  column_max_row_.resize(n);
  if (changed_.size() != n) changed_.setZero(n);
  c_.resize(n);
}

void CompletePivotLu::Factorize(const Eigen::MatrixXd& A) {
  lu_ = A;
  finite_ = lu_.allFinite();
  const Eigen::Index n = lu_.rows();
  Reserve(static_cast<int>(n));  // nothing to do at the size reserved
  nonzero_pivots_ = finite_ ? n : 0;
  max_pivot_ = 0.0;
  if (!finite_) return;  // no direction from a matrix that is not finite (Solve)
  for (Eigen::Index j = 0; j < n; ++j) UpdateColumnMax(j, 0);
  for (Eigen::Index k = 0; k < n; ++k) {
    // The pivot: the largest |entry| of the remaining block, the first in column-major order (Eigen's visitor).
    Eigen::Index pivot_column = k;
    for (Eigen::Index j = k + 1; j < n; ++j) {
      if (column_max_[j] > column_max_[pivot_column]) pivot_column = j;
    }
    const double biggest = column_max_[pivot_column];
    if (!(biggest > 0.0)) {  // the rest is exactly zero
      nonzero_pivots_ = k;
      for (Eigen::Index i = k; i < n; ++i) row_swaps_[i] = column_swaps_[i] = static_cast<int>(i);
      break;
    }
    const Eigen::Index pivot_row = column_max_row_[pivot_column];
    max_pivot_ = std::max(max_pivot_, biggest);
    row_swaps_[k] = static_cast<int>(pivot_row);
    column_swaps_[k] = static_cast<int>(pivot_column);
    if (pivot_row != k) lu_.row(k).swap(lu_.row(pivot_row));
    if (pivot_column != k) {
      lu_.col(k).swap(lu_.col(pivot_column));
      std::swap(column_max_[k], column_max_[pivot_column]);
      std::swap(column_max_row_[k], column_max_row_[pivot_column]);
    }
    const int reached = ScaleBelowPivot(&lu_, k, &below_);
    for (int r = 0; r < reached; ++r) changed_[below_[r]] = 1;
    for (Eigen::Index j = k + 1; j < n; ++j) {
      // Column j lost row k from its remaining rows, row pivot_row now holds what row k held, and the elimination
      // changes the reached rows if its pivot-row entry is not 0. Its maximum stands unless it was in one of those
      // rows (a maximum that row k held was the first one); a changed row may beat it, or tie with it from an earlier
      // row.
      const bool touched = reached > 0 && lu_(k, j) != 0.0;
      if (touched) EliminateColumn(&lu_, k, j, below_, reached);
      const int row = column_max_row_[j];
      if (row == k || row == pivot_row || (touched && changed_[row])) {
        UpdateColumnMax(j, k + 1);
      } else if (touched) {
        for (int r = 0; r < reached; ++r) {
          const double magnitude = std::abs(lu_(below_[r], j));
          if (magnitude > column_max_[j] || (magnitude == column_max_[j] && below_[r] < column_max_row_[j])) {
            column_max_[j] = magnitude;
            column_max_row_[j] = below_[r];
          }
        }
      }
    }
    for (int r = 0; r < reached; ++r) changed_[below_[r]] = 0;
  }
}

int CompletePivotLu::rank() const {
  // Eigen's default threshold: a pivot counts if it exceeds epsilon n times the largest.
  const double threshold = max_pivot_ * (Eigen::NumTraits<double>::epsilon() * static_cast<double>(lu_.rows()));
  int rank = 0;
  for (Eigen::Index i = 0; i < nonzero_pivots_; ++i) rank += std::abs(lu_(i, i)) > threshold;
  return rank;
}

void CompletePivotLu::Solve(const Eigen::VectorXd& b, Eigen::VectorXd* x) {
  const Eigen::Index n = lu_.rows();
  x->resize(n);
  if (!finite_) {  // no direction from a matrix that is not finite
    x->setConstant(std::numeric_limits<double>::quiet_NaN());
    return;
  }
  const int r = rank();
  if (r == 0) {
    x->setZero();
    return;
  }
  c_ = b;
  for (Eigen::Index k = 0; k < n; ++k) {
    if (row_swaps_[k] != k) std::swap(c_[k], c_[row_swaps_[k]]);
  }
  lu_.triangularView<Eigen::UnitLower>().solveInPlace(c_);
  lu_.topLeftCorner(r, r).triangularView<Eigen::Upper>().solveInPlace(c_.head(r));
  c_.tail(n - r).setZero();
  for (Eigen::Index k = n - 1; k >= 0; --k) {
    if (column_swaps_[k] != k) std::swap(c_[k], c_[column_swaps_[k]]);
  }
  *x = c_;
}

}  // namespace implicit_sim
