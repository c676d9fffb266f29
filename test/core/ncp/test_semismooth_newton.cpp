// Semismooth Newton on small NCPs with known solutions (test_ncp_problems.h): exact solutions in dense and sparse
// mode, biactive and singular-Jacobian cases, quadratic convergence, the line search, every termination, smoothing.
#include "implicit_sim/core/ncp/semismooth_newton.h"

#include <cmath>
#include <algorithm>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "ncp/test_ncp_problems.h"

namespace implicit_sim {
namespace {

using ncp_test::ArctanNcp;
using ncp_test::LinearNcp;
using ncp_test::NonlinearNcp;
using ncp_test::PoisonedNcp;
using ncp_test::RecordingNcp;

struct Solved {
  Eigen::VectorXd z;
  NcpSummary summary;
  int solver_lm_fallbacks = 0;  // SemismoothNewton::lm_fallbacks() after the solve
};

// Solves `problem` from `start` with a fresh solver.
Solved SolveWithNewton(const NcpProblem& problem, const Eigen::VectorXd& start, bool sparse,
                       const NewtonOptions& options = NewtonOptions(), double smoothing = 0.0) {
  SemismoothNewton solver(problem.size(), sparse);
  Solved s;
  s.z = start;
  s.summary = solver.Solve(problem, options, &s.z, smoothing);
  s.solver_lm_fallbacks = solver.lm_fallbacks();
  return s;
}

double MaxDifference(const Eigen::VectorXd& a, const Eigen::VectorXd& b) { return (a - b).lpNorm<Eigen::Infinity>(); }

// Converged to `expected` within `tolerance` (max norm), in both modes, and the two modes agree to 1e-12.
void ExpectBothModesReach(const NcpProblem& problem, const Eigen::VectorXd& start, const Eigen::VectorXd& expected,
                          double tolerance, const NewtonOptions& options = NewtonOptions()) {
  const Solved dense = SolveWithNewton(problem, start, false, options);
  const Solved sparse = SolveWithNewton(problem, start, true, options);
  for (const Solved* s : {&dense, &sparse}) {
    SCOPED_TRACE(s == &dense ? "dense" : "sparse");
    EXPECT_TRUE(s->summary.converged) << s->summary.BriefReport();
    EXPECT_EQ(s->summary.termination, NcpTermination::kConverged);
    EXPECT_LE(MaxDifference(s->z, expected), tolerance) << s->z.transpose();
  }
  EXPECT_LE(MaxDifference(dense.z, sparse.z), 1e-12);
}

TEST(NcpSemismoothNewton, ReachesTheUniqueSolutionOfAPositiveDefiniteLcp) {
  ExpectBothModesReach(ncp_test::UniqueLcp(), Eigen::VectorXd::Zero(3), ncp_test::UniqueLcpSolution(), 1e-12);
  ExpectBothModesReach(ncp_test::UniqueLcp(), Eigen::Vector3d(5, 5, -5), ncp_test::UniqueLcpSolution(), 1e-12);
}

TEST(NcpSemismoothNewton, SummarizesAConvergedSolve) {
  const Solved s = SolveWithNewton(ncp_test::UniqueLcp(), Eigen::VectorXd::Zero(3), false);
  EXPECT_TRUE(s.summary.converged);
  EXPECT_EQ(s.summary.termination, NcpTermination::kConverged);
  EXPECT_GE(s.summary.iterations, 1);
  EXPECT_LE(s.summary.residual, NewtonOptions().tolerance * (1.0 + 2.0));  // |z*|_inf = 2
  EXPECT_EQ(s.summary.lm_fallbacks, 0);
  EXPECT_TRUE(std::isnan(s.summary.equation_residual));  // Newton's measure is |Phi|_2 alone
  EXPECT_TRUE(std::isnan(s.summary.complementarity));
  EXPECT_EQ(s.summary.BriefReport().rfind("converged after " + std::to_string(s.summary.iterations), 0), 0u)
      << s.summary.BriefReport();
}

TEST(NcpSemismoothNewton, TakesNoStepFromTheSolution) {
  const Solved s = SolveWithNewton(ncp_test::UniqueLcp(), ncp_test::UniqueLcpSolution(), true);
  EXPECT_EQ(s.summary.termination, NcpTermination::kConverged);
  EXPECT_EQ(s.summary.iterations, 0);
  EXPECT_EQ(s.summary.residual_evaluations, 1);
  EXPECT_EQ(s.summary.residual, 0.0);
  EXPECT_EQ(s.z, ncp_test::UniqueLcpSolution());
}

TEST(NcpSemismoothNewton, SolvesTheSimplexProjectionWithAnEquationRow) {
  ExpectBothModesReach(ncp_test::SimplexProjection(), Eigen::VectorXd::Zero(4), ncp_test::SimplexProjectionSolution(),
                       1e-12);
}

TEST(NcpSemismoothNewton, ConvergesToABiactiveSolution) {
  const LinearNcp problem = ncp_test::DegenerateLcp();
  const Eigen::VectorXd expected = ncp_test::UniqueLcpSolution();
  const Eigen::VectorXd w = problem.M() * expected + problem.q();
  ASSERT_EQ(w, Eigen::VectorXd::Zero(3));  // row 1: z = w = 0
  ExpectBothModesReach(problem, Eigen::VectorXd::Zero(3), expected, 1e-10);
  ExpectBothModesReach(problem, Eigen::Vector3d(1, 1, 1), expected, 1e-10);
}

TEST(NcpSemismoothNewton, UsesTheDiagonalElementAtTheKinkOfABiactiveStart) {
  // At z* row 1 of the degenerate LCP sits on the kink a = b = 0: its Jacobian row is (1 - 1/sqrt 2)(e_1 + M_1).
  const LinearNcp problem = ncp_test::DegenerateLcp();
  Eigen::VectorXd Phi;
  Eigen::MatrixXd J;
  problem.Evaluate(ncp_test::UniqueLcpSolution(), NcpEvalMode(), &Phi, &J);
  EXPECT_EQ(Phi, Eigen::VectorXd::Zero(3));
  const double c = 1.0 - 1.0 / std::sqrt(2.0);
  const Eigen::RowVector3d expected_row = c * (Eigen::RowVector3d(0, 1, 0) + problem.M().row(1));
  EXPECT_LE((J.row(1) - expected_row).lpNorm<Eigen::Infinity>(), 1e-15) << J;
}

// The LCP w = (-z0 + z1 + 1, z1 - 1) from z = (0.5, 0): row 0 has a = b = 0.5, so its FB derivative
// (1 - a/r) - (1 - b/r) in z0 vanishes, and row 1 (a = 0, b = -1) depends on z1 alone: J's first column is 0.
// Solutions: z1 = 1 and z0 in {0, 2}.
LinearNcp SingularAtTheStart() {
  Eigen::MatrixXd M(2, 2);
  M << -1, 1, 0, 1;
  return LinearNcp(M, Eigen::Vector2d(1, -1));
}

// Dense: the basic direction of the fully pivoted LU; sparse: the Levenberg-Marquardt one.
TEST(NcpSemismoothNewton, SolvesWhereTheJacobianIsSingular) {
  const LinearNcp problem = SingularAtTheStart();
  const Eigen::VectorXd start = Eigen::Vector2d(0.5, 0);
  Eigen::VectorXd Phi;
  Eigen::MatrixXd J;
  problem.Evaluate(start, NcpEvalMode(), &Phi, &J);
  ASSERT_EQ(J.col(0), Eigen::VectorXd::Zero(2)) << J;
  ASSERT_GT(Phi.norm(), 1.0);
  NewtonOptions options;
  options.sparse_regularization = 0.0;  // keep J exactly singular
  for (bool sparse : {false, true}) {
    SCOPED_TRACE(sparse ? "sparse" : "dense");
    const Solved s = SolveWithNewton(problem, start, sparse, options);
    EXPECT_TRUE(s.summary.converged) << s.summary.BriefReport();
    if (sparse) {
      EXPECT_GT(s.summary.lm_fallbacks, 0);
    } else {
      EXPECT_EQ(s.summary.lm_fallbacks, 0);
      EXPECT_GT(s.summary.factorizations, s.summary.iterations);  // an LU and a decomposition at the singular start
    }
    EXPECT_EQ(s.solver_lm_fallbacks, s.summary.lm_fallbacks);
    const double to_first = MaxDifference(s.z, Eigen::Vector2d(0, 1));
    const double to_second = MaxDifference(s.z, Eigen::Vector2d(2, 1));
    EXPECT_LE(std::min(to_first, to_second), 1e-12) << s.z.transpose();
  }
}

// 64 uncoupled copies of SingularAtTheStart (128 unknowns): a large island's singular dense J takes the
// column-pivoting QR's basic direction, and every copy reaches one of its two solutions without an LM fallback.
TEST(NcpSemismoothNewton, SolvesALargeIslandWhereTheJacobianIsSingular) {
  constexpr int kCopies = 64;
  const LinearNcp one = SingularAtTheStart();
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(2 * kCopies, 2 * kCopies);
  Eigen::VectorXd q(2 * kCopies), start(2 * kCopies);
  for (int c = 0; c < kCopies; ++c) {
    M.block<2, 2>(2 * c, 2 * c) = one.M();
    q.segment<2>(2 * c) = one.q();
    start.segment<2>(2 * c) = Eigen::Vector2d(0.5, 0);
  }
  const LinearNcp problem(M, q);
  Eigen::VectorXd Phi;
  Eigen::MatrixXd J;
  problem.Evaluate(start, NcpEvalMode(), &Phi, &J);
  ASSERT_EQ(J.col(0), Eigen::VectorXd::Zero(2 * kCopies));
  NewtonOptions options;
  options.sparse_regularization = 0.0;
  const Solved s = SolveWithNewton(problem, start, false, options);
  EXPECT_TRUE(s.summary.converged) << s.summary.BriefReport();
  EXPECT_EQ(s.summary.lm_fallbacks, 0);
  EXPECT_GT(s.summary.factorizations, s.summary.iterations);  // LUs and a decomposition at the singular start
  for (int c = 0; c < kCopies; ++c) {
    const Eigen::Vector2d z = s.z.segment<2>(2 * c);
    const double to_first = MaxDifference(z, Eigen::Vector2d(0, 1));
    const double to_second = MaxDifference(z, Eigen::Vector2d(2, 1));
    EXPECT_LE(std::min(to_first, to_second), 1e-12) << "copy " << c << ": " << z.transpose();
  }
}

TEST(NcpSemismoothNewton, SolvesANonlinearMixedNcp) {
  const NonlinearNcp problem;
  for (const Eigen::Vector3d& start : {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(2, 0.5, 2),
                                       Eigen::Vector3d(0.1, 3, -1)}) {
    SCOPED_TRACE(::testing::Message() << "from " << start.transpose());
    ExpectBothModesReach(problem, start, NonlinearNcp::Solution(), 1e-12);
  }
}

// NonlinearNcp with its equation row (z2^3 + z2 - z0 - 1 = 0: it touches z2 and the "global" z0) declared a
// condensable block, so that the sparse solve goes through CondensedLu.
class BlockedNonlinearNcp : public NonlinearNcp {
 public:
  void CondensableBlocks(std::vector<int>* starts, std::vector<int>* indices) const override {
    *starts = {0, 1};
    *indices = {2};
  }
};

// The condensed direction is the uncondensed one up to rounding: the same iterations to the same solution.
TEST(NcpSemismoothNewton, CondensedBlocksGiveTheSameIterates) {
  const BlockedNonlinearNcp problem;
  for (const Eigen::Vector3d& start : {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(2, 0.5, 2),
                                       Eigen::Vector3d(0.1, 3, -1)}) {
    SCOPED_TRACE(::testing::Message() << "from " << start.transpose());
    NewtonOptions whole;
    whole.condense_blocks = false;
    const Solved condensed = SolveWithNewton(problem, start, true);
    const Solved uncondensed = SolveWithNewton(problem, start, true, whole);
    EXPECT_TRUE(condensed.summary.converged) << condensed.summary.BriefReport();
    EXPECT_EQ(condensed.summary.iterations, uncondensed.summary.iterations);
    EXPECT_LE(MaxDifference(condensed.z, NonlinearNcp::Solution()), 1e-12) << condensed.z.transpose();
  }
}

TEST(NcpSemismoothNewton, RegularizationLeavesTheSolutionExact) {
  NewtonOptions options;
  options.sparse_regularization = 1e-3;  // a large proximal term: slower, but Phi and so the solution are exact
  ExpectBothModesReach(ncp_test::UniqueLcp(), Eigen::VectorXd::Zero(3), ncp_test::UniqueLcpSolution(), 1e-12,
                       options);
  ExpectBothModesReach(NonlinearNcp(), Eigen::Vector3d(2, 0.5, 2), NonlinearNcp::Solution(), 1e-12, options);
}

TEST(NcpSemismoothNewton, ConvergesQuadraticallyOnAWellConditionedNcp) {
  const NonlinearNcp inner;
  NewtonOptions options;
  options.sparse_regularization = 0.0;  // the exact generalized Jacobian
  for (bool sparse : {false, true}) {
    SCOPED_TRACE(sparse ? "sparse" : "dense");
    const RecordingNcp problem(inner);
    const Solved s = SolveWithNewton(problem, Eigen::Vector3d(1.5, 0.5, 1.5), sparse, options);
    ASSERT_TRUE(s.summary.converged) << s.summary.BriefReport();
    const std::vector<double>& r = problem.iterate_residuals();  // |Phi| at z_0, z_1, ..., z_k
    ::testing::Message sequence;
    for (double v : r) sequence << v << " ";
    SCOPED_TRACE(sequence);
    EXPECT_EQ(s.summary.iterations, 6);  // |Phi|: 2.7 1.8 0.17 8.5e-3 2.8e-5 2.9e-10 0
    ASSERT_EQ(static_cast<int>(r.size()), s.summary.iterations + 1);
    EXPECT_EQ(problem.trial_evaluations(), s.summary.iterations);  // every full step accepted
    EXPECT_LE(MaxDifference(s.z, NonlinearNcp::Solution()), 1e-14);
    for (size_t k = 0; k + 1 < r.size(); ++k) {
      if (r[k] < 1e-2) {
        EXPECT_LE(r[k + 1], r[k] * r[k]) << "step " << k;  // observed r_{k+1} / r_k^2 = 0.38
      }
    }
  }
}

TEST(NcpSemismoothNewton, BacktracksWhenTheFullStepOvershoots) {
  const ArctanNcp inner;
  const RecordingNcp problem(inner);
  const Solved s = SolveWithNewton(problem, Eigen::Vector2d(11, 0), false);
  ASSERT_TRUE(s.summary.converged) << s.summary.BriefReport();
  EXPECT_GT(problem.trial_evaluations(), s.summary.iterations);  // some full step was rejected
  EXPECT_EQ(s.summary.residual_evaluations, problem.trial_evaluations() + s.summary.iterations + 1);
  EXPECT_EQ(s.summary.lm_fallbacks, 0);
  EXPECT_LE(MaxDifference(s.z, ArctanNcp::Solution()), 1e-12);
  const Solved sparse = SolveWithNewton(ArctanNcp(), Eigen::Vector2d(11, 0), true);
  EXPECT_LE(MaxDifference(sparse.z, s.z), 1e-12);
}

TEST(NcpSemismoothNewton, StopsAtTheIterationLimitFarFromTheSolution) {
  NewtonOptions options;
  options.max_iterations = 1;
  for (bool sparse : {false, true}) {
    const Solved s = SolveWithNewton(ArctanNcp(), Eigen::Vector2d(11, 0), sparse, options);
    EXPECT_FALSE(s.summary.converged);
    EXPECT_EQ(s.summary.termination, NcpTermination::kMaxIterations);
    EXPECT_EQ(s.summary.iterations, 1);
    EXPECT_GT(s.summary.residual, 0.1);
    EXPECT_TRUE(std::isfinite(s.summary.residual));
  }
}

// sqrt(1 + z^2) = 0 has no root: the line search keeps accepting steps towards z = 0, where the residual's minimum 1
// is, and each gains less than the one before.
class RootlessEquation : public ncp_test::RowNcp {
 public:
  RootlessEquation() : RowNcp({0.0}) {}

 protected:
  double Row(int, const Eigen::VectorXd& z, std::vector<Entry>* gradient) const override {
    const double value = std::sqrt(1.0 + z[0] * z[0]);
    *gradient = {{0, z[0] / value}};
    return value;
  }
};

TEST(NcpSemismoothNewton, StopsAsStalledWhenTheResidualMakesNoProgressOverTheWindow) {
  const Eigen::VectorXd start = Eigen::VectorXd::Constant(1, 2.0);
  NewtonOptions window;
  window.stall_window = 30;
  for (bool sparse : {false, true}) {
    SCOPED_TRACE(sparse ? "sparse" : "dense");
    const Solved stalled = SolveWithNewton(RootlessEquation(), start, sparse, window);
    EXPECT_EQ(stalled.summary.termination, NcpTermination::kStalled) << stalled.summary.BriefReport();
    EXPECT_FALSE(stalled.summary.converged);
    EXPECT_GE(stalled.summary.iterations, window.stall_window);
    EXPECT_LT(stalled.summary.iterations, window.max_iterations);
    EXPECT_GE(stalled.summary.residual, 1.0);
    const Solved unlimited = SolveWithNewton(RootlessEquation(), start, sparse);  // stall_window 0 by default
    EXPECT_NE(unlimited.summary.termination, NcpTermination::kStalled);
    EXPECT_GT(unlimited.summary.iterations, stalled.summary.iterations);
    // The window's test is what stopped it: the iterations it cut made less than 10 % progress.
    EXPECT_GT(unlimited.summary.residual, 0.9 * stalled.summary.residual);
  }
}

TEST(NcpSemismoothNewton, ReportsANonFiniteResidualAtTheStart) {
  const ArctanNcp inner;
  const PoisonedNcp problem(inner, Eigen::VectorXd());  // NaN everywhere
  for (bool sparse : {false, true}) {
    const Eigen::VectorXd start = Eigen::Vector2d(11, 0);
    const Solved s = SolveWithNewton(problem, start, sparse);
    EXPECT_FALSE(s.summary.converged);
    EXPECT_EQ(s.summary.termination, NcpTermination::kNonFinite);
    EXPECT_EQ(s.summary.iterations, 0);
    EXPECT_TRUE(std::isnan(s.summary.residual));
    EXPECT_EQ(s.z, start);
  }
}

TEST(NcpSemismoothNewton, NeverAcceptsANonFiniteTrialPoint) {
  const ArctanNcp inner;
  const Eigen::VectorXd start = Eigen::Vector2d(11, 0);
  const PoisonedNcp problem(inner, start);  // finite at the start only
  Eigen::VectorXd Phi0;
  inner.Evaluate(start, NcpEvalMode(), &Phi0, nullptr);
  for (bool sparse : {false, true}) {
    SCOPED_TRACE(sparse ? "sparse" : "dense");
    const Solved s = SolveWithNewton(problem, start, sparse);
    EXPECT_FALSE(s.summary.converged);
    EXPECT_EQ(s.summary.termination, NcpTermination::kNoDescent);
    EXPECT_EQ(s.summary.iterations, 0);
    EXPECT_EQ(s.z, start);                     // bit for bit: no trial point was taken
    EXPECT_EQ(s.summary.residual, Phi0.norm());  // the residual of the start, finite
    EXPECT_EQ(s.summary.lm_fallbacks, sparse ? 0 : 1);  // dense mode tries LM after a failed LU direction
  }
}

// 0 <= z _|_ z - 1 >= 0 smoothed: FB_mu(z, z - 1) = 0 iff z (z - 1) = mu^2 with z > 1.
TEST(NcpSemismoothNewton, ConvergesToTheSmoothedSolutionOfAOneDimensionalLcp) {
  const LinearNcp problem(Eigen::MatrixXd::Ones(1, 1), -Eigen::VectorXd::Ones(1));
  for (double mu : {0.1, 0.5, 1.0}) {
    for (bool sparse : {false, true}) {
      SCOPED_TRACE(::testing::Message() << "mu " << mu << (sparse ? " sparse" : " dense"));
      const Solved s = SolveWithNewton(problem, Eigen::VectorXd::Zero(1), sparse, NewtonOptions(), mu);
      ASSERT_TRUE(s.summary.converged) << s.summary.BriefReport();
      const double expected = 0.5 * (1.0 + std::sqrt(1.0 + 4.0 * mu * mu));
      EXPECT_NEAR(s.z[0], expected, 1e-12);
      EXPECT_NEAR(s.z[0] * (s.z[0] - 1.0), mu * mu, 3e-12);  // |d(z (z - 1))/dz| <= 3
    }
  }
  const Solved golden = SolveWithNewton(problem, Eigen::VectorXd::Zero(1), false, NewtonOptions(), 1.0);
  EXPECT_NEAR(golden.z[0], (1.0 + std::sqrt(5.0)) / 2.0, 1e-12);  // z^2 - z - 1 = 0
}

TEST(NcpSemismoothNewton, SmoothedSolutionsTendToTheExactOneAsMuVanishes) {
  Eigen::VectorXd z = Eigen::VectorXd::Zero(3);
  SemismoothNewton solver(3, false);
  double previous_error = 1.0;
  for (double mu : {1e-1, 1e-2, 1e-3, 1e-4}) {
    ASSERT_TRUE(solver.Solve(ncp_test::UniqueLcp(), NewtonOptions(), &z, mu).converged);
    const double error = MaxDifference(z, ncp_test::UniqueLcpSolution());
    EXPECT_LT(error, previous_error);
    EXPECT_LT(error, 10.0 * mu * mu);  // O(mu^2): the pair with w_i = 1 has z_i w_i = mu^2
    previous_error = error;
  }
}

}  // namespace
}  // namespace implicit_sim
