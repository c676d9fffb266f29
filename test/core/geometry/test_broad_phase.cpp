// The broad phase and what rests on it: candidate pairs equal a brute-force bounding-sphere test, the end-of-step
// check adds a pair the broad phase could not foresee, the sparse solve with the broad phase follows the dense
// all-pairs solve, and no pair of a pile interpenetrates at any step end by an independent closed-form check.
#include "implicit_sim/core/geometry/broad_phase.h"

#include <random>

#include <gtest/gtest.h>

#include "implicit_sim/core/io/pile_scene.h"
#include "implicit_sim/core/geometry/support.h"
#include "scenario_runner.h"
#include "test_models.h"

namespace implicit_sim {
namespace {

TEST(BroadPhase, CandidatesEqualABruteForceBoundingSphereTest) {
  const Model model = LoadSceneFromString(MakePileUrdf(200, PileShape::kEllipsoid), "pile");
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> margin(0.0, 0.05);
  std::vector<Pose> X_WB(model.bodies.size());
  std::vector<double> inflation(model.bodies.size());
  const State state = State::Initial(model);
  for (size_t b = 0; b < model.bodies.size(); ++b) {
    X_WB[b] = state.X_WB(model, static_cast<int>(b));
    inflation[b] = model.bodies[b].is_fixed ? 0.0 : margin(rng);
  }
  std::vector<double> shape_inflation;  // per shape: its body's
  for (const Geom& geom : model.geoms) shape_inflation.push_back(inflation[geom.body]);
  BroadPhase broad = MakeBroadPhase(model);
  std::vector<int> found;
  broad.FindPairs(X_WB, shape_inflation, &found);
  std::vector<int> expected;
  for (int c = 0; c < static_cast<int>(model.pairs.size()); ++c) {
    const int i = model.pairs[c].body1, j = model.pairs[c].body2;  // i moves
    const Vec3 p_i = X_WB[i].translation();
    const double reach_i = model.bodies[i].shapes[0].BoundingRadius() + inflation[i];
    bool candidate;
    if (model.bodies[j].shapes[0].type == ShapeType::kHalfSpace) {  // the walls and the floor: z <= 0 in their frames
      candidate = (X_WB[j].inverse() * p_i).z() <= reach_i;
    } else {
      candidate = (p_i - X_WB[j].translation()).norm() <= reach_i + model.bodies[j].shapes[0].BoundingRadius() + inflation[j];
    }
    if (candidate) expected.push_back(c);
  }
  EXPECT_EQ(found, expected);
  EXPECT_GT(found.size(), 200u);  // every body has the floor, and neighbours overlap
  EXPECT_LT(found.size(), model.pairs.size() / 20);
}

TEST(BroadPhase, TheEndOfStepCheckAddsAPairTheBroadPhaseCouldNotForesee) {
  // Two spheres 0.1 m apart, at rest, no gravity; a large push on one within the step that the broad phase (which
  // sees only velocities) cannot foresee. The pair enters through the end-of-step check and the step is re-solved.
  Model m;
  m.gravity_W = Vec3::Zero();
  for (double x : {0.0, 0.3, 5.0}) {
    m.bodies.push_back(test_models::MovingBody("s" + std::to_string(m.bodies.size()), MakeSphere(0.1), 1.0,
                                               test_models::MakePose(Vec3(x, 0, 1))));
  }
  const Model model = test_models::Finish(m);
  StepperOptions options;
  options.h = 0.01;
  options.broad_phase_margin = 0.0;
  Data data(model, Data::PairSelection::kBroadPhase);
  State state = State::Initial(model);
  Eigen::VectorXd wrench = Eigen::VectorXd::Zero(model.nv());
  wrench[0] = 2000.0;  // N on s0 along +x: 20 m/s within one step, 0.2 m of travel against the 0.1 m gap
  const StepReport report = Step(model, options, &state, &data, &wrench);
  EXPECT_TRUE(report.converged);
  EXPECT_GE(report.broad_phase_additions, 1);
  const Pose X0 = state.X_WB(model, 0), X1 = state.X_WB(model, 1);
  EXPECT_GE((X1.translation() - X0.translation()).norm() - 0.2, -1e-9);  // touching, not through
  EXPECT_GT(state.v_WB(1).x(), 1.0);                                     // and the push went through the contact
}

TEST(BroadPhase, SparseSolveWithTheBroadPhaseFollowsTheDenseAllPairsSolve) {
  const Model model = LoadSceneFromFile(testing_support::ScenePath("p3_sphere_on_two_spheres.urdf"));
  StepperOptions options;
  Data dense(model, Data::PairSelection::kAllPairs), sparse(model, Data::PairSelection::kBroadPhase);
  ASSERT_FALSE(dense.broad_phase);
  ASSERT_TRUE(sparse.broad_phase);
  State a = State::Initial(model), b = a;
  double max_difference = 0.0;
  for (int i = 0; i < 450; ++i) {  // through both separations (3.21 s, 3.70 s), then free flight
    ASSERT_TRUE(Step(model, options, &a, &dense).converged);
    const StepReport r = Step(model, options, &b, &sparse);
    ASSERT_TRUE(r.converged) << "step " << i;
    max_difference = std::max(max_difference, (a.v - b.v).cwiseAbs().maxCoeff());
  }
  EXPECT_LT(max_difference, 1e-8);
  EXPECT_LT(sparse.layout.blocks().size(), 2u);  // the ball has left the spheres: their pairs left the NCP
}

// Independent of the solver and of support.h: sphere-sphere and sphere-wall distances from the centres alone.
TEST(BroadPhase, NoPairOfASpherePileInterpenetratesAtAnyStepEnd) {
  const int n = 40;
  const double r = 0.05;
  const Model model = LoadSceneFromString(MakePileUrdf(n, PileShape::kSphere), "pile");
  StepperOptions options;
  options.h = 0.005;
  Data data(model);
  ASSERT_TRUE(data.broad_phase);
  State state = State::Initial(model);
  double worst = 0.0;
  int nonconverged = 0, max_in_ncp = 0;
  for (int i = 0; i < 160; ++i) {  // 0.8 s: the spheres land, bounce and settle
    const StepReport report = Step(model, options, &state, &data);
    nonconverged += !report.converged;
    max_in_ncp = std::max(max_in_ncp, report.pairs_in_ncp);
    for (int k = 0; k < n; ++k) {
      const Vec3 p = state.X_WB(model, model.moving_bodies[k]).translation();
      worst = std::max({worst, r - p.z(), r - (0.5 - std::abs(p.x())), r - (0.5 - std::abs(p.y()))});
      for (int j = k + 1; j < n; ++j) {
        worst = std::max(worst, 2 * r - (p - state.X_WB(model, model.moving_bodies[j]).translation()).norm());
      }
    }
  }
  EXPECT_EQ(nonconverged, 0);
  EXPECT_LT(worst, 1e-9) << "largest interpenetration (m)";
  EXPECT_LT(max_in_ncp, static_cast<int>(model.pairs.size()) / 5);  // the broad phase keeps far pairs out
}

}  // namespace
}  // namespace implicit_sim
