// Islands (step/islands.h): which bodies a step solves together, and results that do not depend on the threads.
#include <cstdint>
#include <vector>

#include <gtest/gtest.h>

#include "implicit_sim/core/io/pile_scene.h"
#include "implicit_sim/core/step/islands.h"

#include "scenario_runner.h"
#include "test_models.h"

namespace implicit_sim {
namespace {

// n spheres (r = 0.05 m, 0.1 kg) in a row along x with centres `spacing` apart at height z over the ground.
Model SpheresInARow(int n, double spacing, double z) {
  Model m;
  m.bodies.push_back(test_models::FixedBody("ground", MakeHalfSpace()));
  for (int i = 0; i < n; ++i) {
    m.bodies.push_back(test_models::MovingBody("ball" + std::to_string(i), MakeSphere(0.05), 0.1,
                                               test_models::MakePose(Vec3(spacing * i, 0.0, z))));
  }
  return test_models::Finish(m);
}

TEST(Islands, BodiesRestingApartOnTheGroundAreIslandsOfTheirOwn) {
  // Resting 5 cm apart: the ground (fixed) is in every sphere's pairs but joins none of them.
  const Model model = SpheresInARow(3, 0.15, 0.05);
  Data data(model, Data::PairSelection::kBroadPhase);
  State state = State::Initial(model);
  StepperOptions options;
  const StepReport report = Step(model, options, &state, &data);
  ASSERT_TRUE(report.converged) << report.fault_detail;
  EXPECT_EQ(report.pairs_in_ncp, 3);
  EXPECT_EQ(report.islands, 3);
  EXPECT_EQ(report.largest_island, 1);
}

TEST(Islands, TouchingBodiesAndJointsJoinAnIsland) {
  {
    const Model model = SpheresInARow(3, 0.1, 0.05);  // touching side by side
    Data data(model, Data::PairSelection::kBroadPhase);
    State state = State::Initial(model);
    const StepReport report = Step(model, StepperOptions(), &state, &data);
    ASSERT_TRUE(report.converged) << report.fault_detail;
    EXPECT_EQ(report.islands, 1);
    EXPECT_EQ(report.largest_island, 3);
  }
  {
    const Model model = test_models::JointedRobot();
    Data data(model);
    State state = State::Initial(model);
    const StepReport report = Step(model, StepperOptions(), &state, &data);
    ASSERT_TRUE(report.converged) << report.fault_detail;
    EXPECT_EQ(report.islands, 1);
    EXPECT_EQ(report.largest_island, model.num_moving());
  }
}

TEST(Islands, PartsFallingSideBySideAreSeparateIslands) {
  // 1 cm apart and falling together: their bounding spheres grown by the fall overlap, their relative motion is nil.
  const Model model = SpheresInARow(4, 0.11, 1.0);
  Data data(model, Data::PairSelection::kBroadPhase);
  State state = State::Initial(model);
  for (int k = 0; k < model.num_moving(); ++k) state.v[Model::v_offset(k) + 2] = -3.0;
  StepperOptions options;
  options.h = 0.005;
  const StepReport report = Step(model, options, &state, &data);
  ASSERT_TRUE(report.converged) << report.fault_detail;
  EXPECT_EQ(report.islands, 4);
  EXPECT_EQ(report.pairs_in_ncp, 0);
}

// Ellipsoids (semi-axes 0.06, 0.05, 0.04 m) side by side along y, centres `spacing` apart, at rest at height z, the
// second one moving towards the first at `approach` (m/s).
Model EllipsoidsSideBySide(double spacing, double z) {
  Model m;
  m.bodies.push_back(test_models::FixedBody("ground", MakeHalfSpace()));
  for (int i = 0; i < 2; ++i) {
    m.bodies.push_back(test_models::MovingBody("part" + std::to_string(i), MakeEllipsoid(Vec3(0.06, 0.05, 0.04)), 0.1,
                                               test_models::MakePose(Vec3(0.0, spacing * i, z))));
  }
  return test_models::Finish(m);
}

int PairsInNcpAfterOneStep(double spacing, double approach) {
  const Model model = EllipsoidsSideBySide(spacing, 1.0);
  Data data(model, Data::PairSelection::kBroadPhase);
  State state = State::Initial(model);
  state.v[Model::v_offset(1) + 1] = -approach;
  StepperOptions options;
  options.h = 0.01;
  const StepReport report = Step(model, options, &state, &data);
  EXPECT_TRUE(report.converged) << report.fault_detail;
  return report.pairs_in_ncp;
}

TEST(Islands, EllipsoidsWhoseBoundingSpheresOverlapStayOutWhileCertifiedApart) {
  // 0.11 m apart along y: the shapes are 1 cm apart, their bounding spheres (r = 0.06 m) overlap by 1 cm.
  EXPECT_EQ(PairsInNcpAfterOneStep(0.11, 0.0), 0);
  EXPECT_EQ(PairsInNcpAfterOneStep(0.11, 0.4), 0);  // closes 4 mm of the 1 cm within the step (+ 5 mm margin)
  EXPECT_EQ(PairsInNcpAfterOneStep(0.11, 0.6), 1);  // 6 mm + 5 mm: it may touch, so it is in
  EXPECT_EQ(PairsInNcpAfterOneStep(0.1, 0.0), 1);   // touching
}

TEST(Islands, ResultsAreBitIdenticalForAnyNumberOfThreads) {
  // A pile of 20 spheres landing: islands form, merge and split; some steps climb the retry ladder.
  const Model model = LoadSceneFromString(MakePileUrdf(20, PileShape::kSphere), "pile");
  std::vector<std::vector<uint64_t>> runs;
  int most_islands = 0, largest = 0;
  for (int threads : {1, 2, 3}) {
    StepperOptions options;
    options.h = 0.005;
    options.threads = threads;
    Data data(model);
    State state = State::Initial(model);
    std::vector<uint64_t> hashes;
    for (int i = 0; i < 120; ++i) {
      const StepReport report = Step(model, options, &state, &data);
      ASSERT_TRUE(report.advanced) << report.fault_detail;
      most_islands = std::max(most_islands, report.islands);
      largest = std::max(largest, report.largest_island);
      hashes.push_back(testing_support::HashStep(state, data));
    }
    runs.push_back(hashes);
  }
  EXPECT_GE(most_islands, 10);  // the run had many islands to spread over threads
  EXPECT_GE(largest, 2);        // and some that joined
  for (size_t r = 1; r < runs.size(); ++r) {
    for (size_t i = 0; i < runs[0].size(); ++i) ASSERT_EQ(runs[r][i], runs[0][i]) << "run " << r << " step " << i + 1;
  }
}

}  // namespace
}  // namespace implicit_sim
