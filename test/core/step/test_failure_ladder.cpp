// The retry ladder under injected solver failures (an iteration limit of 1, an impossible tolerance): every rung is
// counted, a failure is reported rather than thrown, and the state never becomes NaN.
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "scenario_runner.h"

namespace implicit_sim {
namespace {

struct Warm {
  Model model = LoadSceneFromFile(testing_support::ScenePath("p3_sphere_on_two_spheres.urdf"));
  Data data{model};
  State state = State::Initial(model);
  Warm() { EXPECT_TRUE(Step(model, StepperOptions(), &state, &data).converged); }  // a good warm start first
};

// Both schemes. The RATTLE step climbs only the ladder's warm rungs and then falls back to the paper's step, which
// climbs every rung: the rungs are counted as the paper's step counts them, once per (sub-)step.
class FailureLadderBothSchemes : public ::testing::TestWithParam<StepperOptions::Scheme> {};

TEST_P(FailureLadderBothSchemes, WhenEveryRungFailsEachIsCountedAndTheBestFiniteIterateIsKept) {
  Warm w;
  StepperOptions options;
  options.scheme = GetParam();
  options.newton.max_iterations = 1;
  options.newton.tolerance = 1e-300;  // below what double precision can reach
  options.proximal_weight = 1.0;
  const StepReport report = Step(w.model, options, &w.state, &w.data);
  const bool rattle = GetParam() == StepperOptions::Scheme::kRattle;
  EXPECT_EQ(report.paper_fallbacks, rattle ? 1 + 2 + 4 + 8 + 16 : 0);  // RATTLE: every (sub-)step falls back,
  EXPECT_EQ(report.velocity_iterations, 0);               // before its velocity stage;
  EXPECT_EQ(report.cold_restarts, 1 + 2 + 4 + 8 + 16);    // every (sub-)step: warm fails, cold fails,
  EXPECT_EQ(report.proximal_solves, 1 + 2 + 4 + 8 + 16);  // the proximal rung fails,
  EXPECT_EQ(report.smoothed_solves, 1 + 2 + 4 + 8 + 16);  // the continuation fails,
  EXPECT_EQ(report.ipopt_solves, 1 + 2 + 4 + 8 + 16);     // Ipopt and its polish fail,
  EXPECT_EQ(report.substeps, 1 + 2 + 4 + 8);              // and it splits down to h / 16
  EXPECT_FALSE(report.converged);
  EXPECT_TRUE(report.advanced);
  EXPECT_NEAR(w.state.t, 0.02, 1e-15);
  EXPECT_TRUE(w.state.q.allFinite());
  EXPECT_TRUE(w.state.v.allFinite());
  EXPECT_TRUE(std::isfinite(report.residual));
  EXPECT_EQ(report.fault, StepFault::kNotConverged);
  EXPECT_TRUE(Step(w.model, StepperOptions(), &w.state, &w.data).converged);  // normal settings recover
}

INSTANTIATE_TEST_SUITE_P(Schemes, FailureLadderBothSchemes,
                         ::testing::Values(StepperOptions::Scheme::kPaper, StepperOptions::Scheme::kRattle));

// With the default ladder one Newton iteration per solve still solves the step: the proximal rounds walk to the
// solution. Without the proximal rung nothing does (the continuation stops at its first level, which one iteration
// cannot converge): the step is reported not converged, and stays finite.
TEST(FailureLadder, AnIterationLimitOfOneIsRescuedByTheProximalRung) {
  for (const double proximal_weight : {0.0, 1.0}) {
    Warm w;
    StepperOptions options;
    options.newton.max_iterations = 1;
    options.proximal_weight = proximal_weight;
    const StepReport report = Step(w.model, options, &w.state, &w.data);
    EXPECT_GE(report.cold_restarts, 1);
    if (proximal_weight > 0.0) {
      EXPECT_TRUE(report.converged);
      EXPECT_GE(report.proximal_solves, 1);
    } else {
      EXPECT_FALSE(report.converged);
      EXPECT_EQ(report.substeps, 1 + 2 + 4 + 8);
      EXPECT_TRUE(w.state.q.allFinite() && w.state.v.allFinite());
    }
  }
}

// The smoothing continuation stops at its first level that does not converge and polishes from there: with one
// Newton iteration a solve, no level converges, so every continuation (one per (sub-)step) traces mu = 1e-2 and then
// the exact polish, never mu = 1e-3 or below.
TEST(FailureLadder, TheContinuationStopsAtItsFirstUnconvergedLevel) {
  Warm w;
  StepperOptions options;
  options.scheme = StepperOptions::Scheme::kPaper;
  options.newton.max_iterations = 1;
  options.newton.tolerance = 1e-300;
  options.ipopt_max_iterations = 1;
  NewtonTrace trace;
  options.newton.trace = &trace;
  const StepReport report = Step(w.model, options, &w.state, &w.data);
  EXPECT_EQ(report.smoothed_solves, 1 + 2 + 4 + 8 + 16);
  int first_level_rows = 0;
  for (const NewtonTraceRow& row : trace.rows) {
    EXPECT_TRUE(row.smoothing == 0.0 || row.smoothing == 1e-2) << "solve " << row.solve << ": mu " << row.smoothing;
    first_level_rows += row.smoothing == 1e-2;
  }
  EXPECT_EQ(first_level_rows, report.smoothed_solves);
}

TEST(FailureLadder, AnImpossibleToleranceIsReportedAsNotConvergedWithTheRightPhysics) {
  const Model model = LoadSceneFromFile(testing_support::ScenePath("p2_sphere_spinning.urdf"));
  Data data(model);
  State state = State::Initial(model);
  StepperOptions options;
  options.newton.tolerance = 1e-300;
  const StepReport report = Step(model, options, &state, &data);
  EXPECT_FALSE(report.converged);
  EXPECT_TRUE(report.advanced);
  EXPECT_LT(report.residual, 1e-6);  // the accepted iterate is still a good one
  EXPECT_NEAR(state.v[5], 1.962 - 0.01 * 1.962, 1e-6);
}

// Two bodies overlapping where a run starts: the first (cold) step refuses to start, names the pair, and leaves the
// state bit-identical; moving them apart lets the run go on.
TEST(StepFaults, AnInitialOverlapIsRefusedInTheFirstStepAndChangesNothing) {
  Model model = LoadSceneFromFile(testing_support::ScenePath("p3_sphere_on_two_spheres.urdf"));
  Data data(model);
  State state = State::Initial(model);
  state.q[2] -= 0.01;  // the ball sinks 1 cm into both spheres
  const State before = state;
  const StepReport report = Step(model, StepperOptions(), &state, &data);
  EXPECT_EQ(report.fault, StepFault::kInitialOverlap);
  EXPECT_FALSE(report.advanced);
  EXPECT_NE(report.fault_detail.find("ball-sphere_"), std::string::npos) << report.fault_detail;
  EXPECT_EQ(state.t, before.t);
  EXPECT_EQ(state.q, before.q);
  EXPECT_EQ(state.v, before.v);
  state.q[2] += 0.01;  // touching again, as the scene gives it: the check passes (no false alarm at contact)
  const StepReport good = Step(model, StepperOptions(), &state, &data);
  EXPECT_EQ(good.fault, StepFault::kNone);
  EXPECT_TRUE(good.converged);
}

// v0 = 1e6 m/s: the first step is undone and reported as diverged; the state stays the finite one it was.
TEST(StepFaults, AVelocityOfAMillionMetresPerSecondIsDetectedInTheSameStep) {
  const Model model = LoadSceneFromFile(testing_support::ScenePath("p2_sphere_spinning.urdf"));
  Data data(model);
  State state = State::Initial(model);
  state.v[0] = 1e6;
  const State before = state;
  const StepReport report = Step(model, StepperOptions(), &state, &data);
  EXPECT_EQ(report.fault, StepFault::kDiverged);
  EXPECT_FALSE(report.advanced);
  EXPECT_NE(report.fault_detail.find("'ball'"), std::string::npos) << report.fault_detail;
  EXPECT_EQ(state.q, before.q);
  EXPECT_EQ(state.v, before.v);
  EXPECT_TRUE(state.q.allFinite() && state.v.allFinite());
  StepperOptions bad;
  bad.max_speed = 0.0;
  EXPECT_THROW(Step(model, bad, &state, &data), std::invalid_argument);
  EXPECT_EQ(std::string(StepFaultName(StepFault::kDiverged)), "diverged");
}

}  // namespace
}  // namespace implicit_sim
