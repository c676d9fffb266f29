// The counter table of StepReport (step/step_report.h): one row per counter, how islands merge, what a run totals.
#include "implicit_sim/core/step/step_report.h"

#include <set>
#include <string>

#include <gtest/gtest.h>

#include "implicit_sim/core/io/run_output.h"
#include "test_models.h"

namespace implicit_sim {
namespace {

TEST(StepCounters, NamesAndFieldsAreUnique) {
  std::set<std::string> names;
  StepReport marked;
  for (const StepCounter& counter : StepCounterTable()) {
    EXPECT_TRUE(names.insert(counter.name).second) << counter.name;
    EXPECT_EQ(marked.*counter.field, 0) << counter.name << " shares its field with another row";
    marked.*counter.field = 1;
  }
}

TEST(StepCounters, IslandsSumTheirCountersAndTheStepKeepsItsOwn) {
  StepReport step, island;
  step.converged = island.converged = true;
  int value = 1;
  for (const StepCounter& counter : StepCounterTable()) {
    step.*counter.field = 100 * value;
    island.*counter.field = value++;
  }
  island.residual = 2.0;
  island.fault = StepFault::kCrossing;
  island.fault_detail = "pair 'a-b' crossed";
  MergeIslandReport(island, &step);
  value = 1;
  for (const StepCounter& counter : StepCounterTable()) {
    const int expected = counter.merge == CounterMerge::kSum ? 101 * value : 100 * value;
    EXPECT_EQ(step.*counter.field, expected) << counter.name;
    ++value;
  }
  EXPECT_EQ(step.cold_restarts, 100 * 2 + 2);  // the table's second row
  EXPECT_EQ(step.pairs_in_ncp, 100 * 12);      // set by the step: never summed
  EXPECT_EQ(step.residual, 2.0);
  EXPECT_EQ(step.fault, StepFault::kCrossing);
  EXPECT_EQ(step.fault_detail, "pair 'a-b' crossed");
  island.converged = false;
  island.fault = StepFault::kDiverged;
  MergeIslandReport(island, &step);
  EXPECT_FALSE(step.converged);
  EXPECT_EQ(step.fault, StepFault::kCrossing);  // the first fault wins
}

TEST(StepCounters, ARunTotalsItsRowsIntoTheSummaryInTableOrder) {
  const Model model = test_models::SphereOnTwoSpheres();
  const Data data(model);
  RunSummary summary;
  StepReport report;
  for (const StepCounter& counter : StepCounterTable()) report.*counter.field = 3;
  for (int i = 0; i < 4; ++i) summary.Add(report, data);
  const std::string json = summary.ToJson();
  size_t last = 0;
  for (const StepCounter& counter : StepCounterTable()) {
    const size_t at = json.find("\"" + std::string(counter.name) + "\": ");
    if (!counter.run_total) {
      EXPECT_EQ(at, std::string::npos) << counter.name;
      continue;
    }
    ASSERT_NE(at, std::string::npos) << counter.name;
    EXPECT_GT(at, last) << counter.name << " out of order";
    last = at;
    EXPECT_EQ(json.substr(at + std::string(counter.name).size() + 4, 3), "12,") << counter.name;
  }
}

}  // namespace
}  // namespace implicit_sim
