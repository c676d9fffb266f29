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

TEST(LandingCases, ConvergeFromTheWarmStartWithoutTheColdRungs) {
  for (const char* name : {"S1_ellipsoid_n100_step0025", "S1_ellipsoid_n100_step0031", "S1_sphere_n100_step0075"}) {
    SCOPED_TRACE(name);
    const StepCase step_case =
        ReadStepCase(std::string(IMPLICIT_SIM_SOURCE_DIR) + "/bench/corpus/" + name + ".case");
    const Model model = LoadStepCaseModel(step_case);
    State end_state;
    const StepReport report = ReplayStepCase(model, step_case, &end_state);
    ASSERT_TRUE(report.converged) << StepFaultName(report.fault);
    EXPECT_EQ(report.cold_restarts, 0);
    EXPECT_EQ(report.proximal_solves, 0);
    EXPECT_EQ(report.substeps, 0);
    EXPECT_LE(report.iterations, 200);
    EXPECT_GE(report.factorizations, report.iterations);  // one direction (at least) per iteration
  }
}

}  // namespace
}  // namespace implicit_sim
