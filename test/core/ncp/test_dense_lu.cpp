// DenseLu against Eigen's PartialPivLU: mostly-zero random matrices (as the step's dense Jacobians are), solves with A
// and A^T, the condition estimate against the exact reciprocal condition number, singular and non-finite matrices.
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

}  // namespace
}  // namespace implicit_sim
