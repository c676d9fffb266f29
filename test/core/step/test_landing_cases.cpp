// Landing steps of the 100-body S1 drops from the replay corpus (bench/corpus/): before unloaded closing pairs got fresh
// friction seeds and piles a short plain warm attempt (doc/method.md, "Landing steps: what the corpus chose"), these
// climbed to the cold start (ellipsoid step0031, sphere step0075) or to the proximal rung (ellipsoid step0025). Each
// must now converge at the projected warm retry at the latest, within 200 Newton iterations (they take 29-143).
#include <string>

#include <gtest/gtest.h>

#include "implicit_sim/core/io/step_case.h"
#include "implicit_sim/core/step/time_stepper.h"

namespace implicit_sim {
namespace {

StepCase CorpusCase(const std::string& name) {
  return ReadStepCase(std::string(IMPLICIT_SIM_SOURCE_DIR) + "/bench/corpus/" + name + ".case");
}

StepReport Replay(const StepCase& step_case) {
  const Model model = LoadStepCaseModel(step_case);
  State end_state;
  return ReplayStepCase(model, step_case, &end_state);
}

TEST(LandingCases, ConvergeFromTheWarmStartWithoutTheColdRungs) {
  for (const char* name : {"S1_ellipsoid_n100_step0025", "S1_ellipsoid_n100_step0031", "S1_sphere_n100_step0075"}) {
    SCOPED_TRACE(name);
    const StepReport report = Replay(CorpusCase(name));
    ASSERT_TRUE(report.converged) << StepFaultName(report.fault);
    EXPECT_EQ(report.cold_restarts, 0);
    EXPECT_EQ(report.proximal_solves, 0);
    EXPECT_EQ(report.substeps, 0);
    EXPECT_LE(report.iterations, 200);
    EXPECT_GE(report.factorizations, report.iterations);  // one direction (at least) per iteration
  }
}

// A part wedged in a corner of the box (the 100-ellipsoid pile without torsion, e_r = 0): a sliding pair's friction
// force is nearly redundant there, and a Newton step along its fractions' unit sphere left the sphere by more than
// the residual; the step took 2 602 Newton iterations and sub-step splits. With the trial points scaled back onto the
// sphere (StepProblem::Retract) it converges from the cold start, in 277 iterations.
TEST(LandingCases, AWedgeConvergesWithTheSlidingFractionsOnTheirSphere) {
  const StepCase step_case = CorpusCase("S1_ellipsoid_n100_er0_step0179");
  ASSERT_TRUE(step_case.options.newton.retract_sliding);  // the default
  const StepReport report = Replay(step_case);
  ASSERT_TRUE(report.converged) << StepFaultName(report.fault);
  EXPECT_LE(report.cold_restarts, 1);
  EXPECT_EQ(report.proximal_solves, 0);
  EXPECT_EQ(report.substeps, 0);
  EXPECT_LE(report.iterations, 600);
}

}  // namespace
}  // namespace implicit_sim
