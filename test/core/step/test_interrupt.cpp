// A step can always be interrupted (Data::interrupt, base/interrupt.h): a due request or deadline stops its solvers
// between factorizations, and the step is undone (StepFault::kInterrupted, the state exactly as before). The long
// steps are second-layer landings of the 100-ellipsoid drop from the replay corpus, which take minutes to finish
// (bench/corpus/README.md); the bounds on the wall time below are 50-100x what the interruption takes.
#include <chrono>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "implicit_sim/core/base/interrupt.h"
#include "implicit_sim/core/io/step_case.h"
#include "implicit_sim/core/step/time_stepper.h"
#include "scenario_runner.h"

namespace implicit_sim {
namespace {

using InterruptClock = StepInterrupt::Clock;

double SecondsSince(InterruptClock::time_point start) {
  return std::chrono::duration<double>(InterruptClock::now() - start).count();
}

void ExpectSameState(const State& a, const State& b) {
  EXPECT_EQ(a.t, b.t);
  EXPECT_EQ(a.q, b.q);
  EXPECT_EQ(a.v, b.v);
}

StepCase LongLandingStep() {
  return ReadStepCase(std::string(IMPLICIT_SIM_SOURCE_DIR) + "/bench/corpus/S1_ellipsoid_n100_step0185.case");
}

TEST(StepInterrupt, DueWhenRequestedOrPastItsDeadlineUntilCleared) {
  StepInterrupt interrupt;
  EXPECT_FALSE(interrupt.Due());
  EXPECT_FALSE(InterruptDue(nullptr));
  interrupt.SetDeadline(InterruptClock::now() + std::chrono::hours(1));
  EXPECT_FALSE(interrupt.Due());
  interrupt.SetDeadline(InterruptClock::now() - std::chrono::milliseconds(1));
  EXPECT_TRUE(interrupt.Due());
  EXPECT_FALSE(interrupt.requested());
  interrupt.ClearDeadline();
  EXPECT_FALSE(interrupt.Due());
  interrupt.Request();
  EXPECT_TRUE(InterruptDue(&interrupt));
  interrupt.Clear();
  EXPECT_FALSE(interrupt.Due());
}

// Requested before the step: nothing is done, the state and the warm start stay, and once cleared the step is the
// one an uninterrupted twin takes, bit for bit.
TEST(StepInterrupt, ARequestBeforeTheStepChangesNothing) {
  const Model model = LoadSceneFromFile(testing_support::ScenePath("p3_sphere_on_two_spheres.urdf"));
  StepperOptions options;
  Data data(model), twin_data(model);
  State state = State::Initial(model), twin = State::Initial(model);
  for (int i = 0; i < 20; ++i) {
    Step(model, options, &state, &data);
    Step(model, options, &twin, &twin_data);
  }
  StepInterrupt interrupt;
  interrupt.Request();
  data.interrupt = &interrupt;
  const State before = state;
  const StepReport refused = Step(model, options, &state, &data);
  EXPECT_EQ(refused.fault, StepFault::kInterrupted);
  EXPECT_STREQ(StepFaultName(refused.fault), "interrupted");
  EXPECT_FALSE(refused.advanced);
  ExpectSameState(state, before);
  interrupt.Clear();
  const StepReport taken = Step(model, options, &state, &data);
  const StepReport twin_report = Step(model, options, &twin, &twin_data);
  ASSERT_TRUE(taken.converged);
  EXPECT_EQ(taken.iterations, twin_report.iterations);
  ExpectSameState(state, twin);
}

// A deadline inside a step that takes minutes (every rung, sub-steps): it stops within a second and is undone.
TEST(StepInterrupt, ADeadlineStopsALongLandingStepAndUndoesIt) {
  const StepCase step_case = LongLandingStep();
  const Model model = LoadStepCaseModel(step_case);
  StepInterrupt interrupt;
  const auto start = InterruptClock::now();
  interrupt.SetDeadlineIn(0.2);
  State end_state;
  const StepReport report = ReplayStepCase(model, step_case, &end_state, &interrupt);
  const double seconds = SecondsSince(start);
  EXPECT_EQ(report.fault, StepFault::kInterrupted);
  EXPECT_FALSE(report.advanced);
  EXPECT_FALSE(report.converged);
  ExpectSameState(end_state, step_case.inputs.state);
  EXPECT_LT(seconds, 10.0) << "the step took " << seconds << " s after a deadline of 0.2 s";
}

// A request from another thread while Ipopt (the primary solver here) iterates stops it at its next iteration.
TEST(StepInterrupt, ARequestFromAnotherThreadStopsIpopt) {
  StepCase step_case = LongLandingStep();
  step_case.options.solver = StepperOptions::Solver::kIpopt;
  const Model model = LoadStepCaseModel(step_case);
  StepInterrupt interrupt;
  const auto start = InterruptClock::now();
  std::thread requester([&interrupt] {
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    interrupt.Request();
  });
  State end_state;
  const StepReport report = ReplayStepCase(model, step_case, &end_state, &interrupt);
  const double seconds = SecondsSince(start);
  requester.join();
  EXPECT_EQ(report.fault, StepFault::kInterrupted);
  EXPECT_FALSE(report.advanced);
  EXPECT_GE(report.ipopt_solves, 1);
  ExpectSameState(end_state, step_case.inputs.state);
  EXPECT_LT(seconds, 10.0) << "the step took " << seconds << " s after a request at 0.3 s";
}

}  // namespace
}  // namespace implicit_sim
