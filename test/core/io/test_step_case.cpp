// Step cases (io/step_case.h): a case reads back bit for bit (also under a ',' locale), bad files fail naming the
// file, line and what was expected, and a replayed case ends bit-identically to the step it was taken from (P3 with
// every pair in the NCP; a 10-sphere pile with the broad phase, landing).
#include "implicit_sim/core/io/step_case.h"

#include <unistd.h>

#include <algorithm>
#include <clocale>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <locale>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "implicit_sim/core/io/pile_scene.h"
#include "implicit_sim/core/model/urdf_loader.h"
#include "implicit_sim/core/step/time_stepper.h"
#include "scenario_runner.h"

namespace implicit_sim {
namespace {

std::string SceneText(const std::string& file) {
  std::ifstream in(testing_support::ScenePath(file), std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

bool SameBits(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}

// A scene run for `steps` steps, then captured as the case of its next step (and that step taken in *data).
struct Captured {
  StepCase step_case;
  State end_state;     // after the original step
  StepReport report;   // of the original step
};

Captured RunAndCapture(const Model& model, const std::string& urdf, const std::string& scene_name,
                       const StepperOptions& options, int steps, const Eigen::VectorXd* wrench) {
  Data data(model);
  State state = State::Initial(model);
  for (int i = 0; i < steps; ++i) Step(model, options, &state, &data, wrench);
  Captured captured;
  StepCase& c = captured.step_case;
  c.name = scene_name + "_step" + std::to_string(steps);
  c.origin = "test_step_case";
  c.scene_name = scene_name;
  c.urdf = urdf;
  c.broad_phase = data.broad_phase;
  c.options = options;
  CaptureStepInputs(state, data, wrench, &c.inputs);
  captured.report = Step(model, options, &state, &data, wrench);
  captured.end_state = state;
  c.recorded = RecordOutcome(captured.report);
  return captured;
}

StepperOptions P3Options() {
  StepperOptions options;
  options.newton.max_iterations = 77;  // not the default: the file must carry it
  options.broad_phase_margin = 0.0123;
  return options;
}

Captured P3Case(int steps) {
  static const Model model = LoadSceneFromFile(testing_support::ScenePath("p3_sphere_on_two_spheres.urdf"));
  Eigen::VectorXd wrench = Eigen::VectorXd::Zero(model.nv());
  wrench << 0.1, -0.2, 0.0, 0.0, 0.0, 1.0 / 3.0;
  return RunAndCapture(model, SceneText("p3_sphere_on_two_spheres.urdf"), "p3_sphere_on_two_spheres", P3Options(),
                       steps, &wrench);
}

void ExpectSameCase(const StepCase& a, const StepCase& b) {
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.origin, b.origin);
  EXPECT_EQ(a.scene_name, b.scene_name);
  EXPECT_EQ(a.urdf, b.urdf);
  EXPECT_EQ(a.broad_phase, b.broad_phase);
  for (const OptionRow& row : OptionTable()) {
    const double x = row.get(a.options), y = row.get(b.options);
    EXPECT_EQ(std::memcmp(&x, &y, sizeof(double)), 0) << row.field;
  }
  EXPECT_EQ(std::memcmp(&a.inputs.state.t, &b.inputs.state.t, sizeof(double)), 0);
  EXPECT_TRUE(SameBits(a.inputs.state.q, b.inputs.state.q));
  EXPECT_TRUE(SameBits(a.inputs.state.v, b.inputs.state.v));
  EXPECT_TRUE(SameBits(a.inputs.external_wrench_W, b.inputs.external_wrench_W));
  const WarmStart &wa = a.inputs.warm_start, &wb = b.inputs.warm_start;
  EXPECT_EQ(wa.valid, wb.valid);
  EXPECT_EQ(wa.pairs, wb.pairs);
  EXPECT_TRUE(SameBits(wa.z, wb.z));
  ASSERT_EQ(wa.tangent_axes.size(), wb.tangent_axes.size());
  for (size_t i = 0; i < wa.tangent_axes.size(); ++i) {
    EXPECT_EQ(std::memcmp(wa.tangent_axes[i].data(), wb.tangent_axes[i].data(), 3 * sizeof(double)), 0) << i;
  }
  EXPECT_EQ(wa.velocity_reversals, wb.velocity_reversals);
  EXPECT_EQ(a.recorded.converged, b.recorded.converged);
  EXPECT_EQ(a.recorded.iterations, b.recorded.iterations);
  EXPECT_EQ(a.recorded.residual_evaluations, b.recorded.residual_evaluations);
  EXPECT_EQ(a.recorded.fault, b.recorded.fault);
}

TEST(StepCase, ReadsBackBitForBitFromTextAndFile) {
  const Captured captured = P3Case(150);
  const StepCase& original = captured.step_case;
  ASSERT_TRUE(original.inputs.warm_start.valid);
  const std::string text = StepCaseToText(original);
  const StepCase parsed = ParseStepCase(text, "p3.case");
  ExpectSameCase(original, parsed);
  EXPECT_EQ(parsed.options.newton.max_iterations, 77);
  EXPECT_EQ(StepCaseToText(parsed), text);
  const std::string path = ::testing::TempDir() + "step_case_" + std::to_string(::getpid()) + ".case";
  WriteStepCase(original, path);
  ExpectSameCase(original, ReadStepCase(path));
  std::remove(path.c_str());
}

TEST(StepCase, TextIsTheSameUnderACommaLocale) {
  const StepCase step_case = P3Case(20).step_case;
  const std::string text = StepCaseToText(step_case);
  const std::string c_locale = std::setlocale(LC_ALL, nullptr);
  const std::locale cpp_locale;
  try {
    std::locale::global(std::locale("de_DE.UTF-8"));  // also sets the C locale
  } catch (const std::runtime_error& e) {
    FAIL() << "de_DE.UTF-8 cannot be set (scripts/common.sh generates it): " << e.what();
  }
  const std::string german = StepCaseToText(step_case);
  StepCase parsed;
  EXPECT_NO_THROW(parsed = ParseStepCase(german, "german.case"));
  std::locale::global(cpp_locale);
  std::setlocale(LC_ALL, c_locale.c_str());
  EXPECT_EQ(german, text);
  ExpectSameCase(step_case, parsed);
}

// The text with the `index`-th line (0-based) replaced.
std::string ReplaceLine(const std::string& text, int index, const std::string& line) {
  size_t begin = 0;
  for (int i = 0; i < index; ++i) begin = text.find('\n', begin) + 1;
  return text.substr(0, begin) + line + text.substr(text.find('\n', begin));
}

int LineOf(const std::string& text, const std::string& line_text) {
  const size_t at = text.find("\n" + line_text + "\n");
  return static_cast<int>(std::count(text.begin(), text.begin() + at + 1, '\n'));  // 0-based index of the line
}

// The message of the std::invalid_argument that parsing `text` throws ("" if none).
std::string ParseError(const std::string& text) {
  try {
    ParseStepCase(text, "bad.case");
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(StepCase, BadFilesNameTheFileTheLineAndWhatWasExpected) {
  const std::string text = StepCaseToText(P3Case(30).step_case);
  const int q_line = LineOf(text, "q 7");
  size_t q4_end = 0;  // the end of the line of q[4]
  for (int i = 0; i <= q_line + 5; ++i) q4_end = text.find('\n', q4_end) + 1;
  EXPECT_EQ(ParseError(text.substr(0, q4_end)),
            "bad.case:" + std::to_string(q_line + 7) + ": unexpected end of file, expected q[5]");
  EXPECT_NE(ParseError(text.substr(0, text.size() - 5)).find("urdf: the file ends before"), std::string::npos);
  EXPECT_EQ(ParseError(ReplaceLine(text, 0, "implicit_sim_step_case 2")),
            "bad.case:1: unsupported step case version '2' (this build reads version 1)");
  EXPECT_NE(ParseError("<robot/>\n").find("bad.case:1: not a step case"), std::string::npos);
  EXPECT_EQ(ParseError(ReplaceLine(text, q_line + 1, "nan")),
            "bad.case:" + std::to_string(q_line + 2) + ": q[0] must be a finite number, got 'nan'");
  EXPECT_EQ(ParseError(ReplaceLine(text, q_line + 1, "1,5")),
            "bad.case:" + std::to_string(q_line + 2) + ": q[0] must be a number, got '1,5'");
  const int options_line = LineOf(text, "options " + std::to_string(OptionTable().size()));
  EXPECT_EQ(ParseError(ReplaceLine(text, options_line + 1, "newton.speed 2")),
            "bad.case:" + std::to_string(options_line + 2) +
                ": unknown option 'newton.speed' (not in this build's options table)");
  EXPECT_NE(ParseError(ReplaceLine(text, options_line + 1, "h -1")).find("option h must be in (0, 1] s, got -1"),
            std::string::npos);
  EXPECT_NE(ParseError(text + "x\n").find("unexpected text after 'end'"), std::string::npos);
  const StepCase p3 = P3Case(30).step_case;
  const int reversals_line =
      LineOf(text, "velocity_reversals " + std::to_string(p3.inputs.warm_start.velocity_reversals.size()));
  EXPECT_EQ(ParseError(ReplaceLine(text, reversals_line + 1, "-1")),
            "bad.case:" + std::to_string(reversals_line + 2) +
                ": velocity_reversals[0] must be in [0, 1000000], got -1");
  // A case written before the reversal counts existed reads as all 0.
  std::string old_text = text;
  const size_t from = old_text.find("\nvelocity_reversals ") + 1;
  const size_t to = old_text.find("\nexternal_wrench ") + 1;
  old_text.erase(from, to - from);
  EXPECT_TRUE(ParseStepCase(old_text, "old.case").inputs.warm_start.velocity_reversals.empty());
  EXPECT_THROW(ReadStepCase("/nonexistent/dir/x.case"), std::runtime_error);
}

TEST(StepCase, SizesThatDoNotFitTheSceneAreRefusedNamingTheCase) {
  StepCase short_q = P3Case(30).step_case;
  short_q.inputs.state.q.conservativeResize(6);
  try {
    LoadStepCaseModel(ParseStepCase(StepCaseToText(short_q), "short.case"));
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()),
              "step case 'p3_sphere_on_two_spheres_step30': q has 6 values, its scene needs 7 (nq)");
  }
  StepCase other_warm_start = P3Case(30).step_case;
  other_warm_start.inputs.warm_start.z.conservativeResize(5);
  const Model model = LoadStepCaseModel(other_warm_start);
  State end;
  try {
    ReplayStepCase(model, other_warm_start, &end);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("step case 'p3_sphere_on_two_spheres_step30': warm start does not belong"),
              std::string::npos)
        << e.what();
  }
}

// Replays the case after a round trip through its text; expects the original step's end state and report, bit for bit.
void ExpectReplayIsBitIdentical(const Captured& captured) {
  const StepCase step_case = ParseStepCase(StepCaseToText(captured.step_case), "replay.case");
  const Model model = LoadStepCaseModel(step_case);
  State end;
  const StepReport report = ReplayStepCase(model, step_case, &end);
  EXPECT_EQ(std::memcmp(&end.t, &captured.end_state.t, sizeof(double)), 0);
  EXPECT_TRUE(SameBits(end.q, captured.end_state.q));
  EXPECT_TRUE(SameBits(end.v, captured.end_state.v));
  EXPECT_EQ(report.iterations, captured.report.iterations);
  EXPECT_EQ(report.residual_evaluations, captured.report.residual_evaluations);
  EXPECT_EQ(report.converged, captured.report.converged);
  EXPECT_EQ(report.pairs_in_ncp, captured.report.pairs_in_ncp);
  EXPECT_EQ(std::memcmp(&report.residual, &captured.report.residual, sizeof(double)), 0);
}

TEST(StepCase, ReplayOfP3StepsIsBitIdentical) {
  for (int steps : {0, 1, 100, 294, 320, 371}) {  // the cold first step, warm steps, around the contact events
    SCOPED_TRACE(steps);
    const Captured captured = P3Case(steps);
    EXPECT_EQ(captured.step_case.inputs.warm_start.valid, steps > 0);
    ExpectReplayIsBitIdentical(captured);
  }
}

TEST(StepCase, ReplayOfPileStepsWithTheBroadPhaseIsBitIdentical) {
  const std::string urdf = MakePileUrdf(10, PileShape::kSphere);
  const Model model = LoadSceneFromString(urdf, "pile");
  StepperOptions options;
  options.h = 0.005;
  int iterations = 0;
  for (int steps : {5, 15, 20, 25, 40}) {  // falling, then the landings
    SCOPED_TRACE(steps);
    const Captured captured = RunAndCapture(model, urdf, "pile", options, steps, nullptr);
    EXPECT_TRUE(captured.step_case.broad_phase);
    iterations += captured.report.iterations;
    ExpectReplayIsBitIdentical(captured);
  }
  EXPECT_GT(iterations, 5);  // some of them solved contacts
}

TEST(StepCase, HighestRungFollowsTheLadder) {
  StepReport report;
  EXPECT_EQ(HighestRung(report, true), "warm");
  EXPECT_EQ(HighestRung(report, false), "cold");
  report.cold_restarts = 1;
  EXPECT_EQ(HighestRung(report, true), "cold");
  report.proximal_solves = 1;
  EXPECT_EQ(HighestRung(report, true), "proximal");
  report.smoothed_solves = 1;
  EXPECT_EQ(HighestRung(report, true), "smoothing");
  report.ipopt_solves = 1;
  EXPECT_EQ(HighestRung(report, true), "ipopt");
  report.substeps = 2;
  EXPECT_EQ(HighestRung(report, true), "substeps");
}

}  // namespace
}  // namespace implicit_sim
