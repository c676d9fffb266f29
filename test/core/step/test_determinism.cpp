// Determinism: the same run twice, a run after a reset, and a run restored from a saved State and WarmStart all
// give bit-identical trajectories (a hash of every step's state and contact forces).
#include <cstdint>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "implicit_sim/core/io/pile_scene.h"

#include "scenario_runner.h"

namespace implicit_sim {
namespace {

std::vector<uint64_t> RunHashed(const Model& model, const StepperOptions& options, int steps, State* state, Data* data) {
  std::vector<uint64_t> hashes;
  for (int i = 0; i < steps; ++i) {
    Step(model, options, state, data);
    hashes.push_back(testing_support::HashStep(*state, *data));
  }
  return hashes;
}

struct Case {
  std::string name;
  Model model;
  double h;
  StepperOptions::Scheme scheme;
  StepperOptions options() const {
    StepperOptions o;
    o.h = h;
    o.scheme = scheme;
    return o;
  }
};

// Both schemes: the RATTLE step's warm start (stage 1's solution, its start frames) must carry as much as the paper's.
std::vector<Case> Cases() {
  std::vector<Case> cases;
  for (const auto& [scheme, name] : {std::make_pair(StepperOptions::Scheme::kPaper, "paper"),
                                     std::make_pair(StepperOptions::Scheme::kRattle, "rattle")}) {
    cases.push_back({std::string("P3 (dense, every pair), ") + name,
                     LoadSceneFromFile(testing_support::ScenePath("p3_sphere_on_two_spheres.urdf")), 0.001, scheme});
    cases.push_back({std::string("10-sphere pile (broad phase, sparse LU), ") + name,
                     LoadSceneFromString(MakePileUrdf(10, PileShape::kSphere), "pile"), 0.005, scheme});
  }
  return cases;
}

TEST(Determinism, TheSameRunTwiceIsBitIdenticalOver10000Steps) {
  for (const Case& c : Cases()) {
    SCOPED_TRACE(c.name);
    const StepperOptions options = c.options();
    State state1 = State::Initial(c.model), state2 = State::Initial(c.model);
    Data data1(c.model), data2(c.model);
    const std::vector<uint64_t> first = RunHashed(c.model, options, 10000, &state1, &data1);
    const std::vector<uint64_t> second = RunHashed(c.model, options, 10000, &state2, &data2);
    ASSERT_EQ(first.size(), second.size());
    for (size_t i = 0; i < first.size(); ++i) ASSERT_EQ(first[i], second[i]) << "step " << i + 1;
    EXPECT_NE(first[0], first[1]);  // the hash sees the motion
  }
}

TEST(Determinism, ARunAfterAResetRepeatsTheFirstRun) {
  for (const Case& c : Cases()) {
    SCOPED_TRACE(c.name);
    const StepperOptions options = c.options();
    Data data(c.model);
    State state = State::Initial(c.model);
    const std::vector<uint64_t> first = RunHashed(c.model, options, 2000, &state, &data);
    state = State::Initial(c.model);
    ClearWarmStart(&data);
    const std::vector<uint64_t> second = RunHashed(c.model, options, 2000, &state, &data);
    for (size_t i = 0; i < first.size(); ++i) ASSERT_EQ(first[i], second[i]) << "step " << i + 1;
  }
}

TEST(Determinism, ARestoredStateAndWarmStartContinueBitIdentically) {
  for (const Case& c : Cases()) {
    SCOPED_TRACE(c.name);
    const StepperOptions options = c.options();
    Data data(c.model);
    State state = State::Initial(c.model);
    RunHashed(c.model, options, 700, &state, &data);  // mid-run: in contact, warm
    const State saved_state = state;
    WarmStart saved_warm;
    SaveWarmStart(data, &saved_warm);
    ASSERT_TRUE(saved_warm.valid);
    const std::vector<uint64_t> continued = RunHashed(c.model, options, 1000, &state, &data);
    // Into the same Data, which has moved on (other pairs, other pivots) ...
    state = saved_state;
    RestoreWarmStart(c.model, saved_warm, &data);
    const std::vector<uint64_t> restored = RunHashed(c.model, options, 1000, &state, &data);
    // ... and into a new one.
    Data fresh(c.model);
    State fresh_state = saved_state;
    RestoreWarmStart(c.model, saved_warm, &fresh);
    const std::vector<uint64_t> restored_fresh = RunHashed(c.model, options, 1000, &fresh_state, &fresh);
    for (size_t i = 0; i < continued.size(); ++i) {
      ASSERT_EQ(continued[i], restored[i]) << "step " << i + 1 << " after the restore";
      ASSERT_EQ(continued[i], restored_fresh[i]) << "step " << i + 1 << " after the restore into a new Data";
    }
    // Without the warm start the continuation differs: the test would see a lost warm start.
    Data cold(c.model);
    State cold_state = saved_state;
    const std::vector<uint64_t> from_cold = RunHashed(c.model, options, 50, &cold_state, &cold);
    EXPECT_NE(std::vector<uint64_t>(continued.begin(), continued.begin() + 50), from_cold);
  }
}

TEST(Determinism, AWarmStartOfAnotherModelIsRefusedAndChangesNothing) {
  const Model p3 = LoadSceneFromFile(testing_support::ScenePath("p3_sphere_on_two_spheres.urdf"));
  const Model p2 = LoadSceneFromFile(testing_support::ScenePath("p2_sphere_spinning.urdf"));
  Data data(p3);
  State state = State::Initial(p3);
  RunHashed(p3, StepperOptions(), 10, &state, &data);
  WarmStart before, other;
  SaveWarmStart(data, &before);
  Data p2_data(p2);
  State p2_state = State::Initial(p2);
  RunHashed(p2, StepperOptions(), 10, &p2_state, &p2_data);
  SaveWarmStart(p2_data, &other);
  EXPECT_THROW(RestoreWarmStart(p3, other, &data), std::invalid_argument);
  WarmStart after;
  SaveWarmStart(data, &after);
  EXPECT_EQ(after.pairs, before.pairs);
  EXPECT_EQ(after.z, before.z);
  EXPECT_EQ(after.valid, before.valid);
}

}  // namespace
}  // namespace implicit_sim
