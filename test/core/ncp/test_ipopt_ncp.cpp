// The second solver: Ipopt on the complementarity-penalty NLP agrees with semismooth Newton on the same steps.
#include "implicit_sim/core/ncp/ipopt_ncp.h"

#include <gtest/gtest.h>

#include "implicit_sim/core/io/pile_scene.h"
#include "implicit_sim/core/step/problems/paper_step.h"
#include "implicit_sim/core/step/seeding.h"
#include "scenario_runner.h"

namespace implicit_sim {
namespace {

// Runs `steps` steps with Newton, then solves the next step with both solvers from the same warm start.
void ExpectSolversAgree(const Model& model, double h, int steps) {
  StepperOptions options;
  options.h = h;
  Data data(model);
  State state = State::Initial(model);
  for (int i = 0; i < steps; ++i) ASSERT_TRUE(Step(model, options, &state, &data).converged);
  Eigen::VectorXd guess = data.z;
  data.kinematics.BeginStep(state, h, nullptr);
  const PaperStepProblem problem(data.layout, data.kinematics, data.joint_drives, /*regular_separated_friction=*/true);
  SeedWarmStart(model, state, problem, &data.layout, &guess);
  Eigen::VectorXd newton = guess, ipopt = guess;
  SemismoothNewton solver(problem.size(), /*sparse=*/data.broad_phase);
  ASSERT_TRUE(solver.Solve(problem, options.newton, &newton).converged);
  const NcpSummary r = SolveNcpWithIpopt(problem, IpoptNcpOptions(), &ipopt);
  EXPECT_TRUE(r.termination == NcpTermination::kConverged || r.termination == NcpTermination::kInaccurate)
      << r.BriefReport();  // Ipopt reported a solution
  EXPECT_LT(r.equation_residual, 1e-6);
  EXPECT_LT(r.complementarity, 1e-6);
  const int nv = model.nv();
  EXPECT_LT((ipopt.head(nv) - newton.head(nv)).cwiseAbs().maxCoeff(), 1e-5)
      << "velocities\nNewton " << newton.head(nv).transpose() << "\nIpopt  " << ipopt.head(nv).transpose();
  for (const PairBlock& blk : data.layout.blocks()) {  // the normal forces
    const double newton_force = newton[blk.normal_force()];
    EXPECT_NEAR(ipopt[blk.normal_force()], newton_force, 1e-4 * std::max(1.0, std::abs(newton_force)));
  }
}

void ExpectSolversAgree(const std::string& scene, double h, int steps) {
  SCOPED_TRACE(scene);
  ExpectSolversAgree(LoadSceneFromFile(testing_support::ScenePath(scene)), h, steps);
}

TEST(IpoptNcp, AgreesWithNewtonOnASmallPile) {  // broad phase and sparse Newton; spheres landed on the floor
  const Model model = LoadSceneFromString(MakePileUrdf(10, PileShape::kSphere), "pile");
  ExpectSolversAgree(model, 0.005, 30);
}

TEST(IpoptNcp, AgreesWithNewtonOnTheRollingDisc) { ExpectSolversAgree("p1_disc_rolling.urdf", 0.01, 20); }
TEST(IpoptNcp, AgreesWithNewtonOnTheSpinningSphere) { ExpectSolversAgree("p2_sphere_spinning.urdf", 0.01, 20); }
TEST(IpoptNcp, AgreesWithNewtonOnTheSphereOnTwoSpheres) {
  ExpectSolversAgree("p3_sphere_on_two_spheres.urdf", 0.01, 100);  // A and B in contact, A sliding
  ExpectSolversAgree("p3_sphere_on_two_spheres.urdf", 0.01, 300);  // B sliding, A about to separate
}

TEST(IpoptNcp, AsThePrimarySolverItFollowsNewtonOnP3) {
  const Model model = LoadSceneFromFile(testing_support::ScenePath("p3_sphere_on_two_spheres.urdf"));
  StepperOptions newton_options, ipopt_options;
  ipopt_options.solver = StepperOptions::Solver::kIpopt;
  Data newton_data(model), ipopt_data(model);
  State newton_state = State::Initial(model), ipopt_state = newton_state;
  int ipopt_nonconverged = 0, ipopt_solves = 0;
  double max_v_difference = 0.0;
  for (int i = 0; i < 100; ++i) {  // 1 s: A sliding, B rolling
    ASSERT_TRUE(Step(model, newton_options, &newton_state, &newton_data).converged);
    const StepReport r = Step(model, ipopt_options, &ipopt_state, &ipopt_data);
    ipopt_nonconverged += !r.converged;
    ipopt_solves += r.ipopt_solves;
    max_v_difference = std::max(max_v_difference, (ipopt_state.v - newton_state.v).cwiseAbs().maxCoeff());
  }
  EXPECT_EQ(ipopt_nonconverged, 0);
  EXPECT_GE(ipopt_solves, 100);
  EXPECT_LT(max_v_difference, 1e-5);  // two independent solvers, one trajectory
}

}  // namespace
}  // namespace implicit_sim
