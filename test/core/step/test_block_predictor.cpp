// The block Gauss-Seidel predictor (step/block_predictor.h): it lowers the residual of a start far from the solution,
// and a step that uses it ends where a step without it does (it changes the start, never the problem).
#include "implicit_sim/core/step/block_predictor.h"

#include <gtest/gtest.h>

#include "implicit_sim/core/io/pile_scene.h"
#include "implicit_sim/core/model/urdf_loader.h"
#include "implicit_sim/core/step/seeding.h"
#include "implicit_sim/core/step/time_stepper.h"
#include "step/step_problems_fixture.h"
#include "test_models.h"

namespace implicit_sim {
namespace {

TEST(BlockPredictor, LowersTheResidualOfAColdStart) {
  const Model model = test_models::SphereOnTwoSpheres();
  testing_support::StepProblems problems(model);
  const StepProblem& problem = problems.paper;
  State state = State::Initial(model);
  state.v[2] = -3.0;  // falling onto both spheres: the cold start's contacts are far from their forces
  problems.kinematics.BeginStep(state, 0.01, nullptr);
  Eigen::VectorXd z(problem.size()), Phi;
  SeedColdStart(model, state, problem, &problems.layout, &z);
  problem.Evaluate(z, NcpEvalMode(), &Phi, nullptr);
  const double before = Phi.norm();
  BlockPredictor predictor;
  Eigen::VectorXd z8 = z;
  const int evaluations = predictor.Run(problem, NewtonOptions(), 2, 0.1, &z);
  problem.Evaluate(z, NcpEvalMode(), &Phi, nullptr);
  const double after2 = Phi.norm();
  EXPECT_GT(evaluations, 2);
  EXPECT_LT(after2, 0.7 * before);  // 0.61x with the projected friction rows, 0.46x with the bilinear ones
  EXPECT_TRUE(z.allFinite());
  // Gauss-Seidel over the two contacts of one body converges, slowly: more sweeps, a smaller residual.
  predictor.Run(problem, NewtonOptions(), 8, 0.1, &z8);
  problem.Evaluate(z8, NcpEvalMode(), &Phi, nullptr);
  EXPECT_LT(Phi.norm(), 0.5 * after2);
}

TEST(BlockPredictor, AStepWithItEndsWhereAStepWithoutItDoes) {
  const Model model = LoadSceneFromString(MakePileUrdf(12, PileShape::kEllipsoid, 5), "pile12");
  StepperOptions plain, predicted;
  plain.h = predicted.h = 0.005;
  predicted.predictor_sweeps = 2;
  predicted.predictor_residual = 1e-6;
  Data data_plain(model), data_predicted(model);
  State a = State::Initial(model), b = State::Initial(model);
  for (int i = 0; i < 60; ++i) {  // the bottom row lands on the floor
    const StepReport ra = Step(model, plain, &a, &data_plain);
    const StepReport rb = Step(model, predicted, &b, &data_predicted);
    ASSERT_TRUE(ra.converged && rb.converged) << "step " << i;
  }
  EXPECT_LT((a.q - b.q).lpNorm<Eigen::Infinity>(), 1e-8);
  EXPECT_LT((a.v - b.v).lpNorm<Eigen::Infinity>(), 1e-6);
}

}  // namespace
}  // namespace implicit_sim
