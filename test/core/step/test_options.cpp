// The options table: its defaults are those of a default-constructed StepperOptions and pass, a value just outside
// each bound fails with a message naming the option, and the node's parameter and runner's flag names are unique.
#include "implicit_sim/core/step/options.h"

#include <cmath>
#include <limits>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace implicit_sim {
namespace {

// Values just outside the bounds of a row (for an open bound, the bound itself; for a closed one, the next double
// past it, and for integer rows also the next integer past it), and for integer and choice rows a non-integer inside
// the range.
std::vector<double> ValuesOutside(const OptionRow& row) {
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<double> values = {row.lower_open ? row.lower : std::nextafter(row.lower, -inf),
                                row.upper_open ? row.upper : std::nextafter(row.upper, inf),
                                std::numeric_limits<double>::quiet_NaN()};
  if (row.kind != OptionKind::kReal) {
    values.insert(values.end(), {row.lower - 1.0, row.upper + 1.0, row.lower + 0.5});
  }
  return values;
}

TEST(Options, TheTableDefaultsAreThoseOfStepperOptionsAndPass) {
  const StepperOptions defaults;
  std::string error;
  EXPECT_TRUE(defaults.IsValid(&error)) << error;
  for (const OptionRow& row : OptionTable()) {
    SCOPED_TRACE(row.field);
    EXPECT_EQ(row.get(defaults), row.default_value);
    EXPECT_TRUE(CheckOptionValue(row, row.default_value, row.field, &error)) << error;
    StepperOptions options;
    row.set(&options, row.default_value);
    EXPECT_EQ(row.get(options), row.default_value);
    EXPECT_NE(std::string(row.description), "");
  }
}

TEST(Options, AValueJustOutsideEachBoundFailsNamingTheOption) {
  for (const OptionRow& row : OptionTable()) {
    for (double value : ValuesOutside(row)) {
      SCOPED_TRACE(std::string(row.field) + " = " + std::to_string(value));
      std::string error;
      EXPECT_FALSE(CheckOptionValue(row, value, row.field, &error));
      EXPECT_NE(error.find(row.field), std::string::npos) << error;
      EXPECT_NE(error.find(OptionRangeText(row)), std::string::npos) << error;
      StepperOptions options;
      row.set(&options, value);
      if (row.kind != OptionKind::kReal && row.get(options) != value) continue;  // set() rounded it into the range
      error.clear();
      EXPECT_FALSE(options.IsValid(&error));
      EXPECT_NE(error.find(row.field), std::string::npos) << error;
      EXPECT_NE(error.find(row.unit), std::string::npos) << error;
    }
  }
}

TEST(Options, TheNewtonToleranceIsInZeroToATenthEverywhere) {
  const OptionRow* row = FindOptionByField("newton.tolerance");
  ASSERT_NE(row, nullptr);
  EXPECT_EQ(row, FindOptionByRosParam("tolerance"));
  EXPECT_EQ(row, FindOptionByRunnerFlag("--tolerance"));
  EXPECT_EQ(OptionRangeText(*row), "(0, 0.1]");
  StepperOptions options;
  options.newton.tolerance = 0.1;
  std::string error;
  EXPECT_TRUE(options.IsValid(&error)) << error;
  options.newton.tolerance = 0.5;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_EQ(error, "newton.tolerance must be in (0, 0.1], got 0.5");
}

TEST(Options, NodeAndRunnerNamesAreUniqueAndFindTheirRow) {
  std::set<std::string> fields, params, flags;
  for (const OptionRow& row : OptionTable()) {
    EXPECT_TRUE(fields.insert(row.field).second) << row.field;
    EXPECT_EQ(FindOptionByField(row.field), &row);
    if (*row.ros_param != '\0') {
      EXPECT_TRUE(params.insert(row.ros_param).second) << row.ros_param;
      EXPECT_EQ(FindOptionByRosParam(row.ros_param), &row);
    }
    if (*row.runner_flag != '\0') {
      EXPECT_TRUE(flags.insert(row.runner_flag).second) << row.runner_flag;
      EXPECT_EQ(std::string(row.runner_flag).rfind("--", 0), 0u) << row.runner_flag;
      EXPECT_EQ(FindOptionByRunnerFlag(row.runner_flag), &row);
    }
  }
  EXPECT_EQ(params, (std::set<std::string>{"time_step", "scheme", "solver", "tolerance", "max_iterations", "threads"}));
  EXPECT_EQ(flags, (std::set<std::string>{"--dt", "--scheme", "--solver", "--tolerance", "--max-iterations", "--threads"}));
  EXPECT_EQ(FindOptionByRosParam(""), nullptr);
  EXPECT_EQ(FindOptionByRunnerFlag("--bogus"), nullptr);
}

TEST(Options, ParsesNumbersAndChoicesFromText) {
  const OptionRow& solver = *FindOptionByField("solver");
  const OptionRow& iterations = *FindOptionByField("newton.max_iterations");
  double value = 0.0;
  std::string error;
  EXPECT_TRUE(ParseOptionValue(solver, "ipopt", "--solver", &value, &error));
  EXPECT_EQ(value, 1.0);
  StepperOptions options;
  solver.set(&options, value);
  EXPECT_EQ(options.solver, StepperOptions::Solver::kIpopt);
  EXPECT_STREQ(OptionChoiceName(solver, options), "ipopt");
  EXPECT_STREQ(OptionChoiceName(*FindOptionByField("scheme"), StepperOptions()), "rattle");
  options.scheme = StepperOptions::Scheme::kPaper;
  EXPECT_STREQ(OptionChoiceName(*FindOptionByField("scheme"), options), "paper");
  EXPECT_FALSE(ParseOptionValue(solver, "path", "--solver", &value, &error));
  EXPECT_EQ(error, "--solver must be newton or ipopt, got 'path'");
  EXPECT_TRUE(ParseOptionValue(iterations, "1e3", "--max-iterations", &value, &error));
  EXPECT_EQ(value, 1000.0);
  EXPECT_FALSE(ParseOptionValue(iterations, "2.5", "--max-iterations", &value, &error));
  EXPECT_EQ(error, "--max-iterations must be an integer in [1, 100000], got 2.5");
  EXPECT_FALSE(ParseOptionValue(iterations, "12abc", "--max-iterations", &value, &error));
  EXPECT_NE(error.find("'12abc'"), std::string::npos) << error;
  EXPECT_FALSE(ParseOptionValue(*FindOptionByField("h"), "2.5", "--dt", &value, &error));
  EXPECT_EQ(error, "--dt must be in (0, 1] s, got 2.5");
}

}  // namespace
}  // namespace implicit_sim
