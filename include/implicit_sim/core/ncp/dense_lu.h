// LU with partial pivoting, right-looking and unblocked, for the Newton matrices of few-body islands (tens to a few
// hundred unknowns), which are stored dense but are mostly zeros (P3: 40 unknowns, a fifth of the entries nonzero).
// Eigen's PartialPivLU works on blocks of 8 columns and does every multiply-add; this one skips the zero multipliers
// and zero pivot-row entries, which changes no operation it does perform. The pivots are those of LAPACK's getf2
// (largest magnitude in the column). Allocates only when the size changes.
#pragma once

#include <Eigen/Core>

namespace implicit_sim {

class DenseLu {
 public:
  // P A = L U in place of a copy of A (square).
  void Factorize(const Eigen::MatrixXd& A);
  // min |u_ii| / max |u_ii| (1 for an empty matrix): 0 when A is exactly singular or not finite. With |l_ij| <= 1 a
  // ratio that is not small means A is far from singular; a small one calls for a real condition estimate.
  double PivotRatio() const;
  // An estimate of 1 / (|A|_1 |A^-1|_1), the reciprocal condition number, from the factors (a few solves; as
  // LAPACK's dgecon and Eigen's rcond()): 0 when A is singular or not finite.
  double ConditionEstimate();
  // x = A^-1 b in place.
  void Solve(Eigen::VectorXd* b) const;
  // x = A^-T b in place.
  void SolveTransposed(Eigen::VectorXd* b) const;

 private:
  Eigen::MatrixXd lu_;
  Eigen::VectorXi row_swaps_;  // at step k, row k was swapped with row row_swaps_[k] (>= k)
  Eigen::VectorXi below_;      // workspace: the rows with a nonzero multiplier in the current column
  Eigen::VectorXd x_, y_, z_;  // the condition estimate's workspace
  double norm1_ = 0.0;         // |A|_1, the largest column sum
  bool finite_ = true;
};

// LU with complete pivoting, P A Q = L U, for the basic direction of a singular Newton matrix of a few-body island: the
// unknowns past its numerical rank are left where they are (0 in the solution). It reproduces Eigen's FullPivLU
// bit for bit (the same pivots, the same arithmetic, its rank threshold and its triangular solves), and differs only in
// the work: it skips zero multipliers and zero pivot-row entries, and finds each pivot from per-column maxima that it
// updates only in the columns the elimination or the row swap touched, instead of scanning the whole remaining block.
class CompletePivotLu {
 public:
  // Allocates the workspace of an n x n matrix, so that factorizing and solving at that size allocate nothing.
  void Reserve(int n);
  void Factorize(const Eigen::MatrixXd& A);
  // The basic solution x of A x = b: rank() pivots solved, the other unknowns 0 (as FullPivLU::solve); NaN if A was
  // not finite.
  void Solve(const Eigen::VectorXd& b, Eigen::VectorXd* x);
  int rank() const;

 private:
  void UpdateColumnMax(Eigen::Index j, Eigen::Index first_row);
  Eigen::MatrixXd lu_;
  Eigen::VectorXi row_swaps_, column_swaps_;  // at step k, row / column k was swapped with this one (>= k)
  Eigen::VectorXi below_;                     // workspace: the rows with a nonzero multiplier in the current column
  Eigen::VectorXd column_max_;                // per column, the largest |entry| in the rows not yet eliminated
  Eigen::VectorXi column_max_row_;            // and its first row
  Eigen::Matrix<char, Eigen::Dynamic, 1> changed_;  // workspace: 1 for the rows the current elimination step changes
  Eigen::VectorXd c_;                         // the solve's workspace
  Eigen::Index nonzero_pivots_ = 0;
  double max_pivot_ = 0.0;
  bool finite_ = true;
};

}  // namespace implicit_sim
