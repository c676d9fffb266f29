// DenseLu against Eigen's PartialPivLU: mostly-zero random matrices (as the step's dense Jacobians are), solves with A
// and A^T, the condition estimate against the exact reciprocal condition number, singular and non-finite matrices.
// CompletePivotLu against Eigen's FullPivLU, bit for bit, on singular mostly-zero matrices with tied entries.
#include "implicit_sim/core/ncp/dense_lu.h"

#include <cmath>
#include <limits>
#include <random>

#include <Eigen/LU>
#include <gtest/gtest.h>

namespace implicit_sim {
namespace {

// n x n with about `density` of the entries nonzero and a nonzero diagonal, entries spread over `decades` powers of 10.
Eigen::MatrixXd SparseRandomMatrix(int n, double density, int decades, std::mt19937* rng) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0), coin(0.0, 1.0);
  std::uniform_int_distribution<int> exponent(0, decades);
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n, n);
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      if (i == j || coin(*rng) < density) A(i, j) = unit(*rng) * std::pow(10.0, exponent(*rng));
    }
  }
  return A;
}

double ExactReciprocalCondition(const Eigen::MatrixXd& A) {
  const double norm = A.cwiseAbs().colwise().sum().maxCoeff();
  const double inverse_norm = A.inverse().cwiseAbs().colwise().sum().maxCoeff();
  return 1.0 / (norm * inverse_norm);
}

TEST(DenseLu, SolvesLikePartialPivLuOnMostlyZeroMatrices) {
  std::mt19937 rng(7);
  DenseLu lu;
  for (int n : {1, 2, 5, 25, 40, 97}) {
    for (double density : {0.05, 0.2, 1.0}) {
      SCOPED_TRACE(testing::Message() << "n = " << n << ", density = " << density);
      const Eigen::MatrixXd A = SparseRandomMatrix(n, density, 2, &rng);
      const Eigen::VectorXd b = Eigen::VectorXd::Random(n);
      lu.Factorize(A);
      Eigen::VectorXd x = b;
      lu.Solve(&x);
      const Eigen::VectorXd reference = A.partialPivLu().solve(b);
      const double scale = 1.0 / ExactReciprocalCondition(A);
      EXPECT_LE((x - reference).norm(), 1e-13 * scale * reference.norm());
      EXPECT_LE((A * x - b).norm(), 1e-12 * (A.norm() * x.norm() + b.norm()));
      Eigen::VectorXd y = b;
      lu.SolveTransposed(&y);
      EXPECT_LE((A.transpose() * y - b).norm(), 1e-12 * (A.norm() * y.norm() + b.norm()));
      EXPECT_GT(lu.PivotRatio(), 0.0);
    }
  }
}

// Hager's estimate never exceeds the exact reciprocal condition number (it estimates |A^-1| from below) and, on these
// matrices, stays within a factor of 10 of it, as LAPACK's does; badly scaled matrices included.
TEST(DenseLu, TheConditionEstimateBracketsTheExactOne) {
  std::mt19937 rng(11);
  DenseLu lu;
  for (int trial = 0; trial < 60; ++trial) {
    const int n = 5 + trial % 40;
    const Eigen::MatrixXd A = SparseRandomMatrix(n, 0.15, trial % 3 == 0 ? 8 : 2, &rng);
    lu.Factorize(A);
    const double exact = ExactReciprocalCondition(A);
    const double estimate = lu.ConditionEstimate();
    EXPECT_GE(estimate, exact * (1.0 - 1e-9)) << "trial " << trial;
    EXPECT_LE(estimate, 10.0 * exact) << "trial " << trial;
  }
}

TEST(DenseLu, SingularAndNonFiniteMatricesAreReportedAsSuch) {
  DenseLu lu;
  Eigen::MatrixXd A = Eigen::MatrixXd::Identity(6, 6);
  A(2, 2) = 0.0;  // a zero column: an unknown without a row, as a locked friction direction would be
  lu.Factorize(A);
  EXPECT_EQ(lu.PivotRatio(), 0.0);
  EXPECT_EQ(lu.ConditionEstimate(), 0.0);
  Eigen::MatrixXd B = Eigen::MatrixXd::Random(6, 6);
  B.row(4) = 3.0 * B.row(1);  // rank 5 with round-off
  lu.Factorize(B);
  EXPECT_LT(lu.PivotRatio(), 1e-8);
  EXPECT_LT(lu.ConditionEstimate(), 1e-13);
  B(0, 0) = std::numeric_limits<double>::quiet_NaN();
  lu.Factorize(B);
  EXPECT_EQ(lu.PivotRatio(), 0.0);
  EXPECT_EQ(lu.ConditionEstimate(), 0.0);
  lu.Factorize(Eigen::MatrixXd(0, 0));
  EXPECT_EQ(lu.PivotRatio(), 1.0);
  EXPECT_EQ(lu.ConditionEstimate(), 1.0);
}

// n x n, mostly zeros, rank deficient in exact arithmetic: whole columns copied (a flat face's free closest point),
// rows and columns of zeros (an unknown without a row), multiples of rows with round-off, and entries drawn from a few
// values (+-1, +-0.5, 2; half the entries, or all of them) so that equal magnitudes tie for the pivot, also after
// elimination steps.
Eigen::MatrixXd SingularMatrix(int n, double density, bool all_tied, std::mt19937* rng) {
  std::uniform_real_distribution<double> coin(0.0, 1.0);
  std::uniform_int_distribution<int> pick(0, 5), index(0, n - 1);
  const double values[] = {1.0, -1.0, 0.5, -0.5, 2.0, 0.0};
  Eigen::MatrixXd A = SparseRandomMatrix(n, density, 3, rng);
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      if (A(i, j) != 0.0 && (all_tied || coin(*rng) < 0.5)) A(i, j) = values[pick(*rng)];
    }
  }
  if (n < 2) return A;
  A.col(index(*rng)) = A.col(index(*rng));
  A.row(index(*rng)).setZero();
  A.col(index(*rng)).setZero();
  A.row(index(*rng)) = 3.0 * A.row(index(*rng));
  return A;
}

TEST(CompletePivotLu, IsEigensFullPivLuBitForBitOnSingularMostlyZeroMatrices) {
  std::mt19937 rng(5);
  CompletePivotLu lu;
  Eigen::VectorXd x;
  int rank_deficient = 0;
  for (int trial = 0; trial < 800; ++trial) {
    const int n = 1 + trial % 60;
    const double density = trial % 3 == 0 ? 0.05 : (trial % 3 == 1 ? 0.2 : 0.6);
    SCOPED_TRACE(testing::Message() << "trial " << trial << ", n = " << n << ", density = " << density);
    const Eigen::MatrixXd A = trial % 7 == 6 ? SparseRandomMatrix(n, density, 2, &rng)
                                             : SingularMatrix(n, density, trial % 2 == 1, &rng);
    const Eigen::VectorXd b = Eigen::VectorXd::Random(n);
    const Eigen::FullPivLU<Eigen::MatrixXd> reference(A);
    lu.Factorize(A);
    ASSERT_EQ(lu.rank(), reference.rank());
    rank_deficient += reference.rank() < n;
    lu.Solve(b, &x);
    const Eigen::VectorXd expected = reference.solve(b);
    for (int i = 0; i < n; ++i) ASSERT_EQ(x[i], expected[i]) << "entry " << i;  // (-0 == 0: a zero's sign may differ)
  }
  EXPECT_GT(rank_deficient, 600);
}

TEST(CompletePivotLu, ZeroAndNonFiniteMatrices) {
  CompletePivotLu lu;
  Eigen::VectorXd x;
  lu.Factorize(Eigen::MatrixXd::Zero(4, 4));
  EXPECT_EQ(lu.rank(), 0);
  lu.Solve(Eigen::VectorXd::Ones(4), &x);
  EXPECT_EQ(x, Eigen::VectorXd::Zero(4));
  Eigen::MatrixXd A = Eigen::MatrixXd::Identity(3, 3);
  A(1, 2) = std::numeric_limits<double>::infinity();
  lu.Factorize(A);
  lu.Solve(Eigen::VectorXd::Ones(3), &x);
  EXPECT_FALSE(x.allFinite());
  lu.Factorize(Eigen::MatrixXd(0, 0));
  lu.Solve(Eigen::VectorXd(0), &x);
  EXPECT_EQ(x.size(), 0);
}

}  // namespace
}  // namespace implicit_sim
