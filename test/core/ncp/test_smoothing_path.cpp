// The smoothing path (SemismoothNewton::FollowSmoothingPath) on small NCPs with known solutions: it ends at the exact
// solution, its counters describe what it did, and its trace holds one row per iteration.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "implicit_sim/core/ncp/semismooth_newton.h"
#include "ncp/test_ncp_problems.h"

namespace implicit_sim {
namespace {

struct PathSolved {
  Eigen::VectorXd z;
  NcpSummary summary;
};

PathSolved FollowPath(const NcpProblem& problem, const Eigen::VectorXd& start, bool sparse,
                      const NewtonOptions& options = NewtonOptions(), const PathOptions& path = PathOptions()) {
  SemismoothNewton solver(problem.size(), sparse);
  PathSolved s{start, {}};
  s.summary = solver.FollowSmoothingPath(problem, options, path, &s.z);
  return s;
}

// A P-matrix LCP of size n with a planted solution: half the pairs closed (z > 0, w = 0), a quarter open, a quarter
// biactive (z = w = 0). M = A A^T + I has a positive definite symmetric part.
struct PlantedLcp {
  ncp_test::LinearNcp problem;
  Eigen::VectorXd solution;
};
PlantedLcp MakePlantedLcp(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  Eigen::MatrixXd A(n, n);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) A(i, j) = uniform(rng);
  }
  const Eigen::MatrixXd M = A * A.transpose() / n + Eigen::MatrixXd::Identity(n, n);
  Eigen::VectorXd z = Eigen::VectorXd::Zero(n), w = Eigen::VectorXd::Zero(n);
  for (int i = 0; i < n; ++i) {
    if (i % 4 < 2) z[i] = 1.0 + uniform(rng) * 0.5;  // closed
    if (i % 4 == 2) w[i] = 1.0 + uniform(rng) * 0.5;  // open; i % 4 == 3: biactive
  }
  const Eigen::VectorXd q = w - M * z;
  return {ncp_test::LinearNcp(M, q), z};
}

TEST(NcpSmoothingPath, EndsAtTheExactSolutionOfAUniqueLcp) {
  for (bool sparse : {false, true}) {
    SCOPED_TRACE(sparse ? "sparse" : "dense");
    const PathSolved s = FollowPath(ncp_test::UniqueLcp(), Eigen::Vector3d(5, 5, -5), sparse);
    ASSERT_TRUE(s.summary.converged) << s.summary.BriefReport();
    EXPECT_LE((s.z - ncp_test::UniqueLcpSolution()).lpNorm<Eigen::Infinity>(), 1e-12);
    EXPECT_GT(s.summary.path_iterations, 0);
    EXPECT_LE(s.summary.path_iterations, s.summary.iterations);
    EXPECT_TRUE(std::isfinite(s.summary.switch_smoothing));
    EXPECT_LE(s.summary.switch_smoothing, 1e-2);
    EXPECT_LE(s.summary.switch_residual, 1e-6);  // the path hands over near the solution
    EXPECT_LE(s.summary.iterations - s.summary.path_iterations, PathOptions().polish_iterations);
  }
}

TEST(NcpSmoothingPath, SolvesPlantedLcpsWithBiactivePairsWithinItsBudget) {
  for (unsigned seed = 1; seed <= 5; ++seed) {
    for (bool sparse : {false, true}) {
      SCOPED_TRACE(::testing::Message() << "seed " << seed << (sparse ? " sparse" : " dense"));
      const PlantedLcp lcp = MakePlantedLcp(40, seed);
      const PathSolved s = FollowPath(lcp.problem, Eigen::VectorXd::Zero(40), sparse);
      ASSERT_TRUE(s.summary.converged) << s.summary.BriefReport();
      // Biactive pairs converge at the rate of their smoothing error; the exact solution to 1e-6.
      EXPECT_LE((s.z - lcp.solution).lpNorm<Eigen::Infinity>(), 1e-6);
      EXPECT_LE(s.summary.path_iterations, PathOptions().max_iterations);
      // Every direction of a P-matrix LCP is the LU one: one solve a factorization (dense), the condensed LU has no
      // blocks here (sparse: KLU, one solve each).
      EXPECT_EQ(s.summary.lm_fallbacks, 0);
      EXPECT_EQ(s.summary.solves, s.summary.factorizations);
      EXPECT_EQ(s.summary.factorizations, s.summary.iterations);
    }
  }
}

TEST(NcpSmoothingPath, TakesNoStepFromTheSolution) {
  Eigen::VectorXd solution = ncp_test::UniqueLcpSolution();
  const PathSolved s = FollowPath(ncp_test::UniqueLcp(), solution, false);
  ASSERT_TRUE(s.summary.converged);
  EXPECT_EQ(s.summary.iterations, 0);
  EXPECT_EQ(s.summary.path_iterations, 0);
  EXPECT_TRUE(std::isnan(s.summary.switch_smoothing));  // no level was followed
  EXPECT_EQ(s.z, solution);
}

TEST(NcpSmoothingPath, ReportsAPathThatRunsOutOfIterations) {
  PathOptions short_path;
  short_path.max_iterations = 1;
  short_path.polish_iterations = 0;
  const PlantedLcp lcp = MakePlantedLcp(40, 7);
  const PathSolved s = FollowPath(lcp.problem, Eigen::VectorXd::Constant(40, 10.0), false, NewtonOptions(), short_path);
  EXPECT_FALSE(s.summary.converged);
  EXPECT_EQ(s.summary.path_iterations, 1);
  EXPECT_EQ(s.summary.termination, NcpTermination::kMaxIterations);
  EXPECT_GT(s.summary.switch_residual, 1e-6);
}

TEST(NcpSmoothingPath, TracesEveryIterationWithItsSmoothing) {
  NewtonTrace trace;
  NewtonOptions options;
  options.trace = &trace;
  const PathSolved s = FollowPath(ncp_test::UniqueLcp(), Eigen::Vector3d(5, 5, -5), true, options);
  ASSERT_TRUE(s.summary.converged);
  ASSERT_EQ(static_cast<int>(trace.rows.size()), s.summary.iterations);
  EXPECT_EQ(trace.solves, 2);  // the path, then the polish
  for (int k = 0; k < s.summary.iterations; ++k) {
    const NewtonTraceRow& row = trace.rows[k];
    const bool on_path = k < s.summary.path_iterations;
    EXPECT_EQ(row.solve, on_path ? 0 : 1);
    EXPECT_EQ(row.smoothing > 0.0, on_path);
    EXPECT_GT(row.step, 0.0);
    EXPECT_FALSE(row.least_squares);
  }
  // A plain solve traces the same way: one row per iteration, its residuals those it stepped from.
  NewtonTrace plain;
  options.trace = &plain;
  SemismoothNewton solver(3, false);
  Eigen::VectorXd z = Eigen::Vector3d(5, 5, -5);
  const NcpSummary summary = solver.Solve(ncp_test::UniqueLcp(), options, &z);
  ASSERT_EQ(static_cast<int>(plain.rows.size()), summary.iterations);
  EXPECT_GT(plain.rows.front().residual, plain.rows.back().residual);
}

}  // namespace
}  // namespace implicit_sim
