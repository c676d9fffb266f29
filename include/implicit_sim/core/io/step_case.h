// A step case: everything one call of Step reads, in one self-contained text file, so that a hard step of a long run
// can be replayed through the solver alone (implicit_sim_replay) and replays bit-identically: the scene's URDF text,
// the pair selection of its Data, the StepperOptions (every row of the options table), the State, the WarmStart in
// the global layout of Data (as SaveWarmStart gives it) and the external wrench, if any. It also records what the
// original step reported (converged, iterations, residual evaluations, fault), so a replay can say whether it
// reproduced it. The file format is documented in bench/README.md (#the-step-case-format); numbers are written in
// the shortest round-trip form with '.' as decimal point whatever the locale.
#pragma once

#include <string>

#include <Eigen/Core>

#include "implicit_sim/core/model/model.h"
#include "implicit_sim/core/model/state.h"
#include "implicit_sim/core/step/data.h"
#include "implicit_sim/core/step/options.h"
#include "implicit_sim/core/step/step_report.h"

namespace implicit_sim {

constexpr int kStepCaseVersion = 1;

// The inputs of one step besides the model and the options.
struct StepInputs {
  State state;                        // before the step
  WarmStart warm_start;               // SaveWarmStart of the Data before the step
  Eigen::VectorXd external_wrench_W;  // 6 values per moving body (N, N m), world frame; empty: no wrench
};

// Saves the inputs of the next step on (state, data), reusing the storage of *out.
void CaptureStepInputs(const State& state, const Data& data, const Eigen::VectorXd* external_wrench_W,
                       StepInputs* out);

// What the original step reported.
struct RecordedOutcome {
  bool converged = false;
  int iterations = 0;
  int residual_evaluations = 0;
  std::string fault = "none";  // StepFaultName
};
RecordedOutcome RecordOutcome(const StepReport& report);

struct StepCase {
  std::string name;        // one line, e.g. "S1_sphere_n100_step0087"
  std::string origin;      // one line: how the case was made (command, step, time)
  std::string scene_name;  // the name the scene was loaded with
  std::string urdf;        // the scene's URDF text, verbatim
  bool broad_phase = false;  // the Data's pair selection: the broad phase, or every pair in every NCP
  StepperOptions options;
  StepInputs inputs;
  RecordedOutcome recorded;
};

// The case as text, and written to a file. Throw std::invalid_argument for a name, origin or scene name that holds a
// line break; WriteStepCase throws std::runtime_error naming the path when it cannot write it.
std::string StepCaseToText(const StepCase& step_case);
void WriteStepCase(const StepCase& step_case, const std::string& path);

// Reads a case. Throws std::invalid_argument "<source>:<line>: ..." naming what was expected (a truncated file, a
// wrong version, an unknown option, a number that is not finite where it must be, a count that does not match);
// ReadStepCase throws std::runtime_error naming the path when it cannot read it.
StepCase ParseStepCase(const std::string& text, const std::string& source);
StepCase ReadStepCase(const std::string& path);

// The case's scene, loaded from its URDF, and checked against the case: throws std::invalid_argument naming the case
// and the sizes when q, v or the wrench do not fit the model (and the loader's message for a bad scene).
Model LoadStepCaseModel(const StepCase& step_case);

// Runs the case's step once: a fresh Data(model) with the case's pair selection, its warm start restored, Step from
// its state with its options and wrench. `model` must be LoadStepCaseModel(step_case). Sets *end_state to the state
// after the step. Throws std::invalid_argument naming the case when the warm start does not fit the model. The step
// watches `interrupt` if given (Data::interrupt).
StepReport ReplayStepCase(const Model& model, const StepCase& step_case, State* end_state,
                          const StepInterrupt* interrupt = nullptr);

// The highest rung of the retry ladder a step reached, from its report's counts: "warm" (or "cold" for a step without
// warm start) when the first solve converged, then "cold", "smoothing", "ipopt", "substeps" (with Ipopt as the
// primary solver every step reaches "ipopt").
std::string HighestRung(const StepReport& report, bool had_warm_start);

}  // namespace implicit_sim
